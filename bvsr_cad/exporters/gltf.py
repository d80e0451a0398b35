"""The 3D scenes as glTF 2.0 binary files (GLB): ``scenes/<scene>.glb``, one per scene of the
report's view.

glTF is the standard for shipping 3D scenes: Blender, three.js, ``<model-viewer>`` and every web
viewer open it. Each file holds one scene of :func:`bvsr_cad.analysis.poses.viewer_scenes`:

- one node per object, named as its label: the assembly's instances as the manifest names them
  (``panel0``, ``j1_soa1``, ...), the mold parts, the rigid twin's pieces;
- lengths in metres (glTF's unit; ``asset.extras.length_unit``), in the scene's own frame (the tail
  frame: +Z along the tail, +Y dorsal; the mold set: its mold frame);
- one PBR material per colour of :mod:`bvsr_cad.colors` (named by its kind, not metallic;
  translucent objects blend), the table's sRGB colour converted to glTF's linear
  ``baseColorFactor``;
- the scene's title, note, up axis and camera direction in the scene's ``extras``.

Objects that share their arrays share one accessor (the SOAs at rest share one mesh; posed, their
triangles). No normals are stored: viewers shade flat from the triangles.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import trimesh
from trimesh.visual import TextureVisuals
from trimesh.visual.material import PBRMaterial

from .. import units
from ..analysis.poses import ViewObject, ViewScene
from .reproducible import write_reproducible_bytes

#: Where the scenes live, relative to the export root.
FOLDER = "scenes"
#: Roughness of every material (a matte plastic or silicone; not metallic).
ROUGHNESS = 0.7


def srgb_to_linear(c: float) -> float:
    """IEC 61966-2-1: an sRGB component (0..1) as linear light, as glTF's ``baseColorFactor`` takes
    it."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


def _material(o: ViewObject) -> PBRMaterial:
    opaque = o.alpha >= 1.0
    return PBRMaterial(
        name=o.kind,
        baseColorFactor=[*(srgb_to_linear(float(c)) for c in o.rgb), float(o.alpha)],
        metallicFactor=0.0,
        roughnessFactor=ROUGHNESS,
        doubleSided=True,
        alphaMode="OPAQUE" if opaque else "BLEND",
    )


def _transform_m(transform_mm: np.ndarray) -> np.ndarray:
    t = np.array(transform_mm, float)
    t[:3, 3] = units.mm_to_m(t[:3, 3])
    return t


def scene_glb(scene: ViewScene) -> bytes:
    """``scene`` as GLB bytes (see the module docstring); the same scene gives the same bytes."""
    out = trimesh.Scene()
    geometry_of: dict[bytes, str] = {}
    for o in scene.objects:
        vertices = np.ascontiguousarray(o.vertices_mm, "<f4")
        triangles = np.ascontiguousarray(o.triangles, "<u4")
        key = hashlib.sha1(
            vertices.tobytes()
            + b"|"
            + triangles.tobytes()
            + b"|"
            + repr((o.kind, tuple(o.rgb), o.alpha)).encode()
        ).digest()
        transform = _transform_m(o.transform)
        if key in geometry_of:  # another node on the same mesh
            out.graph.update(
                frame_from=out.graph.base_frame,
                frame_to=o.label,
                matrix=transform,
                geometry=geometry_of[key],
            )
            continue
        mesh = trimesh.Trimesh(
            units.mm_to_m(vertices.astype(float)),
            triangles,
            process=False,
            visual=TextureVisuals(material=_material(o)),
        )
        geometry_of[key] = f"{o.kind}_{len(geometry_of)}"
        out.add_geometry(mesh, node_name=o.label, geom_name=geometry_of[key], transform=transform)

    def extras(tree: dict[str, Any]) -> None:
        tree["asset"]["extras"] = {"length_unit": "m"}
        tree["scenes"][0]["name"] = scene.name
        tree["scenes"][0]["extras"] = {
            "title": scene.title,
            "note": scene.note,
            "up": list(scene.up),
            "eye": [round(float(v), 6) for v in scene.eye_direction],
        }

    return out.export(file_type="glb", include_normals=False, tree_postprocessor=extras)


def write_scenes(
    root: Path, scenes: Sequence[ViewScene], glb: Mapping[str, bytes] | None = None
) -> dict[str, Any]:
    """Write ``scenes/<scene>.glb`` for every scene under ``root``.

    Args:
        root: the export folder.
        scenes: from :func:`bvsr_cad.analysis.poses.viewer_scenes`.
        glb: their :func:`scene_glb` bytes by name where the caller has them (the report's viewer
            takes the same bytes); made here otherwise.

    Returns:
        The manifest's ``scenes`` entry: ``{"scenes": {"format", "length_unit", "files": [{"name",
        "title", "file", "nodes", "triangles", "bytes"}]}}``.

    Raises:
        ValueError: two scenes share a name, or two objects of a scene share a label.
    """
    names = [s.name for s in scenes]
    if len(set(names)) != len(names):
        raise ValueError(f"scenes must have distinct names, got {names}")
    (root / FOLDER).mkdir(parents=True, exist_ok=True)
    files = []
    for scene in scenes:
        labels = [o.label for o in scene.objects]
        if len(set(labels)) != len(labels):
            raise ValueError(
                f"scene {scene.name}: objects must have distinct labels (glTF node names)"
            )
        rel = f"{FOLDER}/{scene.name}.glb"
        data = glb[scene.name] if glb is not None else scene_glb(scene)
        write_reproducible_bytes(root / rel, data)
        files.append(
            {
                "name": scene.name,
                "title": scene.title,
                "file": rel,
                "nodes": labels,
                "triangles": scene.triangle_count,
                "bytes": len(data),
            }
        )
    return {"scenes": {"format": "glTF 2.0 binary (GLB)", "length_unit": "m", "files": files}}


__all__ = ["FOLDER", "scene_glb", "srgb_to_linear", "write_scenes"]
