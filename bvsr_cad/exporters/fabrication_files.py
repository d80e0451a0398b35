"""Fabrication package of an export: rigid comparison tail, print files per process, BOM.

Filled in by the fabrication issue; returns the manifest fragment to merge.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..assembly.build import Assembly


def write_fabrication(asm: Assembly, root: Path, manifest: dict[str, Any],
                      progress: Callable[[str], None]) -> dict[str, Any]:
    """Write print files, the rigid tail and the BOM under ``root``; returns keys to merge into the manifest."""
    return {}
