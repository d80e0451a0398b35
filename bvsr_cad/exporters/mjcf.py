"""MJCF writer: the tail for MuJoCo, driven by pressures, plus a scene.

Two chains (``chain`` of :func:`mjcf_tree`). The default files carry the *reduced* chain, a
pseudo-rigid-body model that holds at a legged robot's 2-4 ms step: each bending joint is two
universal joints on the arc's axis at L/6 from its ends (hinges ``jk_ax``, ``jk_ay`` at the first,
``jk_by``, ``jk_bx`` at the second, held equal to the first by equality constraints) joined by a
middle link ``jk_soft`` that carries the joint's whole deformable body (its B-rep inertia at rest);
the chord and phi are consequences (:func:`bvsr_cad.models.kinematics.joint_transform_prb`: the
rotation is Eq 2's exactly, the end point within 3.5e-4 L theta^4). Each hinge carries 2 E I / L
(the two pivots' energies add up to (1/2)(E I / L) theta^2). The pivots turning opposite ways (a
shear the exact chain does not have) are held by the equalities alone, and the SOAs' thrust pushes
them over: stepped at 2 ms with the links' own inertia that mode grows. A fixed tendon per axis,
``jk_shear_x`` = ``jk_ax`` - ``jk_bx`` (zero whenever the equalities hold), resists it with what
resists it in the real joint, the rod's and SOAs' bending as fixed-guided columns
(:func:`shear_stiffness_nm_rad`), so it adds nothing to the constant-curvature motion and holds
with a soft rod or none; the mode is damped by the SOAs' own bending damping c N r^2 / 2. The
per-segment model's series SOA tendons lose the SOAs' resistance to a segment's joints bending
unalike: fixed ``spread`` tendons put it back (:func:`_segment_spread_tendons`). The hinges carry
no limits: each joint's bend limit theta <= theta_max holds in every bending direction through
fixed tendons on the two pivots' summed angles, a polygon circumscribing the exact limit
(:func:`_bend_limit_tendons`). The *exact* chain (``robot/bvsr_exact.xml``) is the URDF's,
stepped at ``robot.timestep_s``.

The default file (reduced chain, one actuator per SOA) is built for batched stepping (MuJoCo Warp,
MJX), where every tendon costs each world a pass of the tendon kernels and a limited one a
constraint row: its dampers and shear springs sit on the pivot hinges (:class:`HingeShare`), with
no damped tendon or actuator and no shear tendon (unless a rod far stiffer than the SOAs leaves
some of its shear spring there). To first order in the joint's motion this is
the same physics: each hinge's damping, twice c times the summed squares of the joint's SOAs'
lever arms (about c N r^2), dissipates what the SOA dampers dissipate in the bend and the shear
tendon's damper in the shear; the shear spring, on the hinges, stiffens the bend as much as the
shear, and the SOAs' springs (their n_a) give that up. With every damper on a joint, MuJoCo's
Euler integrator integrates the damping implicitly, as implicitfast does, without implicitfast's
pass over every tendon and actuator for their velocity derivatives; the step is otherwise the
same (implicitfast, too, leaves the inertial forces' velocity derivatives out). Its bend-limit
polygon has :data:`BEND_LIMIT_DIRECTIONS` directions. The per-segment and exact files keep their
dampers on the tendons and the actuators, integrated by implicitfast.

The exact chain of every bending joint is the URDF's, with equality constraints:
``jk_theta_b`` = ``jk_theta_a``, ``jk_phi_b`` = -``jk_phi``, and ``jk_chord``
following ``jk_theta_a`` through an even quartic fitted to
L (sin(theta_a) / theta_a - 1) (its largest error over the joint range is
returned and recorded). The rod's bending stiffness E I / L sits on the two
half-angle hinges as 2 E I / L each (in series their energies add up to
(1/2)(E I / L) theta^2); the phi hinges carry none.

Each SOA is a spatial tendon between its two sockets, and the pressure drives
it through a general actuator whose control is the gauge pressure in Pa:

    force = (A + m_a l0 - m_a l) P  +  n_a (l0 - l)  -  c dl/dt
          = P A - (m_a P + n_a)(l - l0) - c dl/dt          (Eq 3-4 and the SOA damper)

so the SOA's stiffness and damping live in the actuator alone and are not
counted again on the joints (in the default file the hinges carry the damping and part of the
spring, see above). The pressure P in the chamber is the actuator's
activation, a first-order lag of the commanded (supply) pressure u,
P' = (u - P) / tau (``dyntype="filterexact"``), with each line's tau the
least-squares fit to the supply model's fill curve
(:func:`bvsr_cad.assembly.robot.supply_lags_s`; RMS 7 %, worst 13 % of the supply pressure):
a step in ``ctrl`` is a valve opening. A controller that computes the chamber
pressure itself (``bvsr simulate`` plays the supply model's trace) sets
``dyntype="none"``. In the per-segment model the three joints of a
segment share theta and phi (equality constraints) and one actuator drives
each line's tendon through its three SOAs, whose stiffness and damping are
divided by three (the three SOAs of a line stretch alike, so the series
tendon's energy 1/2 (k/3) (3 dl)^2 equals their sum 3 (1/2) k dl^2).
"""

from __future__ import annotations

import dataclasses
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from ..assembly.collision import Collision
from ..assembly.inertia import compose
from ..assembly.robot import RobotModel, chord_joint_value, rest_pair, translation_m
from ..models import reduced_chain
from ..models.kinematics import (
    MOUNT_PIVOT_FRACTION,
    PRB_PIVOT_FRACTION,
    PrbLimitPolygon,
    mount_order,
)
from ..models.reduced_chain import HingeShare, MountJoint
from .xml import num as _f
from .xml import quat_wxyz as _quat
from .xml import vec as _vec
from .xml import write_tree

#: Tail frame (Z along the tail, Y dorsal) mounted horizontally in MuJoCo's
#: world (gravity -Z): tail Z -> world +X, tail Y -> world +Z, tail X -> world +Y.
R_WORLD_TAIL = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
MOUNT_HEIGHT_M = 0.45
#: The chord moves less than half a millimetre over the joint range, so a rotor-like
#: armature along it adds no measurable energy; it keeps the rod's axial spring
#: (E A / L, about 2e6 N/m) stable at the step and the chord equality stiff.
CHORD_ARMATURE_KG = 0.1
#: At theta = 0 the bending-plane angle is undefined (the chain's one singularity);
#: this small damping on phi stops numerical noise spinning it. It is 1e-3 of the
#: SOA dampers' bending damping c 5 r^2 / 2 and is the only damping on the joints.
PHI_DAMPING_NMS = 1e-4
#: The chain's rest pose puts every bending plane in the sagittal plane (phi =
#: 90 deg, the same straight tail): extension and flexion, the tail's main
#: motions, start without passing the singularity.
PHI_REST_RAD = 1.5707963267948966
#: The reduced chain's step: the largest of a legged robot's steps (1, 2, 3, 4 ms) at which, after
#: 0.3 s of a held pressure pattern from rest, its tip stays within 2 mm of the same model stepped
#: at 0.05 ms (tests/test_robot.py measures it; at 4 ms it stays within 5 mm). The exact chain keeps
#: ``robot.timestep_s``: its chord slide and 0.1 mg virtual links need 0.2 ms (at 1 ms its tip ends
#: 41 mm off, at 2 ms it explodes). The per-segment model's couplings between the joints of a
#: segment are soft too: it meets the 2 mm at 1 ms (1.5 mm; 3.3 mm at 2 ms).
REDUCED_CHAIN_TIMESTEP_S = 2e-3
REDUCED_PER_SEGMENT_TIMESTEP_S = 1e-3
#: The equalities' impedance (MuJoCo's solimp): its dmax 0.96 is the share of the coupling force the
#: two-step time constant (the least MuJoCo allows) leaves unregularised. 0.97 moves the 4 ms tip
#: 5.4 mm off the 0.05 ms one (over 5 mm; 0.99: 2.8 mm at 2 ms). With the shear and spread tendons
#: it holds a tail with a soft rod or none (largest residual under gravity, no rod: 7.1 mrad per
#: joint against 10.3 at dmax 0.95, 5.7 per segment against 11.9; checks/robot.py's limit is 10).
EQUALITY_SOLIMP = (0.9, 0.96, 0.001, 0.5, 2.0)
#: The default file's bend limit: fixed tendons along this many directions per joint (twice as many
#: faces), a polygon circumscribing the exact limit theta <= theta_max
#: (:func:`_bend_limit_tendons`). 7 (14 faces) is the fewest that keeps a bend between faces
#: within 3 % past theta_max (2.8 % at the default tail's limits; 6 directions: 3.6 %, 8: 2.1 %,
#: 4: 8.1 %; the hinges' own limits: 39 %): every direction is a limited tendon in every world of
#: a batch (a pass of the tendon kernels and a reserved constraint row), and under a large moment
#: the soft limits themselves give more than the polygon (:data:`LIMIT_SOLIMP`).
BEND_LIMIT_DIRECTIONS = 7
#: The per-segment file's: 8 (16 faces, 2.1 %). The measurement table's pulse rows (``bvsr
#: simulate``) step that model, so it stays as they were validated with.
BEND_LIMIT_DIRECTIONS_PER_SEGMENT = 8
#: The bend limits' impedance (solimplimit; their solreflimit is the equalities', two steps). With
#: MuJoCo's defaults (0.9, 0.95, 0.001, 0.5, 2; 0.02 s) a tip moment 1.5 times the rod's own at
#: theta_max (the SOAs' stiffness off) pushed the default tail's joints 38-49 % past their limits
#: (the exact chain's: 32-47 %); with these, 1.1-3.2 % at the exported 2 ms (3.8-9.2 % at 4 ms).
#: With the SOAs, a tip moment 1.2 times the one that bends the tail to its limits (5.4 Nm) stops
#: every joint 2.6-6.9 % past theta_max in any direction, where the hinges' limits folded the tail
#: (123 % past) or went unstable. (0.99, 0.999) is no tighter under larger moments (14 %) and
#: rattles (joint speeds of 1-6 rad/s against the limit).
LIMIT_SOLIMP = (0.95, 0.99, 0.001, 0.5, 2.0)
#: The chains an MJCF file can carry (``chain`` of :func:`mjcf_tree`).
CHAINS = ("reduced", "exact", "mount")
#: The mount variant's collision shapes: the panels alone. A ball, a floor or a host's leg meets a
#: straight tail on its panels' rims (they stand out of the SOA and rod halves); bent, the halves
#: stand out only on the convex side, away from whatever pushed the tail over. Each shape dropped is
#: a geom fewer to place and bound in every step of the host's scene.
MOUNT_COLLISION_COVERS = ("panel",)
#: Per-segment model: the joints of a segment follow its first joint's (joint suffix, equality tag).
SEGMENT_COUPLED = {
    "reduced": (("ax", "ay"), ("x", "y")),
    "exact": (("theta_a", "phi"), ("theta", "phi")),
}
_AXES = {"x": "1 0 0", "y": "0 1 0"}
#: Contact bits of the tail's collision shapes (their ``contype``; their ``conaffinity`` is 0, see
#: :func:`collision_geom`). A geom with MuJoCo's default conaffinity 1 (a floor, a wall, a robot's
#: legs) meets the panels only. Straight, the panels' rims stand out beyond the SOA and rod halves
#: (a plane on two rims clears them by 0.08 mm); bent, the halves on the convex side pass a plane
#: resting on the rims (measured on the default tail: 1.9 mm at a quarter of the joint limits, 8 mm
#: at the limits), so a floor pressed by a bent tail sinks into its SOAs by that much. A geom that
#: must reach between the panels (the impact scene's ball) adds :data:`COLUMN_CONTACT_BIT` to its
#: conaffinity. It keeps the default scene's contact set to the seven panels against the floor:
#: every shape that may touch the floor is a contact MJX compiles into the step, several times the
#: compile time with all 79 shapes than with the panels alone (benchmarks/RESULTS.md).
COLUMN_CONTACT_BIT = 2
CONTACT_TYPE = {
    "panel": 1 | COLUMN_CONTACT_BIT,
    "soa": COLUMN_CONTACT_BIT,
    "rod": COLUMN_CONTACT_BIT,
}


def chord_polynomial(arc_length_m: float, theta_a_max_rad: float) -> tuple[np.ndarray, float]:
    """Even quartic in theta_a fitted to the chord joint value; (polycoef[5], max |error| m)."""
    x = np.linspace(-theta_a_max_rad, theta_a_max_rad, 2001)
    y = chord_joint_value(2.0 * x, arc_length_m)
    A = np.stack([x**2, x**4], axis=1)
    (a2, a4), *_ = np.linalg.lstsq(A, y, rcond=None)
    coef = np.array([0.0, 0.0, a2, 0.0, a4])
    err = float(np.max(np.abs(A @ np.array([a2, a4]) - y)))
    return coef, err


def mjcf_tree(
    robot: RobotModel,
    mesh_files: dict[str, str],
    per_segment: bool,
    mesh_dir: str = "meshes",
    chain: str = "reduced",
) -> tuple[ET.ElementTree, dict]:
    """The model as an element tree, and facts to record (chord error, counts).

    ``chain``: ``reduced``, the pseudo-rigid-body chain of the default files (see
    module docstring), stepped at :data:`REDUCED_CHAIN_TIMESTEP_S` (per segment
    :data:`REDUCED_PER_SEGMENT_TIMESTEP_S`); ``exact``, the URDF's chain with
    its chord slide and couplings, stepped at ``robot.timestep_s``; ``mount``, the variant a host
    carries (:func:`_mount_bodies`), stepped at :data:`REDUCED_CHAIN_TIMESTEP_S`."""
    if chain not in CHAINS:
        raise ValueError(f"chain {chain!r}: allowed {', '.join(CHAINS)}")
    if chain == "mount" and per_segment:
        raise ValueError("chain 'mount': one actuator per SOA only (per_segment=False)")
    act = robot.actuation
    model = f"{robot.name}_segments" if per_segment else robot.name
    root = ET.Element(
        "mujoco",
        model=f"{robot.name}{'_per_segment' if per_segment else ''}"
        f"{'_exact' if chain == 'exact' else ''}{'_mount' if chain == 'mount' else ''}",
    )
    ET.SubElement(root, "compiler", angle="radian", meshdir=mesh_dir, autolimits="true")
    timestep_s = (
        act.timestep_s
        if chain == "exact"
        else (REDUCED_PER_SEGMENT_TIMESTEP_S if per_segment else REDUCED_CHAIN_TIMESTEP_S)
    )
    # The default file: every damper and the shear springs on the hinges (module docstring); Euler
    # integrates joint damping implicitly.
    shares = None
    if chain == "reduced" and not per_segment:
        shares = {b.name: hinge_share(robot, k) for k, b in enumerate(robot.bending, 1)}
    if chain == "mount":
        shares = {b.name: mount_joint(robot, k) for k, b in enumerate(robot.bending, 1)}
    integrator = "Euler" if shares else "implicitfast"
    ET.SubElement(root, "option", timestep=_f(timestep_s), integrator=integrator)
    _mjcf_defaults(root, model)
    _mjcf_assets(root, robot, mesh_files)
    _mjcf_worldbody(root, robot, model, chain, shares)
    # As stiff as the step allows (MuJoCo needs a time constant of at least two steps).
    solref = _vec((2.0 * timestep_s, 1.0))
    chord_err = _mjcf_equalities(root, robot, chain, per_segment, solref)
    directions = BEND_LIMIT_DIRECTIONS_PER_SEGMENT if per_segment else BEND_LIMIT_DIRECTIONS
    bend_overshoot, actuators = _tendons_and_actuators(
        root, robot, chain, per_segment, solref, directions, shares
    )
    ET.indent(root)
    lags = sorted(set(robot.supply_lag_s.values()))
    facts = {
        "chord_polynomial_max_error_m": chord_err,
        "actuators": actuators,
        "actuator_control": "commanded (supply) gauge pressure, Pa; the chamber pressure is the "
        "actuator's activation, a first-order lag of it"
        if lags
        else "gauge pressure, Pa",
        "supply_lag_s": [lags[0], lags[-1]] if lags else None,
        "per_segment": per_segment,
        "chain": chain,
        "timestep_s": timestep_s,
        "integrator": integrator,
        "bend_limit": None
        if bend_overshoot is None
        else {
            "faces": 2 * directions,
            "max_overshoot": bend_overshoot,
            "tendons": (
                "jk_bend_limit_<i>: cos(phi_i) jk_x + sin(phi_i) jk_y"
                if chain == "mount"
                else "jk_bend_limit_<i>: cos(phi_i) (jk_ax + jk_bx) + sin(phi_i) (jk_ay + jk_by)"
            )
            + f", phi_i = 180 i / {directions} deg",
        },
    }
    return ET.ElementTree(root), facts


def _tendons_and_actuators(
    root: ET.Element,
    robot: RobotModel,
    chain: str,
    per_segment: bool,
    solref: str,
    directions: int,
    shares: dict | None,
) -> tuple[float | None, int]:
    """The ``tendon`` and ``actuator`` sections of ``chain``: the reduced chain's joint tendons
    (bend limits of ``directions`` directions, shear, spread), the mount variant's bend limits, none
    on the exact chain; each SOA's actuator. Returns the bend limit's largest overshoot (None
    without one) and the number of actuators."""
    tendon = ET.SubElement(root, "tendon")
    if chain == "mount":
        overshoot = _bend_limit_tendons(tendon, robot, solref, directions, mount=True)
        return overshoot, _mount_actuators(root, tendon, robot, shares)
    overshoot = None
    if chain == "reduced":
        overshoot = _mjcf_joint_tendons(tendon, robot, per_segment, solref, directions, shares)
    return overshoot, _mjcf_actuators(root, tendon, robot, per_segment, shares)


def _mjcf_defaults(root: ET.Element, model: str) -> None:
    """The ``default`` section: the model's class with its visual and collision classes."""
    default = ET.SubElement(root, "default")
    top = ET.SubElement(default, "default", {"class": model})
    ET.SubElement(top, "joint", armature="1e-7")
    vis = ET.SubElement(top, "default", {"class": "visual"})
    ET.SubElement(vis, "geom", type="mesh", contype="0", conaffinity="0", group="2", density="0")
    col = ET.SubElement(top, "default", {"class": "collision"})
    # Self-contacts off (conaffinity 0), each shape's contype from CONTACT_TYPE: see collision_geom.
    ET.SubElement(col, "geom", group="3", density="0", rgba="0.5 0.5 0.5 0.3", conaffinity="0")
    ET.SubElement(top, "site", size="0.001", rgba="1 0 0 1", group="4")


def _mjcf_assets(root: ET.Element, robot: RobotModel, mesh_files: dict[str, str]) -> None:
    """The ``asset`` section: each visual and collision mesh once, then one material per colour
    name."""
    asset = ET.SubElement(root, "asset")
    mats = {}
    for link in robot.links.values():
        for v in link.visuals:
            mats.setdefault(v.material, v.rgba)
            if not any(m.get("name") == v.name for m in asset.findall("mesh")):
                ET.SubElement(asset, "mesh", name=v.name, file=mesh_files[v.name])
        for c in link.collisions:
            if c.kind == "mesh":
                ET.SubElement(
                    asset,
                    "mesh",
                    name=collision_mesh_name(c),
                    file=mesh_files[collision_mesh_name(c)],
                )
    for name, rgba in mats.items():
        ET.SubElement(asset, "material", name=name, rgba=_vec(rgba))


def _mjcf_worldbody(
    root: ET.Element,
    robot: RobotModel,
    model: str,
    chain: str,
    shares: dict[str, HingeShare] | None = None,
) -> None:
    """The ``worldbody`` section: the mount, then the tail's bodies as the chain nests them
    (``shares``: what the reduced chain's pivot hinges carry in the default file)."""
    world = ET.SubElement(root, "worldbody")
    mount = ET.SubElement(
        world,
        "body",
        name="bvsr_mount",
        pos=_vec((0, 0, MOUNT_HEIGHT_M)),
        quat=_quat(R_WORLD_TAIL),
        childclass=model,
    )
    sites_by_link: dict[str, list] = {}
    for s in robot.sites:
        sites_by_link.setdefault(s.link, []).append(s)
    if chain == "exact":
        children: dict[str, list] = {}
        for j in robot.joints:
            children.setdefault(j.parent, []).append(j)
        _exact_body(mount, robot, robot.root, None, children, sites_by_link)
    elif chain == "mount":
        _mount_bodies(mount, robot, sites_by_link, shares)
    else:
        root_body = ET.SubElement(mount, "body", name=robot.root)
        _link_contents(root_body, robot.links[robot.root], sites_by_link)
        _reduced_bodies(root_body, robot, 1, sites_by_link, shares)


def _link_contents(
    body: ET.Element, link, sites_by_link: dict[str, list], offset_m: float = 0.0
) -> None:
    """A link's inertial, visuals, collisions and sites, ``offset_m`` along the body's Z."""
    shift = np.array([0.0, 0.0, offset_m])
    I = link.inertial.inertia
    ET.SubElement(
        body,
        "inertial",
        pos=_vec(link.inertial.com + shift),
        mass=_f(link.inertial.mass_kg),
        fullinertia=_vec((I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])),
    )
    for v in link.visuals:
        ET.SubElement(
            body,
            "geom",
            {
                "class": "visual",
                "mesh": v.name,
                "material": v.material,
                "name": f"{link.name}_{v.name}_visual",
            },
        )
    for c in link.collisions:
        collision_geom(body, c, shift)
    for s in sites_by_link.get(link.name, []):
        ET.SubElement(body, "site", name=s.name, pos=_vec(s.pos_m))


def _exact_body(
    parent_el: ET.Element,
    robot: RobotModel,
    link_name: str,
    joint,
    children: dict[str, list],
    sites_by_link: dict[str, list],
) -> None:
    """The exact chain: ``link_name``'s body with the joint that moves it, then its children's."""
    act = robot.actuation
    link = robot.links[link_name]
    attrs = {"name": link_name}
    if joint is not None:
        T = np.asarray(joint.T_parent_joint)
        if np.linalg.norm(T[:3, 3]) > 0:
            attrs["pos"] = _vec(T[:3, 3])
        # The rest pose is written at phi = PHI_REST_RAD (see there); `ref` keeps qpos = phi.
        rest = {"phi": PHI_REST_RAD, "phi_b": -PHI_REST_RAD}.get(joint.name.split("_", 1)[1])
        if rest is not None:
            attrs["quat"] = _quat(Rotation.from_euler("z", rest).as_matrix())
    body = ET.SubElement(parent_el, "body", attrs)
    if joint is not None:
        jattrs = {"name": joint.name, "axis": _vec(joint.axis)}
        bj = joint.name.split("_", 1)
        kind = bj[1]
        if joint.type == "prismatic":
            # The rod's axial stiffness carries the SOAs' thrust; the equality only bends it to the
            # arc.
            jattrs.update(
                type="slide",
                range=_vec((joint.lower, joint.upper)),
                stiffness=_f(act.rod_axial_stiffness_n_m),
                armature=_f(CHORD_ARMATURE_KG),
            )
        else:
            jattrs["type"] = "hinge"
            if kind == "phi":
                jattrs.update(ref=_f(PHI_REST_RAD), damping=_f(PHI_DAMPING_NMS))
            elif kind == "phi_b":
                jattrs.update(ref=_f(-PHI_REST_RAD))
            if kind in ("theta_a", "theta_b"):
                lim = next(b.theta_max_rad / 2 for b in robot.bending if b.name == bj[0])
                jattrs.update(
                    range=_vec((-lim, lim)), stiffness=_f(2.0 * act.rod_bending_stiffness_nm_rad)
                )
        ET.SubElement(body, "joint", jattrs)
    _link_contents(body, link, sites_by_link)
    for j in children.get(link_name, []):
        _exact_body(body, robot, j.child, j, children, sites_by_link)


def _reduced_bodies(
    parent_el: ET.Element,
    robot: RobotModel,
    k: int,
    sites_by_link: dict[str, list],
    shares: dict[str, HingeShare] | None = None,
) -> None:
    """The reduced chain from joint k on: its middle link (the whole deformable body) and panel k on
    it, then the rest; with ``shares`` (the default file) the pivot hinges carry them."""
    b = robot.bending[k - 1]
    share = shares[b.name] if shares else None
    stiff_half = 2.0 * robot.actuation.rod_bending_stiffness_nm_rad
    stiff_half += share.stiffness_nm_rad if share else 0.0
    damped = {axis: {"damping": _f(share.damping_nms[axis])} if share else {} for axis in "xy"}
    d = PRB_PIVOT_FRACTION * b.arc_length_m
    t_m = _arc_start_m(robot, b)
    half_a, half_b = robot.links[f"{b.name}_after_theta_a"], robot.links[f"{b.name}_after_chord"]
    soft = dataclasses.replace(
        half_a,
        name=f"{b.name}_soft",
        inertial=rest_pair(half_a.inertial, half_b.inertial, b.arc_length_m),
    )
    body = ET.SubElement(parent_el, "body", name=soft.name, pos=_vec((0, 0, t_m)))
    # No range: the joint's bend limit is the fixed tendons of _bend_limit_tendons.
    for axis in "xy":
        _hinge(body, f"{b.name}_a{axis}", axis, d, stiff_half, damped[axis])
    _link_contents(body, soft, sites_by_link)
    panel = ET.SubElement(body, "body", name=b.tip_link, pos=_vec((0, 0, b.arc_length_m)))
    for axis in "yx":
        _hinge(panel, f"{b.name}_b{axis}", axis, -d, stiff_half, damped[axis])
    _link_contents(panel, robot.links[b.tip_link], sites_by_link)
    if k < len(robot.bending):
        _reduced_bodies(panel, robot, k + 1, sites_by_link, shares)


def _hinge(
    body: ET.Element, name: str, axis: str, z_m: float, stiffness_nm_rad: float, damping: dict
) -> None:
    """A bending hinge of ``body`` about its ``axis`` ("x" or "y") at height ``z_m`` on the body's
    Z, with its spring and (``damping``: the attribute, or none) its damper."""
    ET.SubElement(
        body,
        "joint",
        name=name,
        type="hinge",
        axis=_AXES[axis],
        pos=_vec((0, 0, z_m)),
        stiffness=_f(stiffness_nm_rad),
        **damping,
    )


def _mount_bodies(
    mount_el: ET.Element,
    robot: RobotModel,
    sites_by_link: dict[str, list],
    joints: dict[str, MountJoint],
) -> None:
    """The mount variant's bodies: the panels alone, panel k turning on one universal joint at
    mid-arc (:data:`~bvsr_cad.models.kinematics.MOUNT_PIVOT_FRACTION`; hinges ``jk_x`` and ``jk_y``
    in :func:`~bvsr_cad.models.kinematics.mount_order`) with :class:`MountJoint`'s stiffness and
    damping. Joint k's deformable body is split as the exact chain splits it: the half at the arc's
    start rides on panel k-1, the half at its end on panel k, composed into each panel's one
    inertial at rest (the mass and its centre at rest are the other files'). Its visual rides on
    panel k-1; of the collision shapes, those of :data:`MOUNT_COLLISION_COVERS`."""
    body = mount_el
    for k in range(len(robot.bending) + 1):
        panel = robot.links[robot.root if k == 0 else robot.bending[k - 1].tip_link]
        parts = [panel.inertial]
        visuals = [(v, 0.0) for v in panel.visuals]
        if k == 0:
            body = ET.SubElement(body, "body", name=robot.root)
        else:
            b = robot.bending[k - 1]
            parts.append(robot.links[f"{b.name}_after_chord"].inertial)
            body = ET.SubElement(
                body,
                "body",
                name=b.tip_link,
                pos=_vec((0, 0, _arc_start_m(robot, b) + b.arc_length_m)),
            )
            joint = joints[b.name]
            for axis in mount_order(k):
                _hinge(
                    body,
                    f"{b.name}_{axis}",
                    axis,
                    -(1.0 - MOUNT_PIVOT_FRACTION) * b.arc_length_m,
                    joint.stiffness_nm_rad,
                    {"damping": _f(joint.damping_nms[axis])},
                )
        if k < len(robot.bending):
            b = robot.bending[k]
            t_m = _arc_start_m(robot, b)
            half_a = robot.links[f"{b.name}_after_theta_a"]
            parts.append(half_a.inertial.transformed(translation_m(z=t_m)))
            visuals += [(v, t_m) for v in half_a.visuals]
        inertial = compose(parts)
        I = inertial.inertia
        ET.SubElement(
            body,
            "inertial",
            pos=_vec(inertial.com),
            mass=_f(inertial.mass_kg),
            fullinertia=_vec((I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])),
        )
        for v, z in visuals:
            attrs = {"class": "visual", "mesh": v.name, "material": v.material}
            if z:
                attrs["pos"] = _vec((0, 0, z))
            ET.SubElement(body, "geom", {**attrs, "name": f"{panel.name}_{v.name}_visual"})
        for c in panel.collisions:
            if c.covers in MOUNT_COLLISION_COVERS:
                collision_geom(body, c)
        for site in sites_by_link.get(panel.name, []):
            ET.SubElement(body, "site", name=site.name, pos=_vec(site.pos_m))


def _mount_actuators(
    root: ET.Element, tendon: ET.Element, robot: RobotModel, joints: dict[str, MountJoint]
) -> int:
    """The mount variant's ``actuator`` section: one pressure actuator per SOA, named and
    controlled as the default file's, on a fixed tendon ``<soa>_tendon`` = arm_x ``jk_x`` + arm_y
    ``jk_y`` (the SOA's stretch l - l0 through its rest lever arms, :class:`MountJoint`): force =
    P A - (m_a P + n_a)(l - l0), its damper on the hinges. Returns the number of actuators."""
    law = robot.actuation.law
    actuator = ET.SubElement(root, "actuator")
    for k, b in enumerate(robot.bending, 1):
        joint = joints[b.name]
        for i, s in enumerate(s for s in robot.soas if s.joint == k):
            fixed = ET.SubElement(tendon, "fixed", name=f"{s.name}_tendon")
            for axis in "xy":
                ET.SubElement(
                    fixed, "joint", joint=f"{b.name}_{axis}", coef=_f(joint.arms_m[axis][i])
                )
            # The fixed tendon is l - l0 itself (0 at rest); the damper is on the hinges.
            _pressure_actuator(
                actuator,
                robot,
                s.name,
                s.line,
                0.0,
                law.stiffness_slope_n_per_m_per_pa,
                law.stiffness_offset_n_per_m,
                0.0,
            )
    return len(robot.soas)


def _mjcf_equalities(
    root: ET.Element, robot: RobotModel, chain: str, per_segment: bool, solref: str
) -> float:
    """The ``equality`` section: each joint's couplings (the reduced chain's two halves; the exact
    chain's theta_b, phi_b and chord), then a segment's joints to its first. Returns the chord
    polynomial's largest error, m (0 for the reduced chain)."""
    if chain == "mount":  # one pivot a joint: nothing to couple
        return 0.0
    eq = ET.SubElement(root, "equality")
    solimp = _vec(EQUALITY_SOLIMP)
    chord_err = 0.0
    for b in robot.bending:
        if chain == "reduced":
            for axis in "xy":
                ET.SubElement(
                    eq,
                    "joint",
                    name=f"{b.name}_b{axis}_eq",
                    joint1=f"{b.name}_b{axis}",
                    joint2=f"{b.name}_a{axis}",
                    polycoef="0 1 0 0 0",
                    solref=solref,
                    solimp=solimp,
                )
            continue
        phi, tha, chord, thb, phib = b.urdf_joints
        coef, err = chord_polynomial(b.arc_length_m, b.theta_max_rad / 2)
        chord_err = max(chord_err, err)
        ET.SubElement(
            eq,
            "joint",
            name=f"{b.name}_theta_b_eq",
            joint1=thb,
            joint2=tha,
            polycoef="0 1 0 0 0",
            solref=solref,
        )
        ET.SubElement(
            eq,
            "joint",
            name=f"{b.name}_phi_b_eq",
            joint1=phib,
            joint2=phi,
            polycoef="0 -1 0 0 0",
            solref=solref,
        )
        ET.SubElement(
            eq,
            "joint",
            name=f"{b.name}_chord_eq",
            joint1=chord,
            joint2=tha,
            polycoef=_vec(coef),
            solref=solref,
        )
    if per_segment:
        first: dict[int, str] = {}
        for b in robot.bending:
            if b.segment not in first:
                first[b.segment] = b.name
                continue
            lead = first[b.segment]
            for kind, tag in zip(*(SEGMENT_COUPLED[chain])):
                ET.SubElement(
                    eq,
                    "joint",
                    name=f"{b.name}_{tag}_seg",
                    joint1=f"{b.name}_{kind}",
                    joint2=f"{lead}_{kind}",
                    polycoef="0 1 0 0 0",
                    solref=solref,
                    solimp=solimp,
                )
    return chord_err


def _mjcf_joint_tendons(
    tendon: ET.Element,
    robot: RobotModel,
    per_segment: bool,
    solref: str,
    directions: int,
    shares: dict[str, HingeShare] | None = None,
) -> float:
    """The reduced chain's fixed tendons: each joint's shear between its halves (with ``shares``,
    only what the hinges do not carry, if any), a segment's spread and the bend limits along
    ``directions``. Returns the bend limit polygon's largest overshoot
    (:func:`_bend_limit_tendons`)."""
    for b in robot.bending:
        if shares is None:
            shear = {
                "damping": _f(_soa_bending_damping(robot)),
                "stiffness": _f(shear_stiffness_nm_rad(robot)),
            }
        else:
            left = shares[b.name].shear_tendon_nm_rad
            shear = {"stiffness": _f(left)} if left > 0.0 else None
        for axis in "xy" if shear else "":
            fixed = ET.SubElement(tendon, "fixed", name=f"{b.name}_shear_{axis}", **shear)
            ET.SubElement(fixed, "joint", joint=f"{b.name}_a{axis}", coef="1")
            ET.SubElement(fixed, "joint", joint=f"{b.name}_b{axis}", coef="-1")
    if per_segment:
        _segment_spread_tendons(tendon, robot)
    return _bend_limit_tendons(tendon, robot, solref, directions)


def _mjcf_actuators(
    root: ET.Element,
    tendon: ET.Element,
    robot: RobotModel,
    per_segment: bool,
    shares: dict[str, HingeShare] | None = None,
) -> int:
    """The ``actuator`` section: one pressure actuator per SOA (per line with ``per_segment``) on a
    spatial tendon through its SOAs' sockets; with ``shares`` (the default file) without the SOA's
    damper and with the part of its spring its joint's hinges do not carry. Returns the number of
    actuators."""
    act = robot.actuation
    actuator = ET.SubElement(root, "actuator")
    groups: dict[str, list] = {}
    for s in robot.soas:
        groups.setdefault(s.line if per_segment else s.name, []).append(s)
    for name, soas in groups.items():
        sp = ET.SubElement(tendon, "spatial", name=f"{name}_tendon", width="0.0005")
        # Sockets in chain order: between two SOAs the path crosses a rigid panel (constant length).
        for s in soas:
            ET.SubElement(sp, "site", site=s.bottom_site)
            ET.SubElement(sp, "site", site=s.top_site)
        n = len(soas)
        l0 = sum(s.rest_length_m for s in soas) + _panel_spans(robot, soas)
        k_share = 1.0 / n  # series tendon of n SOAs that stretch alike
        law = act.law
        m_a = law.stiffness_slope_n_per_m_per_pa * k_share
        n_a = law.stiffness_offset_n_per_m * k_share
        c = law.damping_n_s_per_m * k_share
        if shares:
            n_a, c = shares[robot.bending[soas[0].joint - 1].name].soa_stiffness_offset_n_per_m, 0.0
        _pressure_actuator(actuator, robot, name, soas[0].line, l0, m_a, n_a, c)
    return len(groups)


def _pressure_actuator(
    actuator: ET.Element,
    robot: RobotModel,
    name: str,
    line: str,
    l0_m: float,
    m_a: float,
    n_a: float,
    c: float,
) -> None:
    """One pressure actuator ``name`` on the tendon ``<name>_tendon`` of rest length ``l0_m``:
    force = (A + m_a l0 - m_a l) P + n_a (l0 - l) - c dl/dt (Eq 3-4 and the damper), its control
    the commanded gauge pressure of ``line`` (Pa, the chamber pressure its lagged activation)."""
    act = robot.actuation
    lag = robot.supply_lag_s.get(line)
    dyn = {"dyntype": "filterexact", "dynprm": _vec((lag,))} if lag else {}
    ET.SubElement(
        actuator,
        "general",
        name=name,
        tendon=f"{name}_tendon",
        ctrllimited="true",
        ctrlrange=_vec((act.pressure_min_pa, act.pressure_max_pa)),
        **dyn,
        gaintype="affine",
        gainprm=_vec((act.law.area_m2 + m_a * l0_m, -m_a, 0.0)),
        biastype="affine",
        biasprm=_vec((n_a * l0_m, -n_a, -c)),
    )


def collision_mesh_name(c: Collision) -> str:
    """A mesh collision's asset (and file stem): the convex hull of its piece."""
    return f"{c.name}_collision"


def collision_geom(body: ET.Element, c: Collision, shift=(0.0, 0.0, 0.0), **attrs) -> ET.Element:
    """One collision shape of :mod:`bvsr_cad.assembly.collision` as a geom of class ``collision``.

    The tail's shapes never collide with one another: those of neighbouring panels meet in every
    pose (the two halves of each SOA and rod column, at mid-gap), and the clearance analysis's joint
    limits keep all others apart; so the tail's contacts are with the world only, which also keeps
    the scene's contact set (and MJX's compile) small. Which of the world's geoms reach which
    shapes: :data:`CONTACT_TYPE`.
    """
    T = np.asarray(c.T_link_geom)
    geom = {
        "class": "collision",
        "name": f"{c.name}_collision",
        "pos": _vec(T[:3, 3] + np.asarray(shift)),
        "contype": str(CONTACT_TYPE[c.covers]),
    }
    if c.kind == "mesh":
        geom.update(type="mesh", mesh=collision_mesh_name(c))
    else:
        geom.update(type="cylinder", size=_vec((c.radius_m, c.length_m / 2)), quat=_quat(T[:3, :3]))
    geom.update(attrs)
    return ET.SubElement(body, "geom", geom)


def shear_stiffness_nm_rad(robot: RobotModel) -> float:
    """The shear tendon's stiffness of ``robot``'s reduced joints, N m/rad
    (:func:`bvsr_cad.models.reduced_chain.shear_stiffness_nm_rad`)."""
    law = robot.actuation.law
    return reduced_chain.shear_stiffness_nm_rad(
        n_soas=sum(1 for s in robot.soas if s.joint == 1),
        stiffness_offset_n_per_m=law.stiffness_offset_n_per_m,
        area_m2=law.area_m2,
        rod_bending_stiffness_nm_rad=robot.actuation.rod_bending_stiffness_nm_rad,
    )


def _bend_limit_tendons(
    tendon: ET.Element, robot: RobotModel, solref: str, directions: int, mount: bool = False
) -> float:
    """Each reduced joint's bend limit theta <= theta_max, for every bending direction: fixed
    tendons ``jk_bend_limit_i`` = cos(phi_i) (``jk_ax`` + ``jk_bx``) + sin(phi_i) (``jk_ay`` +
    ``jk_by``) (twice a pivot's angle along phi_i while the equalities hold) limited to twice the
    faces of :class:`~bvsr_cad.models.kinematics.PrbLimitPolygon`: a polygon of 2 ``directions``
    faces circumscribing the exact limit. Limits on the pivots' hinges
    instead (a square) let a diagonal bend reach 1.39 theta_max, and they act on one pivot, whose
    light shear mode lets it through. ``mount``: the mount variant's one pivot, whose hinges turn
    the whole bend (cos theta = cos a cos b): the polygon of the limit 2 theta_max on a pivot of the
    default file, on ``jk_x`` and ``jk_y`` alone. Returns the largest overshoot over the joints
    (theta / theta_max - 1 at a vertex)."""
    solimp = _vec(LIMIT_SOLIMP)
    worst = 0.0
    pivots, scale = (("",), 1.0) if mount else (("a", "b"), 2.0)
    for b in robot.bending:
        poly = PrbLimitPolygon.make(b.theta_max_rad * (2.0 if mount else 1.0), directions)
        worst = max(worst, poly.overshoot)
        for i, (phi, half) in enumerate(zip(poly.direction_rad, poly.half_width_rad)):
            fixed = ET.SubElement(
                tendon,
                "fixed",
                name=f"{b.name}_bend_limit_{i}",
                range=_vec((-scale * half, scale * half)),
                solreflimit=solref,
                solimplimit=solimp,
            )
            for axis, coef in (("x", np.cos(phi)), ("y", np.sin(phi))):
                if abs(coef) > 1e-12:
                    for pivot in pivots:
                        ET.SubElement(
                            fixed, "joint", joint=f"{b.name}_{pivot}{axis}", coef=_f(coef)
                        )
    return worst


def _soa_bending(robot: RobotModel, per_soa: float) -> float:
    """``per_soa`` N r^2 / 2 for a joint of ``robot``
    (:func:`bvsr_cad.models.reduced_chain.soa_bending`)."""
    pos = {s.name: np.asarray(s.pos_m) for s in robot.sites}
    return reduced_chain.soa_bending(
        per_soa, [pos[s.bottom_site] for s in robot.soas if s.joint == 1]
    )


def _soa_bending_damping(robot: RobotModel) -> float:
    """c N r^2 / 2 (N m s/rad): a joint's SOA dampers against bending."""
    return _soa_bending(robot, robot.actuation.law.damping_n_s_per_m)


def soa_lever_arms_m(robot: RobotModel, k: int) -> dict[str, np.ndarray]:
    """Reduced joint k's SOAs' lever arms (:func:`bvsr_cad.models.reduced_chain.soa_lever_arms_m`),
    from its sockets at rest in panel k-1's frame."""
    b = robot.bending[k - 1]
    t_m = _arc_start_m(robot, b)
    pos = {s.name: np.asarray(s.pos_m) for s in robot.sites}
    soas = [s for s in robot.soas if s.joint == k]
    return reduced_chain.soa_lever_arms_m(
        bottoms_m=[pos[s.bottom_site] for s in soas],
        tops_m=[pos[s.top_site] + [0.0, 0.0, t_m + b.arc_length_m] for s in soas],
        pivot_mid_m=[0.0, 0.0, t_m + b.arc_length_m / 2],
    )


def hinge_share(robot: RobotModel, k: int) -> HingeShare:
    """What the default file moves onto reduced joint k's pivot hinges (:class:`HingeShare`)."""
    law = robot.actuation.law
    return HingeShare.of(
        soa_lever_arms_m(robot, k),
        law.stiffness_offset_n_per_m,
        law.damping_n_s_per_m,
        shear_stiffness_nm_rad(robot),
    )


def mount_joint(robot: RobotModel, k: int) -> MountJoint:
    """What the mount variant puts on bending joint k's universal joint (:class:`MountJoint`), its
    SOAs' lever arms in :func:`soa_lever_arms_m`'s order (the SOAs of joint k in ``robot.soas``)."""
    return MountJoint.of(
        soa_lever_arms_m(robot, k),
        robot.actuation.law.damping_n_s_per_m,
        robot.actuation.rod_bending_stiffness_nm_rad,
    )


def _arc_start_m(robot: RobotModel, b) -> float:
    """Where bending joint ``b``'s arc starts along panel k-1's axis (its frame), m."""
    return float(
        np.asarray(
            next(j for j in robot.joints if j.child == f"{b.name}_after_phi").T_parent_joint
        )[2, 3]
    )


def _segment_spread_tendons(tendon: ET.Element, robot: RobotModel) -> None:
    """What the per-segment model's series tendons lose: the SOAs resisting a segment's joints
    bending unalike.

    n joints bending theta_i (per axis, theta = a + b) against their own SOAs store (1/2) K sum
    theta_i^2, K = n_a N r^2 / 2; one series tendon of stiffness n_a / n per line stores (1/2) (K /
    n) (sum theta_i)^2. The difference, (1/2) K sum (theta_i - mean)^2 = (1/2) (K / n) sum over
    pairs (theta_i - theta_j)^2, is a fixed tendon per pair of stiffness K / n (and damping c N r^2
    / (2 n) likewise). It is zero whenever the segment's equalities hold, so it adds nothing to the
    coupled motion.
    """
    law = robot.actuation.law
    segments: dict[int, list] = {}
    for b in robot.bending:
        segments.setdefault(b.segment, []).append(b.name)
    for names in segments.values():
        n = len(names)
        stiffness = _f(_soa_bending(robot, law.stiffness_offset_n_per_m) / n)
        damping = _f(_soa_bending(robot, law.damping_n_s_per_m) / n)
        for i, first in enumerate(names):
            for second in names[i + 1 :]:
                for axis in "xy":
                    fixed = ET.SubElement(
                        tendon,
                        "fixed",
                        name=f"{first}_{second}_spread_{axis}",
                        stiffness=stiffness,
                        damping=damping,
                    )
                    for name, coef in ((first, "1"), (second, "-1")):
                        for half in "ab":
                            ET.SubElement(fixed, "joint", joint=f"{name}_{half}{axis}", coef=coef)


def _panel_spans(robot: RobotModel, soas) -> float:
    """Length of the tendon path inside panels between consecutive SOAs of a line (rigid)."""
    if len(soas) < 2:
        return 0.0
    pos = {s.name: np.asarray(s.pos_m) for s in robot.sites}
    total = 0.0
    for a, b in zip(soas, soas[1:]):
        # top socket of a (panel k frame) to bottom socket of b (same panel's frame)
        total += float(np.linalg.norm(pos[b.bottom_site] - pos[a.top_site]))
    return total


def _dress(visual: ET.Element, asset: ET.Element, world: ET.Element) -> None:
    """A scene's headlight, checker floor and overhead light."""
    ET.SubElement(
        visual, "headlight", diffuse="0.6 0.6 0.6", ambient="0.3 0.3 0.3", specular="0 0 0"
    )
    ET.SubElement(
        asset,
        "texture",
        type="2d",
        name="groundplane",
        builtin="checker",
        mark="edge",
        rgb1="0.2 0.3 0.4",
        rgb2="0.1 0.2 0.3",
        markrgb="0.8 0.8 0.8",
        width="300",
        height="300",
    )
    ET.SubElement(
        asset,
        "material",
        name="groundplane",
        texture="groundplane",
        texuniform="true",
        texrepeat="5 5",
        reflectance="0.2",
    )
    ET.SubElement(world, "light", pos="0 0 1.5", dir="0 0 -1", directional="true")
    ET.SubElement(
        world, "geom", name="floor", size="0 0 0.05", type="plane", material="groundplane"
    )


def scene_tree(model_file: str, name: str) -> ET.ElementTree:
    """A menagerie-style scene: the model, a floor, light and a mount block."""
    root = ET.Element("mujoco", model=f"{name} scene")
    ET.SubElement(root, "include", file=model_file)
    ET.SubElement(root, "statistic", center="0.15 0 0.4", extent="0.5")
    visual = ET.SubElement(root, "visual")
    asset = ET.SubElement(root, "asset")
    world = ET.SubElement(root, "worldbody")
    _dress(visual, asset, world)
    ET.SubElement(visual, "global", azimuth="120", elevation="-20")
    ET.SubElement(
        world,
        "geom",
        name="mount_block",
        type="box",
        size="0.03 0.05 0.225",
        pos=_vec((-0.03, 0.0, MOUNT_HEIGHT_M / 2)),
        rgba="0.3 0.3 0.3 1",
        contype="0",
        conaffinity="0",
    )
    ET.indent(root)
    return ET.ElementTree(root)


#: The cart of the platform experiment: wheel radius and deck thickness are drawing choices (they
#: set heights, not the Eq 20-22 dynamics, which take the cart's mass, length and width).
CART_WHEEL_RADIUS_M = 0.02
CART_DECK_THICKNESS_M = 0.015


def cart_scene_tree(
    robot: RobotModel, mesh_files: dict[str, str], cart, mesh_dir: str = "meshes"
) -> ET.ElementTree:
    """The paper's hinged-cart experiment (Sec. IV-B, V-B; Eq 20-22) as one MJCF file.

    The cart (``cart``: :class:`bvsr_cad.parameters.tables.CartPlatform`) turns about its rear axle
    (hinge ``cart_pitch``, the front lifts for a positive angle) and about a vertical shaft through
    the axle (hinge ``cart_yaw``); it rests on its front wheel, a sphere on the floor. Its mass sits
    at mid-length with the inertias Eq 20-22 uses (m l^2 / 12 in pitch, m (l^2 + w^2) / 12 in yaw).
    The per-segment tail is mounted ``tail_mount_behind_hinge_m`` behind the axle, pointing away
    from the cart, high enough that no panel touches the floor at rest.
    """
    # The exact chain: on the reduced one the waggle turns the cart 12.8 deg, not 16.1, against Eq
    # 20-22's 20.3 deg: the paper comparisons stay on the chain they were validated with.
    tree, _ = mjcf_tree(robot, mesh_files, per_segment=True, mesh_dir=mesh_dir, chain="exact")
    root = tree.getroot()
    root.set("model", f"{robot.name}_cart")
    world = root.find("worldbody")
    mount = world.find("body[@name='bvsr_mount']")
    world.remove(mount)
    visual = ET.Element("visual")
    root.insert(list(root).index(root.find("asset")), visual)
    _dress(visual, root.find("asset"), world)
    r, t = CART_WHEEL_RADIUS_M, CART_DECK_THICKNESS_M
    length, width, m = cart.length_m, cart.width_m, cart.mass_kg
    body = ET.SubElement(world, "body", name="cart", pos=_vec((0.0, 0.0, r)))
    ET.SubElement(body, "joint", name="cart_pitch", type="hinge", axis="0 1 0", damping="0")
    ET.SubElement(body, "joint", name="cart_yaw", type="hinge", axis="0 0 1", damping="0")
    ET.SubElement(
        body,
        "inertial",
        pos=_vec((-length / 2, 0.0, 0.0)),
        mass=_f(m),
        diaginertia=_vec((m * width**2 / 12, m * length**2 / 12, m * (length**2 + width**2) / 12)),
    )
    ET.SubElement(
        body,
        "geom",
        name="cart_deck",
        type="box",
        size=_vec((length / 2, width / 2, t / 2)),
        pos=_vec((-length / 2, 0.0, r + t / 2)),
        density="0",
        contype="0",
        conaffinity="0",
        rgba="0.8 0.55 0.2 1",
    )
    # A hard wheel on a hard floor: the stiffest contact the step allows (time constant two steps).
    ET.SubElement(
        body,
        "geom",
        name="cart_front_wheel",
        type="sphere",
        size=_f(r),
        pos=_vec((-length, 0.0, 0.0)),
        density="0",
        rgba="0.15 0.15 0.15 1",
        solref=_vec((2.0 * float(root.find("option").get("timestep")), 1.0)),
    )
    for side in (-1.0, 1.0):
        ET.SubElement(
            body,
            "geom",
            name=f"cart_rear_wheel_{'lr'[side > 0]}",
            type="cylinder",
            size=_vec((r, 0.004)),
            pos=_vec((0.0, side * width / 2, 0.0)),
            euler="1.5707963 0 0",
            density="0",
            contype="0",
            conaffinity="0",
            rgba="0.15 0.15 0.15 1",
        )
    rim_m = max(
        (c.radius_m for link in robot.links.values() for c in link.collisions), default=0.03
    )
    mount.set("pos", _vec((cart.tail_mount_behind_hinge_m, 0.0, rim_m + 0.005)))
    body.append(mount)
    ET.indent(root)
    return tree


def write_mjcf(path: Path, tree: ET.ElementTree) -> None:
    write_tree(tree, path, declaration=False)
