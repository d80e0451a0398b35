"""The export's report (filled in by the fabrication issue).

Written last, after the checks, so it can show their results.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any


def write_report(root: Path, manifest: dict[str, Any]) -> dict[str, Any]:
    """Write the report under ``root``; returns keys to merge into the manifest."""
    return {}
