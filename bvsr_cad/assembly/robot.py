"""The robot model between the assembly and the URDF/MJCF writers, in SI.

Links, joints, inertials, visuals, collisions and SOA actuators, as plain
data. Each bending joint ``jk`` is the exact constant-curvature chain

    Rz(phi) Ry(theta/2) Tz(chord) Ry(theta/2) Rz(-phi),  chord = 2 L sin(theta/2) / theta

realised by five joints ``jk_phi``, ``jk_theta_a``, ``jk_chord``,
``jk_theta_b``, ``jk_phi_b`` and four virtual links. The first joint's origin
is the arc's start (the centre of panel k-1's distal face); the last joint's
child is ``panel{k}``, whose frame (its proximal face centre) is the arc's
end. The chord joint carries ``chord - L`` so that every joint is 0 at rest.

Deformable mass (the five SOAs and the rod piece in the gap) follows the
paper's model, a body whose centre of mass is the chord's midpoint: it is
split into two equal halves carried by the links after ``jk_theta_a`` and
after ``jk_chord`` (see :func:`split_deformable`). Their centre of mass is the
chord midpoint at every theta, and at rest the pair reproduces the exact
B-rep inertia of the SOAs and the rod piece.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import build123d as bd
import numpy as np

from .. import units
from ..colors import rgba
from ..models.actuator import SoaForceLaw, soa_force_law
from ..models.dynamics import ramp_pa
from ..models.kinematics import chord_length_mm
from ..models.pneumatics import first_order_time_constant_s
from ..models.rod import rod_section
from ..parameters.layout import N_SOA
from ..parameters.tables import TailSpec
from ..parts.vertebra import rod
from .assemble import Assembly, Instance, rod_span_mm
from .collision import Collision, CylinderFit, panel_collisions
from .inertia import Inertial, compose, from_solid
from .pneumatic_lines import line_supply

VIRTUAL_MASS_KG = 1e-7  # 0.1 mg: valid for every simulator, negligible, and counted in the totals
VIRTUAL_INERTIA_KG_M2 = 1e-12


def chord_m(theta_rad, arc_length_m: float):
    """Chord of an arc of length L (m) bent by theta (models/kinematics, any length unit)."""
    return chord_length_mm(theta_rad, arc_length_m)


def chord_joint_value(theta_rad, arc_length_m: float):
    """Value of the ``jk_chord`` prismatic joint for a bending angle theta: chord - L (0 at
    rest)."""
    return chord_m(theta_rad, arc_length_m) - arc_length_m


def translation_m(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def mm_to_m_transform(T_mm) -> np.ndarray:
    T = np.array(T_mm, float)
    T[:3, 3] = T[:3, 3] / units.MM_PER_M
    return T


@dataclass
class Visual:
    """A mesh already in its link's frame (identity origin); written by the exporters."""

    name: str  # file stem, unique within the robot
    material: str
    density_g_cm3: float
    rgba: tuple[float, float, float, float]
    solid: bd.Shape  # in the link frame, millimetres


@dataclass
class Link:
    name: str
    inertial: Inertial
    visuals: list[Visual] = field(default_factory=list)
    collisions: list[Collision] = field(default_factory=list)
    # rigid (a panel), deformable (half of a joint's SOAs and rod), virtual (massless frame)
    role: str = "rigid"

    @property
    def virtual(self) -> bool:
        return self.role == "virtual"


@dataclass(frozen=True)
class Mimic:
    joint: str
    multiplier: float
    offset: float = 0.0


@dataclass(frozen=True)
class Joint:
    name: str
    type: str  # revolute, continuous, prismatic
    parent: str
    child: str
    T_parent_joint: tuple[tuple[float, ...], ...]  # metres
    axis: tuple[float, float, float]
    lower: float | None = None
    upper: float | None = None
    velocity: float | None = None
    effort: float | None = None
    mimic: Mimic | None = None
    stiffness: float = 0.0  # N m/rad or N/m (MJCF only)
    damping: float = 0.0


@dataclass(frozen=True)
class Site:
    name: str
    link: str
    pos_m: tuple[float, float, float]


@dataclass(frozen=True)
class SoaActuator:
    """One SOA between two sockets: force P A along it, stiffness k = m_a P + n_a."""

    name: str  # jk_soai
    joint: int
    line: str  # s{segment}_line{i}: the actuator name of its line in the per-segment MJCF
    line_index: int  # i = 1..N_SOA: the line of its segment (the SOA's place on the pentagon)
    bottom_site: str
    top_site: str
    rest_length_m: float


@dataclass(frozen=True)
class BendingJoint:
    name: str
    arc_length_m: float
    urdf_joints: tuple[str, str, str, str, str]
    base_link: str
    tip_link: str
    theta_max_rad: float
    segment: int


@dataclass(frozen=True)
class ActuationSI:
    """What drives and holds the chain, in SI: the SOA force law, the pressure range, the rod."""

    law: SoaForceLaw  # per SOA
    pressure_min_pa: float
    pressure_max_pa: float
    rod_bending_stiffness_nm_rad: float  # E I / L of one joint
    rod_axial_stiffness_n_m: float  # E A / L of one joint's rod piece
    timestep_s: float


def actuation_si(spec: TailSpec) -> ActuationSI:
    """The SOA law (models/actuator), the rod (models/rod) and the pressure range of ``spec`` in
    SI."""
    rod = rod_section(spec)
    L_mm = spec.joint.gap_mm
    return ActuationSI(
        law=soa_force_law(spec),
        pressure_min_pa=units.kpa_to_pa(spec.actuation.pressure_min_kpa),
        pressure_max_pa=units.kpa_to_pa(spec.robot.pulse_pressure_max_kpa),
        rod_bending_stiffness_nm_rad=rod.bending_stiffness_nm_per_rad(L_mm),
        rod_axial_stiffness_n_m=rod.axial_stiffness_n_per_m(L_mm),
        timestep_s=spec.robot.timestep_s,
    )


@dataclass
class RobotModel:
    name: str
    links: dict[str, Link]
    joints: list[Joint]
    bending: list[BendingJoint]
    sites: list[Site]
    soas: list[SoaActuator]
    actuation: ActuationSI
    #: Each line's supply lag tau (s) by line name (``s{segment}_line{i}``): the MJCF actuators'
    #: first-order dynamics, fitted to the supply model (:func:`supply_lags_s`).
    supply_lag_s: dict[str, float] = field(default_factory=dict)
    root: str = "panel0"

    @property
    def mass_kg(self) -> float:
        return sum(link.inertial.mass_kg for link in self.links.values())


def _as_tuple(m: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in np.asarray(m))


def _rod_pieces(
    asm: Assembly,
) -> tuple[dict[int, list[tuple[float, float]]], dict[int, list[tuple[float, float]]]]:
    """z ranges (tail frame, mm) of rod inside each panel and inside each gap."""
    spec = asm.spec
    in_panel: dict[int, list[tuple[float, float]]] = {k: [] for k in range(spec.panels)}
    in_gap: dict[int, list[tuple[float, float]]] = {k: [] for k in range(1, spec.panels)}
    t = spec.joint.panel_thickness_mm
    for s in range(1, spec.segments + 1 if spec.vertebra.has_rod else 1):  # "none": no rod
        z0, z1 = rod_span_mm(spec, s)
        for lay in asm.panel_layouts:
            lo, hi = max(z0, lay.z0_mm), min(z1, lay.z0_mm + t)
            if hi - lo > 1e-9:
                in_panel[lay.index].append((lo, hi))
        for k in range(1, spec.panels):
            g0, g1 = asm.panel_layouts[k - 1].z0_mm + t, asm.panel_layouts[k].z0_mm
            lo, hi = max(z0, g0), min(z1, g1)
            if hi - lo > 1e-9:
                in_gap[k].append((lo, hi))
    return in_panel, in_gap


def _rod_solid(
    ranges: list[tuple[float, float]], diameter_mm: float, z_frame_mm: float
) -> bd.Shape | None:
    pieces = [
        rod(diameter_mm, hi - lo).moved(bd.Location((0, 0, lo - z_frame_mm))) for lo, hi in ranges
    ]
    if not pieces:
        return None
    return pieces[0] if len(pieces) == 1 else bd.Compound(pieces)


def collision_shapes(
    asm: Assembly, fits: dict[str, CylinderFit] | None = None
) -> dict[int, list[Collision]]:
    """Per panel index, its link's collision shapes (``robot.collision_geometry``): geometry alone,
    so a build makes them while its analyses (the joints' limits) are still running. ``fits``: as
    in :func:`~bvsr_cad.assembly.collision.panel_collisions`."""
    return panel_collisions(asm, _rod_pieces(asm)[1], asm.spec.robot.collision_geometry, fits)


def robot_model(
    asm: Assembly,
    theta_max_rad: list[float],
    collisions: bool = True,
    shapes: dict[int, list[Collision]] | None = None,
) -> RobotModel:
    """The robot model of the tail at rest, in SI.

    Args:
        asm: the assembly (mm).
        theta_max_rad: collision-free bending limit of each joint (the minimum over phi), e.g.
            :func:`bvsr_cad.analysis.limits.per_joint_rad`.
        collisions: False leaves the links without collision shapes (a simulation of the tail alone,
            which nothing can touch: the shapes' fits are most of the model's making).
        shapes: :func:`collision_shapes` of ``asm`` where the caller made them ahead.

    The velocity limit of a joint is the segment's peak rate shared by its joints
    times a margin (``[robot]``); the effort limits are what all N_SOA SOAs can
    exert at the pulse pressure (a torque on the pitch circle, a force on the chord).
    """
    spec = asm.spec
    if len(theta_max_rad) != spec.joints:
        raise ValueError(f"theta_max_rad: {len(theta_max_rad)} values for {spec.joints} joints")
    actuation = actuation_si(spec)
    push_n = N_SOA * float(actuation.law.force_n(actuation.pressure_max_pa, 0.0))
    effort_limit_nm = push_n * units.mm_to_m(spec.joint.pitch_diameter_mm / 2)
    limits = _JointLimits(
        effort_limit_nm,
        push_n,
        velocity_limit(
            spec.robot.segment_velocity_deg_s, spec.robot.velocity_margin, spec.joints_per_segment
        ),
    )
    in_panel, in_gap = _rod_pieces(asm)
    # Every collision shape rides on a panel (assembly/collision): exact at rest whatever the chain.
    if not collisions:
        shapes = {lay.index: [] for lay in asm.panel_layouts}
    elif shapes is None:
        shapes = panel_collisions(asm, in_gap, spec.robot.collision_geometry)
    links = _panel_links(asm, in_panel, shapes)
    joints: list[Joint] = []
    sites: list[Site] = []
    soas: list[SoaActuator] = []
    bending: list[BendingJoint] = []
    for k in range(1, spec.panels):
        joint_links, joint_chain, bend = _bending_joint(
            asm, k, float(theta_max_rad[k - 1]), limits, in_gap[k]
        )
        links.update(joint_links)
        joints += joint_chain
        bending.append(bend)
        joint_sites, joint_soas = _soa_sockets(asm, k)
        sites += joint_sites
        soas += joint_soas
    return RobotModel(spec.name, links, joints, bending, sites, soas, actuation, supply_lags_s(asm))


@dataclass(frozen=True)
class _JointLimits:
    """What every bending joint can exert and how fast it may move."""

    effort_nm: float  # the SOAs' torque on the pitch circle
    chord_effort_n: float  # their force along the chord
    velocity_rad_s: float


def _panel_links(asm: Assembly, in_panel, shapes: dict[int, list[Collision]]) -> dict[str, Link]:
    """Each panel's link: the panel and the rod's length inside it, with its collision shapes."""
    spec = asm.spec
    rod_mat = spec.materials.get(spec.vertebra.material)  # None: no rod (no rod pieces either)
    panel_mat = spec.material(spec.use.panel)
    links: dict[str, Link] = {}
    for lay in asm.panel_layouts:
        name = f"panel{lay.index}"
        part = asm.part_of(asm.panel(lay.index))
        visuals = [
            Visual(part.name, part.material, panel_mat.density_g_cm3, rgba("panel"), part.solid)
        ]
        inertials = [
            from_solid(part.solid, panel_mat.density_g_cm3, props=asm.solid_properties(part.name))
        ]
        rod_piece = _rod_solid(in_panel[lay.index], spec.vertebra.diameter_mm, lay.z0_mm)
        if rod_piece is not None:
            visuals.append(
                Visual(
                    f"rod_in_{name}",
                    spec.vertebra.material,
                    rod_mat.density_g_cm3,
                    rgba("rod"),
                    rod_piece,
                )
            )
            inertials.append(from_solid(rod_piece, rod_mat.density_g_cm3))
        links[name] = Link(name, compose(inertials), visuals, shapes[lay.index])
    return links


def _bending_joint(
    asm: Assembly, k: int, th: float, limits: _JointLimits, rod_in_gap
) -> tuple[dict[str, Link], list[Joint], BendingJoint]:
    """Joint k between panels k-1 and k: its four links (two virtual, the deformable body's two
    halves), its five joints (phi, theta_a, chord, theta_b, phi_b) and its record."""
    spec = asm.spec
    j = f"j{k}"
    seg = (k - 1) // spec.joints_per_segment + 1
    L = units.mm_to_m(spec.joint.gap_mm)
    body, visuals = _deformable_body(asm, k, rod_in_gap)
    links = _joint_links(j, body, visuals, L)
    joints = _joint_chain(j, k, th, limits, L, spec.joint.panel_thickness_mm)
    bend = BendingJoint(
        j,
        L,
        tuple(f"{j}_{n}" for n in ("phi", "theta_a", "chord", "theta_b", "phi_b")),
        f"panel{k - 1}",
        f"panel{k}",
        th,
        seg,
    )
    return links, joints, bend


def _deformable_body(asm: Assembly, k: int, rod_in_gap) -> tuple[Inertial, list[Visual]]:
    """Joint k's deformable body at rest in its arc-start frame (the centre of panel k-1's distal
    face): the five SOAs and the rod piece in the gap, as one inertial and their visuals."""
    spec = asm.spec
    j = f"j{k}"
    t_mm = spec.joint.panel_thickness_mm
    rod_mat = spec.materials.get(spec.vertebra.material)
    soa_mat = spec.material(spec.use.soa)
    z_start_mm = asm.panel_layouts[k - 1].z0_mm + t_mm
    T_start_inv = np.eye(4)
    T_start_inv[2, 3] = -z_start_mm
    soa_solids = []
    soa_inertials = []
    for inst in asm.soas_of_joint(k):
        T = T_start_inv @ np.asarray(inst.transform)
        soa_solids.append(asm.part_of(inst).solid.moved(_location(T)))
        soa_inertials.append(
            from_solid(
                asm.part_of(inst).solid, soa_mat.density_g_cm3, T, asm.solid_properties(inst.part)
            )
        )
    rod_gap = _rod_solid(rod_in_gap, spec.vertebra.diameter_mm, z_start_mm)
    parts = list(soa_inertials)
    visuals = [
        Visual(
            f"{j}_soas", spec.use.soa, soa_mat.density_g_cm3, rgba("soa"), bd.Compound(soa_solids)
        )
    ]
    if rod_gap is not None:
        parts.append(from_solid(rod_gap, rod_mat.density_g_cm3))
        visuals.append(
            Visual(f"{j}_rod", spec.vertebra.material, rod_mat.density_g_cm3, rgba("rod"), rod_gap)
        )
    return compose(parts), visuals


def _chain_link_names(j: str) -> tuple[str, str, str, str]:
    """Joint j's four links, named by the joint before each along the chain."""
    return (f"{j}_after_phi", f"{j}_after_theta_a", f"{j}_after_chord", f"{j}_after_theta_b")


def _joint_links(j: str, body: Inertial, visuals: list[Visual], L: float) -> dict[str, Link]:
    """Joint j's four links in chain order: a virtual link after phi, the deformable body's two
    halves after theta_a and after the chord (arc length L, m), a virtual link after theta_b."""
    half_a, half_b = split_deformable(body, L)
    names = _chain_link_names(j)
    return {
        names[0]: Link(
            names[0], Inertial.point(VIRTUAL_MASS_KG, VIRTUAL_INERTIA_KG_M2), role="virtual"
        ),
        names[1]: Link(names[1], half_a, visuals, role="deformable"),
        names[2]: Link(names[2], half_b, role="deformable"),
        names[3]: Link(
            names[3], Inertial.point(VIRTUAL_MASS_KG, VIRTUAL_INERTIA_KG_M2), role="virtual"
        ),
    }


def _joint_chain(
    j: str, k: int, th: float, limits: _JointLimits, L: float, t_mm: float
) -> list[Joint]:
    """Joint j's five joints from panel k-1 to panel k, Rz(phi) Ry(theta/2) Tz(chord) Ry(theta/2)
    Rz(-phi), starting on panel k-1's distal face (t_mm above its frame), bending up to th (rad)
    over an arc of length L (m)."""
    names = _chain_link_names(j)
    t = units.mm_to_m(t_mm)
    half_lim = th / 2.0
    velocity_limit_rad_s, effort_limit_nm = limits.velocity_rad_s, limits.effort_nm
    v_half = velocity_limit_rad_s / 2.0
    chord_lo = float(chord_joint_value(th, L))
    return [
        Joint(
            f"{j}_phi",
            "continuous",
            f"panel{k - 1}",
            names[0],
            _as_tuple(translation_m(z=t)),
            (0, 0, 1),
            velocity=velocity_limit_rad_s * 4,
            effort=effort_limit_nm,
        ),
        Joint(
            f"{j}_theta_a",
            "revolute",
            names[0],
            names[1],
            _as_tuple(np.eye(4)),
            (0, 1, 0),
            -half_lim,
            half_lim,
            v_half,
            effort_limit_nm,
        ),
        Joint(
            f"{j}_chord",
            "prismatic",
            names[1],
            names[2],
            _as_tuple(translation_m(z=L)),
            (0, 0, 1),
            chord_lo - 1e-4,
            1e-4,
            velocity_limit_rad_s * L,
            limits.chord_effort_n,
            mimic=Mimic(f"{j}_theta_a", 0.0, 0.0),
        ),
        Joint(
            f"{j}_theta_b",
            "revolute",
            names[2],
            names[3],
            _as_tuple(np.eye(4)),
            (0, 1, 0),
            -half_lim,
            half_lim,
            v_half,
            effort_limit_nm,
            mimic=Mimic(f"{j}_theta_a", 1.0),
        ),
        Joint(
            f"{j}_phi_b",
            "continuous",
            names[3],
            f"panel{k}",
            _as_tuple(np.eye(4)),
            (0, 0, 1),
            velocity=velocity_limit_rad_s * 4,
            effort=effort_limit_nm,
            mimic=Mimic(f"{j}_phi", -1.0),
        ),
    ]


def _soa_sockets(asm: Assembly, k: int) -> tuple[list[Site], list[SoaActuator]]:
    """Joint k's SOA sockets (the centres of the pocket floors the flanges sit on) and its SOAs
    between them."""
    lo, hi = asm.panel_layouts[k - 1], asm.panel_layouts[k]
    sites: list[Site] = []
    soas: list[SoaActuator] = []
    for inst in asm.soas_of_joint(k):
        T = np.asarray(inst.transform)
        bottom_mm = T[:3, 3]
        top_mm = bottom_mm + _top_socket(asm, inst)
        b_site = Site(
            f"{inst.name}_bottom",
            f"panel{k - 1}",
            tuple(units.mm_to_m(v) for v in (bottom_mm - [0, 0, lo.z0_mm])),
        )
        t_site = Site(
            f"{inst.name}_top",
            f"panel{k}",
            tuple(units.mm_to_m(v) for v in (top_mm - [0, 0, hi.z0_mm])),
        )
        sites += [b_site, t_site]
        rest = units.mm_to_m(float(np.linalg.norm(top_mm - bottom_mm)))
        soas.append(
            SoaActuator(
                inst.name, k, inst.line_name, inst.pressure_line, b_site.name, t_site.name, rest
            )
        )
    return sites, soas


def supply_lags_s(asm: Assembly) -> dict[str, float]:
    """tau of p' = (u - p) / tau per line, u the commanded (supply) pressure, fitted to the spec's
    supply model for a pulse at ``robot.pulse_pressure_max_kpa`` filling that line's SOAs
    (``pneumatics.model = "valve"``: ISO 6358 through the line's own tube; ``"ramp"``: Eq 13)."""
    spec = asm.spec
    p0 = units.kpa_to_pa(spec.robot.pulse_pressure_max_kpa)
    if spec.pneumatics.model == "ramp":
        t0 = spec.fitted("ramp_time_s", spec.pneumatics.ramp_time_s)
        t = np.linspace(0.0, t0, 20001)
        tau = float(t[np.argmax(ramp_pa(t, 1.0, t0) >= 1.0 - np.exp(-1.0))])  # its 63 % time
        return {
            f"s{s}_line{i}": tau for s in range(1, spec.segments + 1) for i in range(1, N_SOA + 1)
        }
    return {
        f"s{s}_line{i}": first_order_time_constant_s(line_supply(asm, s, (i,), p0))
        for s in range(1, spec.segments + 1)
        for i in range(1, N_SOA + 1)
    }


def _top_socket(asm: Assembly, inst: Instance) -> np.ndarray:
    """Offset from an SOA's bottom socket to its top socket (tail frame, mm)."""
    T = np.asarray(inst.transform)
    hi = asm.panel_layouts[inst.joint]
    # The top socket is where the SOA axis meets panel k's lower pocket floor.
    z_top = hi.z0_mm + hi.pocket_depth_mm
    s = (z_top - T[2, 3]) / T[2, 2]
    return T[:3, 2] * s


def _location(T_mm: np.ndarray) -> bd.Location:
    from ..parts.kernel import location

    return location(_as_tuple(T_mm))


def split_deformable(soft: Inertial, arc_length_m: float) -> tuple[Inertial, Inertial]:
    """Two equal halves, one carried by each end of the chord, equal to ``soft`` at rest.

    ``soft`` is given in the arc-start frame at rest. The first half hangs from
    the chord's start at the body's CoM (about L/2 along the chord); the second
    hangs from the chord's end at the same point seen from there (L/2 back).
    Both lie on the chord, at distances L/2 and c - L/2 from its start, so
    the pair's centre of mass is the chord midpoint c/2 at every bending angle
    (the paper's d = (L/theta) sin(theta/2)); at rest they coincide and their
    inertias (each half of the exact one) add up to the B-rep inertia. Bent,
    they separate by L - c (under 0.2 mm at the joint limits).
    """
    half_I = soft.inertia / 2.0
    a = Inertial.make(soft.mass_kg / 2, soft.com, half_I)
    b = Inertial.make(soft.mass_kg / 2, soft.com - [0.0, 0.0, arc_length_m], half_I)
    return a, b


def rest_pair(half_a: Inertial, half_b: Inertial, arc_length_m: float) -> Inertial:
    """The two halves composed at rest in the arc-start frame (for checks and tests)."""
    return compose([half_a, half_b.transformed(translation_m(z=arc_length_m))])


def velocity_limit(segment_deg_s: float, margin: float, joints_per_segment: int) -> float:
    """Per bending joint: the segment's peak rate shared by its joints, times a margin."""
    return units.deg_s_to_rad_s(segment_deg_s) / joints_per_segment * margin
