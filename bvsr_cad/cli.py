"""The `bvsr` command line: the only place that parses arguments and prints.

Exit codes: 0 success, 1 a check or analysis failed, 2 bad input.
Progress goes to stderr; ``--json`` prints exactly one JSON object on stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import threading
import time
from pathlib import Path

from .build._runtime.worker import SecondProcess, library_imports, tune_process

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # argparse exits 2 already; keep the message short
        self.print_usage(sys.stderr)
        print(f"bvsr: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)


def _progress(quiet: bool):
    t0 = time.perf_counter()
    lock = threading.Lock()  # a second process's lines arrive from a reader thread

    def say(msg: str) -> None:
        if not quiet:
            with lock:
                sys.stderr.write(f"[{time.perf_counter() - t0:6.1f}s] {msg}\n")
                sys.stderr.flush()

    return say


def _print_results(results, as_json: bool, extra: dict | None = None, verbose: bool = False) -> int:
    from .checks.result import overall, summary_lines

    ok = overall(results)
    if as_json:
        payload = {"passed": ok, "checks": [r.to_json() for r in results]}
        payload.update(extra or {})
        print(json.dumps(payload))
    else:
        for line in [r.line() for r in results] if verbose else summary_lines(results):
            print(line)
        failed = sum(r.passed is False for r in results)
        skipped = sum(r.skipped for r in results)
        info = sum(r.passed is None for r in results) - skipped
        tail = f"{info} informational, {skipped} skipped"
        print(
            f"{len(results) - failed - info - skipped} passed, {failed} failed ({tail})"
            if failed
            else f"all {len(results) - info - skipped} checks passed ({tail})"
            + ("" if verbose else "; --verbose lists every check")
        )
    return EXIT_OK if ok else EXIT_FAILED


def _params_or_default(args, say) -> str:
    """The parameter file a build or watch names, else ``params/bvsr.toml`` of this folder (a copy
    that ``bvsr init`` wrote), else, for a build, the default tail shipped with the package."""
    from . import defaults

    if args.params is not None:
        return args.params
    if Path(defaults.DEFAULT_PARAMS).is_file():
        return defaults.DEFAULT_PARAMS
    packaged = defaults.path(defaults.DEFAULT_PARAMS)
    say(
        f"no {defaults.DEFAULT_PARAMS} in this folder: building the default tail of bvsr_cad "
        f"{_version()} "
        f"({packaged}); `bvsr init` writes a copy to edit"
    )
    return str(packaged)


def cmd_build(args) -> int:
    say = _progress(args.quiet or args.json)
    args.params = _params_or_default(args, say)

    # The analyses' second process imports its modules beside this process's imports of the
    # pipeline, and builds the tail's assembly from the file while this process decides what the
    # cache holds.
    standby = SecondProcess.standby(
        "bvsr_cad.build._runtime.analyses_process", say, [str(Path(args.params).resolve())]
    )
    try:
        # A bad file is refused, and an export the cache holds whole is published, in a fraction of
        # a second: before the pipeline's imports (seconds).
        from .build.publish import open_build, reuse_whole

        opened = open_build(args.params, args.output, say, use_cache=not args.no_cache)
        res = reuse_whole(opened)
        if res is None:
            with (
                library_imports()
            ):  # a Ctrl-C in the pipeline's imports stops the build (worker.library_imports)
                from .build.pipeline import build_opened

            res = build_opened(opened, standby)
    finally:
        if standby is not None:
            standby.close()  # a no-op once it gave its result; stops one given no work
    failed = [r for r in res.results if r.passed is False]
    summary = {
        "out": str(res.out_dir),
        "seconds": round(res.seconds, 2),
        "passed": not failed,
        "failed_checks": [r.name for r in failed],
        "stages": res.stages,
        "cpu_seconds": res.cpu_s,
    }
    if args.json:
        print(json.dumps(summary))
    else:
        reused = [s["stage"] for s in res.stages if s["status"] == "reused"]
        cpu = ", ".join(f"{name} {s:.1f} s" for name, s in res.cpu_s.items())
        print(
            f"wrote {res.out_dir}/ in {res.seconds:.1f} s (CPU by process: {cpu}); "
            f"{len(res.results)} checks, "
            f"{len(failed)} failed"
            + (f"; reused from the cache: {', '.join(reused)}" if reused else "")
        )
        for r in failed:
            print(r.line())
    return EXIT_FAILED if failed else EXIT_OK


def cmd_watch(args) -> int:
    from .defaults import DEFAULT_PARAMS

    if (
        args.params is None and not Path(DEFAULT_PARAMS).is_file()
    ):  # the packaged tail is not for editing
        print(
            f"bvsr: error: no {DEFAULT_PARAMS} in this folder to watch: `bvsr init` writes one to "
            "edit, or name "
            "a parameter file",
            file=sys.stderr,
        )
        return EXIT_BAD_INPUT
    args.params = _params_or_default(args, _progress(args.quiet))
    with library_imports():
        from .build.watch import watch

    def say(msg: str) -> None:
        print(msg, flush=True)

    on_assembly = None
    if args.show:
        from .exporters.ocp_viewer import assembly_sender, viewer_port

        on_assembly = assembly_sender(
            viewer_port(args.port), say
        )  # no viewer: exit 2 before the first build
    return watch(args.params, args.output, say, _progress(args.quiet), on_assembly=on_assembly)


def cmd_show(args) -> int:
    from .exporters.ocp_viewer import viewer_port

    port = viewer_port(args.port)  # no client or no viewer: exit 2 before the CAD imports (seconds)
    target = Path(args.target or "params/bvsr.toml")
    params = target / "params.toml" if target.is_dir() else target
    if target.is_dir() and not params.is_file():
        print(
            f"bvsr: error: EXPORT {target}: no params.toml in it (an export folder holds the "
            "parameter file "
            "it was built from)",
            file=sys.stderr,
        )
        return EXIT_BAD_INPUT
    with library_imports():
        from .api import load

    tail = load(params)
    posed = None if args.theta is None else tail.posed(theta_deg=args.theta, phi_deg=args.phi)
    names = tail.show(posed=posed, port=port)
    pose = (
        "at rest"
        if posed is None
        else f"every joint bent {args.theta:g} deg towards phi = {args.phi:g} deg"
    )
    if args.json:
        print(
            json.dumps(
                {
                    "port": port,
                    "params": str(params),
                    "theta_deg": args.theta,
                    "phi_deg": args.phi,
                    "instances": names,
                }
            )
        )
    else:
        print(f"sent {tail.name} ({pose}, {len(names)} instances) to OCP CAD Viewer on port {port}")
    return EXIT_OK


def cmd_check(args) -> int:
    with library_imports():
        from .build._runtime.checks_process import run_checks

    results = run_checks(args.export, _progress(args.quiet or args.json), run_slicer=args.slice)
    return _print_results(results, args.json, verbose=args.verbose)


def cmd_simulate(args) -> int:
    from .parameters.load import load_spec

    spec = load_spec(args.params)  # a bad file is refused before the simulator's imports (seconds)
    if args.platform == "quadruped":
        return _simulate_quadruped(args, spec)
    with library_imports():
        from .exporters.plots import plot_simulation
        from .parameters import paper
        from .simulation.sim import check_inputs, joint_limits_rad, simulate

    say = _progress(args.quiet or args.json)
    check_inputs(spec, args.pressure_bar, args.payload_g)
    limits = joint_limits_rad(spec, say)
    if args.platform == "cart":
        return _simulate_cart(args, spec, limits, say)
    if args.impact:
        return _simulate_impact(args, spec, limits, say)
    res = simulate(
        spec, limits, args.pressure_bar, args.payload_g, progress=say, supply=args.supply
    )
    out = Path(args.output) if args.output else Path("exports") / spec.name / "simulate"
    out.mkdir(parents=True, exist_ok=True)
    png = out / f"simulate_{args.pressure_bar:g}bar_{args.payload_g:g}g.png"
    supply = args.supply or spec.pneumatics.model
    how = "Eq 13 ramp" if supply == "ramp" else "ISO 6358 valve supply"
    plot_simulation(res, png, f"{spec.name}: {args.pressure_bar:g} bar pulse ({how})")
    v_ref = paper.SEGMENT_PEAK_VELOCITY_EXTENSION
    peaks = paper.paper_root_peaks(args.payload_g) if args.pressure_bar == 6 else None
    comparison = {
        "peak_velocity_deg_s": {
            "computed": res.peak_velocity_deg_s,
            "paper": v_ref.value,
            "paper_at": v_ref.measured_on,
        },
        "peak_root_force_n": {
            "computed": res.peak_root_force_n,
            "paper": peaks[0].value if peaks else None,
        },
        "peak_root_torque_nm": {
            "computed": res.peak_root_torque_nm,
            "paper": peaks[1].value if peaks else None,
        },
    }
    payload = {
        "pressure_bar": res.pressure_bar,
        "payload_g": res.payload_g,
        "peak_velocity_deg_s": res.peak_velocity_deg_s,
        "segment_angle_reached_deg": res.angle_reached_deg,
        "peak_root_torque_nm": res.peak_root_torque_nm,
        "peak_root_force_n": res.peak_root_force_n,
        "joint_limits_rad": limits,
        "plot": str(png),
        "paper": comparison,
        "supply": supply,
    }
    if args.json:
        print(json.dumps(payload))
    else:
        for key, c in comparison.items():
            ref = (
                "not reported at this pressure/payload"
                if c["paper"] is None
                else f"paper {c['paper']:g} "
                f"({100 * (c['computed'] - c['paper']) / c['paper']:+.0f} %)"
            )
            print(f"{key}: {c['computed']:.3g}  {ref}")
        print(f"segment reached {res.angle_reached_deg:.1f} deg; plot: {png}")
    return EXIT_OK


def _simulate_quadruped(args, spec) -> int:
    with library_imports():
        from .exporters.quadruped_files import write_quadruped_results
        from .simulation import quadruped

    say = _progress(args.quiet or args.json)
    host = quadruped.make_host(args.host or "go1", args.body, args.pose)
    export = Path(args.export) if args.export else Path("exports") / spec.name
    res = quadruped.run_experiments(export, host, progress=say)
    summary = quadruped.summary(res)
    out = Path(args.output) if args.output else Path("exports") / spec.name / "simulate"
    files = write_quadruped_results(summary, res, out, spec.name)
    if args.json:
        print(json.dumps({**summary, "files": files}))
        return EXIT_OK
    h = summary["host"]
    print(f"host {h['model']} ({h['mass_kg']:.2f} kg), tail {h['tail_mass_kg'] * 1e3:.1f} g")
    for r in summary["stand"]:
        print(
            f"stance, tail {r['tail']}: height {r['height_min_m']:.4f}-{r['height_max_m']:.4f} m, "
            f"roll/pitch within {r['max_roll_pitch_deg']:.2f} deg, finite {r['finite']}"
        )
    f17 = summary["fig17"]
    print(f"{'Fig. 17':11} {'tail':6} {'torso m/s':>9} {'F_root N':>9} {'T_root N m':>10}")
    for r in f17["rows"]:
        print(
            f"{r['ball'].split(' (')[0]:11} {r['tail']:6} {r['peak_torso_speed_m_s']:9.3f} "
            f"{r['peak_root_force_n']:9.1f} {r['peak_root_torque_nm']:10.2f}"
        )
    ratios = ", ".join(f"{b}: {v['torso_speed']:.2f}" for b, v in f17["soft_over_rigid"].items())
    print(f"soft/rigid peak torso speed {ratios}; paper: {f17['paper']}; agrees: {f17['agrees']}")
    f18 = summary["fig18"]
    head = f"{'roll':>6} {'pitch':>6} {'yaw deg':>7} {'F_root N':>9} {'T_root N m':>10}"
    print(f"{'Fig. 18 g':9} {head}")
    for r in f18["rows"]:
        e = r["excursion_deg"]
        print(
            f"{r['payload_g']:9g} {e['roll']:6.2f} {e['pitch']:6.2f} {e['yaw']:7.2f} "
            f"{r['peak_root_force_n']:9.2f} {r['peak_root_torque_nm']:10.2f}"
        )
    if "force_minus_paper_n" in f18:
        print(
            f"500 g: paper {f18['paper_force_n_500g']:g} N, {f18['paper_torque_nm_500g']:g} N m; "
            f"computed minus paper {f18['force_minus_paper_n']:+.2f} N, "
            f"{f18['torque_minus_paper_nm']:+.2f} N m"
        )
    print(f"files: {', '.join(files.values())}")
    return EXIT_OK


def _simulate_impact(args, spec, limits, say) -> int:
    from .simulation.sim import impact_table, simulate_impact

    rows = impact_table(simulate_impact(spec, limits, progress=say))
    if args.json:
        print(json.dumps(rows, indent=2))
        return 0
    print(
        f"{'tail':6} {'ball':22} {'F_root N':>9} {'T_root N m':>10} {'tip acc m/s2':>12} "
        f"{'paper m/s2':>10} "
        f"{'pen mm':>7} {'warn':>4} {'v m/s':>6} {'v roll':>6}"
    )
    for r in rows:
        print(
            f"{r['tail']:6} {r['ball']:22} {r['peak_root_force_n']:9.1f} "
            f"{r['peak_root_torque_nm']:10.2f} "
            f"{r['peak_tip_acceleration_m_s2']:12.0f} {r['paper_tip_acceleration_m_s2']:10.0f} "
            f"{r['max_penetration_mm']:7.3f} {r['warnings']:4d} {r['ball_speed_m_s']:6.2f} "
            f"{r['rolling_speed_m_s']:6.2f}"
        )
    return 0 if all(r["warnings"] == 0 and r["max_penetration_mm"] <= 1.0 for r in rows) else 1


def _simulate_cart(args, spec, limits, say) -> int:
    with library_imports():
        from .exporters.plots import plot_cart
        from .simulation.sim import cart_comparison, simulate_cart

    runs = simulate_cart(spec, limits, args.pressure_bar, progress=say, supply=args.supply)
    say("Eq 20-22 on the Eq 6-12 tail model")
    rows = cart_comparison(spec, runs, args.pressure_bar)
    out = Path(args.output) if args.output else Path("exports") / spec.name / "simulate"
    out.mkdir(parents=True, exist_ok=True)
    png = out / f"cart_{args.pressure_bar:g}bar.png"
    plot_cart(runs, png, f"{spec.name} on the hinged cart: {args.pressure_bar:g} bar pulses")
    if args.json:
        print(
            json.dumps(
                {
                    "pressure_bar": args.pressure_bar,
                    "rows": rows,
                    "plot": str(png),
                    "supply": args.supply or spec.pneumatics.model,
                }
            )
        )
        return EXIT_OK
    print(f"{'motion':10} {'quantity':17} {'MuJoCo':>8} {'Eq 20-22':>9} {'paper':>7}")
    for row in rows:
        ref = "" if row["paper"] is None else f"{row['paper']:7.3g}"
        print(
            f"{row['motion']:10} {row['quantity'] + ' (' + row['unit'] + ')':17} "
            f"{row['mujoco']:8.3g} "
            f"{row['eq20_22']:9.3g} {ref:>7}"
        )
    print(f"plot: {png}")
    return EXIT_OK


def cmd_calibrate(args) -> int:
    from .parameters.load import load_spec
    from .parameters.measurements import data_sha256, load_measurements

    spec = load_spec(args.params)  # bad files are refused before the models' imports (seconds)
    rows = load_measurements(args.data)
    with library_imports():
        from .analysis.calibrate import calibrate
        from .analysis.predict import Predictor
        from .exporters.calibration_file import write_calibrated_params
        from .simulation.sim import protocol_radius_mm

    say = _progress(args.quiet or args.json)
    names = [n.strip() for n in args.fit.split(",") if n.strip()] if args.fit else None
    say(
        f"{len(rows)} measurements ({sum(m.role == 'fit' for m in rows)} fit, "
        f"{sum(m.role == 'holdout' for m in rows)} holdout); building the geometry"
    )
    res = calibrate(spec, rows, names, Predictor.from_spec(spec, protocol_radius_mm), progress=say)
    out = None
    if args.output:
        out = write_calibrated_params(
            args.params,
            args.output,
            res,
            args.data,
            data_sha256(args.data),
            spec.name,
            (spec.vertebra.material, spec.vertebra.diameter_mm),
        )
    if args.json:
        print(json.dumps({**res.as_json(), "output": None if out is None else str(out)}))
        return EXIT_OK
    print("fitted (95 % interval from the Jacobian; start = the tables' value):")
    for name, v in res.fitted.items():
        print(
            f"  {name} = {v.value:.4g} {v.unit}  [{v.low:.4g} .. {v.high:.4g}]  start {v.start:.4g}"
        )
    print(
        f"{'row':>4} {'role':8} {'quantity (conditions)':74} {'reported':>10} {'uncalib.':>10} "
        f"{'calib.':>10} "
        f"{'error':>7}"
    )
    for r in res.rows:
        err = r["rel_calibrated"]
        print(
            f"{r['row']:>4} {r['role']:8} {r['label'][:74]:74} {r['reported']:>10.4g} "
            f"{r['uncalibrated']:>10.4g} "
            f"{r['calibrated']:>10.4g} {100 * err:>+6.0f}%"
        )
    print(
        f"RMS relative error: fit {res.rms_rel_fit_uncalibrated:.3f} -> {res.rms_rel_fit:.3f}, "
        f"holdout {res.rms_rel_holdout_uncalibrated:.3f} -> {res.rms_rel_holdout:.3f}"
    )
    if out:
        print(f"wrote {out}")
    return EXIT_OK


def _number(minimum: float, inclusive: bool, kind: type = float):
    """argparse type: a number above ``minimum`` (or equal, if ``inclusive``), with a clear
    message."""

    def parse(text: str):
        try:
            value = kind(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"{text!r} is not {'an integer' if kind is int else 'a number'}"
            ) from None
        if value < minimum or (value == minimum and not inclusive):
            raise argparse.ArgumentTypeError(
                f"{text!r}: must be {'>=' if inclusive else '>'} {minimum:g}"
            )
        return value

    return parse


def cmd_workspace(args) -> int:
    with library_imports():
        from .analysis.workspace import run_workspace
        from .assembly.build import build_assembly
        from .parameters.load import load_spec

    spec = load_spec(args.params)
    say = _progress(args.quiet)
    ws = run_workspace(build_assembly(spec, say), args.samples, args.seed, say)
    out = {
        "samples": ws.samples,
        "seed": ws.seed,
        "tip_extent_mm": ws.extent_mm(),
        "max_theta_rad": ws.max_theta_rad,
    }
    print(json.dumps(out) if args.json else "\n".join(f"{k}: {v}" for k, v in out.items()))
    return EXIT_OK


def cmd_clearance(args) -> int:
    with library_imports():
        from .analysis.clearance import clearance_over, posed_tail
        from .analysis.workspace import run_workspace
        from .assembly.build import build_assembly
        from .parameters.load import load_spec

    spec = load_spec(args.params)
    say = _progress(args.quiet)
    asm = build_assembly(spec, say)
    ws = run_workspace(asm, args.poses, spec.analysis.seed, say)
    pt = posed_tail(asm, say)
    say(f"clearance over {args.poses} workspace poses")
    res = clearance_over(pt, ws.w)
    out = res.to_json() | {
        "required_mm": spec.analysis.min_clearance_mm,
        "seconds": res.seconds,
        "poses_per_s": res.poses_per_s,
    }
    ok = res.min_clearance_mm >= spec.analysis.min_clearance_mm
    print(
        json.dumps(out)
        if args.json
        else f"min clearance {res.min_clearance_mm:.4f} mm between {res.pair[0]} and {res.pair[1]} "
        "over "
        f"{res.poses} poses ({res.poses_per_s:.0f} poses/s; bound {res.lower_bound_mm:.4f} mm, "
        f"certified {res.certified}); required {spec.analysis.min_clearance_mm} mm"
    )
    return EXIT_OK if ok else EXIT_FAILED


def cmd_sweep(args) -> int:
    from .extras import require
    from .parameters.study import load_study

    study = load_study(
        args.study
    )  # a bad study file is refused before the sweep's imports (seconds)
    require("studies", "bvsr sweep")
    with library_imports():
        from .studies.sweep import run_study

    say = _progress(args.quiet or args.json)
    try:
        res = run_study(
            study,
            args.output,
            scheduler=args.scheduler,
            workers=args.workers,
            progress=not args.quiet,
            keep_exports=args.keep_exports,
            say=say,
        )
    except KeyboardInterrupt:
        print(
            "bvsr: interrupted; the variants that finished are kept in results.jsonl: run the same "
            "command "
            "again to resume",
            file=sys.stderr,
        )
        return 130
    summary = res.as_json()
    if args.json:
        print(json.dumps(summary, default=str))
    else:
        counts = ", ".join(f"{n} {s}" for s, n in summary["status"].items() if n)
        print(
            f"{study.name}: {len(res.rows)} variants ({counts}); {res.reused} from earlier runs, "
            f"{res.computed} computed on {res.workers} worker(s) in {res.seconds:.0f} s"
        )
        for r in res.rows:
            if r["status"] != "ok":
                print(f"  {r['label']}: {r['status']}: {r.get('reason', '')}")
        if res.best:
            print(f"best: {res.best}")
        for name, path in res.files.items():
            print(f"{name}: {path}")
    return EXIT_FAILED if summary["status"]["error"] else EXIT_OK


#: What ``bvsr init`` tells about each file it writes.
_STARTER_FILES = {
    "params/bvsr.toml": "the paper's tail (two segments): edit this one",
    "params/bvsr_l.toml": "the paper's longer BVSR_L tail (three segments)",
    "data/paper_bvsr.csv": "the paper's measurements: `bvsr calibrate` fits to them, the build "
    "compares",
    "studies/vertebra.toml": "the paper's vertebra study (rod material and diameter)",
    "studies/optimise.toml": "an Optuna search for the most root torque per gram",
}


def cmd_init(args) -> int:
    from .exporters.starter_files import StarterExistsError, write_starter

    folder = Path(args.folder)
    try:
        written = write_starter(folder, force=args.force)
    except StarterExistsError as exc:
        print(f"bvsr: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    rel = [p.relative_to(folder).as_posix() for p in written]
    if args.json:
        print(json.dumps({"folder": str(folder), "files": rel, "version": _version()}))
        return EXIT_OK
    print(f"wrote the default inputs of bvsr_cad {_version()} into {folder}/:")
    for name in rel:
        print(f"  {name:24} {_STARTER_FILES.get(name, '')}".rstrip())
    cd = [] if folder.resolve() == Path.cwd().resolve() else [f"  cd {args.folder}"]
    print(
        "\n".join(
            [
                "next:",
                *cd,
                "  bvsr build                       # params/bvsr.toml -> exports/bvsr/ (STEP, "
                "STL, URDF, MJCF, report)",
                "  bvsr check exports/bvsr          # every check again on the export",
                "  bvsr watch                       # rebuild each time params/bvsr.toml is saved",
                "  bvsr simulate params/bvsr.toml   # a 6 bar pulse in MuJoCo",
                "  bvsr sweep studies/vertebra.toml # needs pip install 'bvsr_cad[studies]'",
            ]
        )
    )
    return EXIT_OK


def make_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="bvsr",
        description="Parametric CAD and fabrication pipeline for the BVSR soft robotic tail.",
    )
    p.add_argument("--version", action="version", version=f"bvsr_cad {_version()}")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    # Every command takes these two.
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument(
        "--json", action="store_true", help="print the result as one JSON object on stdout"
    )
    common.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    for add in (
        _add_build_and_watch,
        _add_show,
        _add_init,
        _add_check,
        _add_simulate,
        _add_calibrate,
        _add_workspace,
        _add_sweep,
        _add_clearance,
        _add_mount,
    ):
        add(sub, common)
    return p


def _add_build_and_watch(sub, common: argparse.ArgumentParser) -> None:
    """``bvsr build`` and ``bvsr watch``: a parameter file into an export folder, once or at each
    save."""
    for name, func, helptext in (
        ("build", cmd_build, "build every part of a tail into an export folder"),
        ("watch", cmd_watch, "rebuild the export each time the parameter file is saved"),
    ):
        b = sub.add_parser(name, parents=[common], help=helptext)
        b.add_argument(
            "params",
            nargs="?",
            help="parameter file (default params/bvsr.toml"
            + (", else the default tail shipped with the package)" if name == "build" else ")"),
        )
        b.add_argument("-o", "--output", help="export folder (default exports/<name>/)")
        if name == "build":
            b.add_argument(
                "--no-cache",
                action="store_true",
                help="build every stage from scratch (the cache is $BVSR_CACHE/artifacts, default "
                "~/.cache/bvsr_cad/artifacts)",
            )
        if name == "watch":
            b.add_argument(
                "--show",
                action="store_true",
                help="send the tail to a running OCP CAD Viewer on "
                "each save, as soon as its assembly is built (needs the viewer extra)",
            )
            b.add_argument(
                "--port", type=int, help="the viewer's port (default $OCP_PORT, else 3939)"
            )
        b.set_defaults(func=func)


def _add_show(sub, common: argparse.ArgumentParser) -> None:
    """``bvsr show``: the tail to a running OCP CAD Viewer."""
    sh = sub.add_parser(
        "show",
        parents=[common],
        help="send the tail (at rest or posed) to a running OCP CAD "
        "Viewer, named and coloured (needs the viewer extra)",
    )
    sh.add_argument(
        "target",
        nargs="?",
        metavar="EXPORT|PARAMS",
        help="an export folder or a parameter file (default params/bvsr.toml)",
    )
    sh.add_argument(
        "--theta", type=float, help="bend every joint by this angle, degrees (default: at rest)"
    )
    sh.add_argument(
        "--phi",
        type=float,
        default=0.0,
        help="bending direction from +X towards +Y (dorsal), degrees (default 0)",
    )
    sh.add_argument("--port", type=int, help="the viewer's port (default $OCP_PORT, else 3939)")
    sh.set_defaults(func=cmd_show)


def _add_init(sub, common: argparse.ArgumentParser) -> None:
    """``bvsr init``: editable copies of the default inputs."""
    ini = sub.add_parser(
        "init",
        parents=[common],
        help="write editable copies of the default parameter, data and study files into a folder",
    )
    ini.add_argument("folder", nargs="?", default=".", help="where (default: this folder)")
    ini.add_argument("--force", action="store_true", help="overwrite files that exist")
    ini.set_defaults(func=cmd_init)


def _add_check(sub, common: argparse.ArgumentParser) -> None:
    """``bvsr check``: every check on an export folder."""
    c = sub.add_parser("check", parents=[common], help="run every check on an export folder")
    c.add_argument("export", help="export folder made by `bvsr build`")
    c.add_argument(
        "--slice",
        action="store_true",
        help="first slice every printed STL the slice cache does not hold yet with PrusaSlicer "
        "(prusa-slicer, 2 at a time); `bvsr build` and `bvsr check` never slice otherwise",
    )
    c.add_argument(
        "-v",
        "--verbose",
        action="store_true",
        help="print every check (by default: one line per check group, failures in full)",
    )
    c.set_defaults(func=cmd_check)


def _add_simulate(sub, common: argparse.ArgumentParser) -> None:
    """``bvsr simulate``: a pressure pulse through the MJCF."""
    sm = sub.add_parser(
        "simulate",
        parents=[common],
        help="drive the MJCF with a pressure pulse; peak velocity and root torque",
    )
    simulate_args = {
        "params": {"help": "parameter file"},
        "--pressure-bar": {
            "type": _number(0.0, inclusive=False),
            "default": 6.0,
            "help": "pulse gauge pressure in bar (default 6)",
        },
        "--payload-g": {
            "type": _number(0.0, inclusive=True),
            "default": 0.0,
            "help": "tip payload in grams (default 0)",
        },
        "--supply": {
            "choices": ("ramp", "valve"),
            "help": "pressure input: Eq 13 ramp or the ISO 6358 valve supply (default: "
            "pneumatics.model)",
        },
        "--platform": {
            "choices": ("none", "cart", "quadruped"),
            "default": "none",
            "help": "cart: the tail on the paper's hinged 700 g cart (robot/scene_cart.xml), "
            "extension "
            "and waggle; the cart's lift and angles beside Eq 20-22 and the paper. quadruped: "
            "the export's tail on a standing quadruped (default Unitree Go1, the 'quadruped' "
            "extra): the stance, Fig. 17's ball impacts (soft against rigid) and Fig. 18's tip "
            "payloads",
        },
        "--export": {
            "help": "quadruped: the export folder whose tail is mounted (default exports/<name>)"
        },
        "--host": {"help": "quadruped: the host's MJCF or URDF, or a known host (default go1)"},
        "--body": {"help": "quadruped: the host body the tail is mounted on"},
        "--pose": {
            "help": 'quadruped: the mount frame in that body, "x y z roll pitch yaw" (m, deg)'
        },
        "--impact": {
            "action": "store_true",
            "help": "the paper's disturbance test: a 500 g and a 650 g ball down the 1.35 m, 45 "
            "deg ramp "
            "into the soft tail and the rigid PLA twin; peak root force and torque, tip "
            "acceleration",
        },
        "--output": {"help": "folder for the plot (default exports/<name>/simulate/)"},
    }
    for flag, options in simulate_args.items():
        sm.add_argument(*(("-o", flag) if flag == "--output" else (flag,)), **options)
    sm.set_defaults(func=cmd_simulate)


def _add_calibrate(sub, common: argparse.ArgumentParser) -> None:
    """``bvsr calibrate``: the fit of the unknown quantities to measurements."""
    ca = sub.add_parser(
        "calibrate",
        parents=[common],
        help="fit the quantities no table gives to measurements; report fit and holdout errors",
    )
    ca.add_argument("params", help="parameter file")
    ca.add_argument(
        "data", help="measurements CSV (experiment,quantity,conditions,value,unit,role,source)"
    )
    ca.add_argument(
        "-o",
        "--output",
        help="write the calibrated parameter file here ([calibration] table added)",
    )
    ca.add_argument(
        "--fit", help="comma-separated quantities to fit (default: what the fit rows identify)"
    )
    ca.set_defaults(func=cmd_calibrate)


def _add_workspace(sub, common: argparse.ArgumentParser) -> None:
    """``bvsr workspace``: the tip workspace by the paper's protocol."""
    wk = sub.add_parser(
        "workspace",
        parents=[common],
        help="tip workspace by the paper's random chamber-state protocol",
    )
    wk.add_argument("params", help="parameter file")
    wk.add_argument(
        "--samples",
        type=_number(1, inclusive=True, kind=int),
        default=20000,
        help="random chamber states, one settled tip each (default 20000)",
    )
    wk.add_argument(
        "--seed", type=int, default=1, help="seed of the random chamber states (default 1)"
    )
    wk.set_defaults(func=cmd_workspace)


def _add_sweep(sub, common: argparse.ArgumentParser) -> None:
    """``bvsr sweep``: a design study on Dask."""
    sw = sub.add_parser(
        "sweep", parents=[common], help="run a design study (grid, random or Optuna) on Dask"
    )
    sw.add_argument("study", help="study file (TOML; see studies/)")
    sw.add_argument("-o", "--output", help="study folder (default exports/studies/<study name>/)")
    sw.add_argument(
        "--scheduler",
        help="address of a running Dask scheduler (tcp://host:8786); default: a "
        "LocalCluster on this machine",
    )
    sw.add_argument(
        "--workers",
        type=_number(1, inclusive=True, kind=int),
        help="LocalCluster worker processes (default: one per core)",
    )
    sw.add_argument(
        "--keep-exports",
        action="store_true",
        help="with checks: keep each variant's export in <study folder>/variants/<key>/",
    )
    sw.set_defaults(func=cmd_sweep)


def _add_clearance(sub, common: argparse.ArgumentParser) -> None:
    """``bvsr clearance``: the closest approach of the solids over the workspace."""
    cl = sub.add_parser(
        "clearance", parents=[common], help="minimum clearance between solids over the workspace"
    )
    cl.add_argument("params", help="parameter file")
    cl.add_argument(
        "--poses",
        type=_number(1, inclusive=True, kind=int),
        default=20000,
        help="workspace poses the solids are checked at (default 20000; the seed is analysis.seed)",
    )
    cl.set_defaults(func=cmd_clearance)


def _add_mount(sub, common: argparse.ArgumentParser) -> None:
    """``bvsr mount``: the tail on a host robot, one MJCF."""
    mo = sub.add_parser(
        "mount",
        parents=[common],
        help="attach the tail's MJCF to a body or site of a host robot (MJCF or URDF) and write "
        "the combined scene",
    )
    mo.add_argument(
        "host",
        help="the host: an MJCF or URDF file, or a known host's name (go1: Unitree Go1 of the "
        "quadruped extra)",
    )
    at = mo.add_mutually_exclusive_group(required=True)
    at.add_argument("--body", help="the host body the tail is mounted on")
    at.add_argument(
        "--site", help="the host site the tail is mounted on (the pose is in its frame)"
    )
    mo.add_argument(
        "--pose",
        default="0 0 0",
        help="the mount frame (the centre of the tail root's bolt-circle face, Z along the tail, "
        "Y dorsal) in the body's or site's frame: \"x y z [roll pitch yaw]\", x y z in m, roll "
        'pitch yaw in deg, fixed axes as URDF\'s rpy (default "0 0 0")',
    )
    mo.add_argument(
        "--tail",
        default="exports/bvsr",
        help="the tail: an export folder of `bvsr build` or its robot/bvsr.xml (default "
        "exports/bvsr)",
    )
    mo.add_argument("--prefix", default="tail_", help="put before every tail name (default tail_)")
    mo.add_argument("-o", "--output", required=True, help="the combined scene to write (.xml)")
    mo.set_defaults(func=cmd_mount)


def cmd_mount(args) -> int:
    from .exporters.mount import mount, parse_pose, write_mounted

    pos_m, rpy_rad = parse_pose(args.pose)
    say = _progress(args.quiet or args.json)
    say(f"mounting {args.tail} on {args.host}")
    mounted = mount(
        args.host,
        args.tail,
        body=args.body,
        site=args.site,
        pos_m=pos_m,
        rpy_rad=rpy_rad,
        prefix=args.prefix,
    )
    out = write_mounted(mounted, args.output)
    result = {
        "out": str(out),
        "parent": mounted.parent,
        "mount_body": mounted.mount_body,
        "host_mass_kg": mounted.host_mass_kg,
        "tail_mass_kg": mounted.tail_mass_kg,
        "notes": mounted.notes,
    }
    if args.json:
        print(json.dumps(result))
        return EXIT_OK
    print(
        f"wrote {out}: the tail ({mounted.tail_mass_kg * 1e3:.1f} g) on {mounted.parent!r} of "
        f"{args.host} ({mounted.host_mass_kg:.3f} kg), its names prefixed {mounted.prefix!r}"
    )
    for note in mounted.notes:
        print(f"note: {note}")
    return EXIT_OK


#: Which parameters shape each generator (bvsr_cad/parts/<module>.py), for the advice after a
#: failure.
_GENERATOR_PARAMETERS = {
    "mold": (
        "the SOA casting mold set",
        "[casting] (cavity_wall_mm, pins, bolts, gate, vents) or [soa]",
    ),
    "rigid_tail": (
        "the rigid comparison tail",
        "[fabrication_package] (printer_*_mm, pin_*, tie_rod_*) or "
        "[joint] (panel_diameter_mm, joint_height_mm)",
    ),
    "panel": (
        "a panel",
        "[fabrication] (min_wall_mm, min_pocket_gap_mm), [tubes], [lightening], [mount], "
        "[payload], [socket] or [joint]",
    ),
    "soa": ("the SOA", "[soa] (facet_thickness_mm, fillet_radius_mm, sides, dihedral_deg)"),
    "vertebra": ("the rod", "[vertebra] or [joint]"),
}


def _raised_in_parts(exc: BaseException) -> str | None:
    """The generator module (``bvsr_cad/parts/<name>.py``) the exception was raised in, innermost
    first."""
    tb, found = exc.__traceback__, None
    while tb is not None:
        path = Path(tb.tb_frame.f_code.co_filename)
        if path.parent.name == "parts" and path.parent.parent.name == "bvsr_cad":
            found = path.stem if path.stem != "_kernel" or found is None else found
        tb = tb.tb_next
    return found


def _generator_failure(args, exc: BaseException) -> str:
    """One paragraph for a generator that failed on a parameter file that loaded: what, where, what
    to change."""
    import re

    where = _raised_in_parts(exc)
    part, params = _GENERATOR_PARAMETERS.get(
        where or "", ("a part", "the parameters of the part it names")
    )
    text = " ".join(str(exc).split())
    # The keys a message leads with ("casting.cavity_wall_mm = 3.0: ..."), else every key it
    # mentions.
    named = list(dict.fromkeys(re.findall(r"(?:^|; )([a-z_]+\.[a-z_]+) = ", text))) or list(
        dict.fromkeys(re.findall(r"\b[a-z_]+\.[a-z_]+_(?:mm|deg|percent|material|thread)\b", text))
    )
    change = f"change {', '.join(named)}" if named else f"change {params}"
    source = getattr(args, "params", None)
    published = " Nothing was published." if getattr(args, "func", None) is cmd_build else ""
    return (
        f"bvsr: error: {source or 'the input'} passed validation, but building {part} failed: "
        f"{text}."
        f"{published} To build it, {change}; the rules checked at load do not cover this "
        "combination yet, "
        "so please report the parameter file with this message."
    )


def main(argv: list[str] | None = None) -> int:
    # A command runs its own processes and threads side by side (the build's analyses and checks, a
    # sweep's workers): BLAS's worker threads beside them only spin, for the same files. Set before
    # numpy loads, for this process and every process it starts; a user's
    # value stands.
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    try:
        args = make_parser().parse_args(argv)
    except (
        SystemExit
    ) as exc:  # --help (0) or a bad argument (2): return it like every other outcome
        return int(exc.code or 0)
    try:
        return args.func(args)
    except KeyboardInterrupt:
        print("bvsr: interrupted; nothing was published", file=sys.stderr)
        return 130
    except Exception as exc:
        if _interrupted(
            exc
        ):  # Ctrl-C while a C extension initialised: ImportError from KeyboardInterrupt
            print("bvsr: interrupted; nothing was published", file=sys.stderr)
            return 130
        bad_input, geometry_error = (
            _error_classes()
        )  # those loaded: importing them all takes seconds
        if isinstance(exc, bad_input):
            print(f"bvsr: error: {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
        if (geometry_error is not None and isinstance(exc, geometry_error)) or (
            isinstance(exc, ValueError) and _raised_in_parts(exc) is not None
        ):
            print(_generator_failure(args, exc), file=sys.stderr)
            return EXIT_BAD_INPUT
        raise  # a bug, not a parameter: keep its traceback


def _interrupted(exc: BaseException) -> bool:
    """``exc`` was caused by a KeyboardInterrupt (pybind11 turns one raised while OCP's module
    initialises into ``ImportError: initialization failed`` from it; importing OCP again then fails
    too)."""
    seen: set[int] = set()
    cur: BaseException | None = exc
    while cur is not None and id(cur) not in seen:
        if isinstance(cur, KeyboardInterrupt):
            return True
        seen.add(id(cur))
        cur = cur.__cause__ or cur.__context__
    return False


#: The errors that are bad input (exit code 2), by module and class.
_BAD_INPUT = (
    ("analysis.calibrate", "CalibrationError"),
    ("checks.export", "ExportError"),
    ("checks.printability", "SlicerMissingError"),
    ("extras", "ExtraMissing"),
    ("parameters.load", "ParamError"),
    ("parameters.measurements", "MeasurementError"),
    ("parameters.study", "StudyError"),
    ("exporters.ocp_viewer", "ViewerUnavailable"),
    ("exporters.mount", "MountError"),
    ("build.publish", "OutputError"),
    ("simulation.sim", "SimulationInputError"),
    ("simulation.quadruped", "QuadrupedInputError"),
    ("studies.sweep", "SweepError"),
)


def _error_classes() -> tuple[tuple[type[Exception], ...], type[Exception] | None]:
    """(the errors that are bad input, exit code 2; the CAD kernel's failure on valid-looking
    input).

    Only the classes whose modules are loaded: an error of a class never imported cannot have been
    raised (one from the second process is unpickled, which imports its module), and importing them
    all (the pipeline: seconds) would keep a bad parameter file's message waiting."""

    def loaded(module: str, name: str) -> type[Exception] | None:
        mod = sys.modules.get(f"{__package__ or 'bvsr_cad'}.{module}")
        return getattr(mod, name, None) if mod is not None else None

    bad = tuple(c for c in (loaded(m, n) for m, n in _BAD_INPUT) if c is not None)
    return bad, loaded("parts._kernel", "GeometryError")


def _version() -> str:
    """The installed version, looked up when printed: :mod:`importlib.metadata` takes tens of
    milliseconds to import, and ``import bvsr_cad.cli`` is the start of every ``bvsr`` command."""
    from . import __version__

    return __version__


def console() -> None:
    """The ``bvsr`` command (and ``python -m bvsr_cad.cli``): :func:`main`, then the process ends
    without the interpreter's teardown, which frees every object of the CAD kernel, MuJoCo and the
    rest one by one, after a build's "wrote" line, with its work published, its second processes
    stopped and nothing left to write (what it printed is flushed first). A bug's
    traceback ends it the usual way. Called in-process (tests, scripts), :func:`main` returns its
    exit code instead. The process is tuned as every ``bvsr`` process
    (:func:`bvsr_cad.build._runtime.worker.tune_process`: freed memory kept for reuse, its libraries
    frozen out of the garbage collector, no OpenGL for MuJoCo, OpenBLAS on one thread)."""
    import signal

    try:
        if getattr(signal.getsignal(signal.SIGINT), "bvsr_starting", False):  # bvsr_cad.__main__'s
            signal.signal(signal.SIGINT, signal.default_int_handler)
        tune_process()
        code = main()
    except KeyboardInterrupt:  # before main's own handling: the process settings, the parser
        print("bvsr: interrupted; nothing was published", file=sys.stderr)
        code = 130
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


if __name__ == "__main__":
    console()
