"""STEP and STL writers (the only code, with the other exporters, that writes files)."""

from __future__ import annotations

from pathlib import Path

import build123d as bd

from ..assembly.build import Assembly, PartDef, instance_solid
from ..colors import rgb

#: Tessellation for print STLs: fine enough that the mesh volume stays within
#: 0.05% of the B-rep volume on every part (checked by `bvsr check`).
STL_LINEAR_TOLERANCE_MM = 0.005
STL_ANGULAR_TOLERANCE_RAD = 0.05


def write_step(solid: bd.Shape, label: str, rgb: tuple[float, float, float], path: Path) -> None:
    """One named, coloured solid as a STEP file in millimetres."""
    solid.label = label
    solid.color = bd.Color(*rgb)
    if not bd.export_step(solid, path, unit=bd.Unit.MM):
        raise OSError(f"STEP export failed: {path}")


def write_stl(shape: bd.Shape, path: Path, tolerance_mm: float = STL_LINEAR_TOLERANCE_MM,
              angular_tolerance_rad: float = STL_ANGULAR_TOLERANCE_RAD, scale: float = 1.0) -> None:
    """The one STL writer: binary STL of a shape tessellated by OCCT in millimetres, optionally
    scaled afterwards (``scale = 1e-3``: metres, for robot descriptions)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    target = path if scale == 1.0 else path.with_suffix(".mm.stl")
    if not bd.export_stl(shape, target, tolerance=tolerance_mm, angular_tolerance=angular_tolerance_rad,
                         ascii_format=False):
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


def write_assembly_step(asm: Assembly, path: Path) -> None:
    """The tail at rest as one STEP assembly with named, coloured instances."""
    children = []
    for inst in asm.instances:
        solid = instance_solid(asm, inst)
        solid.label = inst.name
        solid.color = bd.Color(*rgb(asm.part_of(inst).kind))
        children.append(solid)
    compound = bd.Compound(children=children, label=asm.spec.name)
    if not bd.export_step(compound, path, unit=bd.Unit.MM):
        raise OSError(f"STEP export failed: {path}")
