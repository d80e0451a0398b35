"""Every check on an export, in one list."""

from __future__ import annotations

from collections.abc import Callable
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


def run_checks(root: str | Path, progress: Callable[[str], None] | None = None, *,
               run_slicer: bool = False) -> list[CheckResult]:
    """Run every check on the export at ``root``.

    The checks never start the slicer: the ``slice:*`` results come from the slice cache. With
    ``run_slicer`` (``bvsr check --slice``), every printed STL the cache does not hold is sliced
    first (:func:`~bvsr_cad.checks.printability.slice_stls`).

    Raises:
        ExportError: the folder is not a readable export.
        SlicerMissingError: ``run_slicer`` and PrusaSlicer is not installed.
    """
    say = progress or (lambda _m: None)
    exp = Export.open(root)
    sliced_now: dict = {}
    if run_slicer:
        sliced_now = slice_stls(exp, progress=say)
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
    say("printability")
    results.extend(check_printability(exp, sliced_now=sliced_now))
    say("molds")
    results.extend(check_molds(exp))
    clear_cache()
    return results
