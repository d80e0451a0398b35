"""Derived dimensions of the rigid comparison tail (the PLA twin), computed from
the spec and the panel layouts alone (no CAD).

:func:`bvsr_cad.parts.rigid_tail.rigid_tail_pieces` drills its pin, tie-rod
and nut holes to these numbers and judges the printer fit with
:func:`fits_printer`; :func:`twin_problems` checks the same numbers when a
parameter file is loaded, so a twin that validates is the one that gets built.

A piece (one per joint, split at every panel's lower face) is panel
``k - 1`` on the bed with joint ``k``'s five SOA columns and its rod standing
on it, up to panel ``k``'s lower face; the tip panel is a piece of its own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .layout import N_SOA, PanelLayout, half_angle_rad, panel_layout, rounded_square_support
from .standard_parts import metric
from .tables import FabricationPackage, TailSpec

#: The rigid comparison tail is printed in this material (a key of [materials], checked at load).
RIGID_TWIN_MATERIAL = "PLA"

#: Extra room around a nut in its printed pocket (FDM holes print small).
NUT_POCKET_CLEARANCE_MM = 0.3
#: A pin hole is this much deeper than half the pin so the pin never bottoms out.
PIN_HOLE_EXTRA_MM = 0.5
#: Material kept over a pin hole in a panel (the tip panel's distal face).
PANEL_PIN_FLOOR_MM = 1.5
#: The SOA columns' tilt (the taper) and the sampled support function stay within this (mm).
COLUMN_MARGIN_MM = 0.01


def tie_rod_hole_mm(spec: TailSpec) -> float:
    fp = spec.fabrication_package
    return fp.tie_rod_thread + fp.tie_rod_clearance_mm


def pin_hole_mm(spec: TailSpec) -> float:
    fp = spec.fabrication_package
    return fp.pin_diameter_mm + fp.pin_hole_clearance_mm


def nut_pocket_depth_mm(spec: TailSpec) -> float:
    return metric(spec.fabrication_package.tie_rod_thread).nut_height_mm + 0.5


def tie_rod_length_mm(spec: TailSpec) -> float:
    """Cut length of the tie rod: through the tail, nut pockets at both ends, flush with the nuts'
    outer faces."""
    return (
        spec.length_mm
        - 2.0 * nut_pocket_depth_mm(spec)
        + 2.0 * metric(spec.fabrication_package.tie_rod_thread).nut_height_mm
    )


@dataclass(frozen=True)
class RigidJoining:
    """The bought hardware that joins the rigid twin's pieces (ISO 2338 pins, DIN 976-1 tie rod, ISO
    4032 nuts)."""

    pin_designation: str
    pin_count: int
    pin_hole_mm: float
    tie_rod_designation: str
    tie_rod_cut_length_mm: float
    tie_rod_hole_mm: float
    nut_designation: str
    nut_count: int
    nut_pocket_depth_mm: float


def rigid_joining(spec: TailSpec) -> RigidJoining:
    """One dowel pin per SOA column end (N_SOA per joint), one tie rod and a nut at each end."""
    fp = spec.fabrication_package
    return RigidJoining(
        f"ISO 2338 {fp.pin_diameter_mm:g} m6 x {fp.pin_length_mm:g}",
        N_SOA * (spec.panels - 1),
        pin_hole_mm(spec),
        f"DIN 976-1 M{fp.tie_rod_thread:g}",
        tie_rod_length_mm(spec),
        tie_rod_hole_mm(spec),
        f"ISO 4032 M{fp.tie_rod_thread:g}",
        2,
        nut_pocket_depth_mm(spec),
    )


def pin_depths_mm(spec: TailSpec, panel_thickness_mm: float) -> tuple[float, float]:
    """(panel, column) pin hole depths: the pin sits deeper in the column than in the panel so the
    tip panel keeps a floor over its holes; each hole is PIN_HOLE_EXTRA_MM deeper than the pin
    reaches."""
    pin = spec.fabrication_package.pin_length_mm
    panel = min(pin / 2.0 + PIN_HOLE_EXTRA_MM, panel_thickness_mm - PANEL_PIN_FLOOR_MM)
    column = pin - (panel - PIN_HOLE_EXTRA_MM) + PIN_HOLE_EXTRA_MM
    return panel, column


def fits_printer(size_mm: tuple[float, float, float], fp: FabricationPackage) -> bool:
    """A part's bounding box fits the FDM printer, either way round on the bed."""
    lo, hi = min(fp.printer_x_mm, fp.printer_y_mm), max(fp.printer_x_mm, fp.printer_y_mm)
    x, y, z = size_mm
    return (x <= hi and y <= lo or y <= hi and x <= lo) and z <= fp.printer_z_mm


def soa_column_reach_mm(spec: TailSpec, pitch_radius_mm: float) -> float:
    """Farthest distance from the tail axis of an SOA column (flange disc or bellows) standing on
    the pitch circle at ``pitch_radius_mm``: max over directions u of u.c + h(u), h the support
    function."""
    soa = spec.soa
    psi = np.linspace(-math.pi, math.pi, 7201)
    bellows = pitch_radius_mm * np.cos(psi) + rounded_square_support(
        soa.long_side_mm, soa.fillet_radius_mm, psi - math.radians(soa.rotation_deg)
    )
    return (
        max(float(np.max(bellows)), pitch_radius_mm + spec.joint.base_diameter_mm / 2.0)
        + COLUMN_MARGIN_MM
    )


@dataclass(frozen=True)
class PieceEnvelope:
    """An upper bound of a twin piece's bounding box (exact when the panel rim is the widest
    feature)."""

    name: str
    index: int
    radius_mm: float  #: farthest point from the tail axis
    height_mm: float
    widest: str  #: what sets radius_mm
    tallest: str  #: what sets height_mm

    @property
    def size_mm(self) -> tuple[float, float, float]:
        return (2.0 * self.radius_mm, 2.0 * self.radius_mm, self.height_mm)


def piece_envelopes(
    spec: TailSpec, layouts: list[PanelLayout] | None = None
) -> list[PieceEnvelope]:
    """Every twin piece's bounding-box bound, root to tip (piece k = panel k - 1 with joint k on
    it)."""
    if layouts is None:
        beta = half_angle_rad(spec)
        layouts = [panel_layout(spec, k, beta) for k in range(spec.panels)]
    n = len(layouts)
    out = []
    for k in range(1, n + 1):
        lay = layouts[k - 1]
        reach = [
            (lay.rim_radius_lower_mm, f"{lay.name} rim D {2 * lay.rim_radius_lower_mm:.2f} mm")
        ]
        reach += [
            (
                math.hypot(*b.xy) + b.diameter_mm / 2.0,
                f"{lay.name} {b.name} D {b.diameter_mm:.2f} mm",
            )
            for b in lay.bosses
        ]
        if k < n:
            height = layouts[k].z0_mm - lay.z0_mm
            tallest = f"joint height H_j = {height:.2f} mm"
            reach.append(
                (soa_column_reach_mm(spec, lay.pitch_radius_lower_mm), f"joint {k}'s SOA columns")
            )
        else:
            below = max([-b.z_range[0] for b in lay.bosses] + [0.0])
            height = lay.thickness_mm + below
            tallest = f"tip panel {lay.thickness_mm:.2f} mm" + (
                f" + collar {below:.2f} mm" if below else ""
            )
        radius, widest = max(reach)
        out.append(
            PieceEnvelope(
                f"rigid_j{k}" if k < n else "rigid_tip", k, radius, height, widest, tallest
            )
        )
    return out


def _column_half_width_mm(spec: TailSpec, z_mm: float) -> float:
    """Half the narrowest width of the SOA's filled envelope at height z of the SOA frame (0 = lower
    flange face)."""
    soa = spec.soa
    f, rise, h = soa.flange_thickness_mm, soa.row_rise_mm, soa.built_height_mm
    if z_mm <= f + 1e-9 or z_mm >= h - f - 1e-9:
        return spec.joint.base_diameter_mm / 2.0
    m = min(int((z_mm - f) // rise), soa.facet_rows - 1)
    s0, s1 = (
        (soa.long_side_mm, soa.short_side_mm)
        if m % 2 == 0
        else (soa.short_side_mm, soa.long_side_mm)
    )
    frac = (z_mm - f - m * rise) / rise
    return (s0 + (s1 - s0) * frac) / 2.0


def _column_narrowest_mm(spec: TailSpec, z0: float, z1: float) -> tuple[float, float]:
    """(narrowest half-width, where) of the SOA envelope between z0 and z1 (SOA frame)."""
    soa = spec.soa
    f, rise = soa.flange_thickness_mm, soa.row_rise_mm
    zs = [z0, z1] + [f + m * rise for m in range(soa.facet_rows + 1) if z0 < f + m * rise < z1]
    return min((_column_half_width_mm(spec, z), z) for z in zs)


def twin_problems(spec: TailSpec) -> list[str]:
    """Every reason the rigid twin cannot be built or printed, naming the key, its value, the
    derived dimension that breaks and what is allowed (empty when it can)."""
    return _printer_problems(spec) + _dowel_pin_problems(spec) + _tie_rod_problems(spec)


def _printer_problems(spec: TailSpec) -> list[str]:
    """The widest and the tallest rigid twin piece against the printer's bed and height."""
    fp = spec.fabrication_package
    out: list[str] = []
    envs = piece_envelopes(spec)
    lo_key = "printer_x_mm" if fp.printer_x_mm <= fp.printer_y_mm else "printer_y_mm"
    wide = max(envs, key=lambda e: e.radius_mm)
    tall = max(envs, key=lambda e: e.height_mm)
    width = 2.0 * wide.radius_mm
    if width > min(fp.printer_x_mm, fp.printer_y_mm):
        out.append(
            f"fabrication_package.{lo_key} = {getattr(fp, lo_key)!r}: rigid twin piece {wide.name} "
            "is "
            f"{width:.2f} mm wide ({wide.widest}), {width - getattr(fp, lo_key):.2f} mm more than "
            "the "
            f"{fp.printer_x_mm:g} x {fp.printer_y_mm:g} mm bed allows; one joint per piece is the "
            "smallest "
            "split that prints without support; allowed: fabrication_package.printer_x_mm and "
            "printer_y_mm "
            f">= {width:.2f} mm (or a smaller joint.panel_diameter_mm)"
        )
    if tall.height_mm > fp.printer_z_mm:
        out.append(
            f"fabrication_package.printer_z_mm = {fp.printer_z_mm!r}: rigid twin piece {tall.name} "
            "is "
            f"{tall.height_mm:.2f} mm tall ({tall.tallest}), "
            f"{tall.height_mm - fp.printer_z_mm:.2f} mm "
            f"more than the printer; one joint per piece is the smallest split that prints without "
            f"support; allowed: >= {tall.height_mm:.2f} mm (or a smaller joint.joint_height_mm)"
        )
    return out


def _dowel_pin_problems(spec: TailSpec) -> list[str]:
    """The dowel pins: every panel holds a pin's lower half under a floor, and each SOA column its
    upper half with fabrication_package.fdm_min_wall_mm around the hole."""
    fp = spec.fabrication_package
    j = spec.joint
    t = j.panel_thickness_mm
    out: list[str] = []
    panel_depth, column_depth = pin_depths_mm(spec, t)
    if panel_depth - PIN_HOLE_EXTRA_MM <= 0:
        out.append(
            f"joint.joint_height_mm = {j.joint_height_mm!r}: the rigid twin's {t:.2f} mm panels "
            "(H_j - H_a) "
            f"cannot hold a dowel pin under a {PANEL_PIN_FLOOR_MM:g} mm floor with "
            f"{PIN_HOLE_EXTRA_MM:g} mm "
            f"below the pin ({PANEL_PIN_FLOOR_MM + PIN_HOLE_EXTRA_MM - t:.2f} mm short); allowed: "
            "panels "
            f"thicker than {PANEL_PIN_FLOOR_MM + PIN_HOLE_EXTRA_MM:g} mm"
        )
    d_pin = pin_hole_mm(spec)
    depth = (spec.soa.built_height_mm - j.gap_mm) / 2.0  # the SOA's flange seat in each panel
    z_top = spec.soa.built_height_mm - depth  # the piece's top face in the SOA frame
    half, at = _column_narrowest_mm(spec, max(z_top - column_depth, 0.0), z_top)
    web = half - d_pin / 2.0
    if web < fp.fdm_min_wall_mm:
        out.append(
            f"fabrication_package.pin_diameter_mm = {fp.pin_diameter_mm!r}: the rigid twin's "
            f"{d_pin:.2f} mm dowel hole (pin_diameter_mm + pin_hole_clearance_mm), "
            f"{column_depth:.2f} mm deep "
            "from the top of each SOA column (fabrication_package.pin_length_mm = "
            f"{fp.pin_length_mm!r}), "
            f"leaves {web:.2f} mm where the bellows narrows to {2 * half:.2f} mm, "
            f"{fp.fdm_min_wall_mm - web:.2f} mm short of fabrication_package.fdm_min_wall_mm = "
            f"{fp.fdm_min_wall_mm!r}; allowed: "
            + (
                f"a hole <= {2 * (half - fp.fdm_min_wall_mm):.2f} mm or a shorter pin"
                if half > fp.fdm_min_wall_mm
                else f"fabrication_package.fdm_min_wall_mm < {half:.2f} mm (no hole fits beside a "
                "wall that thick)"
            )
        )
    return out


def _tie_rod_problems(spec: TailSpec) -> list[str]:
    """The tie rod through the rod column, and its nuts' pockets in the root and tip panels."""
    fp = spec.fabrication_package
    t = spec.joint.panel_thickness_mm
    out: list[str] = []
    d_tie = tie_rod_hole_mm(spec)
    rod_web = (spec.vertebra.diameter_mm - d_tie) / 2.0
    if rod_web < fp.fdm_min_wall_mm:
        out.append(
            f"fabrication_package.tie_rod_thread = {fp.tie_rod_thread!r}: the rigid twin's "
            f"{d_tie:.2f} mm "
            "tie-rod hole (thread + fabrication_package.tie_rod_clearance_mm) leaves "
            f"{rod_web:.2f} mm in "
            f"the {spec.vertebra.diameter_mm:g} mm rod column (vertebra.diameter_mm), "
            f"{fp.fdm_min_wall_mm - rod_web:.2f} mm short of fabrication_package.fdm_min_wall_mm = "
            f"{fp.fdm_min_wall_mm!r}; allowed: "
            + (
                f"a hole <= {spec.vertebra.diameter_mm - 2 * fp.fdm_min_wall_mm:.2f} mm (a thinner "
                "thread)"
                if spec.vertebra.diameter_mm > 2 * fp.fdm_min_wall_mm
                else f"fabrication_package.fdm_min_wall_mm < {spec.vertebra.diameter_mm / 2:g} mm "
                "(no hole fits in "
                "the rod column beside a wall that thick)"
            )
        )
    plate = t - nut_pocket_depth_mm(spec)
    if plate < fp.fdm_min_plate_mm:
        out.append(
            f"fabrication_package.tie_rod_thread = {fp.tie_rod_thread!r}: the rigid twin's "
            f"{nut_pocket_depth_mm(spec):.2f} mm nut pockets in the root and tip faces leave "
            f"{plate:.2f} mm of "
            f"the {t:.2f} mm panels (joint.joint_height_mm - joint.gap_mm), "
            f"{fp.fdm_min_plate_mm - plate:.2f} mm short of fabrication_package.fdm_min_plate_mm = "
            f"{fp.fdm_min_plate_mm!r}; allowed: a thinner thread or thicker panels"
        )
    return out


__all__ = [
    "NUT_POCKET_CLEARANCE_MM",
    "PIN_HOLE_EXTRA_MM",
    "PANEL_PIN_FLOOR_MM",
    "PieceEnvelope",
    "fits_printer",
    "nut_pocket_depth_mm",
    "piece_envelopes",
    "pin_depths_mm",
    "pin_hole_mm",
    "soa_column_reach_mm",
    "tie_rod_hole_mm",
    "tie_rod_length_mm",
    "twin_problems",
]
