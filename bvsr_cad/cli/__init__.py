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

from ..errors import BadInput, GeneratorFailure
from ..pipeline.processes.worker import SecondProcess
from ..process import library_imports, tune_process
from . import parser
from .parser import _version

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2


def _progress(quiet: bool):
    t0 = time.perf_counter()
    lock = threading.Lock()  # a second process's lines arrive from a reader thread

    def say(msg: str) -> None:
        if not quiet:
            with lock:
                sys.stderr.write(f"[{time.perf_counter() - t0:6.1f}s] {msg}\n")
                sys.stderr.flush()

    return say


def _print_results(results, as_json: bool, verbose: bool = False) -> int:
    from ..checks.result import overall, summary_lines, tally_line

    ok = overall(results)
    if as_json:
        print(json.dumps({"passed": ok, "checks": [r.to_json() for r in results]}))
    else:
        lines = [r.line() for r in results] if verbose else summary_lines(results)
        print("\n".join([*lines, tally_line(results, verbose)]))
    return EXIT_OK if ok else EXIT_FAILED


def _params_or_default(args, say) -> str:
    """The parameter file a build or watch names, else ``params/bvsr.toml`` of this folder (a copy
    that ``bvsr init`` wrote), else, for a build, the default tail shipped with the package."""
    from .. import defaults

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
        "bvsr_cad.pipeline.processes.analyses_process", say, [str(Path(args.params).resolve())]
    )
    try:
        # A bad file is refused, and an export the cache holds whole is published, in a fraction of
        # a second: before the pipeline's imports (seconds).
        from ..pipeline.publish import open_build, reuse_whole

        opened = open_build(args.params, args.output, say, use_cache=not args.no_cache)
        res = reuse_whole(opened)
        if res is None:
            # A Ctrl-C in the pipeline's imports stops the build (process.library_imports).
            with library_imports():
                from ..pipeline.stages import build_opened

            res = build_opened(opened, standby)
    finally:
        if standby is not None:
            standby.close()  # a no-op once it gave its result; stops one given no work
    failed = res.failed
    if args.json:
        print(json.dumps(res.summary()))
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
    from ..defaults import DEFAULT_PARAMS

    if args.params is None and not Path(DEFAULT_PARAMS).is_file():  # not the packaged tail
        raise BadInput(
            f"no {DEFAULT_PARAMS} in this folder to watch: `bvsr init` writes one to edit, or name "
            "a parameter file"
        )
    args.params = _params_or_default(args, _progress(args.quiet))
    with library_imports():
        from ..pipeline.watch import watch

    def say(msg: str) -> None:
        print(msg, flush=True)

    on_assembly = None
    if args.show:
        from ..exporters.ocp_viewer import assembly_sender, viewer_port

        # No viewer: exit 2 before the first build.
        on_assembly = assembly_sender(viewer_port(args.port), say)
    return watch(args.params, args.output, say, _progress(args.quiet), on_assembly=on_assembly)


def cmd_show(args) -> int:
    from ..exporters.ocp_viewer import viewer_port

    port = viewer_port(args.port)  # no client or no viewer: exit 2 before the CAD imports (seconds)
    target = Path(args.target or "params/bvsr.toml")
    params = target / "params.toml" if target.is_dir() else target
    if target.is_dir() and not params.is_file():
        raise BadInput(
            f"EXPORT {target}: no params.toml in it (an export folder holds the parameter file it "
            "was built from)"
        )
    with library_imports():
        from ..api import load

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
        from ..pipeline.cache import ArtifactCache
        from ..pipeline.processes.checks_process import run_checks

    cache = None if args.no_cache else ArtifactCache()
    results = run_checks(
        args.export, _progress(args.quiet or args.json), run_slicer=args.slice, cache=cache
    )
    return _print_results(results, args.json, verbose=args.verbose)


def _simulate_folder(args, spec) -> Path:
    return Path(args.output) if args.output else Path("exports") / spec.name / "simulate"


def cmd_simulate(args) -> int:
    from ..parameters.load import load_spec

    spec = load_spec(args.params)  # a bad file is refused before the simulator's imports (seconds)
    say = _progress(args.quiet or args.json)
    if args.platform == "quadruped":
        with library_imports():
            from ..simulation.quadruped import on_quadruped, quadruped_lines

        export = Path(args.export) if args.export else Path("exports") / spec.name
        folder = _simulate_folder(args, spec)
        res = on_quadruped(export, args.host, args.body, args.pose, folder, spec.name, say)
        return _print_lines(res, args.json, quadruped_lines)
    with library_imports():
        from ..simulation import experiments as ex
        from ..simulation.sim import check_inputs, joint_limits_rad

    check_inputs(spec, args.pressure_bar, args.payload_g)
    limits = joint_limits_rad(spec, say)
    folder = _simulate_folder(args, spec)
    if args.platform == "cart":
        res = ex.cart(spec, limits, args.pressure_bar, folder, args.supply, say)
        return _print_lines(res, args.json, ex.cart_lines)
    if args.impact:
        rows = ex.impact(spec, limits, say)
        if args.json:
            print(json.dumps(rows, indent=2))
            return EXIT_OK
        print("\n".join(ex.impact_lines(rows)))
        return EXIT_OK if ex.impact_resolved(rows) else EXIT_FAILED
    res = ex.pulse(spec, limits, args.pressure_bar, args.payload_g, folder, args.supply, say)
    return _print_lines(res, args.json, ex.pulse_lines)


def _print_lines(result: dict, as_json: bool, lines) -> int:
    """``result`` as one JSON object, or as the text ``lines(result)`` makes of it."""
    print(json.dumps(result) if as_json else "\n".join(lines(result)))
    return EXIT_OK


def cmd_calibrate(args) -> int:
    from ..parameters.load import load_spec
    from ..parameters.measurements import load_measurements

    spec = load_spec(args.params)  # bad files are refused before the models' imports (seconds)
    rows = load_measurements(args.data)
    with library_imports():
        from ..simulation.experiments import calibration, calibration_lines

    say = _progress(args.quiet or args.json)
    res, out = calibration(spec, rows, args.params, args.data, args.fit, args.output, say)
    if args.json:
        print(json.dumps({**res.as_json(), "output": None if out is None else str(out)}))
        return EXIT_OK
    print("\n".join(calibration_lines(res) + ([f"wrote {out}"] if out else [])))
    return EXIT_OK


def cmd_workspace(args) -> int:
    with library_imports():
        from ..analysis.workspace import run_workspace
        from ..assembly.assemble import build_assembly
        from ..parameters.load import load_spec

    spec = load_spec(args.params)
    say = _progress(args.quiet)
    out = run_workspace(build_assembly(spec, say), args.samples, args.seed, say).summary()
    print(json.dumps(out) if args.json else "\n".join(f"{k}: {v}" for k, v in out.items()))
    return EXIT_OK


def cmd_clearance(args) -> int:
    with library_imports():
        from ..analysis.clearance import workspace_clearance
        from ..parameters.load import load_spec

    spec = load_spec(args.params)
    res, out = workspace_clearance(spec, args.poses, _progress(args.quiet))
    print(
        json.dumps(out)
        if args.json
        else f"min clearance {res.min_clearance_mm:.4f} mm between {res.pair[0]} and {res.pair[1]} "
        f"over {res.poses} poses ({res.poses_per_s:.0f} poses/s; bound {res.lower_bound_mm:.4f} "
        f"mm, certified {res.certified}); required {out['required_mm']} mm"
    )
    return EXIT_OK if out["passed"] else EXIT_FAILED


def cmd_sweep(args) -> int:
    from ..extras import require
    from ..parameters.study import load_study

    study = load_study(
        args.study
    )  # a bad study file is refused before the sweep's imports (seconds)
    require("studies", "bvsr sweep")
    with library_imports():
        from ..studies.sweep import run_study

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


def cmd_init(args) -> int:
    from ..exporters.starter_files import STARTER_FILES, write_starter

    folder = Path(args.folder)
    written = write_starter(folder, force=args.force)  # files there: StarterExistsError, exit 2
    rel = [p.relative_to(folder).as_posix() for p in written]
    if args.json:
        print(json.dumps({"folder": str(folder), "files": rel, "version": _version()}))
        return EXIT_OK
    print(f"wrote the default inputs of bvsr_cad {_version()} into {folder}/:")
    for name in rel:
        print(f"  {name:24} {STARTER_FILES.get(name, '')}".rstrip())
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


def cmd_mount(args) -> int:
    from ..exporters.mount import mount, parse_pose, write_mounted

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
    if args.json:
        print(json.dumps(mounted.summary(out)))
        return EXIT_OK
    print(
        f"wrote {out}: the tail ({mounted.tail_mass_kg * 1e3:.1f} g) on {mounted.parent!r} of "
        f"{args.host} ({mounted.host_mass_kg:.3f} kg), its names prefixed {mounted.prefix!r}"
    )
    for note in mounted.notes:
        print(f"note: {note}")
    return EXIT_OK


def make_parser() -> argparse.ArgumentParser:
    """The ``bvsr`` parser with this module's handlers, ``cmd_<command>``, as they are now
    (:func:`bvsr_cad.cli.parser.make_parser`)."""
    return parser.make_parser({name: globals()[f"cmd_{name}"] for name in COMMANDS})


def main(argv: list[str] | None = None) -> int:
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
        message = _bad_input_message(args, exc)
        if message is None:
            raise  # a bug, not a parameter: keep its traceback
        print(message, file=sys.stderr)
        return EXIT_BAD_INPUT


def _bad_input_message(args, exc: Exception) -> str | None:
    """What ``bvsr`` prints for an error that is the input's (exit code 2): a
    :class:`~bvsr_cad.errors.BadInput` as it is, a generator's failure on parameters that loaded
    with the keys to change; None for a bug."""
    from ..parts.failure import generator_failure, raised_in_parts

    if isinstance(exc, BadInput):
        return f"bvsr: error: {exc}"
    if isinstance(exc, GeneratorFailure) or (
        isinstance(exc, ValueError) and raised_in_parts(exc) is not None
    ):
        published = " Nothing was published." if getattr(args, "command", None) == "build" else ""
        return generator_failure(exc, getattr(args, "params", None), published)
    return None


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


def console() -> None:
    """The ``bvsr`` command (and ``python -m bvsr_cad.cli``): :func:`main`, then the process ends
    without the interpreter's teardown, which frees every object of the CAD kernel, MuJoCo and the
    rest one by one, after a build's "wrote" line, with its work published, its second processes
    stopped and nothing left to write (what it printed is flushed first). A bug's
    traceback ends it the usual way. Called in-process (tests, scripts), :func:`main` returns its
    exit code instead. The process is tuned as every ``bvsr`` process
    (:func:`bvsr_cad.process.tune_process`: freed memory kept for reuse, its libraries
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


#: The commands; each one's handler is ``cmd_<name>`` here.
COMMANDS = (
    "build",
    "watch",
    "show",
    "init",
    "check",
    "simulate",
    "calibrate",
    "workspace",
    "sweep",
    "clearance",
    "mount",
)
