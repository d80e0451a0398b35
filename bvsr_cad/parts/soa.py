"""The soft origami actuator (SOA): a square bellows of PU rubber, open at both
ends, with a round flange at each end (the paper's Table II).

Frame: the SOA axis is +Z, the lower flange face at z = 0, the square's sides
parallel to X and Y (the assembly turns it by ``soa.rotation_deg``).
"""

from __future__ import annotations

from dataclasses import dataclass

import build123d as bd

from ..parameters.tables import SoaTable
from .kernel import cut_all, fuse_all, remembered, ruled_loft, single_solid


@dataclass(frozen=True)
class BellowsProfile:
    """Fold levels (z, mm) and square sides (mm) of the outer and inner surface."""

    z_mm: tuple[float, ...]
    outer_side_mm: tuple[float, ...]
    inner_side_mm: tuple[float, ...]
    corner_radius_mm: float
    flange_thickness_mm: float
    flange_diameter_mm: float
    height_mm: float


def bellows_profile(soa: SoaTable, flange_diameter_mm: float) -> BellowsProfile:
    """Fold levels of the square bellows: mountain folds (side b) at both ends
    and between pleats, valley folds (side a) in each pleat."""
    f = soa.flange_thickness_mm
    rise = soa.row_rise_mm
    off = soa.wall_offset_mm
    z, outer, inner = [], [], []
    for m in range(soa.facet_rows + 1):
        side = soa.long_side_mm if m % 2 == 0 else soa.short_side_mm
        z.append(f + m * rise)
        outer.append(side)
        inner.append(side - 2.0 * off)
    return BellowsProfile(
        tuple(z),
        tuple(outer),
        tuple(inner),
        soa.fillet_radius_mm,
        f,
        flange_diameter_mm,
        soa.built_height_mm,
    )


def rounded_square(side_mm: float, radius_mm: float, z_mm: float) -> bd.Face:
    """A square section of the bellows at height z, its corners rounded at R (sharp at R = 0)."""
    plane = bd.Plane.XY.offset(z_mm)
    if radius_mm > 1e-6:
        sk = bd.RectangleRounded(side_mm, side_mm, radius_mm)
    else:
        sk = bd.Rectangle(side_mm, side_mm)
    return plane * sk.face()


@remembered
def soa_envelope(soa: SoaTable, flange_diameter_mm: float) -> bd.Solid:
    """The SOA's outer surface, filled: both flange discs and the bellows' outer ruled loft.

    The one home of the SOA's outside: the SOA body, the mold cavity and the
    rigid twin's columns all start from it.
    """
    p = bellows_profile(soa, flange_diameter_mm)
    outer = ruled_loft(
        [rounded_square(s, p.corner_radius_mm, z) for s, z in zip(p.outer_side_mm, p.z_mm)],
        "SOA outer loft",
    )
    r = flange_diameter_mm / 2.0
    lower = bd.Solid.make_cylinder(r, p.flange_thickness_mm)
    upper = bd.Solid.make_cylinder(
        r, p.flange_thickness_mm, bd.Plane.XY.offset(p.height_mm - p.flange_thickness_mm)
    )
    return single_solid(fuse_all(lower, [outer, upper]), "SOA envelope")


@remembered
def soa_interior(
    soa: SoaTable, flange_diameter_mm: float, beyond_ends_mm: float = 0.01
) -> bd.Solid:
    """The SOA's air space: the inner ruled loft, prolonged at the end size through both
    flanges and ``beyond_ends_mm`` past them (the mold core's prints use the same sections)."""
    p = bellows_profile(soa, flange_diameter_mm)
    inner_z = (-beyond_ends_mm, *p.z_mm, p.height_mm + beyond_ends_mm)
    inner_s = (p.inner_side_mm[0], *p.inner_side_mm, p.inner_side_mm[-1])
    return ruled_loft([rounded_square(s, 0.0, z) for s, z in zip(inner_s, inner_z)], "SOA interior")


@remembered
def soa_body(soa: SoaTable, flange_diameter_mm: float) -> bd.Solid:
    """The cast SOA as one solid (mm).

    Args:
        soa: Table II parameters.
        flange_diameter_mm: the flange disc (D_b, the actuator base).

    Raises:
        GeometryError: the kernel did not produce one valid solid.
    """
    # The interior runs straight through both flanges at the end size.
    body = cut_all(soa_envelope(soa, flange_diameter_mm), [soa_interior(soa, flange_diameter_mm)])
    return single_solid(body, "SOA body")
