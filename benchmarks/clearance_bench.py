"""Clearance benchmark: the two-stage check over 10,000 workspace poses against a
brute-force exact mesh check (python-fcl, every pair) on a subset.

Run: .venv/bin/python benchmarks/clearance_bench.py [params/bvsr.toml] [subset]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from bvsr_cad.analysis.clearance import brute_force, clearance_over, posed_tail
from bvsr_cad.analysis.workspace import run_workspace
from bvsr_cad.assembly.assemble import build_assembly
from bvsr_cad.parameters.load import load_spec


def main() -> None:
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("params", nargs="?", default="params/bvsr.toml")
    ap.add_argument(
        "subset", nargs="?", type=int, default=20, help="poses checked by brute force (default 20)"
    )
    args = ap.parse_args()
    params, subset = args.params, args.subset
    asm = build_assembly(load_spec(params))
    ws = run_workspace(asm, 2000, 7)
    rng = np.random.default_rng(3)
    w = ws.w[rng.integers(0, ws.samples, 10_000)]
    t0 = time.perf_counter()
    pt = posed_tail(asm)
    setup_s = time.perf_counter() - t0
    res = clearance_over(pt, w)  # the first call also fills the stage-1b table it needs
    warm = clearance_over(pt, w)
    t0 = time.perf_counter()
    bf = brute_force(pt, w[:subset])
    bf_s = time.perf_counter() - t0
    sub = clearance_over(pt, w[:subset])
    rate, bf_rate = res.poses_per_s, subset / bf_s
    print(f"{params}: {len(pt.pairs)} pairs; setup (meshes, rest distances) {setup_s:.2f} s")
    print(
        f"two-stage: {res.poses} poses in {res.seconds:.3f} s = {rate:.0f} poses/s (again: "
        f"{warm.poses_per_s:.0f}); "
        f"min {res.min_clearance_mm:.4f} mm {res.pair}; stage-1a minimum {res.stage1_min_mm:.4f} "
        "mm, "
        f"{res.refined} candidates refined, {res.confirmed} exact, certified {res.certified} "
        f"(lower bound {res.lower_bound_mm:.4f} mm)"
    )
    print(
        f"brute force: {subset} poses x {len(pt.pairs)} pairs in {bf_s:.2f} s = {bf_rate:.2f} "
        "poses/s; "
        f"min {bf.min():.4f} mm"
    )
    print(
        f"ratio {rate / bf_rate:.0f}x; largest disagreement in the minimum clearance on the "
        "subset: "
        f"{abs(sub.min_clearance_mm - bf.min()):.2e} mm"
    )


if __name__ == "__main__":
    main()
