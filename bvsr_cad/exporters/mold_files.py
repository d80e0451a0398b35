"""Writes the SOA casting mold set into an export.

Filled in by the molds issue; returns the manifest fragment to merge.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..assembly.build import Assembly


def write_molds(asm: Assembly, root: Path, progress: Callable[[str], None]) -> dict[str, Any]:
    """Build the mold set for the assembly's SOA and write it under ``root/molds``.

    Returns:
        Keys to merge into the manifest (``{"molds": {...}}``).
    """
    return {}
