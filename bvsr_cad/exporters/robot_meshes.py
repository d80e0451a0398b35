"""Robot-description meshes: binary STL in metres, in their link's frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh

from .. import units
from ..assembly.robot import RobotModel

#: Fine enough that link inertias from these meshes match the B-rep within 0.1 %.
MESH_TOLERANCE_MM = 0.01


def tessellate_m(shape, tolerance_mm: float = MESH_TOLERANCE_MM) -> trimesh.Trimesh:
    verts, tris = shape.tessellate(tolerance_mm, 0.1)
    v = np.array([(p.X, p.Y, p.Z) for p in verts]) / units.MM_PER_M
    mesh = trimesh.Trimesh(v, np.asarray(tris), process=True)
    mesh.fix_normals()
    return mesh


def write_robot_meshes(robot: RobotModel, mesh_dir: Path) -> dict[str, str]:
    """Write every visual mesh once (shared panels share a file); returns visual name -> file name."""
    mesh_dir.mkdir(parents=True, exist_ok=True)
    files: dict[str, str] = {}
    for link in robot.links.values():
        for vis in link.visuals:
            if vis.name in files:
                continue
            name = f"{vis.name}.stl"
            tessellate_m(vis.solid).export(mesh_dir / name)
            files[vis.name] = name
    return files
