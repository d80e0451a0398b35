"""Writing an export's manifest.json (without :mod:`bvsr_cad.exporters.manifest`'s CAD imports: a
rebuild that reuses the whole export from the cache rewrites only its volatile section)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any


def write_manifest(root: Path, manifest: dict[str, Any]) -> None:
    """``root/manifest.json``, indented; a non-finite number is written as null."""

    def default(o: Any) -> Any:
        if isinstance(o, float) and not math.isfinite(o):
            return None
        raise TypeError(f"not JSON serialisable: {type(o)}")

    (root / "manifest.json").write_text(json.dumps(manifest, indent=2, default=default) + "\n")


__all__ = ["write_manifest"]
