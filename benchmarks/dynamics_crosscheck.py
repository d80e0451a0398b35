"""The paper's Eq 6-12 model against the MJCF in MuJoCo: one segment's peak extension velocity
(up to 38 deg) at 1, 3 and 6 bar, same parameters, same pressure input.

    python benchmarks/dynamics_crosscheck.py [PARAMS] [--supply ramp|valve] [--uncalibrated]

Prints one row per pressure: both peak velocities and their difference. Both sides take the chamber
pressure from the same input (Eq 13 or the ISO 6358 fill trace of the pulsed lines); the MuJoCo side
uses the exported per-segment model with its actuators' own lag removed (the trace is the chamber
pressure already).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from bvsr_cad.analysis.calibrate import uncalibrated
from bvsr_cad.analysis.predict import Predictor
from bvsr_cad.parameters.load import load_spec
from bvsr_cad.simulation.sim import joint_limits_rad, segment_extension

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("params", nargs="?", default=str(ROOT / "params" / "bvsr.toml"))
    ap.add_argument("--supply", choices=("ramp", "valve"), default=None)
    ap.add_argument(
        "--uncalibrated", action="store_true", help="the tables' values, not the file's fitted ones"
    )
    ap.add_argument("--pressures", default="1,3,6", help="gauge pressures in bar (default 1,3,6)")
    args = ap.parse_args()
    spec = load_spec(args.params)
    if args.uncalibrated:
        spec = uncalibrated(spec)
    supply = args.supply or spec.pneumatics.model
    limits = joint_limits_rad(spec)
    pred = Predictor.from_spec(spec)
    if pred.spec.pneumatics.model != supply:
        import dataclasses

        pred = pred.with_spec(
            dataclasses.replace(spec, pneumatics=dataclasses.replace(spec.pneumatics, model=supply))
        )
    print(
        f"{spec.name} ({'uncalibrated' if args.uncalibrated else 'as the file says'}), supply "
        f"{supply}"
    )
    print(
        f"{'P (bar)':>8} {'Eq 6-12 (deg/s)':>16} {'MuJoCo (deg/s)':>15} {'MuJoCo / Eq':>12} "
        f"{'seconds':>8}"
    )
    for p in (float(x) for x in args.pressures.split(",")):
        t0 = time.perf_counter()
        eq = pred.segment_peak_velocity("extension", p)
        mj = segment_extension(spec, limits, p, supply, seconds=0.6)[3]
        print(f"{p:8g} {eq:16.1f} {mj:15.1f} {mj / eq - 1:+11.1%} {time.perf_counter() - t0:8.1f}")


if __name__ == "__main__":
    main()
