"""What the models predict for each measured quantity
(:data:`bvsr_cad.parameters.measurements.QUANTITIES`).

One function per quantity, each from the models' one home: the statics
(Table III), the Eq 6-12 dynamics with the spec's supply (Eq 13 ramp or the
ISO 6358 valve), the workspace protocol run in time (in MuJoCo, given by
the caller as ``workspace_sim``), the root wrench of the whole tail,
and the cart of Eq 20-22. ``spec`` may carry fitted values
(``[calibration.fitted]``); the geometry comes from an assembly built once.

Conventions shared by every prediction (and stated in the data's sources):
the tail is mounted horizontally with gravity along -Y; a pulse pressurises
the lines on the side opposite the bend (extension: lines 3 and 4) and leaves
the others open; the quasi-static figures are at the lines' pressure limits
(``actuation.pressure_max_kpa`` and ``pressure_min_kpa``).
"""

from __future__ import annotations

import dataclasses
import threading
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .. import units
from ..assembly.assemble import Assembly, build_assembly
from ..assembly.bodies import moving_body
from ..assembly.pneumatic_lines import line_supply
from ..models.actuator import soa_force_law
from ..models.dynamics import (
    G_M_S2,
    TIP_OVER_COM,
    VELOCITY_WINDOW_DEG,
    JointModel,
    Trajectory,
    com_position_m,
    ramp_pa,
    simulate_joint,
)
from ..models.kinematics import joint_geometries
from ..models.platform import Platform, TailOnPlatform, platform_motion
from ..models.rod import rod_section
from ..models.statics import MOTION_PHI_RAD, pressure_pattern_kpa, quasi_static_segment
from ..parameters.measurements import Measurement
from ..parameters.tables import TailSpec
from .limits import theta_max_per_joint_rad
from .workspace import tail_statics

GRAVITY_M_S2 = np.array([0.0, -G_M_S2, 0.0])
PULSE_SECONDS = 0.3
EXPONENT_PRESSURES_BAR = (1.0, 2.0, 3.0, 4.0, 5.0, 6.0)


def pulse_places(motion: str) -> tuple[int, ...]:
    """The SOA places (= line numbers) a pulse pressurises for a motion: those opposite the bend."""
    pattern = pressure_pattern_kpa(MOTION_PHI_RAD[motion], -1.0, 1.0)
    return tuple(int(i) + 1 for i in np.nonzero(pattern > 0)[0])


#: The workspace protocol run in time: (assembly, spec of the same geometry, the joints' limits in
#: rad) -> the tip's largest lateral excursion from its rest point, mm. It needs the robot model in
#: a simulator, so the layers that can build one give it
#: (:func:`bvsr_cad.simulation.sim.protocol_radius_mm`).
WorkspaceSim = Callable[[Assembly, TailSpec, list[float]], float]


class NeedsSimulator(ValueError):
    """A quantity asked of a Predictor made without the simulator it needs (a caller's mistake)."""


class _Locks:
    """One lock per memo entry, so that threads asking for the same entry make it once."""

    def __init__(self) -> None:
        self._guard = threading.Lock()
        self._locks: dict[tuple[int, object], threading.Lock] = {}

    def once(self, store: dict, key: object, make: Callable[[], object]):
        """``store[key]``, made by ``make()`` if absent (by one thread; the others wait for it)."""
        with self._guard:
            lock = self._locks.setdefault((id(store), key), threading.Lock())
        with lock:
            if key not in store:
                store[key] = make()
            return store[key]


@dataclass
class Predictor:
    """Predictions for one tail geometry; ``spec`` (same geometry) may change between calls.

    ``workspace_sim`` predicts the measured tip workspace (:data:`WorkspaceSim`); without it that
    quantity raises :class:`NeedsSimulator`."""

    asm: Assembly
    spec: TailSpec
    workspace_sim: WorkspaceSim | None = None
    _other: dict = field(default_factory=dict)  # assemblies of variants (e.g. more segments)
    _limits: dict = field(
        default_factory=dict
    )  # segments -> the joints' limits (geometry only), rad
    #: Predictions may run in threads (:func:`bvsr_cad.analysis.calibrate.compare_rows`): each memo
    #: entry is made once, under its own lock; shared with the Predictors of other specs
    #: (``with_spec``).
    _locks: _Locks = field(default_factory=lambda: _Locks(), repr=False)

    @classmethod
    def from_spec(cls, spec: TailSpec, workspace_sim: WorkspaceSim | None = None) -> Predictor:
        return cls(build_assembly(spec), spec, workspace_sim)

    def with_spec(self, spec: TailSpec) -> Predictor:
        return Predictor(
            self.asm, spec, self.workspace_sim, self._other, self._limits, _locks=self._locks
        )

    def known_limits(self, theta_max_rad: list[float] | Callable[[], list[float]]) -> None:
        """The joints' limits of this geometry where a build has them (saves a clearance analysis),
        or what gives them when a prediction first needs them (a build computing them beside)."""
        self._limits[self.spec.segments] = (
            theta_max_rad if callable(theta_max_rad) else list(theta_max_rad)
        )

    # -- building blocks ---------------------------------------------------
    def joint_model(self, first_joint: int, n_joints: int, payload_g: float = 0.0) -> JointModel:
        spec = self.spec
        body = moving_body(self.asm, first_joint, n_joints)
        # on the arc's end: the last panel's distal face
        body = body.with_tip_mass(units.g_to_kg(payload_g))
        geoms = joint_geometries(spec)[first_joint - 1 : first_joint - 1 + n_joints]
        rod = rod_section(spec).bending_stiffness_nm_per_rad(spec.joint.gap_mm)
        return JointModel(geoms, soa_force_law(spec), rod, body, GRAVITY_M_S2)

    def pulse(
        self,
        model: JointModel,
        motion: str,
        pressure_bar: float,
        seconds: float = PULSE_SECONDS,
        stop_angle_deg: float | None = None,
    ) -> Trajectory:
        """The model's response to a pulse at ``pressure_bar`` (gauge) through the spec's supply."""
        spec = self.spec
        places = pulse_places(motion)
        p0 = pressure_bar * units.PA_PER_BAR
        phi = MOTION_PHI_RAD[motion]
        if spec.pneumatics.model == "ramp":
            t0 = spec.fitted("ramp_time_s", spec.pneumatics.ramp_time_s)
            mask = np.array([i + 1 in places for i in range(5)], float)
            return simulate_joint(
                model,
                lambda t: mask * ramp_pa(t, p0, t0),
                seconds,
                phi0_rad=phi,
                stop_angle_deg=stop_angle_deg,
            )
        supply = line_supply(self.asm, 1, places, p0, spec)
        return simulate_joint(
            model, None, seconds, phi0_rad=phi, supply=supply, stop_angle_deg=stop_angle_deg
        )

    def segment_pulse(self, motion: str, pressure_bar: float) -> Trajectory:
        model = self.joint_model(1, self.spec.joints_per_segment)
        return self.pulse(model, motion, pressure_bar, stop_angle_deg=VELOCITY_WINDOW_DEG)

    def tail_pulse(
        self, motion: str, pressure_bar: float, payload_g: float, seconds: float = PULSE_SECONDS
    ) -> tuple[JointModel, Trajectory]:
        model = self.joint_model(1, self.spec.joints, payload_g)
        return model, self.pulse(model, motion, pressure_bar, seconds)

    # -- quantities ----------------------------------------------------------
    def segment_max_angle(self, motion: str) -> float:
        return self.quasi_static(motion).max_angle_deg

    def segment_blocked_force(self, motion: str) -> float:
        return self.quasi_static(motion).blocked_force_n

    def quasi_static(self, motion: str):
        st = tail_statics(self.asm, spec=self.spec).first_segment()
        return quasi_static_segment(st, motion)

    def soa_stiffness(self, pressure_kpa: float) -> float:
        return float(soa_force_law(self.spec).stiffness_n_per_m(units.kpa_to_pa(pressure_kpa)))

    def segment_peak_velocity(self, motion: str, pressure_bar: float) -> float:
        return self.segment_pulse(motion, pressure_bar).peak_velocity_deg_s()

    def _exponent(
        self, motion: str, lo: float, hi: float, what: Callable[[Trajectory], float]
    ) -> float:
        pressures = [p for p in EXPONENT_PRESSURES_BAR if lo - 1e-9 <= p <= hi + 1e-9]
        values = np.array([what(self.segment_pulse(motion, p)) for p in pressures])
        ok = np.isfinite(values) & (values > 0)
        if ok.sum() < 2:
            return float("nan")
        return float(np.polyfit(np.log(np.array(pressures)[ok]), np.log(values[ok]), 1)[0])

    def velocity_pressure_exponent(
        self, motion: str, pressure_min_bar: float, pressure_max_bar: float
    ) -> float:
        return self._exponent(
            motion, pressure_min_bar, pressure_max_bar, lambda tr: tr.peak_velocity_deg_s()
        )

    def time_pressure_exponent(
        self, motion: str, pressure_min_bar: float, pressure_max_bar: float
    ) -> float:
        return self._exponent(
            motion, pressure_min_bar, pressure_max_bar, lambda tr: tr.time_to_deg_s()
        )

    def tip_workspace_radius(
        self, segments: float, pressurised_max_kpa_abs: float, depressurised_min_kpa_abs: float
    ) -> float:
        """The paper's workspace experiment (Sec. IV-A-5) run in time: the tail horizontal, a new
        random pressure per line every ``actuation.workspace_cycle_s``, the tip recorded throughout
        (its transients included, as motion capture records them); the largest lateral distance from
        rest."""
        if self.workspace_sim is None:
            raise NeedsSimulator(
                "tip_workspace_radius needs the workspace protocol simulated in time: make the "
                "Predictor with workspace_sim=bvsr_cad.simulation.sim.protocol_radius_mm"
            )
        spec = dataclasses.replace(
            self.spec,
            segments=int(segments),
            actuation=dataclasses.replace(
                self.spec.actuation,
                workspace_pressurised_max_kpa_abs=pressurised_max_kpa_abs,
                workspace_depressurised_min_kpa_abs=depressurised_min_kpa_abs,
            ),
        )
        asm, limits = self.workspace_geometry(int(segments))
        return float(self.workspace_sim(asm, spec, limits))

    def workspace_geometry(self, segments: int) -> tuple[Assembly, list[float]]:
        """(the assembly, its joints' limits) of this tail with ``segments`` segments: what the
        workspace protocol is simulated on (made once, by the first thread that asks; limits given
        by :meth:`known_limits` may still be computing elsewhere, and are waited for)."""
        once = self._locks.once
        asm = (
            self.asm
            if segments == self.spec.segments
            else once(
                self._other,
                segments,
                lambda: build_assembly(dataclasses.replace(self.spec, segments=segments)),
            )
        )
        limits = once(self._limits, segments, lambda: theta_max_per_joint_rad(asm))
        if callable(limits):  # given by known_limits, still to come
            limits = list(limits())
        return asm, limits

    def prepare(self, m: Measurement) -> None:
        """What :meth:`predict` of ``m`` computes in Python before it simulates in C (the workspace
        protocol's geometry and joint limits), so that a caller can let the rest wait for it."""
        if m.quantity == "tip_workspace_radius":
            self.workspace_geometry(int(dict(m.conditions)["segments"]))

    def root_wrench(
        self, motion: str, pressure_bar: float, payload_g: float
    ) -> tuple[float, float]:
        """(peak force N, peak torque N m) at the root sensor (the root panel's proximal face),
        tared."""
        model, tr = self.tail_pulse(motion, pressure_bar, payload_g)
        body = model.body
        big = model.n * tr.theta_rad
        pos = np.array([com_position_m(body, ph, th) for ph, th in zip(tr.phi_rad, big)])
        tip = TIP_OVER_COM * pos  # the payload, a point mass at the arc's end (tip_position_m)

        def second_derivative(x: np.ndarray) -> np.ndarray:
            return np.gradient(np.gradient(x, tr.time_s, axis=0), tr.time_s, axis=0)

        force_body = body.mass_kg * second_derivative(pos)
        force_tip = body.tip_mass_kg * second_derivative(tip)
        # The sensor sits under the root panel: its face is the panel's thickness below the base
        # face.
        face = np.array([0.0, 0.0, units.mm_to_m(self.spec.joint.panel_thickness_mm)])
        ang_acc = np.gradient(np.gradient(big / 2.0, tr.time_s), tr.time_s)
        torque = np.cross(pos + face, force_body) + np.cross(tip + face, force_tip)
        normal = np.stack([-np.sin(tr.phi_rad), np.cos(tr.phi_rad), np.zeros_like(tr.phi_rad)], -1)
        torque = torque + body.inertia_theta_kg_m2 * ang_acc[:, None] * normal
        force = force_body + force_tip
        return float(np.max(np.linalg.norm(force, axis=1))), float(
            np.max(np.linalg.norm(torque, axis=1))
        )

    def root_peak_force(self, pressure_bar: float, payload_g: float, motion: str) -> float:
        return self.root_wrench(motion, pressure_bar, payload_g)[0]

    def root_peak_torque(self, pressure_bar: float, payload_g: float, motion: str) -> float:
        return self.root_wrench(motion, pressure_bar, payload_g)[1]

    def cart_motion(self, pressure_bar: float, motion: str):
        cart = self.spec.cart
        model, tr = self.tail_pulse(motion, pressure_bar, 0.0, seconds=0.5)
        body = model.body
        tail = TailOnPlatform(
            body.mass_kg,
            body.inertia_theta_kg_m2,
            cart.tail_mount_behind_hinge_m + body.arc_length_m / 2,
        )
        depth = cart.width_m if motion == "waggle" else 0.0
        platform = Platform(
            cart.mass_kg,
            cart.mass_kg * (cart.length_m**2 + depth**2) / 12,
            cart.length_m / 2,
            cart.length_m,
        )
        beta = (
            model.n * tr.theta_rad / 2.0
        )  # the tail's body turns by half its bending angle (Eq 7)
        return platform, platform_motion(
            platform, tail, tr.time_s, beta, gravity=motion != "waggle"
        )

    def cart_lift(self, pressure_bar: float, motion: str) -> float:
        platform, result = self.cart_motion(pressure_bar, motion)
        return result.lift_mm(platform.wheelbase_m)

    def cart_peak_angle(self, pressure_bar: float, motion: str) -> float:
        return self.cart_motion(pressure_bar, motion)[1].peak_angle_deg

    def predict(self, m: Measurement) -> float:
        """The model's value of a measurement's quantity under its conditions."""
        return float(getattr(self, m.quantity)(**dict(m.conditions)))


__all__ = ["Predictor", "NeedsSimulator", "WorkspaceSim", "pulse_places", "GRAVITY_M_S2"]
