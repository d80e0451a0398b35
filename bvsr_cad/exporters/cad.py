"""STEP and STL writers (the only code, with the other exporters, that writes files)."""

from __future__ import annotations

from pathlib import Path

import build123d as bd
from OCP.BRepBuilderAPI import BRepBuilderAPI_Copy

from ..assembly.assemble import Assembly, PartDef
from ..assembly.placed import labelled_compound, placed_instances
from ..colors import rgb
from ..parts.kernel import mesh_absolute

#: Tessellation for print STLs, absolute: no facet strays more than 0.01 mm from the surface (ten
#: times finer than the printers' resolution) nor turns more than 0.1 rad; the mesh volume stays
#: within 0.05 % of the B-rep volume on every part (checked by `bvsr check`). Absolute, because a
#: deflection relative to each edge's size meshes the large flat panels far finer than any printer
#: resolves: meshing time and facets for nothing a print shows.
STL_LINEAR_TOLERANCE_MM = 0.01
STL_ANGULAR_TOLERANCE_RAD = 0.1


def write_step(solid: bd.Shape, label: str, rgb: tuple[float, float, float], path: Path) -> None:
    """One named, coloured solid as a STEP file in millimetres."""
    solid.label = label
    solid.color = bd.Color(*rgb)
    if not bd.export_step(solid, path, unit=bd.Unit.MM):
        raise OSError(f"STEP export failed: {path}")


def write_stl(
    shape: bd.Shape,
    path: Path,
    tolerance_mm: float = STL_LINEAR_TOLERANCE_MM,
    angular_tolerance_rad: float = STL_ANGULAR_TOLERANCE_RAD,
    scale: float = 1.0,
    relative: bool = False,
) -> None:
    """The one STL writer: binary STL of a shape tessellated by OCCT in millimetres (``relative``:
    ``tolerance_mm`` is a fraction of each edge's size), optionally scaled afterwards (``scale =
    1e-3``: metres, for robot descriptions)."""
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.StlAPI import StlAPI_Writer

    path.parent.mkdir(parents=True, exist_ok=True)
    target = path if scale == 1.0 else path.with_suffix(".mm.stl")
    if relative:
        BRepMesh_IncrementalMesh(shape.wrapped, tolerance_mm, True, angular_tolerance_rad, True)
    else:  # the one absolute meshing, shared with the robot's collision fits (kernel.mesh_arrays)
        mesh_absolute(shape, tolerance_mm, angular_tolerance_rad)
    writer = StlAPI_Writer()
    writer.ASCIIMode = False
    if not writer.Write(shape.wrapped, str(target)):
        raise OSError(f"STL export failed: {target}")
    if scale != 1.0:
        import trimesh

        mesh = trimesh.load(target, force="mesh")
        target.unlink()
        mesh.apply_scale(scale)
        mesh.export(path)


def write_part_step(part: PartDef, path: Path) -> None:
    write_step(part.solid, part.name, rgb(part.kind), path)


def write_part_stl(part: PartDef, path: Path) -> None:
    """Binary STL in print orientation (mm)."""
    write_stl(part.print_solid, path)


def write_labelled_step(compound: bd.Compound, path: Path) -> None:
    """A compound of labelled, coloured, located children as one STEP assembly in millimetres.

    Each child is written with its own copy of its geometry, so that it is its
    own product, named after it. Shared geometry would be written once, as one
    product named after one of its instances, and readers that name objects
    after products (FreeCAD's importer without link groups) would then show
    the thirty SOAs under one name. Placements stay transforms, not moved
    geometry. A child with children of its own (a posed SOA: its slices) is
    written as a sub-assembly of its pieces.
    """
    if not bd.export_step(_own_copy(compound), path, unit=bd.Unit.MM):
        raise OSError(f"STEP export failed: {path}")


def _own_copy(node: bd.Shape) -> bd.Shape:
    """The labelled tree with every leaf's geometry copied (locations kept)."""
    if isinstance(node, bd.Compound) and node.children:
        out = bd.Compound(children=[_own_copy(c) for c in node.children])
    else:
        out = bd.Shape.cast(BRepBuilderAPI_Copy(node.wrapped).Shape())  # keeps the location
    out.label, out.color = node.label, node.color
    return out


def write_assembly_step(asm: Assembly, path: Path) -> None:
    """The tail at rest as one STEP assembly: every instance a named, coloured product at its
    place."""
    write_labelled_step(labelled_compound(placed_instances(asm), asm.spec.name), path)
