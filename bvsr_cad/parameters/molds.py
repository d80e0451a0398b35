"""Derived dimensions of the SOA casting mold set, computed from Table II, the
flange diameter D_b and ``[casting]`` alone (no CAD).

:func:`bvsr_cad.parts.mold.mold_set` builds its block, walls, pins, bolts and
channels from these numbers, and :func:`mold_problems` checks the same numbers
when a parameter file is loaded, so a mold set that validates is the one that
gets built (as :mod:`bvsr_cad.parameters.layout` serves the panels).

Frame: the cast frame of :mod:`bvsr_cad.parts.mold` (SOA axis +Z, lower flange
face at z = 0), every length already scaled by 1 + shrinkage where the cast
sets it. ``u`` runs along the halves' pull direction (the diagonal of the
square), ``e`` along the parting plane.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from .tables import Casting, SoaTable, feasible_span, rule_bounds

#: Sockets are this much deeper than their pins so a pin never bottoms out.
SOCKET_EXTRA_DEPTH_MM = 0.5
#: Pins are fused this deep into their own part so the fuse makes one solid.
PIN_ROOT_MM = 0.5


@dataclass(frozen=True)
class MoldDims:
    """Every dimension of the mold set that a rule constrains (mm, cast frame)."""

    scale: float  #: k = 1 + shrinkage: the cast is the SOA scaled by k about the origin
    flange_radius_mm: float  #: D_b / 2 in the SOA frame (unscaled)
    cast_height_mm: float  #: h = k H (as built)
    flange_mm: float  #: k f, one flange's thickness
    z_lo_mm: float  #: halves from here (the lower flange's upper face) ...
    z_hi_mm: float  #: ... to here (the upper flange's lower face)
    cast_flange_radius_mm: float  #: k D_b / 2
    cavity_radius_mm: float  #: rho_max: the cavity's largest radius (flange or bellows corners)
    core_half_mm: float  #: half the square core print (the SOA's interior at its ends, scaled)
    wall_mm: float  #: casting.cavity_wall_mm
    block_half_mm: float  #: w: half-width of the square block along u and e
    plate_mm: float  #: bottom plate and lid thickness beyond the flange faces
    socket_mm: float  #: pin socket diameter (pin + clearance)
    pin_circle_mm: float  #: rho_pin: radius of the pins, mid-wall
    bolt_edge_mm: float  #: bolt axis to the block edges
    bolt_uv_mm: float  #: bolt axes at (+-this, +-this) in (u, e)
    z_bottom_mm: float  #: lower face of the bottom plate
    z_top_mm: float  #: upper face of the lid
    min_wall_mm: float  #: casting.min_print_wall_mm

    # --- The margins the rules judge (each >= 0 when the mold can be built).
    @property
    def pin_socket_web_mm(self) -> float:
        """Smallest web beside a pin socket: to the cavity and to the block's outside."""
        return min(
            self.pin_circle_mm - self.socket_mm / 2.0 - self.cavity_radius_mm,
            self.block_half_mm - self.pin_circle_mm - self.socket_mm / 2.0,
        )

    @property
    def halves_height_mm(self) -> float:
        return self.z_hi_mm - self.z_lo_mm

    def bolt_to_cavity_mm(self, bolt_hole_mm: float) -> float:
        """Material between a bolt hole and the cavity's largest radius."""
        return (
            math.hypot(self.bolt_uv_mm, self.bolt_uv_mm)
            - bolt_hole_mm / 2.0
            - self.cavity_radius_mm
        )

    def bolt_to_pin_mm(self, bolt_hole_mm: float) -> float:
        """Web between a bolt hole and the nearest pin socket."""
        return (
            math.hypot(self.bolt_uv_mm - self.pin_circle_mm, self.bolt_uv_mm)
            - bolt_hole_mm / 2.0
            - self.socket_mm / 2.0
        )

    def channel_span_mm(self, d_mm: float) -> tuple[float, float]:
        """(innermost, outermost) radius of a channel of diameter d on the flange face:
        a printable wall to the square core print inside, fully on the flange outside."""
        return (
            self.core_half_mm + self.min_wall_mm + d_mm / 2.0,
            self.cast_flange_radius_mm - d_mm / 2.0,
        )

    def channel_radius_mm(self, d_mm: float) -> float:
        lo, hi = self.channel_span_mm(d_mm)
        return (lo + hi) / 2.0


def mold_dimensions(soa: SoaTable, flange_diameter_mm: float, casting: Casting) -> MoldDims:
    """The mold set's dimensions for the SOA ``soa`` with flange D_b = ``flange_diameter_mm``."""
    c = casting
    k = 1.0 + c.shrinkage_percent / 100.0
    f = soa.flange_thickness_mm
    height = soa.built_height_mm
    r_flange = flange_diameter_mm / 2.0
    h = k * height
    fk = k * f
    inner_end = (
        soa.long_side_mm - 2.0 * soa.wall_offset_mm
    )  # the bellows' interior at a mountain fold (the ends)
    rho_max = k * max(
        r_flange, soa.computed_circumcircle_mm / 2.0
    )  # corners may stand proud of the flange
    wall = c.cavity_wall_mm
    w = rho_max + wall
    t = wall
    mw = c.min_print_wall_mm
    bolt_c = c.bolt_hole_diameter_mm / 2.0 + 2.0 * mw
    return MoldDims(
        scale=k,
        flange_radius_mm=r_flange,
        cast_height_mm=h,
        flange_mm=fk,
        z_lo_mm=fk,
        z_hi_mm=h - fk,
        cast_flange_radius_mm=k * r_flange,
        cavity_radius_mm=rho_max,
        core_half_mm=k * inner_end / 2.0,
        wall_mm=wall,
        block_half_mm=w,
        plate_mm=t,
        socket_mm=c.pin_diameter_mm + c.pin_clearance_mm,
        pin_circle_mm=rho_max + wall / 2.0,
        bolt_edge_mm=bolt_c,
        bolt_uv_mm=w - bolt_c,
        z_bottom_mm=-t,
        z_top_mm=h + t,
        min_wall_mm=mw,
    )


def _violations(d: MoldDims, c: Casting) -> list[tuple[str, str]]:
    """(key, which derived dimension breaks and by how much) for every rule the mold set breaks."""
    out: list[tuple[str, str]] = []
    mw = c.min_print_wall_mm
    web = d.pin_socket_web_mm
    if web < mw:
        out.append(
            (
                "casting.cavity_wall_mm",
                f"the pins sit mid-wall, so a {d.socket_mm:g} mm pin socket "
                "(casting.pin_diameter_mm + "
                f"casting.pin_clearance_mm) leaves a {web:.2f} mm web to the cavity and to the "
                "outside, "
                f"{mw - web:.2f} mm short of casting.min_print_wall_mm = {mw!r}",
            )
        )
    floor = d.plate_mm - c.core_print_mm
    if floor < mw:
        out.append(
            (
                "casting.core_print_mm",
                f"the core print's socket leaves a {floor:.2f} mm floor in the {d.plate_mm:g} mm "
                "bottom plate "
                f"and lid (as thick as casting.cavity_wall_mm), {mw - floor:.2f} mm short of "
                f"casting.min_print_wall_mm = {mw!r}",
            )
        )
    reach = c.pin_length_mm + SOCKET_EXTRA_DEPTH_MM + mw
    if reach > d.halves_height_mm / 2.0:
        out.append(
            (
                "casting.pin_length_mm",
                f"the bottom-plate and lid pin sockets ({SOCKET_EXTRA_DEPTH_MM:g} mm deeper than "
                "the pins, "
                f"{mw:g} mm wall) from both ends of the {d.halves_height_mm:.2f} mm tall mold "
                "halves would meet "
                f"({2 * reach - d.halves_height_mm:.2f} mm too long together)",
            )
        )
    to_cavity = d.bolt_to_cavity_mm(c.bolt_hole_diameter_mm)
    to_pin = d.bolt_to_pin_mm(c.bolt_hole_diameter_mm)
    if to_cavity < c.cavity_wall_mm or to_pin < mw:
        out.append(
            (
                "casting.bolt_hole_diameter_mm",
                f"the four clamping bolts in the block corners ({d.bolt_edge_mm:.2f} mm from the "
                "edges of the "
                f"{2 * d.block_half_mm:.2f} mm block) leave {to_cavity:.2f} mm to the cavity "
                "(needs "
                f"casting.cavity_wall_mm = {c.cavity_wall_mm!r}: "
                f"{max(c.cavity_wall_mm - to_cavity, 0.0):.2f} mm "
                f"short) and {to_pin:.2f} mm to a pin socket (needs casting.min_print_wall_mm = "
                f"{mw!r}: "
                f"{max(mw - to_pin, 0.0):.2f} mm short)",
            )
        )
    for what, dia in (("gate", c.gate_diameter_mm), ("vent", c.vent_diameter_mm)):
        lo, hi = d.channel_span_mm(dia)
        if lo > hi:
            out.append(
                (
                    f"casting.{what}_diameter_mm",
                    f"the {what} does not fit on the flange face between the core print "
                    f"({2 * d.core_half_mm:.2f} "
                    f"mm square, casting.min_print_wall_mm = {mw!r} around it) and the flange rim "
                    "(D "
                    f"{2 * d.cast_flange_radius_mm:.2f} mm, from joint.base_diameter_mm): "
                    f"{lo - hi:.2f} mm "
                    "too wide",
                )
            )
    return out


def _with(c: Casting, name: str, value: float) -> Casting:
    if dataclasses.is_dataclass(c):
        return dataclasses.replace(c, **{name: value})
    return type(c)(**{**vars(c), name: value})  # a stand-in object (tests)


def _allowed(soa: SoaTable, flange_diameter_mm: float, c: Casting, name: str) -> str:
    """What ``casting.<name>`` may be with every other value fixed: the feasible part of its rule
    range."""
    meta = {f.name: f.metadata for f in dataclasses.fields(Casting)}[name]
    lo, hi = rule_bounds(meta)
    span = feasible_span(
        meta,
        lambda x: (
            not _violations(
                mold_dimensions(soa, flange_diameter_mm, _with(c, name, x)), _with(c, name, x)
            )
        ),
        2000,
    )
    if span is None:
        return "no value within its rule range, with the other [casting] values"
    first, last = span
    if first > lo and last < hi:
        return f"{first:.2f} to {last:.2f} mm with the other [casting] values"
    return (
        f">= {first:.2f} mm" if first > lo else f"<= {last:.2f} mm"
    ) + " with the other [casting] values"


def mold_problems(soa: SoaTable, flange_diameter_mm: float, casting: Casting) -> list[str]:
    """Every reason the mold set of this SOA cannot be built, each naming the key, its value, the
    derived dimension that breaks and what is allowed (empty when it can be built)."""
    c = casting
    found = _violations(mold_dimensions(soa, flange_diameter_mm, c), c)
    out = []
    for key, why in found:
        name = key.split(".")[1]
        line = (
            f"{key} = {getattr(c, name)!r}: mold set: {why}; allowed: "
            f"{_allowed(soa, flange_diameter_mm, c, name)}"
        )
        if name in ("gate_diameter_mm", "vent_diameter_mm"):  # the core print: the SOA's interior
            line += (
                " (the core print is the bellows' interior: soa.long_side_mm = "
                f"{soa.long_side_mm!r} less twice "
                f"the wall's {soa.wall_offset_mm:.2f} mm offset, which soa.facet_thickness_mm = "
                f"{soa.facet_thickness_mm!r} sets along the fold's slope)"
            )
        if name in ("core_print_mm", "bolt_hole_diameter_mm"):  # a thicker wall also makes room
            wall = _allowed(soa, flange_diameter_mm, c, "cavity_wall_mm")
            if wall[0] in "<>0123456789":
                line += f"; or casting.cavity_wall_mm {wall}"
        out.append(line)
    return out


__all__ = ["MoldDims", "mold_dimensions", "mold_problems", "PIN_ROOT_MM", "SOCKET_EXTRA_DEPTH_MM"]
