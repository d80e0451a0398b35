"""`bvsr simulate`: the MJCF driven by a pressure pulse (the Eq 13 ramp or the valve supply model).

Two runs, as in the paper's experiments (Sec. IV-A):

- one standalone segment (the same parameters with one segment) in
  extension, the two ventral lines pressurised: its bending angle (the tilt of
  the distal panel) and the peak angular velocity before the angle passes
  38 deg, the paper's window;
- the whole tail in extension, every segment's ventral lines pressurised,
  with an optional tip payload: the force and torque at the root (the
  mount's six-axis sensor).

Nothing is tuned to the paper; its figures are printed beside the results.
"""

from __future__ import annotations

import dataclasses
import math
import tempfile
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import units
from ..assembly.assemble import Assembly, build_assembly
from ..assembly.robot import robot_model
from ..errors import BadInput
from ..exporters.mjcf import mjcf_tree, write_mjcf
from ..exporters.robot_meshes import write_robot_meshes
from ..models.dynamics import VELOCITY_WINDOW_DEG, ramp_pa
from ..models.platform import front_lift_mm
from ..parameters.tables import TailSpec

EXTENSION_LINES = (3, 4)
SETTLE_S = 0.3  # the two ventral SOAs push: the tail bends dorsally (+Y)


def pressure_input(
    spec: TailSpec, p0_pa: float, supply: str, places: tuple[int, ...] = EXTENSION_LINES, asm=None
) -> Callable[[float], float]:
    """The gauge pressure of a pulsed line over time (s), for ``supply``:

    - ``ramp``: the paper's Eq 13 with t_0 = ``pneumatics.ramp_time_s`` (or its calibrated value);
    - ``valve``: the ISO 6358 supply model (:mod:`bvsr_cad.models.pneumatics`) filling one line's
      tube and SOAs held at rest length, precomputed and played back as the actuators' control
      (plain MuJoCo has no chamber state; the SOAs' growth during the motion is not fed back).
    """
    if supply == "ramp":
        t0 = spec.fitted("ramp_time_s", spec.pneumatics.ramp_time_s)
        return lambda t: float(ramp_pa(t, p0_pa, t0))
    from ..assembly.pneumatic_lines import line_supply
    from ..models.pneumatics import fill_curve

    t_s, p_pa = fill_curve(
        line_supply(asm or build_assembly(spec), 1, places, p0_pa, spec), 1.0, samples=4001
    )
    return lambda t: float(np.interp(t, t_s, p_pa))


class SimulationInputError(ValueError, BadInput):
    """A simulation argument outside what the model allows (exit code 2)."""


def _supply(spec: TailSpec, supply: str | None) -> str:
    """The pressure input asked for, or the spec's (``pneumatics.model``)."""
    supply = supply or spec.pneumatics.model
    if supply not in ("ramp", "valve"):
        raise SimulationInputError(f"--supply {supply}: allowed ramp, valve")
    return supply


def _without_supply_lag(root: ET.Element) -> None:
    """The inputs here are the chamber pressure itself (Eq 13 or the supply model's trace): the
    exported actuators' own supply lag would filter it a second time."""
    for act in root.iter("general"):
        act.attrib.pop("dyntype", None)
        act.attrib.pop("dynprm", None)


@dataclass
class SimResult:
    pressure_bar: float
    payload_g: float
    time_s: np.ndarray
    segment_angle_deg: np.ndarray
    segment_rate_deg_s: np.ndarray
    peak_velocity_deg_s: float
    angle_reached_deg: float
    tail_time_s: np.ndarray
    root_force_n: np.ndarray  # (n, 3) in the tail frame
    root_torque_nm: np.ndarray
    peak_root_force_n: float
    peak_root_torque_nm: float


def _model_xml(
    spec: TailSpec, theta_max_rad: list[float], folder: Path, payload_g: float
) -> tuple[Path, list[str]]:
    """Per-segment MJCF of ``spec`` with a root force/torque sensor and an optional tip payload,
    and the names of its extension lines' actuators."""
    asm = build_assembly(spec)
    robot = robot_model(asm, theta_max_rad)
    mesh_files = write_robot_meshes(robot, folder / "meshes")
    tree, _ = mjcf_tree(robot, mesh_files, per_segment=True)
    root = tree.getroot()
    panel0 = root.find(".//body[@name='panel0']")
    ET.SubElement(panel0, "site", name="root_ft", pos="0 0 0", size="0.002")
    tip = root.find(f".//body[@name='panel{spec.panels - 1}']")
    if payload_g > 0:
        t_m = units.mm_to_m(spec.joint.panel_thickness_mm)
        payload = ET.SubElement(tip, "body", name="payload", pos=f"0 0 {t_m:.6g}")
        r = 0.01  # a 20 mm solid sphere's inertia: small next to its offset
        m = units.g_to_kg(payload_g)
        i = 0.4 * m * r * r
        ET.SubElement(
            payload,
            "inertial",
            pos="0 0 0.01",
            mass=f"{m:.6g}",
            diaginertia=f"{i:.6g} {i:.6g} {i:.6g}",
        )
    _without_supply_lag(root)
    sensor = ET.SubElement(root, "sensor")
    ET.SubElement(sensor, "force", name="root_force", site="root_ft")
    ET.SubElement(sensor, "torque", name="root_torque", site="root_ft")
    path = folder / f"{spec.name}_sim.xml"
    write_mjcf(path, tree)
    return path, sorted({s.line for s in robot.soas if s.line_index in EXTENSION_LINES})


def _run(
    model: tuple[Path, list[str]],
    spec: TailSpec,
    pressure: Callable[[float], float],
    seconds: float,
    stop_angle_deg: float | None = None,
):
    import mujoco

    path, extension = model
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    lines = [m.actuator(name).id for name in extension]
    tip = m.body(f"panel{spec.panels - 1}").id
    # Settle under gravity first and tare the sensor, as the paper's six-axis sensor reads changes.
    for _ in range(int(round(SETTLE_S / m.opt.timestep))):
        mujoco.mj_step(m, d)
    tare_f, tare_t = d.sensor("root_force").data.copy(), d.sensor("root_torque").data.copy()
    z_rest = d.xmat[tip].reshape(3, 3)[:, 2].copy()
    t_start = d.time
    steps = int(round(seconds / m.opt.timestep))
    t = np.zeros(steps)
    angle = np.zeros(steps)
    force = np.zeros((steps, 3))
    torque = np.zeros((steps, 3))
    for n in range(steps):
        d.ctrl[lines] = pressure(d.time - t_start)
        mujoco.mj_step(m, d)
        t[n] = d.time - t_start
        z_tip = d.xmat[tip].reshape(3, 3)[:, 2]
        # The bending angle swept from the settled pose (sagged slightly under gravity).
        angle[n] = math.degrees(math.acos(float(np.clip(z_tip @ z_rest, -1.0, 1.0))))
        force[n] = d.sensor("root_force").data - tare_f
        torque[n] = d.sensor("root_torque").data - tare_t
        if stop_angle_deg is not None and angle[n] > stop_angle_deg + 5.0:
            steps = n + 1
            break
    return t[:steps], angle[:steps], force[:steps], torque[:steps]


def check_inputs(spec: TailSpec, pressure_bar: float, payload_g: float) -> None:
    """Raises SimulationInputError naming the argument and what is allowed."""
    p_max = spec.robot.pulse_pressure_max_kpa * units.PA_PER_KPA / units.PA_PER_BAR
    if not 0 < pressure_bar <= p_max:
        raise SimulationInputError(
            f"--pressure-bar {pressure_bar:g}: allowed 0 < P <= {p_max:g} bar "
            "(robot.pulse_pressure_max_kpa)"
        )
    if payload_g < 0:
        raise SimulationInputError(f"--payload-g {payload_g:g}: must be >= 0")


def joint_limits_rad(
    spec: TailSpec, progress: Callable[[str], None] | None = None, asm: Assembly | None = None
) -> list[float]:
    """Collision-free theta_max of every joint (minimum over phi), as the build's limits analysis
    gives (``asm``: the spec's assembly, if already built)."""
    from ..analysis.limits import theta_max_per_joint_rad

    say = progress or (lambda _m: None)
    say("joint limits from the clearance analysis")
    return theta_max_per_joint_rad(asm or build_assembly(spec))


@dataclass
class ProtocolRun:
    """The workspace protocol of Sec. IV-A-5 run in time on the exported (reduced-chain) MJCF, the
    tail horizontal: every ``actuation.workspace_cycle_s`` each line draws a new pressure
    (:func:`bvsr_cad.analysis.workspace.sample_line_pressures_kpa`), reached through the actuators'
    supply lag. Positions in mm, in the model's world frame."""

    tip_mm: np.ndarray  # (n, 3): the distal panel's origin, every PROTOCOL_SAMPLE_S
    settled_mm: np.ndarray  # (cycles, 3): the same at the end of each cycle
    rest_mm: np.ndarray  # (3,): settled under gravity with every line at atmospheric
    axis: np.ndarray  # the tail's axis at rest (unit, base to tip)
    warnings: int  # MuJoCo warnings raised during the run

    def lateral_mm(self, points_mm: np.ndarray) -> np.ndarray:
        """Distance of each point from the rest point across the tail's axis (the radius the paper
        reads)."""
        rel = np.asarray(points_mm) - self.rest_mm
        return np.linalg.norm(rel - np.outer(rel @ self.axis, self.axis), axis=1)

    @property
    def radius_mm(self) -> float:
        """The largest lateral excursion over the whole recording (what motion capture sees)."""
        return float(np.max(self.lateral_mm(self.tip_mm)))

    @property
    def settled_radius_mm(self) -> float:
        """The same over the settled ends of the cycles only (close to the quasi-static
        workspace)."""
        return float(np.max(self.lateral_mm(self.settled_mm)))


#: The paper records the workspace at 100-120 Hz; the path is kept at this interval.
PROTOCOL_SAMPLE_S = 0.008


class _UnwrittenMeshes(dict):
    """Mesh file names for :func:`mjcf_tree` when no mesh is written (the protocol needs none)."""

    def __missing__(self, key: str) -> str:
        return f"{key}.stl"


def _drop(root: ET.Element, unwanted: Callable[[ET.Element, ET.Element], bool]) -> None:
    """Remove every element for which ``unwanted(parent, child)`` holds."""
    for parent in root.iter():
        for child in list(parent):
            if unwanted(parent, child):
                parent.remove(child)


def _without_meshes(root: ET.Element) -> None:
    """Drop mesh assets and mesh geoms (visuals, mass-less: every body's inertia is explicit)."""
    _drop(
        root,
        lambda parent, child: (
            (child.tag == "mesh" and parent.tag == "asset")
            or (child.tag == "geom" and bool(child.get("mesh") or child.get("class") == "visual"))
        ),
    )


def protocol_model(
    asm: Assembly,
    spec: TailSpec,
    theta_max_rad: list[float],
    tip_body: str,
    keep_geoms: bool = False,
):
    """(MjModel, robot model) of the workspace protocol: ``asm``'s exported reduced-chain MJCF with
    ``spec``'s values, a ``framepos`` sensor on ``tip_body`` (sensors do not act on the dynamics).

    Its geoms are mass-less (every body's inertia is explicit) and, in this scene of the tail alone,
    collide with nothing (no geom has a non-zero ``conaffinity``, the scene declares no contact
    pair): unless ``keep_geoms``, the robot model is made without its collision shapes (their fits
    are most of its making) and any geom left is dropped, so each step skips their kinematics and
    the collision pass. The run is the same either way (``tests/test_workspace_protocol.py``
    compares the two)."""
    import mujoco

    with_values = dataclasses.replace(asm, spec=spec)
    with_values._properties.update(asm._properties)  # same geometry: its mass properties carry over
    robot = robot_model(with_values, theta_max_rad, collisions=keep_geoms)
    tree, _ = mjcf_tree(robot, _UnwrittenMeshes(), per_segment=False)
    root = tree.getroot()
    _without_meshes(root)
    sensor = root.find("sensor")
    if sensor is None:
        sensor = ET.SubElement(root, "sensor")
    ET.SubElement(sensor, "framepos", name="protocol_tip", objtype="xbody", objname=tip_body)
    m = mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))
    if (
        not keep_geoms
        and m.ngeom
        and not m.geom_conaffinity.any()
        and m.npair == 0
        and m.nexclude == 0
    ):
        _drop(root, lambda _parent, child: child.tag == "geom")
        m = mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))
    return m, robot


def _hold(m, d, ctrl: np.ndarray, steps: int) -> np.ndarray:
    """``steps`` steps of ``d`` with ``ctrl`` held, in MuJoCo's rollout (C, without Python's lock:
    protocols run side by side in threads); ``d`` is left at the last step. The sensor data of each
    step."""
    import mujoco
    from mujoco import rollout

    spec_full = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state = np.empty(mujoco.mj_stateSize(m, spec_full))
    mujoco.mj_getState(m, d, state, spec_full)
    d.ctrl[:] = ctrl
    _, sensordata = rollout.rollout(
        m,
        d,
        state[None],
        d.ctrl[None, None].copy(),
        nstep=steps,
        initial_warmstart=d.qacc_warmstart[None].copy(),
    )
    return sensordata[0]


def workspace_protocol(
    asm: Assembly,
    spec: TailSpec | None = None,
    theta_max_rad: list[float] | None = None,
    cycles: int | None = None,
    progress: Callable[[str], None] | None = None,
    keep_geoms: bool = False,
) -> ProtocolRun:
    """The paper's workspace experiment (Sec. IV-A-5) in MuJoCo: ``cycles`` pressure draws (default
    ``analysis.workspace_protocol_cycles``, seed ``analysis.seed``) held
    ``actuation.workspace_cycle_s`` each, on ``asm``'s exported MJCF with ``spec``'s values (same
    geometry; it may carry fitted ones).

    ``theta_max_rad``: the joints' limits (default: from the clearance analysis of ``asm``);
    ``keep_geoms``: see :func:`protocol_model`."""
    import mujoco

    from ..analysis.workspace import sample_line_pressures_kpa

    spec = spec or asm.spec
    say = progress or (lambda _m: None)
    if theta_max_rad is None:
        theta_max_rad = joint_limits_rad(spec, say, asm)
    m, robot = protocol_model(asm, spec, theta_max_rad, f"panel{spec.panels - 1}", keep_geoms)
    d = mujoco.MjData(m)
    cycles = int(cycles or spec.analysis.workspace_protocol_cycles)
    draws_kpa = sample_line_pressures_kpa(spec, cycles, np.random.default_rng(spec.analysis.seed))
    jps = spec.joints_per_segment
    actuator = np.array([m.actuator(s.name).id for s in robot.soas])
    segment = np.array([(s.joint - 1) // jps for s in robot.soas])
    place = np.array([s.line_index - 1 for s in robot.soas])
    tip, base = m.body(f"panel{spec.panels - 1}").id, m.body("panel0").id
    sensor = m.sensor("protocol_tip").adr[0]
    _hold(m, d, d.ctrl.copy(), int(round(SETTLE_S / m.opt.timestep)))
    rest = units.m_to_mm(d.xpos[tip].copy())
    axis = d.xpos[tip] - d.xpos[base]
    axis = axis / np.linalg.norm(axis)
    steps = int(round(spec.actuation.workspace_cycle_s / m.opt.timestep))
    every = max(1, int(round(PROTOCOL_SAMPLE_S / m.opt.timestep)))
    path, settled = [], []
    say(f"workspace protocol: {cycles} cycles of {spec.actuation.workspace_cycle_s:g} s in MuJoCo")
    ctrl = d.ctrl.copy()
    for c in range(cycles):
        ctrl[actuator] = units.kpa_to_pa(draws_kpa[c, segment, place])
        tips = _hold(m, d, ctrl, steps)[:, sensor : sensor + 3]
        path.append(tips[every - 1 :: every])
        settled.append(tips[-1])
    warnings = int(sum(w.number for w in d.warning))
    return ProtocolRun(
        units.m_to_mm(np.concatenate(path)), units.m_to_mm(np.array(settled)), rest, axis, warnings
    )


def protocol_radius_mm(asm: Assembly, spec: TailSpec, theta_max_rad: list[float]) -> float:
    """:data:`bvsr_cad.analysis.predict.WorkspaceSim`: the radius of :func:`workspace_protocol`'s
    tip path, mm."""
    run = workspace_protocol(asm, spec, theta_max_rad)
    if run.warnings:
        raise RuntimeError(f"workspace protocol: MuJoCo raised {run.warnings} warnings")
    return run.radius_mm


def segment_extension(
    spec: TailSpec,
    theta_max_rad: list[float],
    pressure_bar: float,
    supply: str,
    seconds: float = 0.5,
    progress: Callable[[str], None] | None = None,
    pressure: Callable[[float], float] | None = None,
):
    """One standalone segment of ``spec`` pulsed in extension (``pressure``: the line's input, by
    default :func:`pressure_input` of ``supply``): (time s, bending angle deg, its rate deg/s, the
    peak rate before the angle passes 38 deg)."""
    say = progress or (lambda _m: None)
    pressure = pressure or pressure_input(
        spec, pressure_bar * units.PA_PER_BAR, _supply(spec, supply)
    )
    one = dataclasses.replace(spec, name=f"{spec.name}_segment", segments=1)
    with tempfile.TemporaryDirectory() as tmp:
        say("segment model")
        seg_xml = _model_xml(one, theta_max_rad[: one.joints], Path(tmp) / "segment", 0.0)
        say(f"segment extension at {pressure_bar:g} bar")
        t, angle, _, _ = _run(seg_xml, one, pressure, seconds, stop_angle_deg=VELOCITY_WINDOW_DEG)
    rate = np.gradient(angle, t)
    window = angle <= VELOCITY_WINDOW_DEG
    return t, angle, rate, float(np.max(rate[window])) if window.any() else float("nan")


def simulate(
    spec: TailSpec,
    theta_max_rad: list[float],
    pressure_bar: float,
    payload_g: float = 0.0,
    seconds: float = 0.5,
    progress: Callable[[str], None] | None = None,
    supply: str | None = None,
) -> SimResult:
    """Run the two experiments at a pulse pressure (gauge, bar).

    Raises:
        SimulationInputError: a pressure outside the actuators' control range or a negative payload.
    """
    say = progress or (lambda _m: None)
    check_inputs(spec, pressure_bar, payload_g)
    supply = _supply(spec, supply)
    pressure = pressure_input(spec, pressure_bar * units.PA_PER_BAR, supply)
    t, angle, rate, peak_v = segment_extension(
        spec, theta_max_rad, pressure_bar, supply, seconds, say, pressure
    )
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        say("tail model")
        tail_xml = _model_xml(spec, theta_max_rad, folder / "tail", payload_g)
        say(f"tail extension at {pressure_bar:g} bar, payload {payload_g:g} g")
        tt, _, force, torque = _run(tail_xml, spec, pressure, seconds)
    return SimResult(
        pressure_bar,
        payload_g,
        t,
        angle,
        rate,
        peak_v,
        float(angle.max()),
        tt,
        force,
        torque,
        float(np.max(np.linalg.norm(force, axis=1))),
        float(np.max(np.linalg.norm(torque, axis=1))),
    )


@dataclass
class CartRun:
    motion: str
    time_s: np.ndarray
    pitch_deg: np.ndarray
    yaw_deg: np.ndarray
    wheelbase_m: float

    @property
    def peak_angle_deg(self) -> float:
        """The cart's largest turn: pitch for extension and flexion, yaw for waggle."""
        trace = self.yaw_deg if self.motion == "waggle" else self.pitch_deg
        return float(np.max(np.abs(trace)))

    @property
    def lift_mm(self) -> float:
        return front_lift_mm(self.wheelbase_m, np.radians(self.pitch_deg))


def simulate_cart(
    spec: TailSpec,
    theta_max_rad: list[float],
    pressure_bar: float,
    motions: tuple[str, ...] = ("extension", "waggle"),
    seconds: float = 0.5,
    progress: Callable[[str], None] | None = None,
    supply: str | None = None,
) -> list[CartRun]:
    """The tail on the paper's hinged cart (``robot/scene_cart.xml``) pulsed at ``pressure_bar``:
    the cart's pitch (front lift) and yaw over time for each motion."""
    import mujoco

    from ..analysis.predict import pulse_places
    from ..exporters.mjcf import cart_scene_tree

    say = progress or (lambda _m: None)
    check_inputs(spec, pressure_bar, 0.0)
    supply = _supply(spec, supply)
    asm = build_assembly(spec)
    robot = robot_model(asm, theta_max_rad)
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        mesh_files = write_robot_meshes(robot, folder / "meshes")
        tree = cart_scene_tree(robot, mesh_files, spec.cart)
        _without_supply_lag(tree.getroot())
        path = folder / "scene_cart.xml"
        write_mjcf(path, tree)
        m = mujoco.MjModel.from_xml_path(str(path))
        for motion in motions:
            places = pulse_places(motion)
            say(f"cart: {motion} at {pressure_bar:g} bar (lines {places})")
            p_of_t = pressure_input(spec, pressure_bar * units.PA_PER_BAR, supply, places, asm)
            lines = [
                m.actuator(f"s{s}_line{i}").id for s in range(1, spec.segments + 1) for i in places
            ]
            d = mujoco.MjData(m)
            for _ in range(int(round(SETTLE_S / m.opt.timestep))):
                mujoco.mj_step(m, d)
            pitch0, yaw0 = float(d.joint("cart_pitch").qpos[0]), float(d.joint("cart_yaw").qpos[0])
            t0 = d.time
            steps = int(round(seconds / m.opt.timestep))
            t, pitch, yaw = np.zeros(steps), np.zeros(steps), np.zeros(steps)
            for n in range(steps):
                d.ctrl[lines] = p_of_t(d.time - t0)
                mujoco.mj_step(m, d)
                t[n] = d.time - t0
                pitch[n] = math.degrees(float(d.joint("cart_pitch").qpos[0]) - pitch0)
                yaw[n] = math.degrees(float(d.joint("cart_yaw").qpos[0]) - yaw0)
            runs.append(CartRun(motion, t, pitch, yaw, spec.cart.length_m))
    return runs


def cart_comparison(spec: TailSpec, runs: list[CartRun], pressure_bar: float) -> list[dict]:
    """Each run's cart figures from MuJoCo beside Eq 20-22 on the Eq 6-12 tail model, and the
    paper's figure where it reports one at this pressure (Sec. IV-B, V-B: 5 bar)."""
    from ..analysis.predict import Predictor
    from ..parameters import paper

    pred = Predictor.from_spec(spec)
    reported = {
        ("extension", "angle"): paper.CART_ANGLE_EXTENSION_5BAR,
        ("waggle", "angle"): paper.CART_ANGLE_WAGGLE_5BAR,
        ("extension", "lift"): paper.CART_LIFT_9MM,
    }
    rows = []
    for r in runs:
        items = [("angle", "deg", r.peak_angle_deg, pred.cart_peak_angle(pressure_bar, r.motion))]
        if r.motion != "waggle":
            items.append(("lift", "mm", r.lift_mm, pred.cart_lift(pressure_bar, r.motion)))
        for what, unit, mj, eq in items:
            ref = reported.get((r.motion, what)) if pressure_bar == 5 else None
            rows.append(
                {
                    "motion": r.motion,
                    "quantity": f"cart_{what}",
                    "unit": unit,
                    "mujoco": mj,
                    "eq20_22": eq,
                    "paper": None if ref is None else ref.value,
                }
            )
    return rows


@dataclass
class ImpactRun:
    """One ball into one tail (``bvsr simulate --impact``); forces tared just before the first
    touch."""

    tail: str  # soft, rigid
    ball: str
    peak_root_force_n: float
    peak_root_torque_nm: float
    peak_tip_acceleration_m_s2: float
    max_penetration_mm: float
    warnings: int
    ball_speed_at_contact_m_s: float
    rolling_speed_m_s: float  # the closed form at the ramp's foot from its drop (models/impact)
    contact_impulse_n_s: np.ndarray  # on the tail, world frame, over the window
    root_impulse_n_s: (
        np.ndarray
    )  # the root sensor's force (tared; the mount's on the tail), world frame
    time_s: np.ndarray
    root_force_n: np.ndarray
    touched: tuple[str, ...] = ()  # the tail's collision geoms the ball touched, sorted


#: How long an impact run records after the ball first touches the tail.
IMPACT_WINDOW_S = 0.15
#: Peaks are of the signals' running mean over this time, a 1 kHz sensor (the paper's six-axis
#: sensors and IMUs sample at most that fast): the ball skin's first touch is a spike a few steps
#: long whose height is set by the skin's mass share (exporters/impact_scene), not by the ball.
SENSOR_AVERAGE_S = 1e-3


def _running_mean(x: np.ndarray, n: int) -> np.ndarray:
    c = np.cumsum(np.vstack([np.zeros((1, x.shape[1])), x]), axis=0)
    return (c[n:] - c[:-n]) / n if len(x) >= n else x.mean(axis=0, keepdims=True)


def simulate_impact(
    spec: TailSpec,
    theta_max_rad: list[float],
    balls: tuple[str, ...] = ("size5", "size7"),
    ramp_length_m: float | None = None,
    window_s: float = IMPACT_WINDOW_S,
    progress: Callable[[str], None] | None = None,
    asm: Assembly | None = None,
) -> list[ImpactRun]:
    """The paper's disturbance test (Sec. IV-D): each ball rolls down the ramp into the soft tail
    and into the rigid PLA twin (:mod:`bvsr_cad.exporters.impact_scene`). ``asm``: ``spec``'s
    assembly where the caller has built it already."""
    from ..assembly.products import build_rigid_twin, rigid_robot_model
    from ..exporters.impact_scene import ramp_drop_m, rigid_impact_tree, soft_impact_tree
    from ..models.impact import BALLS, RAMP_LENGTH_M, rolling_speed_m_s

    say = progress or (lambda _m: None)
    unknown = [b for b in balls if b not in BALLS]
    if unknown:
        raise SimulationInputError(f"--ball {unknown[0]}: allowed {', '.join(BALLS)}")
    ramp = RAMP_LENGTH_M if ramp_length_m is None else ramp_length_m
    asm = asm or build_assembly(spec)
    robot = robot_model(asm, theta_max_rad)
    say("rigid twin")
    twin = rigid_robot_model(asm, build_rigid_twin(asm))
    t_mm = spec.joint.panel_thickness_mm
    tip = asm.panel_layouts[-1]
    tip_z_m = units.mm_to_m(tip.z0_mm + t_mm / 2)
    panel_z_m = {f"panel{lay.index}": units.mm_to_m(lay.z0_mm) for lay in asm.panel_layouts}
    runs = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        mesh_files = write_robot_meshes(robot, folder / "meshes")
        for key in balls:
            ball = BALLS[key]
            trees = {
                "soft": soft_impact_tree(
                    robot, mesh_files, ball, tip_z_m, units.mm_to_m(t_mm / 2), ramp
                ),
                "rigid": rigid_impact_tree(robot, twin, panel_z_m, ball, tip_z_m, ramp),
            }
            for tail, tree in trees.items():
                say(f"impact: {ball.name} into the {tail} tail")
                path = folder / f"impact_{tail}_{key}.xml"
                write_mjcf(path, tree)
                runs.append(
                    _impact_run(
                        path, tail, ball.name, window_s, rolling_speed_m_s(ramp_drop_m(ramp))
                    )
                )
    return runs


def _impact_run(path: Path, tail: str, ball: str, window_s: float, v_roll: float) -> ImpactRun:
    import mujoco

    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    ball_geom = m.geom("ball").id
    tail_bodies = {
        b for b in range(m.nbody) if m.body(b).name.startswith(("panel", "rigid_tail", "j"))
    }
    site = m.site("root_ft").id
    sensors = ("root_force", "root_torque", "tip_acc")
    history: list[np.ndarray] = []
    f6 = np.zeros(6)
    contact_impulse = np.zeros(3)
    root_impulse = np.zeros(3)
    pen = 0.0
    touch_t = v_touch = None
    tare = None
    touched: set[str] = set()
    times, forces, torques, accs = [], [], [], []
    limit_s = 5.0
    while d.time < limit_s and (touch_t is None or d.time < touch_t + window_s):
        mujoco.mj_step(m, d)
        touching = False
        for i in range(d.ncon):
            c = d.contact[i]
            if ball_geom not in (c.geom1, c.geom2):
                continue
            pen = max(pen, -float(c.dist))
            other = c.geom2 if c.geom1 == ball_geom else c.geom1
            if m.geom_bodyid[other] in tail_bodies:
                touching = True
                touched.add(m.geom(other).name)
                mujoco.mj_contactForce(m, d, i, f6)
                # Contact frame rows: normal first; the force acts on geom2 along +normal.
                f_world = c.frame.reshape(3, 3).T @ f6[:3]
                contact_impulse += (f_world if c.geom2 == other else -f_world) * m.opt.timestep
        values = np.concatenate([d.sensor(s).data for s in sensors])
        if touch_t is None:
            if not touching:
                history = (history + [values.copy()])[-20:]
                continue
            touch_t, tare = d.time, np.mean(history, axis=0)  # the 20 steps before the touch
            v_touch = float(np.linalg.norm(d.sensor("ball_vel").data))
        rel = values - tare
        R = d.site_xmat[site].reshape(3, 3)
        root_impulse += R @ rel[:3] * m.opt.timestep
        times.append(d.time - touch_t)
        forces.append(rel[:3])
        torques.append(rel[3:6])
        accs.append(rel[6:9])
    if touch_t is None:
        raise RuntimeError(f"{path.name}: the ball did not reach the tail within {limit_s:g} s")
    warnings = int(sum(w.number for w in d.warning))
    n = max(1, int(round(SENSOR_AVERAGE_S / m.opt.timestep)))

    def peak(x) -> float:
        return float(np.max(np.linalg.norm(_running_mean(np.asarray(x), n), axis=1)))

    return ImpactRun(
        tail,
        ball,
        peak(forces),
        peak(torques),
        peak(accs),
        units.m_to_mm(pen),
        warnings,
        v_touch,
        v_roll,
        contact_impulse,
        root_impulse,
        np.asarray(times),
        np.asarray(forces),
        tuple(sorted(touched)),
    )


def impact_table(runs: list[ImpactRun]) -> list[dict]:
    """One row per run, the paper's tip acceleration beside (Sec. IV-D: rod strikes, not balls;
    shown, never used)."""
    from ..parameters.paper import IMPACT_TIP_ACCELERATION

    return [
        {
            "tail": r.tail,
            "ball": r.ball,
            "peak_root_force_n": r.peak_root_force_n,
            "peak_root_torque_nm": r.peak_root_torque_nm,
            "peak_tip_acceleration_m_s2": r.peak_tip_acceleration_m_s2,
            "paper_tip_acceleration_m_s2": IMPACT_TIP_ACCELERATION.value,
            "tip_acceleration_minus_paper_m_s2": r.peak_tip_acceleration_m_s2
            - IMPACT_TIP_ACCELERATION.value,
            "max_penetration_mm": r.max_penetration_mm,
            "warnings": r.warnings,
            "ball_speed_m_s": r.ball_speed_at_contact_m_s,
            "rolling_speed_m_s": r.rolling_speed_m_s,
        }
        for r in runs
    ]
