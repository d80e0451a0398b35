"""The checks as the build and ``bvsr check`` run them: the printability and mold checks (and, for a
build, the part meshes' and the robot's) in a second process beside the others, and every group's
verdicts kept in the artifact cache while what it reads is unchanged. The checks themselves
(:mod:`bvsr_cad.checks.run`) start no process and see no cache: they are handed both from here.
"""

from __future__ import annotations

import json
import threading
from collections.abc import Callable, Collection
from pathlib import Path
from typing import Any

from ...checks.export import Export
from ...checks.memo import CheckMemo
from ...checks.result import CheckResult
from ...checks.run import Checks, StartBeside, printability_groups
from ..cache import ArtifactCache
from ..runner import cache_memo
from .worker import SecondProcess

#: The second process's module: it serves :data:`SECOND_PROCESS`.
MODULE = "bvsr_cad.pipeline.processes.checks_process"


def beside(cache: ArtifactCache | None) -> StartBeside:
    """What starts the printability checks' second process, its verdicts kept in ``cache`` (None:
    none kept). It works in the export's folder: MuJoCo may write its log into the working folder.
    The manifest goes on its input (too long for its command line), from a thread: the process
    reads it once its imports are done, and the caller goes on meanwhile."""
    root = str(cache.root) if cache is not None else ""

    def start(
        export: Path, sliced_now: Collection[str], meshes: bool, robot: bool, manifest: dict
    ) -> SecondProcess | None:
        proc = SecondProcess.start(MODULE, [], Path(export), standby=True)
        if proc is not None:
            work = [
                str(export),
                json.dumps(sorted(sliced_now)),
                root,
                "1" if meshes else "",
                "1" if robot else "",
                json.dumps(manifest),
            ]
            threading.Thread(target=_hand, args=(proc, work, Path(export)), daemon=True).start()
        return proc

    return start


def _hand(proc: SecondProcess, work: list[str], cwd: Path) -> None:
    """Give the waiting process its work; one closed meanwhile (a failed build) gets none."""
    try:
        proc.begin(work, cwd)
    except (AttributeError, ValueError):  # closed while this thread wrote
        pass


def start_checks(
    root: str | Path,
    progress: Callable[[str], None] | None = None,
    *,
    parallel: bool = True,
    cache: ArtifactCache | None = None,
    **kw: Any,
) -> Checks:
    """:meth:`bvsr_cad.checks.run.Checks.start` with the second process (``parallel``, on two cores
    or more) and the verdicts kept in ``cache``; ``kw``: the rest of its arguments."""
    return Checks.start(
        root,
        progress,
        beside=beside(cache) if parallel else None,
        store=cache_memo(cache) if cache is not None else None,
        **kw,
    )


def finish_checks(
    checks: Checks, cache: ArtifactCache | None, manifest: dict[str, Any] | None = None
) -> list[CheckResult]:
    """:meth:`bvsr_cad.checks.run.Checks.finish` (``manifest``: as there), then the cache trimmed to
    its size once (after the groups' small entries)."""
    results = checks.finish(manifest)
    if cache is not None:
        cache.evict()
    return results


def run_checks(
    root: str | Path,
    progress: Callable[[str], None] | None = None,
    *,
    run_slicer: bool = False,
    parallel: bool = True,
    cache: ArtifactCache | None = None,
) -> list[CheckResult]:
    """Every check on the export at ``root`` (:func:`bvsr_cad.checks.run.run_checks`); with
    ``parallel`` (and two cores) the printability checks in a second process, with ``cache`` the
    verdicts of groups whose reads are unchanged from it."""
    return finish_checks(
        start_checks(root, progress, run_slicer=run_slicer, parallel=parallel, cache=cache), cache
    )


def _printability(
    root: str, sliced_now: str, cache_root: str, meshes: str, robot: str, manifest: str
) -> dict[str, Any]:
    """The second process's work (``python -m bvsr_cad.pipeline.processes.worker
    bvsr_cad.pipeline.processes.checks_process --standby``, given ``[ROOT, SLICED, CACHE, MESHES,
    ROBOT, MANIFEST]`` on its input): :func:`bvsr_cad.checks.run.printability_groups` of the export
    at ``root`` whose manifest is ``manifest`` (JSON), the verdicts kept in the artifact cache at
    ``cache_root`` (when given): each group's verdicts with the state of its reads, which the
    build's :class:`~bvsr_cad.checks.run.Checks` keeps while that state is unchanged."""
    exp = Export.open(root, json.loads(manifest))
    store = cache_memo(ArtifactCache(Path(cache_root))) if cache_root else None
    return printability_groups(
        exp, json.loads(sliced_now), CheckMemo(exp, store), bool(meshes), bool(robot)
    )


#: What the printability checks' second process serves
#: (:func:`bvsr_cad.pipeline.processes.worker.child_main`).
SECOND_PROCESS = (_printability, None)
