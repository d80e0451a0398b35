"""Cold, no-op and one-edit rebuild times of `bvsr build` with the artifact cache.

    python benchmarks/rebuild_bench.py [PARAMS] [--edits a,b,...] [--cold N]

Runs in a private cache (a temporary ``BVSR_CACHE``) and a temporary output
folder: first a cold build (empty cache), then the same file again (no-op),
in this process and then as the command `bvsr build` (what a shell sees:
the interpreter's start, its imports and the cache lookup), then each
one-parameter edit of the base file, each from the cache the cold build
filled. Each build starts its analyses' process ahead, as `bvsr build` does
(it imports and builds the file's assembly while the build reads its cache).
Prints one row per build: seconds, ratio to cold, the CPU seconds of the
build's processes (this one and its second processes: on two cores a build
is CPU-bound when they are near twice its seconds), the same by process as
the build reports them (``build``, ``analyses``, ``checks``), and which
stages were reused. A reference loop (ten million additions in plain Python) is timed
before and after: the machines this runs on differ by up to 1.7x in it, and a
shared machine's speed drifts, so seconds compare between runs only where
that figure does.
"""

from __future__ import annotations

import argparse
import compileall
import json
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: name -> (table, key, new value as TOML)
EDITS = {
    "rod material": ("vertebra", "material", '"PVC"'),
    "rod diameter": ("vertebra", "diameter_mm", "5.0"),
    "pocket clearance": ("fabrication", "pocket_clearance_mm", "0.08"),
    "taper": ("taper", "half_angle_deg", "0.2"),
    "segment count": ("", "segments", "3"),
    "casting shrinkage": ("casting", "shrinkage_percent", "0.4"),
    "printer volume": ("fabrication_package", "printer_x_mm", "220.0"),
    "effective area": ("actuation", "effective_area_mm2", "150.0"),
}


def edited(text: str, table: str, key: str, value: str) -> str:
    """The parameter text with ``table.key`` set to ``value`` (the first such line of the table)."""
    lines = text.splitlines()
    current = ""
    for i, line in enumerate(lines):
        head = re.match(r"^\s*\[([^\]]+)\]", line)
        if head:
            current = head.group(1).strip()
            continue
        m = re.match(rf"^(\s*{re.escape(key)}\s*=\s*)([^#]*?)(\s*#.*)?$", line)
        if m and current == table:
            lines[i] = f"{m.group(1)}{value}{m.group(3) or ''}"
            return "\n".join(lines) + "\n"
    raise KeyError(f"{table}.{key} not in the file")


def command_seconds(path: Path, out: Path) -> tuple[float, float, list[dict], dict[str, float]]:
    """`bvsr build PATH -o OUT --json` in a new interpreter: (wall seconds, CPU seconds of it and
    its children, its stages and its CPU seconds by process as ``--json`` lists them)."""
    c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-m", "bvsr_cad.cli", "build", str(path), "-o", str(out), "--json"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    )
    seconds = time.perf_counter() - t0
    c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    summary = json.loads(done.stdout)
    return (
        seconds,
        (c1.ru_utime + c1.ru_stime) - (c0.ru_utime + c0.ru_stime),
        summary["stages"],
        summary["cpu_seconds"],
    )


#: The reference loop benchmarks/RESULTS.md quotes: ``time python3 -c`` of this, at module level
#: (global names: about 2.5 times the seconds of the same loop inside a function); timed here
#: without the interpreter's start, which a ``time python3 -c`` figure includes (0.1-0.15 s more).
REFERENCE_LOOP = "s = 0\nfor i in range(10000000):\n    s += i\n"


def reference_loop_s() -> float:
    """Seconds of :data:`REFERENCE_LOOP` (ten million additions in plain Python), this machine's
    single-core speed."""
    code = compile(REFERENCE_LOOP, "<reference loop>", "exec")
    t0 = time.perf_counter()
    exec(code, {})
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("params", nargs="?", default=str(ROOT / "params" / "bvsr.toml"))
    ap.add_argument(
        "--edits", default=",".join(EDITS), help="comma-separated edit names (default: all)"
    )
    ap.add_argument(
        "--cold",
        type=int,
        default=1,
        metavar="N",
        help="cold builds, each from an empty cache (default 1); the ratios are to their median: "
        "a shared machine's speed drifts between minutes",
    )
    args = ap.parse_args()
    if args.cold < 1:
        ap.error(f"--cold must be at least 1, not {args.cold}")
    work = Path(tempfile.mkdtemp(prefix="bvsr-rebuild-bench-"))
    users_cache = os.environ.get("BVSR_CACHE")
    os.environ["BVSR_CACHE"] = str(work / "cache")
    from bvsr_cad.pipeline.cache import process_start
    from bvsr_cad.pipeline.processes.worker import SecondProcess
    from bvsr_cad.process import library_imports, tune_process

    tune_process()  # as the `bvsr` command does, and its imports
    with library_imports():
        from bvsr_cad.pipeline.stages import build_export
    base = Path(args.params).resolve()
    text = base.read_text()
    for stale in base.parent.glob(".bench-*.toml"):  # left by a benchmark that was killed
        pid = stale.name.split("-")[1]
        if pid.isdigit() and process_start(int(pid)) is None:
            stale.unlink(missing_ok=True)
    rows = []

    def cpu_s() -> float:
        return sum(
            u.ru_utime + u.ru_stime
            for u in (
                resource.getrusage(resource.RUSAGE_SELF),
                resource.getrusage(resource.RUSAGE_CHILDREN),
            )
        )

    def row(
        label: str, seconds: float, cpu: float, stages: list[dict], by_process: dict[str, float]
    ) -> float:
        reused = [s["stage"] for s in stages if s["status"] == "reused"]
        split = " + ".join(f"{name} {s:.1f}" for name, s in by_process.items())
        rows.append((label, seconds, cpu, split))
        print(
            f"{label:18} {seconds:7.1f} s  {cpu:6.1f} CPU s  reused: {', '.join(reused) or '-'}",
            flush=True,
        )
        print(
            "    " + "; ".join(f"{s['stage']} {s['status']} {s['seconds']:.1f} s" for s in stages),
            flush=True,
        )
        print(f"    CPU s by process, as the build reports them: {split}", flush=True)
        return seconds

    def run(label: str, path: Path) -> float:
        t0, c0 = time.perf_counter(), cpu_s()
        # As `bvsr build` does: the analyses' process started ahead, building the assembly of the
        # file.
        res = build_export(
            path,
            work / "out",
            standby=SecondProcess.standby(
                "bvsr_cad.pipeline.processes.analyses_process", None, [str(path)]
            ),
        )
        return row(label, time.perf_counter() - t0, cpu_s() - c0, res.stages, res.cpu_s)

    # The package's bytecode, as Python writes it on a first run and `make` at install: where the
    # environment sets PYTHONDONTWRITEBYTECODE (this machine's does) and the files changed since,
    # every process of every build would compile the package's modules again (0.2 CPU s each,
    # measured).
    compileall.compile_dir(ROOT / "bvsr_cad", quiet=1)
    before = reference_loop_s()
    print(f"reference loop {before:.2f} s, {os.cpu_count()} cores", flush=True)
    try:
        colds = []
        for i in range(args.cold):
            if i:
                shutil.rmtree(work / "cache", ignore_errors=True)  # empty again: each one cold
            colds.append(run("cold" if args.cold == 1 else f"cold {i + 1}", base))
        cold = statistics.median(colds)
        run("no-op", base)
        row("no-op, command", *command_seconds(base, work / "out"))
        for name in (n.strip() for n in args.edits.split(",") if n.strip()):
            table, key, value = EDITS[name]
            # Beside the base, so its data_file resolves as the base's does; named by this process,
            # so the next run removes it if this one is killed before its `finally`.
            path = base.parent / f".bench-{os.getpid()}-{name.replace(' ', '_')}.toml"
            path.write_text(edited(text, table, key, value))
            try:
                run(name, path)
            except ValueError as exc:  # a ParamError: the edit makes an infeasible tail
                print(f"{name:18} refused at load: {str(exc).splitlines()[-1].strip()}", flush=True)
            finally:
                path.unlink()
        print()
        print(f"{'build':18} {'seconds':>8} {'/ cold':>7} {'CPU s':>7}  CPU s by process")
        for label, seconds, cpu, split in rows:
            print(f"{label:18} {seconds:8.1f} {seconds / cold:7.2f} {cpu:7.1f}  {split}")
        if args.cold > 1:
            print(f"cold, median of {args.cold}: {cold:.1f} s (the ratios' base)")
        print(f"reference loop {before:.2f} s before, {reference_loop_s():.2f} s after")
    finally:
        shutil.rmtree(work, ignore_errors=True)
        if (
            users_cache is None
        ):  # the environment as it was (main() may run inside a longer process)
            os.environ.pop("BVSR_CACHE", None)
        else:
            os.environ["BVSR_CACHE"] = users_cache


if __name__ == "__main__":
    main()
