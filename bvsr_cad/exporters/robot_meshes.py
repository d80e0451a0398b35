"""Robot-description meshes: binary STL in metres, in their link's frame."""

from __future__ import annotations

from pathlib import Path

import trimesh

from .. import units
from ..assembly.robot import RobotModel
from ..parts.kernel import mesh_arrays
from .cad import write_stl
from .mjcf import collision_mesh_name

#: Fine enough that link inertias from these meshes match the B-rep within 0.1 %.
MESH_TOLERANCE_MM = 0.01
#: Collision hulls: coarse (a hull of the tessellation's vertices lies inside the B-rep's by at most
#: this).
COLLISION_MESH_TOLERANCE_MM = 0.05


def write_robot_meshes(robot: RobotModel, mesh_dir: Path) -> dict[str, str]:
    """Write every visual mesh once (shared panels share a file); returns visual name -> file
    name."""
    mesh_dir.mkdir(parents=True, exist_ok=True)
    files: dict[str, str] = {}
    for link in robot.links.values():
        for vis in link.visuals:
            if vis.name in files:
                continue
            name = f"{vis.name}.stl"
            _write_m(vis.solid, mesh_dir / name)
            files[vis.name] = name
        for col in link.collisions:
            if col.kind == "mesh":
                stem = collision_mesh_name(col)
                _write_hull_m(col.solid, mesh_dir / f"{stem}.stl")
                files[stem] = f"{stem}.stl"
    return files


def _write_hull_m(shape, path: Path) -> None:
    """The convex hull of a collision piece (robot.collision_geometry = "convex"), in metres."""
    points, tris = mesh_arrays(shape, COLLISION_MESH_TOLERANCE_MM, 0.2)
    trimesh.Trimesh(points * units.mm_to_m(1.0), tris, process=False).convex_hull.export(path)


def _write_m(shape, path: Path, tolerance_mm: float = MESH_TOLERANCE_MM) -> None:
    """Tessellate in millimetres with OCCT (fast), then scale the mesh to metres. An absolute
    deflection at the print STLs' tolerances: a panel's or an SOA's robot mesh is its print STL's
    triangulation (and its collision fit's), the same whichever stages ran before (a compound of
    placed parts included: :func:`bvsr_cad.parts.kernel.mesh_absolute` meshes each solid in its own
    frame)."""
    write_stl(shape, path, tolerance_mm, 0.1, scale=units.mm_to_m(1.0), relative=False)
