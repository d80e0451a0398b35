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
from .printability import check_printability
from .result import CheckResult
from .robot import check_robot


def run_checks(root: str | Path, progress: Callable[[str], None] | None = None) -> list[CheckResult]:
    """Run every check on the export at ``root``.

    Raises:
        ExportError: the folder is not a readable export.
    """
    say = progress or (lambda _m: None)
    exp = Export.open(root)
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
    results.extend(check_printability(exp))
    say("molds")
    results.extend(check_molds(exp))
    clear_cache()
    return results
