"""Writes the kinematic analyses (workspace, quasi-static table, clearance, joint limits) into an export."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..analysis.clearance import clearance_map, clearance_over, plot_clearance_map, posed_tail
from ..analysis.limits import fold_stack, joint_limits, stack_limit_rad
from ..analysis.workspace import plot_workspace, quasi_static_table, run_workspace
from ..assembly.build import Assembly

#: Limits in the build: 36 bending planes, 1 mrad steps.
BUILD_LIMIT_PHIS = 36


def write_analyses(asm: Assembly, root: Path, progress: Callable[[str], None]) -> dict[str, Any]:
    """Run the analyses on ``asm`` and write them under ``root/analysis``.

    Returns:
        ``{"analysis": {...}}``: paths relative to the manifest.
    """
    spec = asm.spec
    cfg = spec.analysis
    out = root / "analysis"
    out.mkdir(exist_ok=True)
    t0 = time.perf_counter()
    progress("analysis: workspace")
    ws = run_workspace(asm, cfg.build_workspace_samples, cfg.seed, progress)
    plot_workspace(ws, out / "workspace.png", spec.name)
    quasi = quasi_static_table(asm, (1.0, 2.0))
    ws_json = {"samples": ws.samples, "seed": ws.seed, "tip_extent_mm": ws.extent_mm(),
               "max_theta_rad": ws.max_theta_rad, "quasi_static_segment": quasi}
    (out / "workspace.json").write_text(json.dumps(ws_json, indent=1))
    progress("analysis: clearance")
    pt = posed_tail(asm, progress)
    import numpy as np

    rng = np.random.default_rng(cfg.seed)
    idx = rng.integers(0, ws.samples, cfg.build_clearance_poses)
    res = clearance_over(pt, ws.w[idx])
    cl_json = res.to_json() | {"required_mm": cfg.min_clearance_mm,
                               "note": "poses resampled from the build's workspace samples"}
    (out / "clearance.json").write_text(json.dumps(cl_json, indent=1))
    progress("analysis: joint limits")
    stack = fold_stack(spec)
    lims = joint_limits(pt, cfg.min_clearance_mm, BUILD_LIMIT_PHIS, exact=True, stack=stack, progress=progress)
    tip = spec.joints - 1
    th, ph, bound = clearance_map(pt, tip, 1.0)
    phis = np.asarray(lims[tip].phi_rad)
    plot_clearance_map(th, ph, bound, out / "clearance_map.png",
                       f"{spec.name}: minimum clearance (bound) with j{spec.joints} bending alone",
                       ws.max_theta_rad, cfg.min_clearance_mm,
                       {"theta_max (saved limit)": (phis, np.asarray(lims[tip].theta_max_rad)),
                        "SOAs fully folded (fold stack)": (phis, stack_limit_rad(pt, tip, phis, *stack))})
    lim_json = {"required_clearance_mm": cfg.min_clearance_mm, "theta_search_max_rad": 1.0,
                "resolution_rad": 1e-3, "fold_stack_lambda": stack[0],
                "method": "the smaller of the SOAs' fold stack and the clearance limit: free for certain up to "
                          "theta_bound_rad (stage-1 bounds), exact distances above it (analysis/limits.py)",
                "joints": [vars(lim) for lim in lims], "workspace_max_theta_rad": ws.max_theta_rad}
    (out / "limits.json").write_text(json.dumps(lim_json, indent=1))
    progress(f"analysis: {time.perf_counter() - t0:.1f} s")
    return {"analysis": {"limits": "analysis/limits.json", "workspace": "analysis/workspace.json",
                         "clearance": "analysis/clearance.json", "workspace_png": "analysis/workspace.png",
                         "clearance_map_png": "analysis/clearance_map.png"}}


def _analyses_from_params(params: str, root: str, sha256: str) -> dict[str, Any]:
    """The second process's work (``bvsr build``): the same analyses from the parameter file (the
    one the build read: ``sha256``), progress on stderr (the parent relays it)."""
    import sys

    from ..assembly.build import build_assembly
    from ..parameters.load import ParamError, load_spec, params_sha256

    if params_sha256(params) != sha256:
        raise ParamError(params, ["the file changed while the build was running; build again"])

    def say(msg: str) -> None:
        print(f"(second process) {msg}", file=sys.stderr, flush=True)

    return write_analyses(build_assembly(load_spec(params)), Path(root), say)


if __name__ == "__main__":
    import sys

    from ..worker import serve

    sys.exit(serve(sys.argv[1], _analyses_from_params, *sys.argv[2:]))
