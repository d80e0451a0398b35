"""The rigid comparison tail: the BVSR's outer geometry at rest, in PLA.

The paper's disturbance tests compare the BVSR with a rigid twin of
"identical geometric parameters". Here the twin is the union of the panel
rims, the five SOA envelopes of every joint (filled: a rigid twin needs no air
inside) and the rod, cut into pieces that print on an FDM printer.

Split: one piece per joint, at the lower face of every panel. Piece ``k`` is
panel ``k-1`` lying on the bed with joint ``k``'s five SOA columns and its rod
standing on it, up to panel ``k``'s lower face; the tip panel is a piece of
its own. That is the only split for which no panel hangs over air (a panel in
the middle of a piece would need support under its whole lower face), so the
split is fixed by printability and the printer volume is checked, not used to
choose it.

Joining: a dowel pin per SOA column end (the column's top face and the next
panel's lower face get matching blind holes) locates the pieces and takes
the shear; a threaded tie rod through the rod column with a nut in a pocket in
the root face and in the tip face clamps the stack.

Simplified against the BVSR (none of it shows from outside): the SOA pockets,
air channels, fitting ports, tube ports and feed passages and the rod socket
are filled; the lightening holes, the tube pass-through holes and the mount
and payload insert bores are kept, so the twin bolts to the same robot and
carries the same payloads.

Frame of a piece: its print frame (panel lower face on z = 0, tail axes),
i.e. the tail frame moved down by the panel's z0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import build123d as bd
import numpy as np

from ..parameters.layout import PanelLayout, polar, soa_angles_deg
from ..parameters.standard_parts import metric
from ..parameters.tables import TailSpec

# The twin's derived dimensions (pin depths, nut pockets, the printer fit) live with the rules that
# validate them.
from ..parameters.twin import (
    NUT_POCKET_CLEARANCE_MM,
    fits_printer,
    nut_pocket_depth_mm,
    pin_depths_mm,
    pin_hole_mm,
    tie_rod_hole_mm,
    twin_problems,
)
from .kernel import (
    GeometryError,
    bounds,
    cut_all,
    cylinder_between,
    fuse_all,
    location,
    single_solid,
)
from .soa import soa_envelope

#: Panel features kept in the twin (they show from outside or carry the robot and payload).
KEPT_ROLES = ("lightening", "tube", "insert")


@dataclass(frozen=True)
class PrintFeature:
    """A hole added only to assemble the twin (excluded from the envelope comparison).

    ``p0``/``p1`` are in the tail frame (mm); the hole is the cylinder between them.
    """

    name: str
    kind: str  # pin_hole, tie_rod_hole, nut_pocket
    p0: tuple[float, float, float]
    p1: tuple[float, float, float]
    diameter_mm: float


@dataclass(frozen=True)
class RigidPiece:
    name: str
    index: int  # 1..joints for joint pieces, joints + 1 for the tip piece
    z0_mm: float  # the piece's bed face in the tail frame
    solid: bd.Solid  # print frame
    features: tuple[PrintFeature, ...]
    size_mm: tuple[float, float, float]
    volume_mm3: float  # the solid's, measured once (OCCT integrates the B-rep on every query)


def _frustum(lay: PanelLayout) -> bd.Solid:
    if abs(lay.rim_radius_lower_mm - lay.rim_radius_upper_mm) < 1e-9:
        return bd.Solid.make_cylinder(lay.rim_radius_lower_mm, lay.thickness_mm)
    return bd.Solid.make_cone(lay.rim_radius_lower_mm, lay.rim_radius_upper_mm, lay.thickness_mm)


def _hex_prism(af_mm: float, z0: float, z1: float) -> bd.Solid:
    """A hexagonal pocket (flats across ``af_mm``) between z0 and z1 on the axis."""
    r = af_mm / math.sqrt(3.0)  # circumradius
    face = bd.Plane.XY.offset(z0) * bd.RegularPolygon(r, 6).face()
    return bd.Solid.extrude(face, bd.Vector(0, 0, z1 - z0))


def rigid_tail_pieces(
    spec: TailSpec, layouts: list[PanelLayout], soa_transforms: dict[int, list[np.ndarray]]
) -> list[RigidPiece]:
    """Build every piece of the rigid twin in its print frame.

    Args:
        spec: the validated tail spec.
        layouts: every panel's layout (the same ones the BVSR panels are built from).
        soa_transforms: per joint k (1-based), the five SOA placements (4x4, SOA frame -> tail
            frame, mm).

    Returns:
        The pieces from root to tip.

    Raises:
        ValueError: the spec breaks a rule of the twin
            (:func:`bvsr_cad.parameters.twin.twin_problems`, checked when the parameter file is
            loaded; names the key).
        GeometryError: a piece does not fit the printer volume of ``[fabrication_package]``, or the
            kernel failed.
    """
    problems = twin_problems(spec)
    if problems:
        raise ValueError("; ".join(problems))
    soa_env = soa_envelope(spec.soa, spec.joint.base_diameter_mm)
    return [
        _rigid_piece(spec, layouts, k, soa_env, soa_transforms) for k in range(1, len(layouts) + 1)
    ]


def _piece_features(
    spec: TailSpec, layouts: list[PanelLayout], k: int, top: float
) -> list[PrintFeature]:
    """Piece k's tie rod hole, pin holes and nut pockets, in the tail frame. Pin holes go up from
    the piece's bed face (into the panel, under the previous joint's columns) and down from its
    columns' top faces."""
    n = len(layouts)
    lay = layouts[k - 1]
    z0 = lay.z0_mm
    d_pin, d_tie = pin_hole_mm(spec), tie_rod_hole_mm(spec)
    # The pin sits deeper in the column than in the panel so the tip panel keeps a floor over its
    # holes.
    panel_pin_depth, column_pin_depth = pin_depths_mm(spec, layouts[0].thickness_mm)
    features = [
        PrintFeature(
            "tie_rod", "tie_rod_hole", (0.0, 0.0, z0 - 1e-3), (0.0, 0.0, top + 1e-3), d_tie
        )
    ]
    angles = soa_angles_deg()
    if k > 1:
        for i, a in enumerate(angles, start=1):
            xy = polar(lay.pitch_radius_lower_mm, a)
            features.append(
                PrintFeature(
                    f"pin_{k - 1}_{i}_upper",
                    "pin_hole",
                    (*xy, z0 - 1e-3),
                    (*xy, z0 + panel_pin_depth),
                    d_pin,
                )
            )
    if k < n:
        nxt = layouts[k]
        for i, a in enumerate(angles, start=1):
            xy = polar(nxt.pitch_radius_lower_mm, a)
            features.append(
                PrintFeature(
                    f"pin_{k}_{i}_lower",
                    "pin_hole",
                    (*xy, top - column_pin_depth),
                    (*xy, top + 1e-3),
                    d_pin,
                )
            )
    return features


def _rigid_piece(
    spec: TailSpec,
    layouts: list[PanelLayout],
    k: int,
    soa_env: bd.Solid,
    soa_transforms: dict[int, list[np.ndarray]],
) -> RigidPiece:
    """Piece k: panel k-1 with joint k's SOA columns and rod fused on (the tip piece: the tip panel
    alone), less the panel's kept cuts, the next panel's flange pockets, its holes and its nut
    pocket."""
    fp = spec.fabrication_package
    nut_af = metric(fp.tie_rod_thread).nut_af_mm + NUT_POCKET_CLEARANCE_MM
    nut_depth = nut_pocket_depth_mm(spec)
    n = len(layouts)
    lay = layouts[k - 1]
    z0 = lay.z0_mm
    top = layouts[k].z0_mm if k < n else z0 + lay.thickness_mm
    h = top - z0
    down = np.eye(4)
    down[2, 3] = -z0
    body = _frustum(lay)
    body = fuse_all(body, (cylinder_between(b.p0, b.p1, b.diameter_mm) for b in lay.bosses))
    if k < n:
        rod = bd.Solid.make_cylinder(spec.vertebra.diameter_mm / 2.0, top - z0)
        columns = [soa_env.moved(location(down @ m)) for m in soa_transforms[k]]
        body = fuse_all(body, [rod, *columns])
    features = _piece_features(spec, layouts, k, top)
    tools = [cylinder_between(c.p0, c.p1, c.diameter_mm) for c in lay.cuts if c.role in KEPT_ROLES]
    if k < n:
        # The SOA flanges reach into the next panel's pockets: that part belongs to the next piece.
        side = max(400.0, 4.0 * (lay.rim_radius_lower_mm + spec.joint.base_diameter_mm))
        tools.append(
            bd.Solid.make_box(side, side, max(20.0, 2.0 * lay.thickness_mm)).moved(
                bd.Location((-side / 2.0, -side / 2.0, h))
            )
        )
    for f in features:
        p0 = (f.p0[0], f.p0[1], f.p0[2] - z0)
        p1 = (f.p1[0], f.p1[1], f.p1[2] - z0)
        tools.append(cylinder_between(p0, p1, f.diameter_mm))
    if k == 1:
        features.append(
            PrintFeature(
                "nut_root",
                "nut_pocket",
                (0.0, 0.0, z0 - 1e-3),
                (0.0, 0.0, z0 + nut_depth),
                nut_af * 2 / math.sqrt(3.0),
            )
        )
        tools.append(_hex_prism(nut_af, -1e-3, nut_depth))
    if k == n:
        features.append(
            PrintFeature(
                "nut_tip",
                "nut_pocket",
                (0.0, 0.0, top - nut_depth),
                (0.0, 0.0, top + 1e-3),
                nut_af * 2 / math.sqrt(3.0),
            )
        )
        tools.append(_hex_prism(nut_af, h - nut_depth, h + 1e-3))
    name = f"rigid_j{k}" if k < n else "rigid_tip"
    solid = single_solid(cut_all(body, tools), f"rigid tail piece {name}")
    box = bounds(solid)
    size = (box.size.X, box.size.Y, box.size.Z)
    # Either way round on the bed.
    if not fits_printer(size, fp):
        raise GeometryError(
            f"rigid tail piece {name} is {size[0]:.1f} x {size[1]:.1f} x {size[2]:.1f} mm and does "
            "not fit the "
            "printer (fabrication_package.printer_x_mm/printer_y_mm/printer_z_mm = "
            f"{fp.printer_x_mm:g} x "
            f"{fp.printer_y_mm:g} x {fp.printer_z_mm:g} mm); one joint per piece is the smallest "
            "split that "
            "prints without support"
        )
    return RigidPiece(name, k, z0, solid, tuple(features), size, solid.volume)
