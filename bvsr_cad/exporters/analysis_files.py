"""Writes the kinematic analyses (workspace, clearance, joint limits) into an export.

Filled in by the kinematics issue; returns the manifest fragment to merge.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..assembly.build import Assembly


def write_analyses(asm: Assembly, root: Path, progress: Callable[[str], None]) -> dict[str, Any]:
    """Run the analyses on ``asm`` and write them under ``root/analysis``.

    Returns:
        Keys to merge into the manifest (for example ``{"analysis": {...}}``).
    """
    return {}
