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


def write_part_step(part: PartDef, path: Path) -> None:
    write_step(part.solid, part.name, rgb(part.kind), path)


def write_part_stl(part: PartDef, path: Path) -> None:
    """Binary STL in print orientation (mm)."""
    solid = part.print_solid
    if not bd.export_stl(solid, path, tolerance=STL_LINEAR_TOLERANCE_MM,
                         angular_tolerance=STL_ANGULAR_TOLERANCE_RAD, ascii_format=False):
        raise OSError(f"STL export failed: {path}")


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
