"""The paper's disturbance test as MJCF (Sec. IV-D, Fig. 17): a ball rolls down a ramp into the
tail.

World: gravity -Z; the ramp (``ramp_length_m`` at ``RAMP_ANGLE_DEG``, then a fillet, :func:`_ramp`)
descends along +X to its foot at the origin, the floor is Z = 0. The tail's mount is a fixed stand
(the six-axis sensor of the paper's force tests; the quadruped is not modelled), the tail horizontal
and across the ball's path (tail Z -> world -Y, dorsal up), ``IMPACT_DISTANCE_M`` past the ramp's
foot, its tip panel's centre on the path at the ball's centre height: the ball strikes the tip panel
side-on, at its equator. The paper's text does not fix the tail's heading towards the ramp; across
the path is the case in which a tail's compliance can act (head-on, the rod's axial stiffness takes
the blow in both tails).

The ball is a shell that gives (:mod:`bvsr_cad.models.impact`): a core body with most of the mass
(free joint) and a skin body (:data:`SKIN_MASS_FRACTION`) that carries the contact sphere, held by
three slide springs of the ball's stiffness and damping. The contacts themselves are hard (time
constant two steps, :data:`IMPACT_TIMESTEP_S`), so what gives is the ball, not the tail's collision
shapes.

Two tails: ``soft``, the exported MJCF model (its collision shapes, SOAs unpressurised); ``rigid``,
the PLA twin as one body welded to the stand, with the twin's B-rep inertial and the same shapes
placed at rest.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np

from ..assembly.robot import RobotModel
from ..models.impact import RAMP_ANGLE_DEG, SHELL_INERTIA_RATIO, Ball
from .mjcf import COLUMN_CONTACT_BIT, _dress, collision_geom, mjcf_tree
from .xml import num as _f
from .xml import quat_wxyz as _quat
from .xml import vec as _vec

#: Tail frame -> world: tail Z along world -Y (across the ball's path), tail Y (dorsal) up.
R_WORLD_TAIL_IMPACT = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
#: From the ramp's foot to the tail's axis along the ball's path (the paper: "at the bottom of the
#: ramp").
IMPACT_DISTANCE_M = 0.5
#: The step of the impact scenes: the contacts are hard (time constant two steps) and a ball arrives
#: at over 3 m/s; at this step no contact sinks deeper than 1 mm (checked by ``bvsr simulate
#: --impact``).
IMPACT_TIMESTEP_S = 1e-4
#: The share of a ball's mass in its skin body (the flattening cap that meets the obstacle first).
SKIN_MASS_FRACTION = 0.05
RAMP_WIDTH_M = 0.4
#: Below the paper's 1.35 m incline, a fillet to the floor: without it the ball leaves the ramp's
#: foot bouncing (to 0.3 m at its centre, over the tail); with it the ball meets the tail rolling.
RAMP_FILLET_RADIUS_M = 0.3
RAMP_FILLET_STEP_DEG = 3.0
RAMP_THICKNESS_M = 0.02


def _world(root: ET.Element, ball: Ball, ramp_length_m: float, timestep_s: float) -> ET.Element:
    """Light, floor, ramp and ball into ``root``'s worldbody; returns the worldbody."""
    root.find("option").set("timestep", _f(timestep_s))
    world = root.find("worldbody")
    asset = root.find("asset")
    visual = ET.Element("visual")
    root.insert(list(root).index(asset), visual)
    _dress(visual, asset, world)
    top = _ramp(world, ramp_length_m)
    a = math.radians(RAMP_ANGLE_DEG)
    normal = np.array([math.sin(a), 0.0, math.cos(a)])
    r, m = ball.radius_m, ball.mass_kg
    m_skin = SKIN_MASS_FRACTION * m
    body = ET.SubElement(world, "body", name="ball", pos=_vec(top + normal * r))
    ET.SubElement(body, "freejoint", name="ball_free")
    i_core = SHELL_INERTIA_RATIO * (m - m_skin) * r * r
    ET.SubElement(
        body, "inertial", pos="0 0 0", mass=_f(m - m_skin), diaginertia=_vec((i_core,) * 3)
    )
    skin = ET.SubElement(body, "body", name="ball_skin")
    for axis in ("1 0 0", "0 1 0", "0 0 1"):
        ET.SubElement(
            skin,
            "joint",
            name=f"ball_give_{'xyz'[axis.split().index('1')]}",
            type="slide",
            axis=axis,
            stiffness=_f(ball.stiffness_n_per_m),
            damping=_f(ball.damping_n_s_per_m()),
        )
    i_skin = SHELL_INERTIA_RATIO * m_skin * r * r
    ET.SubElement(skin, "inertial", pos="0 0 0", mass=_f(m_skin), diaginertia=_vec((i_skin,) * 3))
    # The ball's contacts win over the other geom's (priority): hard, two steps. It reaches the SOAs
    # and the rod between the panels as well as the panels (conaffinity: mjcf.CONTACT_TYPE).
    ET.SubElement(
        skin,
        "geom",
        name="ball",
        type="sphere",
        size=_f(r),
        priority="1",
        condim="3",
        conaffinity=str(1 | COLUMN_CONTACT_BIT),
        solref=_vec((2.0 * timestep_s, 1.0)),
        rgba="0.85 0.4 0.1 1",
        density="0",
    )
    return world


def _facet(
    world: ET.Element, name: str, p0: np.ndarray, p1: np.ndarray, overlap_m: float = 0.0
) -> None:
    """A box whose top face runs from p0 down to p1 (X-Z plane), across the whole ramp width."""
    down = (p1 - p0) / np.linalg.norm(p1 - p0)
    normal = np.array([-down[2], 0.0, down[0]])
    R = np.stack([down, [0.0, 1.0, 0.0], normal], axis=1)
    half = np.linalg.norm(p1 - p0) / 2 + overlap_m
    ET.SubElement(
        world,
        "geom",
        name=name,
        type="box",
        pos=_vec((p0 + p1) / 2 - normal * RAMP_THICKNESS_M / 2),
        quat=_quat(R),
        size=_vec((half, RAMP_WIDTH_M / 2, RAMP_THICKNESS_M / 2)),
        rgba="0.6 0.5 0.35 1",
    )


def ramp_drop_m(ramp_length_m: float) -> float:
    """Height from the ramp's top to the floor: the paper's incline and the fillet below it."""
    a = math.radians(RAMP_ANGLE_DEG)
    return ramp_length_m * math.sin(a) + RAMP_FILLET_RADIUS_M * (1.0 - math.cos(a))


def _ramp(world: ET.Element, ramp_length_m: float) -> np.ndarray:
    """The paper's ramp, then a fillet of :data:`RAMP_FILLET_RADIUS_M` down to the floor at the
    origin (facets of :data:`RAMP_FILLET_STEP_DEG`); returns the top edge's point (X-Z)."""
    a = math.radians(RAMP_ANGLE_DEG)
    centre = np.array([0.0, 0.0, RAMP_FILLET_RADIUS_M])
    n = max(1, math.ceil(RAMP_ANGLE_DEG / RAMP_FILLET_STEP_DEG))
    arc = [
        centre - RAMP_FILLET_RADIUS_M * np.array([math.sin(t), 0.0, math.cos(t)])
        for t in np.linspace(a, 0.0, n + 1)
    ]
    top = arc[0] - ramp_length_m * np.array([math.cos(a), 0.0, -math.sin(a)])
    _facet(world, "ramp", top, arc[0])
    for i in range(n):
        _facet(world, f"ramp_fillet{i}", arc[i], arc[i + 1], overlap_m=0.001)
    return top


def _mount(world: ET.Element, tip_z_m: float, height_m: float) -> ET.Element:
    return ET.SubElement(
        world,
        "body",
        name="bvsr_mount",
        pos=_vec((IMPACT_DISTANCE_M, tip_z_m, height_m)),
        quat=_quat(R_WORLD_TAIL_IMPACT),
    )


def _sensors(root: ET.Element) -> None:
    sensor = ET.SubElement(root, "sensor")
    ET.SubElement(sensor, "force", name="root_force", site="root_ft")
    ET.SubElement(sensor, "torque", name="root_torque", site="root_ft")
    ET.SubElement(sensor, "accelerometer", name="tip_acc", site="tip_imu")
    ET.SubElement(sensor, "framelinvel", name="ball_vel", objtype="body", objname="ball")


def ramp_ball_tree(
    ball: Ball, ramp_length_m: float, timestep_s: float = IMPACT_TIMESTEP_S
) -> ET.ElementTree:
    """The floor, the ramp and the ball of the impact scenes alone, to roll the ball on its own or
    to attach to another scene (``MjsFrame.attach_body``): the floor and the ramp's facets are the
    geoms of one fixed body ``ramp``, the ball's body is ``ball`` (its ``framelinvel`` sensor
    ``ball_vel``); the ramp's foot is at the origin and the ball, at its top, rolls along +X."""
    root = ET.Element("mujoco", model=f"ramp_{ball.name.split()[1]}")
    ET.SubElement(root, "compiler", angle="radian", autolimits="true")
    ET.SubElement(root, "option", timestep=_f(timestep_s))
    ET.SubElement(root, "asset")
    ET.SubElement(root, "worldbody")
    world = _world(root, ball, ramp_length_m, timestep_s)
    fixed = ET.SubElement(world, "body", name="ramp")
    for geom in world.findall("geom"):
        world.remove(geom)
        fixed.append(geom)
    sensor = ET.SubElement(root, "sensor")
    ET.SubElement(sensor, "framelinvel", name="ball_vel", objtype="body", objname="ball")
    ET.indent(root)
    return ET.ElementTree(root)


def soft_impact_tree(
    robot: RobotModel,
    mesh_files: dict[str, str],
    ball: Ball,
    tip_z_m: float,
    tip_site_m: float,
    ramp_length_m: float,
    timestep_s: float = IMPACT_TIMESTEP_S,
    mesh_dir: str = "meshes",
) -> ET.ElementTree:
    """The exported tail model in the impact scene (``tip_z_m``: the tail-frame z of the struck
    point, ``tip_site_m``: the tip IMU's z in the tip panel's frame)."""
    tree, _ = mjcf_tree(robot, mesh_files, per_segment=False, mesh_dir=mesh_dir)
    root = tree.getroot()
    root.set("model", f"{robot.name}_impact_soft")
    world = root.find("worldbody")
    old = world.find("body[@name='bvsr_mount']")
    world.remove(old)
    world = _world(root, ball, ramp_length_m, timestep_s)
    mount = _mount(world, tip_z_m, ball.radius_m)
    for child in list(old):
        mount.append(child)
    mount.set("childclass", old.get("childclass"))
    panels = [b for b in root.iter("body") if b.get("name", "").startswith("panel")]
    ET.SubElement(panels[0], "site", name="root_ft", pos="0 0 0")
    ET.SubElement(
        root.find(f".//body[@name='{robot.bending[-1].tip_link}']"),
        "site",
        name="tip_imu",
        pos=_vec((0.0, 0.0, tip_site_m)),
    )
    _sensors(root)
    ET.indent(root)
    return tree


def rigid_impact_tree(
    robot: RobotModel,
    rigid,
    panel_z_m: dict[str, float],
    ball: Ball,
    tip_z_m: float,
    ramp_length_m: float,
    timestep_s: float = IMPACT_TIMESTEP_S,
) -> ET.ElementTree:
    """The rigid twin (``rigid``: :class:`bvsr_cad.assembly.products.RigidRobot`) welded to the
    stand, with the soft tail's collision shapes at rest (``panel_z_m``: each panel link's
    tail-frame z)."""
    root = ET.Element("mujoco", model=f"{robot.name}_impact_rigid")
    ET.SubElement(root, "compiler", angle="radian", autolimits="true")
    ET.SubElement(root, "option", timestep=_f(timestep_s), integrator="implicitfast")
    default = ET.SubElement(root, "default")
    col = ET.SubElement(default, "default", {"class": "collision"})
    ET.SubElement(col, "geom", group="3", density="0", rgba="0.9 0.9 0.8 1", conaffinity="0")
    ET.SubElement(root, "asset")
    ET.SubElement(root, "worldbody")
    world = _world(root, ball, ramp_length_m, timestep_s)
    mount = _mount(world, tip_z_m, ball.radius_m)
    body = ET.SubElement(mount, "body", name="rigid_tail")
    I = rigid.inertial.inertia
    ET.SubElement(
        body,
        "inertial",
        pos=_vec(rigid.inertial.com),
        mass=_f(rigid.inertial.mass_kg),
        fullinertia=_vec((I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])),
    )
    for name, z in panel_z_m.items():
        for c in robot.links[name].collisions:
            if c.kind != "cylinder":
                raise ValueError(
                    "the rigid impact scene takes primitive collision shapes "
                    '(robot.collision_geometry = "primitives")'
                )
            geom = collision_geom(body, c, (0.0, 0.0, z))
            geom.set("name", f"rigid_{geom.get('name')}")
    ET.SubElement(body, "site", name="root_ft", pos="0 0 0")
    ET.SubElement(body, "site", name="tip_imu", pos=_vec((0.0, 0.0, tip_z_m)))
    _sensors(root)
    ET.indent(root)
    return ET.ElementTree(root)
