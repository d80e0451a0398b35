"""Checks on the kinematic analyses saved in an export (reads files only)."""

from __future__ import annotations

import json

from ..parameters import paper
from .export import Export
from .result import CheckResult


def check_analyses(exp: Export) -> list[CheckResult]:
    """The analysis files the manifest names are there, the clearance holds over the workspace and
    the joint limits cover it; the workspace and Table III against the paper."""
    ana = exp.manifest.get("analysis")
    if not ana:
        return [
            CheckResult(
                "analysis:present", False, 0, 1, "", "manifest.json", "no analysis in the manifest"
            )
        ]
    out, files = _analysis_files(exp, ana)
    if "clearance" in files:
        out.append(_clearance_result(files["clearance"], ana["clearance"]))
    if "limits" in files and "workspace" in files:
        out.append(_limits_result(files["limits"], files["workspace"], ana["limits"]))
    if "workspace" in files:
        out += _workspace_paper_results(
            files["workspace"], ana["workspace"], exp.manifest.get("segments", 2)
        )
    return out


def _analysis_files(exp: Export, ana: dict) -> tuple[list[CheckResult], dict[str, dict]]:
    """Whether each analysis file is in the export, and the JSON ones read, by manifest key."""
    out: list[CheckResult] = []
    files = {}
    for key in ("limits", "workspace", "clearance", "workspace_png", "clearance_map_png"):
        path = exp.root / ana.get(key, "")
        ok = key in ana and path.is_file()
        out.append(CheckResult(f"analysis_file:{key}", ok, int(ok), 1, "", ana.get(key, "?")))
        if ok and path.suffix == ".json":
            files[key] = json.loads(path.read_text())
    return out, files


def _clearance_result(c: dict, rel: str) -> CheckResult:
    """The smallest clearance over the workspace (``clearance.json``) reaches the required one."""
    return CheckResult(
        "clearance:min_over_workspace",
        c["min_clearance_mm"] >= c["required_mm"],
        c["min_clearance_mm"],
        c["required_mm"],
        "mm",
        rel,
        f"{c['pair'][0]} / {c['pair'][1]} over {c['poses']} poses "
        f"(bound {c['lower_bound_mm']:.3f} mm, certified {c['certified']})",
    )


def _limits_result(lim: dict, workspace: dict, rel: str) -> CheckResult:
    """The joint limits (``limits.json``) allow the largest bend of the workspace."""
    lowest = min(min(j["theta_max_rad"]) for j in lim["joints"])
    reach = workspace["max_theta_rad"]
    return CheckResult(
        "limits:cover_workspace",
        lowest >= reach,
        lowest,
        reach,
        "rad",
        rel,
        "smallest theta_max(phi) (clearance bounds, SOA fold stack) against the largest "
        "workspace theta",
    )


def _workspace_paper_results(w: dict, rel: str, segments: int) -> list[CheckResult]:
    """The tip's sideways reach and each motion's quasi-static angle and blocked force (Table III)
    against the paper's (informational)."""
    ref = paper.paper_workspace_half_width(segments)
    ext = w["tip_extent_mm"]
    half = max(abs(v) for ax in ("x", "y") for v in ext[ax])
    out = [
        CheckResult(
            "paper:workspace_half_width",
            None,
            half,
            ref.value,
            "mm",
            rel,
            f"largest sideways tip reach vs paper {ref.where}",
        )
    ]
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
                rel,
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
                rel,
                "Table III",
            )
        )
    return out
