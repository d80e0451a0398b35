"""Checks on the kinematic analyses saved in an export (reads files only)."""

from __future__ import annotations

import json

from ..parameters import paper
from .export import Export
from .result import CheckResult


def check_analyses(exp: Export) -> list[CheckResult]:
    ana = exp.manifest.get("analysis")
    if not ana:
        return [
            CheckResult(
                "analysis:present", False, 0, 1, "", "manifest.json", "no analysis in the manifest"
            )
        ]
    out: list[CheckResult] = []
    files = {}
    for key in ("limits", "workspace", "clearance", "workspace_png", "clearance_map_png"):
        path = exp.root / ana.get(key, "")
        ok = key in ana and path.is_file()
        out.append(CheckResult(f"analysis_file:{key}", ok, int(ok), 1, "", ana.get(key, "?")))
        if ok and path.suffix == ".json":
            files[key] = json.loads(path.read_text())
    if "clearance" in files:
        c = files["clearance"]
        out.append(
            CheckResult(
                "clearance:min_over_workspace",
                c["min_clearance_mm"] >= c["required_mm"],
                c["min_clearance_mm"],
                c["required_mm"],
                "mm",
                ana["clearance"],
                f"{c['pair'][0]} / {c['pair'][1]} over {c['poses']} poses "
                f"(bound {c['lower_bound_mm']:.3f} mm, certified {c['certified']})",
            )
        )
    if "limits" in files and "workspace" in files:
        lim = files["limits"]
        lowest = min(min(j["theta_max_rad"]) for j in lim["joints"])
        reach = files["workspace"]["max_theta_rad"]
        out.append(
            CheckResult(
                "limits:cover_workspace",
                lowest >= reach,
                lowest,
                reach,
                "rad",
                ana["limits"],
                "smallest theta_max(phi) (clearance bounds, SOA fold stack) against the largest "
                "workspace theta",
            )
        )
    if "workspace" in files:
        w = files["workspace"]
        ref = paper.paper_workspace_half_width(exp.manifest.get("segments", 2))
        ext = w["tip_extent_mm"]
        half = max(abs(v) for ax in ("x", "y") for v in ext[ax])
        out.append(
            CheckResult(
                "paper:workspace_half_width",
                None,
                half,
                ref.value,
                "mm",
                ana["workspace"],
                f"largest sideways tip reach vs paper {ref.where}",
            )
        )
        for row in w["quasi_static_segment"]:
            if abs(row["area_mm2"] - w["quasi_static_segment"][0]["area_mm2"]) > 1e-9:
                continue  # the sensitivity rows (other A) are in the file only
            m = row["motion"]
            out.append(
                CheckResult(
                    f"paper:qs_max_angle:{m}",
                    None,
                    row["max_angle_deg"],
                    paper.QS_MAX_ANGLE_DEG[m].value,
                    "deg",
                    ana["workspace"],
                    "Table III",
                )
            )
            out.append(
                CheckResult(
                    f"paper:qs_blocked_force:{m}",
                    None,
                    row["blocked_force_n"],
                    paper.QS_BLOCKED_FORCE_N[m].value,
                    "N",
                    ana["workspace"],
                    "Table III",
                )
            )
    return out
