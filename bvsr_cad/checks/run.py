"""Every check on an export, in one list."""

from __future__ import annotations

import json
import os
import pickle
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Collection
from pathlib import Path

from .export import Export, clear_cache
from .layout import check_layout
from .mass import check_masses
from .mesh import check_part_mesh
from .analyses import check_analyses
from .molds import check_molds
from .paper import check_paper
from .printability import check_printability, slice_stls
from .result import CheckResult
from .robot import check_robot


def _printability_worker(root: str, out: str, sliced_now: str) -> int:
    """``python -m bvsr_cad.checks.run ROOT OUT SLICED``: the printability checks of the export at ``ROOT``,
    pickled into the file ``OUT`` as ("ok", results) or ("error", exception)."""
    try:
        payload = ("ok", check_printability(Export.open(root), sliced_now=set(json.loads(sliced_now))))
    except BaseException as exc:  # noqa: BLE001 - handed to the parent, which raises it
        payload = ("error", exc)
    try:
        data = pickle.dumps(payload)
    except Exception:  # an exception that does not pickle
        data = pickle.dumps(("error", RuntimeError(f"printability checks failed: {payload[1]!r}")))
    Path(out).write_bytes(data)
    return 0


class _Printability:
    """The printability checks, the slowest group, in a second process (a fresh interpreter that
    is given only the export's path and opens it itself) while the other groups run here. A
    separate interpreter started with ``-m``, not multiprocessing: a spawned child would first
    re-run the caller's main script. On one core, or when the process fails, they run here."""

    def __init__(self, exp: Export, sliced_now: Collection[str], say: Callable[[str], None], parallel: bool):
        self.exp, self.sliced_now, self.say = exp, sliced_now, say
        self.proc: subprocess.Popen | None = None
        if not parallel or (os.cpu_count() or 1) < 2:
            return
        fd, self.out = tempfile.mkstemp(prefix="bvsr-printability-", suffix=".pickle")
        os.close(fd)
        package_root = str(Path(__file__).resolve().parents[2])  # the bvsr_cad this process runs
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(
            [package_root] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])}
        try:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "bvsr_cad.checks.run", str(exp.root), self.out,
                 json.dumps(sorted(sliced_now))],
                cwd=exp.root,  # MuJoCo may write its log into the working folder: as the robot checks
                env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL)
        except OSError as exc:
            say(f"printability: no second process ({exc}); they run after the robot checks")
            os.unlink(self.out)
            return
        self.t0 = time.perf_counter()
        say("printability: started in a second process")

    def results(self) -> list[CheckResult]:
        if self.proc is None:
            self.say("printability")
            return check_printability(self.exp, sliced_now=self.sliced_now)
        if self.proc.poll() is None:
            self.say("printability: waiting for the second process")
        code = self.proc.wait()
        try:
            status, payload = pickle.loads(Path(self.out).read_bytes())
        except (OSError, EOFError, pickle.UnpicklingError):
            self.say(f"printability: the second process ended (exit code {code}) without results; "
                     "running them here")
            self.close()
            return check_printability(self.exp, sliced_now=self.sliced_now)
        self.close()
        if status == "error":
            raise payload
        self.say(f"printability: done in the second process ({time.perf_counter() - self.t0:.1f} s)")
        return payload

    def close(self) -> None:
        if self.proc is not None:
            if self.proc.poll() is None:
                self.proc.terminate()
                self.proc.wait()
            self.proc = None
            try:
                os.unlink(self.out)
            except OSError:
                pass


def run_checks(root: str | Path, progress: Callable[[str], None] | None = None, *,
               run_slicer: bool = False, parallel: bool = True) -> list[CheckResult]:
    """Run every check on the export at ``root``; the results come in the same order either way.

    The checks never start the slicer: the ``slice:*`` results come from the slice cache. With
    ``run_slicer`` (``bvsr check --slice``), every printed STL the cache does not hold is sliced
    first (:func:`~bvsr_cad.checks.printability.slice_stls`). With ``parallel`` (and two cores)
    the printability checks run in a second process beside the others.

    Raises:
        ExportError: the folder is not a readable export.
        SlicerMissingError: ``run_slicer`` and PrusaSlicer is not installed.
    """
    say = progress or (lambda _m: None)
    exp = Export.open(root)
    sliced_now: dict = {}
    if run_slicer:
        sliced_now = slice_stls(exp, progress=say)
    printability = _Printability(exp, sliced_now, say, parallel)
    try:
        results: list[CheckResult] = []
        for part in exp.parts:
            say(f"mesh {part['name']}")
            results.extend(check_part_mesh(exp, part))
        say("masses")
        results.extend(check_masses(exp))
        say("pentagon layout")
        results.extend(check_layout(exp))
        results.extend(check_paper(exp))
        say("analyses")
        results.extend(check_analyses(exp))
        say("robot descriptions (URDF, MJCF, MuJoCo, PyBullet)")
        results.extend(check_robot(exp))
        if printability.proc is None:  # in-process: in its usual place, before the molds
            results.extend(printability.results())
            say("molds")
            results.extend(check_molds(exp))
        else:
            say("molds")
            molds = check_molds(exp)
            results.extend(printability.results())
            results.extend(molds)
    finally:
        printability.close()
        clear_cache()
    return results


if __name__ == "__main__":
    sys.exit(_printability_worker(*sys.argv[1:]))

