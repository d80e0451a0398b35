"""Where bvsr_cad keeps what it remembers between runs: ``$BVSR_CACHE`` (default
``~/.cache/bvsr_cad``) holds the build's artifact cache (``artifacts/``) and the checks' slicing
results (``slices.json``)."""

from __future__ import annotations

import os
from pathlib import Path


def cache_folder() -> Path:
    """``$BVSR_CACHE`` (default ``~/.cache/bvsr_cad``), made absolute: a relative ``BVSR_CACHE`` is
    where the user stands, not the folder a second process works in."""
    return Path(os.environ.get("BVSR_CACHE", Path.home() / ".cache" / "bvsr_cad")).absolute()
