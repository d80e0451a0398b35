"""What is made, and how many: the one list that print jobs and the bill of materials both read.

Every fabricated item of the three products (the BVSR's parts, the rigid
twin's pieces, the SOA mold set) with its material, process, quantity,
volume and mass, computed from the typed products (the assembly, the
:class:`~bvsr_cad.parts.rigid_tail.RigidPiece` list, the
:class:`~bvsr_cad.parts.mold.MoldSet`). Quantities are decided here once: a
sacrificial core per SOA cast, ``fabrication_package.mold_sets`` rigid mold
sets, one of each twin piece.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from .. import units
from ..parts.mold import MoldSet
from ..parts.rigid_tail import RigidPiece
from .assemble import Assembly
from .products import RIGID_MATERIAL


@dataclass(frozen=True)
class MadeItem:
    product: str  # "BVSR", "rigid tail", "molds"
    label: str  # unique over the products: the part name, the piece name, mold_<name>
    source: str  # the name within its product (asm.parts, pieces, mold_set.parts)
    kind: str  # panel, soa, rod, rigid_tail, mold, mold_core
    material: str  # a key of [materials]
    process: str  # MJF, cast, cut, FDM
    quantity: int
    volume_mm3: float  # one item
    mass_each_g: float


def made_items(
    asm: Assembly, pieces: Sequence[RigidPiece] = (), mold_set: MoldSet | None = None
) -> list[MadeItem]:
    spec = asm.spec
    fp = spec.fabrication_package
    items = []
    for name, part in asm.parts.items():
        items.append(
            MadeItem(
                "BVSR",
                name,
                name,
                part.kind,
                part.material,
                part.process,
                len(asm.instances_of(name)),
                part.solid.volume,
                asm.mass_g(name),
            )
        )
    rigid_density = spec.material(RIGID_MATERIAL).density_g_cm3
    for p in pieces:
        items.append(
            MadeItem(
                "rigid tail",
                p.name,
                p.name,
                "rigid_tail",
                RIGID_MATERIAL,
                "FDM",
                1,
                p.volume_mm3,
                units.mass_g(p.volume_mm3, rigid_density),
            )
        )
    soa_casts = sum(i.quantity for i in items if i.kind == "soa")
    for name, mp in mold_set.parts.items() if mold_set is not None else ():
        material = fp.core_material if mp.sacrificial else fp.mold_material
        items.append(
            MadeItem(
                "molds",
                f"mold_{name}",
                name,
                "mold_core" if mp.sacrificial else "mold",
                material,
                "FDM",
                soa_casts if mp.sacrificial else fp.mold_sets,
                mp.solid.volume,
                units.mass_g(mp.solid.volume, spec.material(material).density_g_cm3),
            )
        )
    return items


__all__ = ["MadeItem", "made_items"]
