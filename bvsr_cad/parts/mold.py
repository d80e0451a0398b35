"""The SOA casting mold set: printed rigid parts around a sacrificial core.

The SOA (a 1 mm square bellows with a round flange at both ends, see
:mod:`bvsr_cad.parts.soa`) is cast in PU rubber. Its interior narrows to
about 2.8 mm at the valley folds, so no rigid or silicone core can be pulled
out of it: the core is sacrificial (printed in a soluble material such as
PVA/BVOH, or cast in wax) and is located by square core prints in sockets at
both ends, so it can neither shift nor turn while the PU flows.

Split strategy, with the reasons:

* Two shell halves split on the diagonal plane x = y through two opposite
  corners of the square. Pulled along +/-(1, -1, 0)/sqrt(2), every facet of the
  bellows has the same draft, asin(cos(45 deg) cos(facet tilt)), about 35 deg:
  the diagonal is the pull that maximises the smallest draft of the four facet
  families (a split through the middle of two sides would leave those two
  sides with no draft at all). Only the corner fillets on the parting line
  have none, and there the flash follows a corner crease where it does no harm.
* The bottom plate and the lid each form one whole flange (end face and rim)
  as a single round pocket, so the two bonded surfaces of the SOA (flange face
  and rim, glued into the panel pockets) are free of parting lines, come out
  round and coaxial, and carry no flash. The flange's inner annulus lies in the
  plane where the halves meet the plate or lid: a flat shut-off face.
* Bottom fill: the gate rises through the bottom plate into the lower flange
  face; the cavity's wall rises monotonically from the lower to the upper
  flange (each facet row only moves in or out as it rises), so the only place
  air can gather is the upper flange's end face, the cavity's high point.
  Four vents leave it through the lid.
* Registration: half_a carries two pins into half_b on the parting plane;
  the bottom plate and the lid each carry one pin into each half. Four
  clamping bolts run through lid, halves and bottom plate at the corners.

Frames: the *cast frame* is the SOA frame (axis +Z, lower flange face at
z = 0, the square's sides along X and Y) in which the cast part is the SOA
scaled about the origin by 1 + shrinkage. Every solid here is in that frame;
``print_transform`` moves a part onto the print bed (z = 0, a flat face down).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import build123d as bd
import numpy as np

from ..parameters.layout import Cyl
from ..parameters.molds import PIN_ROOT_MM, SOCKET_EXTRA_DEPTH_MM, mold_dimensions, mold_problems
from ..parameters.tables import Casting, SoaTable
from .kernel import (
    GeometryError,
    PrintPosed,
    bounds,
    cut_all,
    cylinder_between,
    fuse_all,
    location,
    single_solid,
)
from .soa import bellows_profile, soa_body, soa_envelope, soa_interior

#: Pull direction of half_a (the side x - y > 0); half_b is pulled the other way.
DIAGONAL_PULL = (1.0 / math.sqrt(2.0), -1.0 / math.sqrt(2.0), 0.0)
#: In-plane direction of the parting plane x = y (towards the +X+Y corner).
DIAGONAL_ALONG = (1.0 / math.sqrt(2.0), 1.0 / math.sqrt(2.0), 0.0)

Matrix = tuple[tuple[float, ...], ...]


@dataclass(frozen=True)
class MoldPart(PrintPosed):
    """One printed (or cast) part of the mold set, in the cast frame (mm)."""

    name: str
    role: str  # shell, bottom_plate, lid, core
    solid: bd.Solid
    pull_direction: tuple[float, float, float] | None  # None: sacrificial
    print_transform: Matrix  # 4x4, cast frame -> print frame
    parting_planes: tuple[
        tuple[tuple[float, float, float], tuple[float, float, float]], ...
    ]  # (point, normal)
    note: str = ""
    features: tuple[
        Cyl, ...
    ] = ()  #: its round holes and pins, as cut and fused (the drawings' hole tables)

    @property
    def sacrificial(self) -> bool:
        return self.pull_direction is None


@dataclass(frozen=True)
class Channel:
    """An empty channel of the closed mold (gate or vent), in the cast frame."""

    name: str
    kind: str  # gate, vent
    diameter_mm: float
    solid: bd.Solid
    opening_mm: tuple[float, float, float]  # where it meets the cavity


@dataclass(frozen=True)
class MoldSet:
    """The closed mold around the cast part, everything in the cast frame (mm)."""

    cast: bd.Solid
    parts: dict[str, MoldPart]
    channels: tuple[Channel, ...]
    scale: float  # cast = SOA scaled by this about the origin
    soa_volume_mm3: float
    parting_margin_mm: float
    info: dict = field(default_factory=dict, hash=False, compare=False)


def _as_matrix(m: np.ndarray) -> Matrix:
    return tuple(tuple(float(v) for v in row) for row in m)


def _print_transform(x_dir: np.ndarray, z_dir: np.ndarray, solid: bd.Solid) -> np.ndarray:
    """Rotation taking x_dir, z_dir (cast frame) to the print X and Z axes, then
    a shift that puts the part on the bed (z = 0) centred on the origin in X, Y."""
    x = np.asarray(x_dir, float) / np.linalg.norm(x_dir)
    z = np.asarray(z_dir, float) / np.linalg.norm(z_dir)
    y = np.cross(z, x)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = x, y, z
    box = bounds(solid.moved(location(_as_matrix(m))))
    m[:3, 3] = (-(box.min.X + box.max.X) / 2.0, -(box.min.Y + box.max.Y) / 2.0, -box.min.Z)
    return m


def _uez(u: float, e: float, z: float) -> tuple[float, float, float]:
    """A point given along the pull (u), along the parting plane (e) and z."""
    d, a = DIAGONAL_PULL, DIAGONAL_ALONG
    return (u * d[0] + e * a[0], u * d[1] + e * a[1], z)


def _uez_box(u0: float, u1: float, e0: float, e1: float, z0: float, z1: float) -> bd.Solid:
    plane = bd.Plane(origin=_uez(u0, e0, z0), x_dir=DIAGONAL_PULL, z_dir=(0, 0, 1))
    return bd.Solid.make_box(u1 - u0, e1 - e0, z1 - z0, plane)


@dataclass(frozen=True)
class _MoldFeatures:
    """The round features shared by several mold parts, declared once: the parts' solids are cut and
    fused from these, and the drawings' hole tables list them."""

    bolts: list[Cyl]
    ab_pins: list[Cyl]  # half_a -> half_b, on the parting plane either side of the cavity
    ab_sockets: list[Cyl]
    plate_pins: list[Cyl]  # bottom plate and lid pins, one into each half on the pull axis
    lid_pins: list[Cyl]
    plate_sockets: list[Cyl]
    lid_sockets: list[Cyl]
    gate: Cyl
    vents_xy: list[tuple[float, float]]
    vents: list[Cyl]
    plate_flange: Cyl  # the flange pockets the cast envelope leaves (not cut from these)
    lid_flange: Cyl

    def shell(self, side: int) -> tuple[Cyl, ...]:
        """Half_a's (``side`` 1) or half_b's (-1) features: its plate and lid sockets, its bolts and
        the parting plane's pins (half_a) or sockets (half_b)."""
        mine = [
            f
            for f, su in zip(
                self.plate_sockets + self.lid_sockets + self.bolts, (1, -1, 1, -1, 1, 1, -1, -1)
            )
            if su == side
        ]
        return tuple(mine + (self.ab_pins if side > 0 else self.ab_sockets))


def _solids(features: list[Cyl]) -> list[bd.Solid]:
    return [cylinder_between(f.p0, f.p1, f.diameter_mm) for f in features]


def _mold_features(dims, c: Casting) -> _MoldFeatures:
    """The bolts, pins, sockets, gate, vents and flange pockets in the cast frame."""
    z_lo, z_hi, h = dims.z_lo_mm, dims.z_hi_mm, dims.cast_height_mm
    ab_pins, ab_sockets = _parting_pins(dims, c)
    plate_pins, plate_sockets = _end_pins(dims, c, z_lo, 1.0, "plate_socket")
    lid_pins, lid_sockets = _end_pins(dims, c, z_hi, -1.0, "lid_socket")
    gate, vents_xy, vents = _pour_channels(dims, c)
    d_fl = 2.0 * dims.cast_flange_radius_mm
    return _MoldFeatures(
        bolts=_bolts(dims, c),
        ab_pins=ab_pins,
        ab_sockets=ab_sockets,
        plate_pins=plate_pins,
        lid_pins=lid_pins,
        plate_sockets=plate_sockets,
        lid_sockets=lid_sockets,
        gate=gate,
        vents_xy=vents_xy,
        vents=vents,
        plate_flange=Cyl("flange_pocket", "flange_pocket", (0.0, 0.0, 0.0), (0.0, 0.0, z_lo), d_fl),
        lid_flange=Cyl("flange_pocket", "flange_pocket", (0.0, 0.0, h), (0.0, 0.0, z_hi), d_fl),
    )


def _bolts(dims, c: Casting) -> list[Cyl]:
    """The four bolts that clamp the stack, through it from below the bottom plate to above the
    lid, at the corners (+-u, +-e)."""
    bolt_uv = dims.bolt_uv_mm
    return [
        Cyl(
            f"bolt_{i}",
            "bolt",
            _uez(su * bolt_uv, se * bolt_uv, dims.z_bottom_mm - 1.0),
            _uez(su * bolt_uv, se * bolt_uv, dims.z_top_mm + 1.0),
            c.bolt_hole_diameter_mm,
        )
        for i, (su, se) in enumerate(((1, 1), (1, -1), (-1, 1), (-1, -1)), start=1)
    ]


def _parting_pins(dims, c: Casting) -> tuple[list[Cyl], list[Cyl]]:
    """Half_a's two pins into half_b's sockets, on the parting plane either side of the cavity at
    mid-height of the cast."""
    rho_pin = dims.pin_circle_mm
    z_mid = (dims.z_lo_mm + dims.z_hi_mm) / 2.0
    sock_len = c.pin_length_mm + SOCKET_EXTRA_DEPTH_MM
    pins = [
        Cyl(
            f"pin_{i}",
            "pin",
            _uez(PIN_ROOT_MM, se * rho_pin, z_mid),
            _uez(-c.pin_length_mm, se * rho_pin, z_mid),
            c.pin_diameter_mm,
        )
        for i, se in enumerate((1, -1), start=1)
    ]
    sockets = [
        Cyl(
            f"socket_{i}",
            "pin_socket",
            _uez(0.1, se * rho_pin, z_mid),
            _uez(-sock_len, se * rho_pin, z_mid),
            dims.socket_mm,
        )
        for i, se in enumerate((1, -1), start=1)
    ]
    return pins, sockets


def _end_pins(
    dims, c: Casting, z_face: float, inward: float, socket_name: str
) -> tuple[list[Cyl], list[Cyl]]:
    """The bottom plate's (``inward`` +1, its face at z_lo) or the lid's (-1, at z_hi) two pins,
    one into each half on the pull axis, and the halves' sockets for them."""
    rho_pin = dims.pin_circle_mm
    sock_len = c.pin_length_mm + SOCKET_EXTRA_DEPTH_MM
    pins = [
        Cyl(
            f"pin_{i}",
            "pin",
            _uez(su * rho_pin, 0, z_face - inward * PIN_ROOT_MM),
            _uez(su * rho_pin, 0, z_face + inward * c.pin_length_mm),
            c.pin_diameter_mm,
        )
        for i, su in enumerate((1, -1), 1)
    ]
    sockets = [
        Cyl(
            f"{socket_name}_{i}",
            "pin_socket",
            _uez(su * rho_pin, 0, z_face - inward * 0.1),
            _uez(su * rho_pin, 0, z_face + inward * sock_len),
            dims.socket_mm,
        )
        for i, su in enumerate((1, -1), 1)
    ]
    return pins, sockets


def _pour_channels(dims, c: Casting) -> tuple[Cyl, list[tuple[float, float]], list[Cyl]]:
    """The gate from below the bottom plate into the cavity's floor, and the four vents (their xy
    and their channels) from the cast's top through the lid."""
    r_gate = dims.channel_radius_mm(c.gate_diameter_mm)
    r_vent = dims.channel_radius_mm(c.vent_diameter_mm)
    vents_xy = [(r_vent, 0.0), (0.0, r_vent), (-r_vent, 0.0), (0.0, -r_vent)]
    gate = Cyl(
        "gate",
        "gate",
        (r_gate, 0.0, dims.z_bottom_mm - 1.0),
        (r_gate, 0.0, 0.0),
        c.gate_diameter_mm,
    )
    vents = [
        Cyl(
            f"vent_{i}",
            "vent",
            (x, y, dims.cast_height_mm),
            (x, y, dims.z_top_mm + 1.0),
            c.vent_diameter_mm,
        )
        for i, (x, y) in enumerate(vents_xy, start=1)
    ]
    return gate, vents_xy, vents


_Z_AXIS = np.array([0.0, 0.0, 1.0])
_PULL_A = np.array(DIAGONAL_PULL)
_PLANE_DIAG = ((0.0, 0.0, 0.0), tuple(DIAGONAL_PULL))


def _shell_part(side: int, dims, feats: _MoldFeatures, envelope: bd.Solid) -> MoldPart:
    """Half_a (``side`` 1: pins on its parting face) or half_b (-1: the pins' sockets): the block
    between the flanges on one side of the diagonal parting plane, pulled along the diagonal."""
    w, z_lo, z_hi = dims.block_half_mm, dims.z_lo_mm, dims.z_hi_mm
    u0, u1 = (0.0, w) if side > 0 else (-w, 0.0)
    body = cut_all(_uez_box(u0, u1, -w, w, z_lo, z_hi), [envelope])
    body = cut_all(body, _solids([f for f in feats.shell(side) if f.role != "pin"]))
    body = fuse_all(body, _solids(feats.ab_pins)) if side > 0 else body
    name = "half_a" if side > 0 else "half_b"
    solid = single_solid(body, f"mold {name}")
    planes = (_PLANE_DIAG, ((0.0, 0.0, z_lo), (0.0, 0.0, 1.0)), ((0.0, 0.0, z_hi), (0.0, 0.0, 1.0)))
    return MoldPart(
        name,
        "shell",
        solid,
        tuple(float(v) for v in side * _PULL_A),
        _as_matrix(_print_transform(_Z_AXIS, -side * _PULL_A, solid)),
        planes,
        "printed lying on its back face, pins up" if side > 0 else "printed lying on its back face",
        feats.shell(side),
    )


def _bottom_plate(dims, feats: _MoldFeatures, envelope: bd.Solid, core: bd.Solid) -> MoldPart:
    """The plate under the lower flange: it forms that flange, holds the core's lower print and the
    gate."""
    w, z_lo = dims.block_half_mm, dims.z_lo_mm
    plate = cut_all(
        _uez_box(-w, w, -w, w, dims.z_bottom_mm, z_lo),
        [envelope, core, *_solids([feats.gate]), *_solids(feats.bolts)],
    )
    plate = single_solid(fuse_all(plate, _solids(feats.plate_pins)), "mold bottom_plate")
    return MoldPart(
        "bottom_plate",
        "bottom_plate",
        plate,
        (0.0, 0.0, -1.0),
        _as_matrix(_print_transform(_PULL_A, _Z_AXIS, plate)),
        (((0.0, 0.0, z_lo), (0.0, 0.0, 1.0)),),
        "forms the lower flange; gate from below",
        (feats.gate, feats.plate_flange, *feats.bolts, *feats.plate_pins),
    )


def _lid(dims, feats: _MoldFeatures, envelope: bd.Solid, core: bd.Solid) -> MoldPart:
    """The lid over the upper flange: it forms that flange, holds the core's upper print and the
    vents."""
    w, z_hi = dims.block_half_mm, dims.z_hi_mm
    lid = cut_all(
        _uez_box(-w, w, -w, w, z_hi, dims.z_top_mm),
        [envelope, core, *_solids(feats.vents), *_solids(feats.bolts)],
    )
    lid = single_solid(fuse_all(lid, _solids(feats.lid_pins)), "mold lid")
    return MoldPart(
        "lid",
        "lid",
        lid,
        (0.0, 0.0, 1.0),
        _as_matrix(_print_transform(_PULL_A, -_Z_AXIS, lid)),
        (((0.0, 0.0, z_hi), (0.0, 0.0, 1.0)),),
        "forms the upper flange; printed upside down",
        (*feats.vents, feats.lid_flange, *feats.bolts, *feats.lid_pins),
    )


def _core_part(core: bd.Solid) -> MoldPart:
    """The sacrificial core: the SOA's interior and its prints."""
    return MoldPart(
        "core",
        "core",
        core,
        None,
        _as_matrix(_print_transform(np.array([1.0, 0, 0]), _Z_AXIS, core)),
        (),
        "sacrificial: print in PVA/BVOH and dissolve, or cast in wax and melt out",
    )


def _channels(dims, feats: _MoldFeatures, c: Casting) -> tuple[Channel, ...]:
    """The gate and the vents as the material fills them: their cylinders within the mold block."""
    w = dims.block_half_mm
    block = _uez_box(-w, w, -w, w, dims.z_bottom_mm, dims.z_top_mm)
    r_gate, h = dims.channel_radius_mm(c.gate_diameter_mm), dims.cast_height_mm
    gate = _solids([feats.gate])[0]
    return (
        Channel(
            "gate",
            "gate",
            c.gate_diameter_mm,
            single_solid(gate.intersect(block), "gate channel"),
            (r_gate, 0.0, 0.0),
        ),
        *(
            Channel(
                f"vent_{i}",
                "vent",
                c.vent_diameter_mm,
                single_solid(v.intersect(block), f"vent {i}"),
                (x, y, h),
            )
            for i, (v, (x, y)) in enumerate(zip(_solids(feats.vents), feats.vents_xy), start=1)
        ),
    )


def mold_set(soa: SoaTable, flange_diameter_mm: float, casting: Casting) -> MoldSet:
    """Build the mold set that casts the SOA described by ``soa``.

    Args:
        soa: Table II parameters (the part to cast).
        flange_diameter_mm: the SOA flange disc (D_b).
        casting: mold allowances (walls, pins, bolts, gate, vents, shrinkage).

    Returns:
        The cast part and the mold parts in the cast frame, with pull
        directions, print orientations and the gate and vent channels.

    Raises:
        ValueError: the allowances do not fit around this SOA (names the field).
        GeometryError: the kernel did not produce one valid solid per part.
    """
    c = casting
    problems = mold_problems(
        soa, flange_diameter_mm, c
    )  # the rules the parameter file was validated by
    if problems:
        raise ValueError("; ".join(problems))
    dims = mold_dimensions(
        soa, flange_diameter_mm, c
    )  # the same numbers the parameter validation judges
    k = dims.scale

    # The cast and the envelope it fills, in the SOA frame, then scaled.
    soa_solid = soa_body(soa, flange_diameter_mm)
    cast = single_solid(soa_solid.scale(k), "cast part")
    envelope = single_solid(soa_envelope(soa, flange_diameter_mm).scale(k), "cast envelope")
    # The core is the SOA's interior, prolonged at the end size into the core
    # prints (the same ruled sections the SOA cuts, so it fits exactly).
    core = single_solid(soa_interior(soa, flange_diameter_mm, c.core_print_mm / k).scale(k), "core")

    feats = _mold_features(dims, c)
    parts = {
        "half_a": _shell_part(1, dims, feats, envelope),
        "half_b": _shell_part(-1, dims, feats, envelope),
        "bottom_plate": _bottom_plate(dims, feats, envelope, core),
        "lid": _lid(dims, feats, envelope, core),
        "core": _core_part(core),
    }
    channels = _channels(dims, feats, c)
    for p in parts.values():
        if not p.solid.is_valid:
            raise GeometryError(f"mold {p.name}: invalid solid")
    return MoldSet(
        cast=cast,
        parts=parts,
        channels=channels,
        scale=k,
        soa_volume_mm3=soa_solid.volume,
        parting_margin_mm=k * soa.fillet_radius_mm,
        info=_mold_info(soa, flange_diameter_mm, dims, c),
    )


def _mold_info(soa: SoaTable, flange_diameter_mm: float, dims, c: Casting) -> dict:
    """The mold set's figures for the export's records: block, cast, channels, bolts, demolding
    order."""
    w, k, r_fl, bolt_uv = (
        dims.block_half_mm,
        dims.scale,
        dims.cast_flange_radius_mm,
        dims.bolt_uv_mm,
    )
    prof = bellows_profile(soa, flange_diameter_mm)
    return {
        "block_mm": [2 * w, 2 * w, dims.z_top_mm - dims.z_bottom_mm],
        "cast_height_mm": dims.cast_height_mm,
        "flange_diameter_mm": 2 * r_fl,
        "gate_radius_mm": dims.channel_radius_mm(c.gate_diameter_mm),
        "vent_radius_mm": dims.channel_radius_mm(c.vent_diameter_mm),
        "pin_radius_mm": dims.pin_circle_mm,
        "bolt_positions_mm": [
            list(_uez(su * bolt_uv, se * bolt_uv, 0.0)[:2]) for su in (1, -1) for se in (1, -1)
        ],
        "bolt_length_mm": dims.z_top_mm - dims.z_bottom_mm,
        "corner_proud_of_flange_mm": k * soa.computed_circumcircle_mm / 2.0 - r_fl,
        "valley_core_width_mm": k * min(prof.inner_side_mm),
        "demolding_order": ["lid", "bottom_plate", "half_a", "half_b", "core"],
    }
