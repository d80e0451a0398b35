"""Writes the report's interactive 3D view into an export: ``report/viewer.js`` and one data file
per scene.

The view is three.js (a pinned copy of the npm package ``three``, shipped in ``web/three/`` with its
licence) reading the export's GLB scenes (:mod:`bvsr_cad.exporters.gltf`) with its GLTFLoader, moved
by its OrbitControls: drag to orbit, wheel to zoom, right-drag or shift-drag to pan, double-click to
reset. The project's own JavaScript is ``web/bvsr-viewer.mjs`` (buttons, framing, light, caption and
legend) and ``web/bvsr-viewer-loader.js``.

``report.html`` works opened straight from the export folder, offline. Chromium refuses module
scripts and ``fetch`` of ``file://`` URLs but runs classic scripts and inline modules, so:

- ``report/viewer.js`` is a classic script holding three.js's modules as ``data:`` URLs in an import
  map (their relative imports rewritten to the map's names, :data:`REWRITES`) and the viewer as an
  inline module;
- each scene is ``report/viewer_<scene>.js``, one call ``BVSRViewer.addScene(name, data)`` where
  ``data`` is the scene's GLB, the bytes of ``scenes/<scene>.glb``, gzipped (the browser's
  ``DecompressionStream`` undoes it) and base64-encoded.
"""

from __future__ import annotations

import base64
import gzip
import json
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from .reproducible import write_reproducible_bytes

#: Where the viewer lives, relative to the export root.
SCRIPT = "report/viewer.js"
#: three.js's licence, beside the viewer in the export.
LICENSE = "report/three-LICENSE.txt"
#: What a scene file holds (``viewer.format`` in the manifest).
FORMAT = "GLB, gzip, base64: BVSRViewer.addScene(name, data)"
#: The JavaScript call each scene file makes.
CALL = "BVSRViewer.addScene("
WEB = Path(__file__).with_name("web")
THREE = WEB / "three"
#: The modules the viewer imports: import-map name -> file in ``web/three``.
MODULES = {
    "three": "three.module.min.js",
    "three/core": "three.core.min.js",
    "three/addons/loaders/GLTFLoader.js": "GLTFLoader.js",
    "three/addons/controls/OrbitControls.js": "OrbitControls.js",
    "three/addons/utils/BufferGeometryUtils.js": "BufferGeometryUtils.js",
    "three/addons/utils/SkeletonUtils.js": "SkeletonUtils.js",
}
#: Relative imports inside the modules (which a ``data:`` URL cannot resolve), rewritten to the
#: map's names.
REWRITES = {
    "three.module.min.js": [('"./three.core.min.js"', '"three/core"')],
    "GLTFLoader.js": [
        ("'../utils/BufferGeometryUtils.js'", "'three/addons/utils/BufferGeometryUtils.js'"),
        ("'../utils/SkeletonUtils.js'", "'three/addons/utils/SkeletonUtils.js'"),
    ],
}


def three_version() -> str:
    return json.loads((THREE / "package.json").read_text())["version"]


def _module(file: str) -> str:
    text = (THREE / file).read_text()
    for old, new in REWRITES.get(file, []):
        if old not in text:
            raise RuntimeError(
                f"web/three/{file}: the import {old} to rewrite is not there (another three.js?)"
            )
        text = text.replace(old, new)
    return text


def viewer_js() -> str:
    """``report/viewer.js``: the loader with three.js's modules and the viewer's module filled
    in."""
    imports = {
        name: "data:text/javascript;base64," + base64.b64encode(_module(f).encode()).decode("ascii")
        for name, f in MODULES.items()
    }
    loader = (WEB / "bvsr-viewer-loader.js").read_text()
    app = (WEB / "bvsr-viewer.mjs").read_text()
    return (
        loader.replace("__LICENSE__", f"three {three_version()}, {Path(LICENSE).name}")
        .replace("__IMPORTS__", json.dumps(imports, indent=1))
        .replace("__APP__", json.dumps(app).replace("</", "<\\/"))
    )


#: gzip's level for the scene files: 1, the fastest. Higher levels make the files barely smaller
#: (float32 coordinates do not compress much further) for several times the time.
GZIP_LEVEL = 1


#: The gzip header's operating-system byte: 255 ("unknown"), as Python 3.13 writes it; 3.11 and 3.12
#: write 3 (Unix), so the same scene would give another file on another Python.
GZIP_OS = 255


def scene_script(name: str, glb: bytes) -> str:
    """A scene file: the GLB gzipped (no time stamp, one OS byte: the same bytes give the same file
    on every Python) and base64."""
    packed = bytearray(gzip.compress(glb, compresslevel=GZIP_LEVEL, mtime=0))
    packed[9] = GZIP_OS  # outside the CRC, which covers the data only
    data = base64.b64encode(bytes(packed)).decode("ascii")
    return f'{CALL}{json.dumps(name)}, "{data}");\n'


def write_viewer(
    root: Path, scenes: Sequence[Mapping[str, Any]], glb: Mapping[str, bytes]
) -> dict[str, Any]:
    """Write ``report/viewer.js``, three.js's licence and ``report/viewer_<scene>.js`` for every
    scene.

    Args:
        root: the export folder.
        scenes: the manifest's ``scenes.files`` (:func:`bvsr_cad.exporters.gltf.write_scenes`), in
            the order of the report's buttons.
        glb: every scene's GLB bytes by name, as written to ``scenes/``.

    Returns:
        The manifest's ``viewer`` entry: ``{"viewer": {"script", "library", "format", "scenes":
        [...], "bytes"}}``, ``bytes`` the viewer's files in all.
    """
    out = root / "report"
    out.mkdir(parents=True, exist_ok=True)
    script = viewer_js().encode()
    write_reproducible_bytes(root / SCRIPT, script)
    licence = (THREE / "LICENSE").read_bytes()
    write_reproducible_bytes(root / LICENSE, licence)
    total = len(script) + len(licence)
    entries = []
    for s in scenes:
        rel = f"report/viewer_{s['name']}.js"
        text = scene_script(s["name"], glb[s["name"]]).encode()
        write_reproducible_bytes(root / rel, text)
        total += len(text)
        entries.append(
            {
                "name": s["name"],
                "title": s["title"],
                "file": rel,
                "glb": s["file"],
                "bytes": len(text),
            }
        )
    return {
        "viewer": {
            "script": SCRIPT,
            "library": f"three {three_version()}",
            "format": FORMAT,
            "scenes": entries,
            "bytes": total,
        }
    }


__all__ = ["SCRIPT", "write_viewer", "viewer_js", "scene_script", "three_version"]
