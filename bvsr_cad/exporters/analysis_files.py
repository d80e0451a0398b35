"""Writes the analyses (:class:`bvsr_cad.analysis.run.AnalysisResults`) into an export
(``analysis/``)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from ..analysis.limits import LIMIT_RESOLUTION_RAD, THETA_SEARCH_MAX_RAD
from ..analysis.measured import LANDS_WITHIN_REL
from ..analysis.run import AnalysisResults


def write_analysis_pictures(res: AnalysisResults, root: Path, name: str) -> None:
    """The analyses' pictures under ``root/analysis`` (the workspace, the clearance map and, with
    measured rows, the model against them), as :func:`write_analyses` draws them. They are most of
    that function's time, so the build's analyses' process draws them once its analyses are done,
    beside the build's own stages (:mod:`bvsr_cad.pipeline.processes.analyses_process`). Matplotlib
    is imported here, not with this module: the build's own process, which writes the analyses'
    files, then imports it only when it draws them itself (matplotlib's import is a large part of
    the build's imports)."""
    from .plots import plot_clearance_map, plot_measurements, plot_workspace

    out = root / "analysis"
    out.mkdir(exist_ok=True)
    ws = res.workspace
    plot_workspace(ws, out / "workspace.png", name)
    cm = res.clearance_map
    plot_clearance_map(
        cm.theta_rad,
        cm.phi_rad,
        cm.bound_mm,
        out / "clearance_map.png",
        f"{name}: minimum clearance (bound) with j{cm.joint} bending alone",
        ws.max_theta_rad,
        res.required_clearance_mm,
        {
            "theta_max (saved limit)": (cm.limit_phi_rad, cm.limit_theta_rad),
            "SOAs fully folded (fold stack)": (cm.limit_phi_rad, cm.stack_theta_rad),
        },
    )
    if res.measured is not None and res.measured.rows:
        plot_measurements(
            res.measured.rows,
            out / "measurements.png",
            f"{name}: model against {Path(res.measured.data_file).name}",
            LANDS_WITHIN_REL,
        )


def write_analyses(
    res: AnalysisResults, root: Path, name: str, pictures: bool = True
) -> dict[str, Any]:
    """Serialise ``res`` under ``root/analysis``; ``pictures``: draw them too (False: they are
    drawn, by :func:`write_analysis_pictures` of the same ``res`` and ``name``).

    Returns:
        ``{"analysis": {...}}``: paths relative to the manifest.
    """
    out = root / "analysis"
    out.mkdir(exist_ok=True)
    if pictures:
        write_analysis_pictures(res, root, name)
    ws = res.workspace
    ws_json = {
        "samples": ws.samples,
        "seed": ws.seed,
        "tip_extent_mm": ws.extent_mm(),
        "max_theta_rad": ws.max_theta_rad,
        "quasi_static_segment": res.quasi_static,
    }
    (out / "workspace.json").write_text(json.dumps(ws_json, indent=1))
    cl_json = res.clearance.to_json() | {
        "required_mm": res.required_clearance_mm,
        "note": res.clearance_poses_note,
    }
    (out / "clearance.json").write_text(json.dumps(cl_json, indent=1))
    lim_json = {
        "required_clearance_mm": res.required_clearance_mm,
        "theta_search_max_rad": THETA_SEARCH_MAX_RAD,
        "resolution_rad": LIMIT_RESOLUTION_RAD,
        "fold_stack_lambda": res.fold_stack_lambda,
        "method": "the smaller of the SOAs' fold stack and the clearance limit: free for certain "
        "up to "
        "theta_bound_rad (stage-1 bounds), exact distances above it (analysis/limits.py)",
        "joints": [vars(lim) for lim in res.limits],
        "workspace_max_theta_rad": ws.max_theta_rad,
    }
    (out / "limits.json").write_text(json.dumps(lim_json, indent=1))
    files = {
        "limits": "analysis/limits.json",
        "workspace": "analysis/workspace.json",
        "clearance": "analysis/clearance.json",
        "workspace_png": "analysis/workspace.png",
        "clearance_map_png": "analysis/clearance_map.png",
    }
    if res.measured is not None:
        (out / "measurements.json").write_text(json.dumps(res.measured.to_json(), indent=1))
        files["measurements"] = "analysis/measurements.json"
        if res.measured.rows:
            files["measurements_png"] = "analysis/measurements.png"
    return {"analysis": files}
