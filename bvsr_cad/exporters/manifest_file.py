"""Writing an export's manifest.json (without :mod:`bvsr_cad.exporters.manifest`'s CAD imports: a
rebuild that reuses the whole export from the cache rewrites only its volatile section)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any


def manifest_text(manifest: dict[str, Any]) -> str:
    """The text of ``manifest.json`` for ``manifest``: indented JSON."""

    def default(o: Any) -> Any:
        if isinstance(o, float) and not math.isfinite(o):
            return None
        raise TypeError(f"not JSON serialisable: {type(o)}")

    return json.dumps(manifest, indent=2, default=default) + "\n"


def write_manifest(root: Path, manifest: dict[str, Any]) -> None:
    """``root/manifest.json``: :func:`manifest_text`."""
    (root / "manifest.json").write_text(manifest_text(manifest))


def as_written(manifest: dict[str, Any]) -> dict[str, Any]:
    """``manifest`` as a reader of its file gets it (lists for tuples, plain numbers): what a build
    hands its checks, which read the same values from the file of a published export."""
    return json.loads(manifest_text(manifest))


__all__ = ["as_written", "manifest_text", "write_manifest"]
