"""Derived panel layout: where every hole, pocket and passage of every panel
goes, in millimetres, computed from the spec alone (no CAD).

Both the panel generator and the parameter validation read this one layout,
so a combination that validates is exactly the one that gets built.

Frames: Z along the tail from the root face (z = 0), Y dorsal,
X lateral; SOA i sits at 90 + 72 (i - 1) deg from +X towards +Y. Panel k
occupies z in [k H_j, k H_j + t_p]; in a panel's own frame its lower face is
z = 0. The taper is one cone: pitch radius and rim radius both shrink by
tan(half-angle) per millimetre of z.
"""

from __future__ import annotations

import dataclasses
import math
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .standard_parts import MetricSize, metric, size_for_tap_drill
from .tables import AUTO, TailSpec

N_SOA = 5


def soa_angles_deg() -> np.ndarray:
    """Angle of SOA i = 1..5 from +X towards +Y (soa1 dorsal, on +Y)."""
    return 90.0 + 72.0 * np.arange(N_SOA)


def mid_angles_deg() -> np.ndarray:
    """Angles half-way between SOA i and SOA i+1."""
    return soa_angles_deg() + 36.0


def polar(radius_mm: float, angle_deg: float) -> tuple[float, float]:
    a = math.radians(angle_deg)
    return (radius_mm * math.cos(a), radius_mm * math.sin(a))


@dataclass(frozen=True)
class Tapped:
    """A bore drilled (printed) at a tap drill and tapped after printing."""

    size: MetricSize
    drill_mm: (
        float  #: the nominal tap drill (the printed bore adds fabrication.hole_compensation_mm)
    )

    @property
    def designation(self) -> str:
        return f"M{self.size.diameter_mm:g}x{self.size.pitch_mm:g}"


@dataclass(frozen=True)
class Cyl:
    """A cylinder from p0 to p1 (part frame, mm): a cut unless ``boss`` or ``pin``."""

    name: str
    # pocket, channel, port, tube, tube_port, feed, rod, setscrew, insert, lightening, boss; molds:
    # bolt, pin, pin_socket, gate, vent, flange_pocket
    role: str
    p0: tuple[float, float, float]
    p1: tuple[float, float, float]
    diameter_mm: float
    thread: Tapped | None = None  #: tapped after printing (the drawings' hole tables)

    @property
    def xy(self) -> tuple[float, float]:
        return ((self.p0[0] + self.p1[0]) / 2.0, (self.p0[1] + self.p1[1]) / 2.0)

    @property
    def z_range(self) -> tuple[float, float]:
        return (min(self.p0[2], self.p1[2]), max(self.p0[2], self.p1[2]))

    @property
    def vertical(self) -> bool:
        return abs(self.p0[2] - self.p1[2]) > 1e-9 and math.hypot(
            self.p1[0] - self.p0[0], self.p1[1] - self.p0[1]
        ) < 0.2 * abs(self.p1[2] - self.p0[2])


@dataclass(frozen=True)
class PanelLayout:
    index: int
    kind: str  # root, intermediate, boundary, tip
    z0_mm: float  # lower face in the tail frame
    thickness_mm: float
    rim_radius_lower_mm: float
    rim_radius_upper_mm: float
    pitch_radius_lower_mm: float
    pitch_radius_upper_mm: float
    pocket_depth_mm: float
    lower_pockets: bool
    upper_pockets: bool
    cuts: tuple[Cyl, ...] = field(default=())
    bosses: tuple[Cyl, ...] = field(default=())
    passages: tuple[Cyl, ...] = field(default=())

    @property
    def name(self) -> str:
        return f"panel{self.index}"

    def pocket_centres(self, face: str) -> np.ndarray:
        r = self.pitch_radius_lower_mm if face == "lower" else self.pitch_radius_upper_mm
        return np.array([polar(r, a) for a in soa_angles_deg()])


#: The parameter keys that size or place a panel feature, by the start of its name (first match).
_HOLE = "fabrication.hole_compensation_mm"  # every printed hole (hole_d) is this much wider
_FEATURE_KEYS: tuple[tuple[str, tuple[str, ...]], ...] = (
    (
        "pocket_depth",
        ("soa.height_mm", "joint.gap_mm", "joint.joint_height_mm", "fabrication.socket_floor_mm"),
    ),
    (
        "pocket_",
        ("joint.base_diameter_mm", "fabrication.pocket_clearance_mm", "joint.pitch_diameter_mm"),
    ),
    ("channel_", ("joint.channel_diameter_mm", "joint.pitch_diameter_mm", _HOLE)),
    ("fitting_port_", ("mount.fitting_tap_drill_mm", "joint.pitch_diameter_mm", _HOLE)),
    ("tube_port_", ("tubes.outer_diameter_mm", _HOLE)),
    ("tube_", ("tubes.outer_diameter_mm", "tubes.clearance_mm", _HOLE)),
    ("feed_", ("tubes.passage_diameter_mm", "joint.pitch_diameter_mm", _HOLE)),
    ("passage_", ("tubes.passage_diameter_mm", _HOLE)),
    ("rod_bore", ("vertebra.diameter_mm", "socket.rod_clearance_mm", _HOLE)),
    ("set_screw", ("socket.set_screw_tap_drill_mm", _HOLE)),
    ("clamp_boss", ("socket.boss_wall_mm", "vertebra.diameter_mm", _HOLE)),
    (
        "mount_insert_",
        (
            "mount.insert_diameter_mm",
            "mount.bolt_circle_diameter_mm",
            "mount.insert_depth_mm",
            _HOLE,
        ),
    ),
    (
        "payload_insert_",
        (
            "payload.insert_diameter_mm",
            "payload.insert_circle_diameter_mm",
            "payload.insert_count",
            "payload.insert_depth_mm",
            _HOLE,
        ),
    ),
    ("lightening_", ("lightening.hole_diameter_mm",)),
    ("rim", ("joint.panel_diameter_mm",)),
    (
        "bellows",
        ("soa.long_side_mm", "soa.fillet_radius_mm", "soa.rotation_deg", "joint.pitch_diameter_mm"),
    ),
)
#: The tube rings: the tubes of segment s sit on this radius.
_RING_KEYS = {"2": "tubes.inner_radius_mm", "3": "tubes.second_radius_mm"}


def feature_keys(name: str) -> tuple[str, ...]:
    """The parameter keys that size or place the panel feature ``name`` (see
    :class:`LayoutProblem`)."""
    keys: tuple[str, ...] = ()
    for start, found in _FEATURE_KEYS:
        if name.startswith(start):
            keys = found
            break
    m = re.match(r"(tube|tube_port|passage)_s(\d)_", name)
    if m and m.group(2) in _RING_KEYS:
        keys += (_RING_KEYS[m.group(2)],)
    return keys


def key_value(spec: TailSpec, key: str) -> Any:
    """The value of a dotted parameter key in ``spec``."""
    value: Any = spec
    for part in key.split("."):
        value = getattr(value, part)
    return value


def with_key(spec: TailSpec, key: str, value: Any) -> TailSpec:
    """``spec`` with one dotted parameter key replaced."""
    *tables, name = key.split(".")
    if not tables:
        return dataclasses.replace(spec, **{name: value})
    section = key_value(spec, ".".join(tables))
    return with_key(spec, ".".join(tables), dataclasses.replace(section, **{name: value}))


def half_angle_rad(spec: TailSpec) -> float:
    """The taper half-angle actually used (resolving 'auto': the largest the panel rules allow,
    :func:`~bvsr_cad.parameters.panel_rules.max_feasible_taper_deg`)."""
    if spec.taper.half_angle_deg == AUTO:
        from .panel_rules import max_feasible_taper_deg  # the rules place panels: not at import

        return math.radians(max_feasible_taper_deg(spec))
    return math.radians(float(spec.taper.half_angle_deg))


def pocket_depth_mm(spec: TailSpec) -> float:
    """Each flange sits (H - H_a) / 2 deep: the SOA is longer than the gap by design."""
    return (spec.soa.built_height_mm - spec.joint.gap_mm) / 2.0


def pocket_diameter_mm(spec: TailSpec) -> float:
    return spec.joint.base_diameter_mm + spec.fabrication.pocket_clearance_mm


def hole_d(spec: TailSpec, nominal_mm: float) -> float:
    """Printed hole diameter with the MJF compensation."""
    return nominal_mm + spec.fabrication.hole_compensation_mm


def rod_thread(spec: TailSpec) -> Tapped | None:
    """The rod socket's thread (a ``threaded`` socket), or None (a set-screw socket)."""
    if spec.vertebra.socket != "threaded":
        return None
    size = metric(spec.vertebra.diameter_mm)
    return Tapped(size, size.tap_drill_mm)


def tapped(drill_mm: float) -> Tapped:
    """The thread a parameter file's tap drill is for (the nearest ISO size)."""
    return Tapped(size_for_tap_drill(drill_mm), drill_mm)


def rod_bore_mm(spec: TailSpec) -> float:
    thread = rod_thread(spec)
    if thread is not None:
        return hole_d(spec, thread.drill_mm)
    return hole_d(spec, spec.vertebra.diameter_mm + spec.socket.rod_clearance_mm)


def tube_hole_mm(spec: TailSpec) -> float:
    return hole_d(spec, spec.tubes.outer_diameter_mm + spec.tubes.clearance_mm)


def panel_kind(spec: TailSpec, k: int) -> str:
    if k == 0:
        return "root"
    if k == spec.panels - 1:
        return "tip"
    if k % spec.joints_per_segment == 0:
        return "boundary"
    return "intermediate"


def lightening_radius_mm(pitch_r: float, rim_r: float, pocket_r: float) -> tuple[float, float]:
    """Centre radius on a mid-angle that balances the web to the pockets and
    to the rim, and that web (for a hole of zero size)."""
    lo, hi = pitch_r, rim_r
    c36 = math.cos(math.radians(36.0))

    def to_pocket(rho: float) -> float:
        return math.sqrt(rho * rho + pitch_r * pitch_r - 2 * rho * pitch_r * c36) - pocket_r

    for _ in range(60):
        mid = (lo + hi) / 2.0
        if to_pocket(mid) < rim_r - mid:
            lo = mid
        else:
            hi = mid
    rho = (lo + hi) / 2.0
    return rho, rim_r - rho


def panel_layout(spec: TailSpec, k: int, half_angle: float | None = None) -> PanelLayout:
    """Every feature of panel k, in the panel's own frame (lower face z = 0)."""
    beta = half_angle_rad(spec) if half_angle is None else half_angle
    tan_b = math.tan(beta)
    j = spec.joint
    t = j.panel_thickness_mm
    z0 = k * j.joint_height_mm
    kind = panel_kind(spec, k)
    depth = pocket_depth_mm(spec)
    r_pitch_lo = j.pitch_diameter_mm / 2 - z0 * tan_b
    r_pitch_hi = j.pitch_diameter_mm / 2 - (z0 + t) * tan_b
    r_rim_lo = j.panel_diameter_mm / 2 - z0 * tan_b
    r_rim_hi = j.panel_diameter_mm / 2 - (z0 + t) * tan_b
    lower = kind != "root"
    upper = kind != "tip"
    d_pocket = pocket_diameter_mm(spec)
    cuts = _soa_cuts(spec, kind, t, depth, r_pitch_lo, r_pitch_hi, d_pocket)
    tube_cuts, passages = _tube_cuts(spec, k, t, r_pitch_lo, r_pitch_hi)
    socket_cuts, bosses = _rod_socket(spec, kind, t)
    cuts += (
        tube_cuts
        + socket_cuts
        + _insert_and_lightening_cuts(spec, kind, t, r_pitch_hi, r_rim_hi, d_pocket)
    )
    return PanelLayout(
        index=k,
        kind=kind,
        z0_mm=z0,
        thickness_mm=t,
        rim_radius_lower_mm=r_rim_lo,
        rim_radius_upper_mm=r_rim_hi,
        pitch_radius_lower_mm=r_pitch_lo,
        pitch_radius_upper_mm=r_pitch_hi,
        pocket_depth_mm=depth,
        lower_pockets=lower,
        upper_pockets=upper,
        cuts=tuple(cuts),
        bosses=tuple(bosses),
        passages=tuple(passages),
    )


def _soa_cuts(
    spec: TailSpec,
    kind: str,
    t: float,
    depth: float,
    r_pitch_lo: float,
    r_pitch_hi: float,
    d_pocket: float,
) -> list[Cyl]:
    """Each SOA's pockets on the faces it meets, and the channel through the panel (the root: the
    fitting port) that feeds it."""
    j = spec.joint
    cuts: list[Cyl] = []
    for i, a in enumerate(soa_angles_deg(), start=1):
        lo_xy = polar(r_pitch_lo, a)
        hi_xy = polar(r_pitch_hi, a)
        if kind != "root":
            cuts.append(
                Cyl(f"pocket_lower_{i}", "pocket", (*lo_xy, -1e-3), (*lo_xy, depth), d_pocket)
            )
        if kind != "tip":
            cuts.append(
                Cyl(
                    f"pocket_upper_{i}", "pocket", (*hi_xy, t - depth), (*hi_xy, t + 1e-3), d_pocket
                )
            )
        if kind == "intermediate":
            # Oblique by the taper (a few hundredths of a mm) so both pockets stay concentric.
            cuts.append(
                Cyl(
                    f"channel_{i}",
                    "channel",
                    (*lo_xy, -1e-3),
                    (*hi_xy, t + 1e-3),
                    hole_d(spec, j.channel_diameter_mm),
                )
            )
        elif kind == "root":
            cuts.append(
                Cyl(
                    f"fitting_port_{i}",
                    "port",
                    (*hi_xy, -1e-3),
                    (*hi_xy, t + 1e-3),
                    hole_d(spec, spec.mount.fitting_tap_drill_mm),
                    tapped(spec.mount.fitting_tap_drill_mm),
                )
            )
    return cuts


def _tube_cuts(
    spec: TailSpec, k: int, t: float, r_pitch_lo: float, r_pitch_hi: float
) -> tuple[list[Cyl], list[Cyl]]:
    """The tubes of the distal segments through panel k (segment s >= 2 starts at boundary panel
    p_s, where its tubes end in ports, passages and feed holes): (cuts, passages)."""
    j = spec.joint
    angles = soa_angles_deg()
    cuts: list[Cyl] = []
    passages: list[Cyl] = []
    d_tube = tube_hole_mm(spec)
    rings = {
        2: (spec.tubes.inner_radius_mm, mid_angles_deg()),
        3: (spec.tubes.second_radius_mm, angles),
    }
    for s in range(2, spec.segments + 1):
        p_s = spec.joints_per_segment * (s - 1)
        if s not in rings:
            continue  # reported by validate_layout: no room for a fourth tube ring
        ring_r, ring_a = rings[s]
        # The rings move inwards with the pockets, keeping their webs along the cone.
        ring_r -= j.pitch_diameter_mm / 2 - (r_pitch_lo + r_pitch_hi) / 2
        for i, a in enumerate(ring_a, start=1):
            xy = polar(ring_r, a)
            if k < p_s:
                cuts.append(Cyl(f"tube_s{s}_{i}", "tube", (*xy, -1e-3), (*xy, t + 1e-3), d_tube))
            elif k == p_s:
                # Tube port on the lower face, a passage at mid-thickness to the
                # axis of SOA i, and a feed hole up into its upper pocket.
                zm = t / 2.0
                cuts.append(
                    Cyl(
                        f"tube_port_s{s}_{i}",
                        "tube_port",
                        (*xy, -1e-3),
                        (*xy, spec.tubes.port_depth_mm),
                        hole_d(spec, spec.tubes.outer_diameter_mm),
                    )
                )
                target = polar(r_pitch_hi, angles[i - 1])
                d_pass = hole_d(spec, spec.tubes.passage_diameter_mm)
                passages.append(
                    Cyl(f"passage_s{s}_{i}", "passage", (*xy, zm), (*target, zm), d_pass)
                )
                cuts.append(
                    Cyl(f"feed_s{s}_{i}", "feed", (*target, zm), (*target, t + 1e-3), d_pass)
                )
    return cuts, passages


def _rod_socket(spec: TailSpec, kind: str, t: float) -> tuple[list[Cyl], list[Cyl]]:
    """The vertebra's socket: the rod bore and, for set screws, the collar, its screw and its bore:
    (cuts, bosses)."""
    d_rod = rod_bore_mm(spec)
    cuts = [
        Cyl("rod_bore", "rod", (0.0, 0.0, -1e-3), (0.0, 0.0, t + 1e-3), d_rod, rod_thread(spec))
    ]
    bosses: list[Cyl] = []
    if spec.vertebra.socket == "set_screw":
        boss_d = d_rod + 2 * spec.socket.boss_wall_mm
        h = spec.socket.boss_height_mm
        # Tip panel: the collar goes under the panel (its distal face carries the payload).
        if kind == "tip":
            bosses.append(Cyl("clamp_boss", "boss", (0.0, 0.0, -h), (0.0, 0.0, 1e-3), boss_d))
            zc = -h / 2.0
        else:
            bosses.append(
                Cyl("clamp_boss", "boss", (0.0, 0.0, t - 1e-3), (0.0, 0.0, t + h), boss_d)
            )
            zc = t + h / 2.0
        # Radial set screw along -Y (ventral midline, between SOA 3 and SOA 4).
        cuts.append(
            Cyl(
                "set_screw",
                "setscrew",
                (0.0, 0.0, zc),
                (0.0, -boss_d, zc),
                hole_d(spec, spec.socket.set_screw_tap_drill_mm),
                tapped(spec.socket.set_screw_tap_drill_mm),
            )
        )
        z_lo, z_hi = bosses[-1].z_range
        cuts.append(
            Cyl("rod_bore_boss", "rod", (0.0, 0.0, z_lo - 1e-3), (0.0, 0.0, z_hi + 1e-3), d_rod)
        )
    return cuts, bosses


def _insert_and_lightening_cuts(
    spec: TailSpec, kind: str, t: float, r_pitch_hi: float, r_rim_hi: float, d_pocket: float
) -> list[Cyl]:
    """The root's mount inserts (else the lightening holes between the pockets) and the tip's
    payload inserts."""
    cuts: list[Cyl] = []
    if kind == "root":
        for i, a in enumerate(mid_angles_deg(), start=1):
            xy = polar(spec.mount.bolt_circle_diameter_mm / 2, a)
            cuts.append(
                Cyl(
                    f"mount_insert_{i}",
                    "insert",
                    (*xy, -1e-3),
                    (*xy, spec.mount.insert_depth_mm),
                    hole_d(spec, spec.mount.insert_diameter_mm),
                )
            )
    elif spec.lightening.hole_diameter_mm > 0:
        rho, _ = lightening_radius_mm(r_pitch_hi, r_rim_hi, d_pocket / 2)
        for i, a in enumerate(mid_angles_deg(), start=1):
            xy = polar(rho, a)
            cuts.append(
                Cyl(
                    f"lightening_{i}",
                    "lightening",
                    (*xy, -1e-3),
                    (*xy, t + 1e-3),
                    spec.lightening.hole_diameter_mm,
                )
            )
    if kind == "tip":
        n = spec.payload.insert_count
        for i in range(n):
            xy = polar(spec.payload.insert_circle_diameter_mm / 2, 90.0 + 360.0 * i / n + 180.0 / n)
            cuts.append(
                Cyl(
                    f"payload_insert_{i + 1}",
                    "insert",
                    (*xy, t - spec.payload.insert_depth_mm),
                    (*xy, t + 1e-3),
                    hole_d(spec, spec.payload.insert_diameter_mm),
                )
            )
    return cuts


def soa_frame(
    lower: PanelLayout, upper: PanelLayout, angle_deg: float, rotation_deg: float
) -> np.ndarray:
    """Placement (4 x 4, tail frame) of the SOA at ``angle_deg`` between two neighbouring panels:
    its lower flange face centred on the lower panel's upper pocket floor, its axis to the upper
    panel's lower pocket floor, its square turned by ``rotation_deg`` from the radial line (columns:
    the unit axes, the origin)."""
    b = np.array(
        [
            *polar(lower.pitch_radius_upper_mm, angle_deg),
            lower.z0_mm + lower.thickness_mm - lower.pocket_depth_mm,
        ]
    )
    m = np.array(
        [*polar(upper.pitch_radius_lower_mm, angle_deg), upper.z0_mm + upper.pocket_depth_mm]
    )
    z = m - b
    z /= np.linalg.norm(z)
    x = np.array(
        [
            math.cos(math.radians(angle_deg + rotation_deg)),
            math.sin(math.radians(angle_deg + rotation_deg)),
            0.0,
        ]
    )
    x = x - np.dot(x, z) * z
    x /= np.linalg.norm(x)
    out = np.eye(4)
    out[:3, 0], out[:3, 1], out[:3, 2], out[:3, 3] = x, np.cross(z, x), z, b
    return out


def rounded_square_support(side_mm: float, radius_mm: float, psi: np.ndarray) -> np.ndarray:
    """Support function of a square (corners rounded at R) at angle psi from a side normal."""
    return (side_mm / 2 - radius_mm) * (np.abs(np.cos(psi)) + np.abs(np.sin(psi))) + radius_mm


def soa_neighbour_gap_mm(spec: TailSpec, pitch_r: float) -> float:
    """Smallest gap between the bellows of two neighbouring SOAs (separating axis)."""
    s, rr = spec.soa.long_side_mm, spec.soa.fillet_radius_mm
    a1, a2 = math.radians(90.0), math.radians(162.0)
    c1 = np.array(polar(pitch_r, 90.0))
    c2 = np.array(polar(pitch_r, 162.0))
    u = np.linspace(0, 2 * math.pi, 7200, endpoint=False)
    dirs = np.stack([np.cos(u), np.sin(u)], axis=1)
    rot = math.radians(spec.soa.rotation_deg)
    h1 = rounded_square_support(s, rr, u - (a1 + rot))
    h2 = rounded_square_support(s, rr, u + math.pi - (a2 + rot))
    return float(np.max(dirs @ (c2 - c1) - h1 - h2))


def soa_radial_extent_mm(spec: TailSpec) -> tuple[float, float]:
    """(outward, inward) extent of the bellows from its axis along the radial line."""
    rot = math.radians(spec.soa.rotation_deg)
    h = rounded_square_support(spec.soa.long_side_mm, spec.soa.fillet_radius_mm, np.array([-rot]))
    return float(h[0]), float(h[0])


def replace_taper(spec: TailSpec, half_angle_deg: float | str) -> TailSpec:
    return dataclasses.replace(
        spec, taper=dataclasses.replace(spec.taper, half_angle_deg=half_angle_deg)
    )
