#!/usr/bin/env python
"""Compare two export folders file for file, the manifest's ``volatile`` section (times, hosts)
aside.

    python tools/compare_exports.py REFERENCE EXPORT     # exit 0: equal, 1: files differ

Standard library only, so that it runs in any virtualenv (tools/wheel_check.sh runs it in the
wheel's); the cache tests use the same functions (tests/test_cache.py).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def export_files(root: Path) -> dict[str, bytes]:
    """Each file's bytes by its path in the export; the top manifest without its volatile
    section."""
    out = {}
    for p in sorted(root.rglob("*")):
        if p.is_file():
            data = p.read_bytes()
            if p.name == "manifest.json" and p.parent == root:
                manifest = json.loads(data)
                manifest.pop("volatile")
                data = json.dumps(manifest, sort_keys=True).encode()
            out[p.relative_to(root).as_posix()] = data
    return out


def differences(a: Path, b: Path) -> list[str]:
    """The files in only one of the two exports, then those whose bytes differ."""
    fa, fb = export_files(a), export_files(b)
    return sorted(set(fa) ^ set(fb)) + sorted(k for k in set(fa) & set(fb) if fa[k] != fb[k])


def main(argv: list[str]) -> int:
    if len(argv) != 2:
        print(__doc__.strip().splitlines()[2].strip(), file=sys.stderr)
        return 2
    reference, export = (Path(a) for a in argv)
    differ = differences(reference, export)
    print(
        f"export against {reference}: {len(export_files(export))} files, {len(differ)} differ"
        + (f": {differ[:20]}" if differ else "")
    )
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
