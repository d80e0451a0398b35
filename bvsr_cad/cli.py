"""The `bvsr` command line: the only place that parses arguments and prints.

Exit codes: 0 success, 1 a check or analysis failed, 2 bad input.
Progress goes to stderr; ``--json`` prints exactly one JSON object on stdout.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # argparse exits 2 already; keep the message short
        self.print_usage(sys.stderr)
        print(f"bvsr: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_BAD_INPUT)


def _progress(quiet: bool):
    t0 = time.perf_counter()

    def say(msg: str) -> None:
        if not quiet:
            print(f"[{time.perf_counter() - t0:6.1f}s] {msg}", file=sys.stderr, flush=True)

    return say


def _print_results(results, as_json: bool, extra: dict | None = None) -> int:
    from .checks.result import overall

    ok = overall(results)
    if as_json:
        payload = {"passed": ok, "checks": [r.to_json() for r in results]}
        payload.update(extra or {})
        print(json.dumps(payload))
    else:
        for r in results:
            print(r.line())
        failed = [r for r in results if r.passed is False]
        print(f"{len(results) - len(failed)} passed, {len(failed)} failed"
              if failed else f"all {len(results)} checks passed ({sum(r.passed is None for r in results)} "
              "informational)")
    return EXIT_OK if ok else EXIT_FAILED


def cmd_build(args) -> int:
    from .pipeline import build_export

    res = build_export(args.params, args.output, _progress(args.quiet))
    failed = [r for r in res.results if r.passed is False]
    summary = {"out": str(res.out_dir), "seconds": round(res.seconds, 2),
               "passed": not failed, "failed_checks": [r.name for r in failed]}
    if args.json:
        print(json.dumps(summary))
    else:
        print(f"wrote {res.out_dir}/ in {res.seconds:.1f} s; {len(res.results)} checks, {len(failed)} failed")
        for r in failed:
            print(r.line())
    return EXIT_FAILED if failed else EXIT_OK


def cmd_check(args) -> int:
    from .checks.run import run_checks

    results = run_checks(args.export, _progress(args.quiet or args.json))
    return _print_results(results, args.json)


def make_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="bvsr", description="Parametric CAD and fabrication pipeline for the BVSR soft robotic tail.")
    sub = p.add_subparsers(dest="command", required=True, parser_class=_Parser)
    b = sub.add_parser("build", help="build every part of a tail into an export folder")
    b.add_argument("params", nargs="?", default="params/bvsr.toml", help="parameter file (default params/bvsr.toml)")
    b.add_argument("-o", "--output", help="export folder (default exports/<name>/)")
    b.add_argument("--json", action="store_true", help="print one JSON summary on stdout")
    b.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    b.set_defaults(func=cmd_build)
    c = sub.add_parser("check", help="run every check on an export folder")
    c.add_argument("export", help="export folder made by `bvsr build`")
    c.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    c.add_argument("-q", "--quiet", action="store_true", help="no progress on stderr")
    c.set_defaults(func=cmd_check)
    return p


def main(argv: list[str] | None = None) -> int:
    args = make_parser().parse_args(argv)
    from .checks.export import ExportError
    from .parts._kernel import GeometryError
    from .pipeline import OutputError
    from .spec.load import ParamError

    try:
        return args.func(args)
    except (ParamError, OutputError, ExportError) as exc:
        print(f"bvsr: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except GeometryError as exc:
        print(f"bvsr: geometry error: {exc}", file=sys.stderr)
        return EXIT_FAILED
    except KeyboardInterrupt:
        print("bvsr: interrupted; nothing was published", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
