"""What outside an export its checks' results depend on, read without the checks' imports.

The build keys its whole-export cache entry on it (:func:`environment_state`), and a rebuild that
finds that entry must decide so before importing the CAD kernel and the mesh libraries (seconds):
this module uses the standard library only.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path
from typing import Any

from ..folders import cache_folder

SLICER = "prusa-slicer"


def slicer_exe() -> str | None:
    """PrusaSlicer's command line on PATH, or None."""
    return shutil.which(SLICER)


def slicer_identity(exe: str) -> str:
    """The installed slicer without running it: its resolved path, size and modification time."""
    real = os.path.realpath(exe)
    st = os.stat(real)
    return f"{real}|{st.st_size}|{st.st_mtime_ns}"


def slice_cache_path() -> Path:
    """The slicing results' cache file: ``slices.json`` beside the artifact cache
    (:func:`bvsr_cad.folders.cache_folder`: ``$BVSR_CACHE`` or ``~/.cache/bvsr_cad``)."""
    return cache_folder() / "slices.json"


def environment_state() -> dict[str, Any]:
    """What outside the export the checks' results depend on: the installed slicer and the slice
    cache, and Debian's ``check_urdf`` (a cached export is reused only while these are
    unchanged)."""
    exe = slicer_exe()
    cache = slice_cache_path()
    return {
        "slicer": slicer_identity(exe) if exe else None,
        "slice_cache": cache.read_bytes() if cache.is_file() else b"",
        "check_urdf": shutil.which("check_urdf"),
    }


__all__ = ["SLICER", "environment_state", "slice_cache_path", "slicer_exe", "slicer_identity"]
