"""Every check on an export, in one list."""

from __future__ import annotations

import json
import sys
from collections.abc import Callable, Collection
from pathlib import Path

from ..cache import ArtifactCache
from ..worker import SecondProcess, result_or, serve
from .export import Export, clear_cache
from .layout import check_layout
from .mass import check_masses
from .memo import CheckMemo
from .mesh import check_part_mesh, part_mesh_reads
from .analyses import check_analyses
from .molds import check_molds, molds_reads
from .paper import check_paper
from .printability import check_printability, slice_stls
from .result import CheckResult
from .robot import check_robot


def _printability(root: str, sliced_now: str, cache_root: str = "") -> list[CheckResult]:
    """The second process's work: the printability checks of the export at ``root`` (verdicts of
    unchanged inputs from the artifact cache at ``cache_root``, when given)."""
    exp = Export.open(root)
    memo = CheckMemo(exp, ArtifactCache(Path(cache_root)) if cache_root else None)
    return check_printability(exp, sliced_now=set(json.loads(sliced_now)), memo=memo)


class _Printability:
    """The printability checks, the slowest group, in a second process (given only the export's
    path, it opens the export itself) while the other groups run here. On one core, or when the
    process fails, they run here."""

    def __init__(self, exp: Export, sliced_now: Collection[str], say: Callable[[str], None], parallel: bool,
                 memo: CheckMemo | None = None):
        self.exp, self.sliced_now, self.say = exp, sliced_now, say
        self.memo = memo = memo or CheckMemo(exp)
        self.proc = None
        if parallel:
            # cwd: MuJoCo may write its log into the working folder, as in the robot checks.
            cache_root = str(memo.cache.root) if memo.cache is not None else ""
            self.proc = SecondProcess.start("bvsr_cad.checks.run", [str(exp.root), json.dumps(sorted(sliced_now)),
                                                                   cache_root], exp.root)
            if self.proc is not None:
                say("printability: started in a second process")

    def results(self) -> list[CheckResult]:
        return result_or(self.proc, lambda: check_printability(self.exp, sliced_now=self.sliced_now,
                                                               memo=self.memo), self.say, "printability")

    def close(self) -> None:
        if self.proc is not None:
            self.proc.close()


def run_checks(root: str | Path, progress: Callable[[str], None] | None = None, *,
               run_slicer: bool = False, parallel: bool = True, cache: ArtifactCache | None = None
               ) -> list[CheckResult]:
    """Run every check on the export at ``root``; the results come in the same order either way.

    The checks never start the slicer: the ``slice:*`` results come from the slice cache. With
    ``run_slicer`` (``bvsr check --slice``), every printed STL the cache does not hold is sliced
    first (:func:`~bvsr_cad.checks.printability.slice_stls`). With ``parallel`` (and two cores)
    the printability checks run in a second process beside the others. With ``cache`` the groups whose
    files and manifest values are unchanged (the meshes, the molds, the printed STLs, the twin's
    envelope) take their verdicts from the artifact cache (:mod:`bvsr_cad.checks.memo`).

    Raises:
        ExportError: the folder is not a readable export.
        SlicerMissingError: ``run_slicer`` and PrusaSlicer is not installed.
    """
    say = progress or (lambda _m: None)
    exp = Export.open(root)
    sliced_now: dict = {}
    if run_slicer:
        sliced_now = slice_stls(exp, progress=say)
    memo = CheckMemo(exp, cache)
    printability = _Printability(exp, sliced_now, say, parallel, memo)
    try:
        results: list[CheckResult] = []
        for part in exp.parts:
            say(f"mesh {part['name']}")
            results.extend(memo("part_mesh", part_mesh_reads(part), lambda: check_part_mesh(exp, part)))
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
            results.extend(memo("molds", molds_reads(exp), lambda: check_molds(exp)))
        else:
            say("molds")
            molds = memo("molds", molds_reads(exp), lambda: check_molds(exp))
            results.extend(printability.results())
            results.extend(molds)
    finally:
        printability.close()
        clear_cache()
    if cache is not None:
        cache.evict()  # once, after the groups' small entries
    return results


if __name__ == "__main__":
    sys.exit(serve(sys.argv[1], _printability, *sys.argv[2:]))

