"""The paper's Euler-Lagrange model of a BVSR joint (Eq 6-12), for one joint and for a segment.

Generalised coordinates q = [phi, theta] (bending plane, bending angle). The
moving part is one rigid body whose centre of mass sits on the chord at
d = (L / theta) sin(theta / 2) from the base and which turns by theta / 2
(Fig. 2b). A tip payload m_p is a point mass at the arc's end, p_tip = 2 p_com
(the chord's end): it adds 4 m_p to m in Eq 7's translational terms (and so to Eq 8)
and 2 m_p to m in the gravity potential. Then, in SI,

    M(q) q'' + c(q, q') + D(q) q' + G(q) = K(q),                       (Eq 6)

    M = diag(I_phi + m L^2 sin^2(theta/2) / theta^2,                                     (Eq 7)
             I_theta / 4 + m L^2 (theta^2 - 2 theta sin theta - 2 cos theta + 2) / (4 theta^4))

    c = [M_phi' phi' theta',  M_theta' theta'^2 / 2 - M_phi' phi'^2 / 2]   (Eq 8: the Christoffel
        terms of M; ' on M is d/dtheta; :func:`paper_coriolis` is Eq 8 as printed, for the tests)
    K = J^T F - [0, (E I / L) theta],  F = P A - (m_a P + n_a) dl           (Eq 3-4, 10)
    D = c_a J^T J                                                        (Eq 11-12)

with J = dl/dq (5 x 2), the SOA lengths of Eq 1 from the joint's real socket
geometry (:mod:`bvsr_cad.models.kinematics`), and the SOA force law of
:mod:`bvsr_cad.models.actuator` and the rod of :mod:`bvsr_cad.models.rod`
(each quantity's one home). As in the statics, the actuators' generalised
force is J^T F by virtual work; the paper's J^T F r with J = dq/dl is not
dimensionally consistent.

Gravity (Eq 9) is derived here from the body's height for a tail mounted
horizontally with gravity along the base frame's -Y (the mount of the paper's
experiments); Eq 9 as printed assumes another mount and is not reused.

A *segment* of n joints is the same model with all its joints bending
together (the paper's "equivalent single continuum", Sec. II-D): q is the
joint's (phi, theta), the segment bends by n theta, the body is the whole
distal part of the segment on the segment's arc of length n H_j, and the
joints' actuator, rod and damper terms add up (each joint's own socket
geometry, taper included).

Pressure reaches the model as a function of time: the paper's Eq 13 ramp
(:func:`ramp_pa`) or the pneumatic supply of :mod:`bvsr_cad.models.pneumatics`,
whose chamber pressures are integrated with the motion.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from .. import units
from .actuator import SoaForceLaw
from .kinematics import JointGeometry, socket_lengths_and_jacobian

#: Standard gravity, m/s^2.
G_M_S2 = units.STANDARD_GRAVITY_M_S2
#: The arc's end over the body's centre of mass: the chord is 2 (L / theta) sin(theta / 2) along the
#: direction theta / 2, and the centre of mass sits at its midpoint (Eq 7's premise), so p_tip = 2
#: p_com.
TIP_OVER_COM = 2.0
#: The paper measures a segment's peak velocity before its angle passes this (Sec. IV-A-3).
VELOCITY_WINDOW_DEG = 38.0


def ramp_pa(t_s, p0_pa: float, t0_s: float):
    """Eq 13: P(t) = P0 t^2 (3 / t0^2 - 2 t / t0^3) for 0 < t < t0, then P0 (and 0 before 0)."""
    t = np.clip(np.asarray(t_s, float), 0.0, t0_s)
    return p0_pa * t * t * (3.0 / t0_s**2 - 2.0 * t / t0_s**3)


@dataclass(frozen=True)
class RigidBody:
    """The moving body of Fig. 2b: mass, inertias about its centre of mass, arc length it rides on,
    and a point mass at the arc's end (a tip payload)."""

    mass_kg: float
    inertia_phi_kg_m2: float  # about the tail axis
    inertia_theta_kg_m2: float  # about an axis normal to the bending plane
    arc_length_m: float  # L of Eq 7-9 (one joint: H_a; a segment: its whole bending length)
    tip_mass_kg: float = (
        0.0  # m_p, a point mass at the arc's end: TIP_OVER_COM times the body's p_com
    )

    def with_tip_mass(self, mass_kg: float) -> RigidBody:
        """This body with a point mass ``mass_kg`` added at the end of its arc (a tip payload)."""
        if mass_kg < 0:
            raise ValueError(f"tip payload mass_kg = {mass_kg}: allowed >= 0")
        if mass_kg == 0:
            return self
        return replace(self, tip_mass_kg=self.tip_mass_kg + mass_kg)

    @property
    def total_mass_kg(self) -> float:
        """The body with its tip payload."""
        return self.mass_kg + self.tip_mass_kg

    @property
    def translational_mass_kg(self) -> float:
        """The mass that multiplies |p_com'|^2 / 2 in the kinetic energy: the tip moves at
        TIP_OVER_COM times the centre of mass's velocity."""
        return self.mass_kg + TIP_OVER_COM**2 * self.tip_mass_kg

    @property
    def gravity_mass_kg(self) -> float:
        """The mass that multiplies -g . p_com in the potential (the tip is at TIP_OVER_COM
        p_com)."""
        return self.mass_kg + TIP_OVER_COM * self.tip_mass_kg


def _chord_factor(theta: float) -> float:
    """sin(theta/2) / theta, with its series near 0 (d = L * this)."""
    if abs(theta) < 1e-4:
        return 0.5 - theta**2 / 48.0
    return math.sin(theta / 2.0) / theta


def _m_theta_factor(theta: float) -> float:
    """(theta^2 - 2 theta sin theta - 2 cos theta + 2) / (4 theta^4), with its series near 0."""
    if abs(theta) < 2e-2:
        return 1.0 / 16.0 - theta**2 / 288.0
    return (theta**2 - 2 * theta * math.sin(theta) - 2 * math.cos(theta) + 2) / (4 * theta**4)


def _mass_diagonal(body: RigidBody, theta: float) -> tuple[float, float]:
    """Eq 7's diagonal (M_phi, M_theta) as floats (the integrators' right-hand sides ask for it
    thousands of times a run: no array per call)."""
    L, m = body.arc_length_m, body.translational_mass_kg
    m_phi = body.inertia_phi_kg_m2 + m * (L * _chord_factor(theta)) ** 2
    m_theta = body.inertia_theta_kg_m2 / 4.0 + m * L**2 * _m_theta_factor(theta)
    return m_phi, m_theta


def mass_matrix(body: RigidBody, theta: float) -> np.ndarray:
    """Eq 7 (diagonal)."""
    return np.diag(_mass_diagonal(body, theta))


def _mass_diagonal_derivative(
    body: RigidBody, theta: float, h: float = 1e-6
) -> tuple[float, float]:
    (a_phi, a_theta), (b_phi, b_theta) = (
        _mass_diagonal(body, theta + h),
        _mass_diagonal(body, theta - h),
    )
    return (a_phi - b_phi) / (2 * h), (a_theta - b_theta) / (2 * h)


def mass_matrix_derivative(body: RigidBody, theta: float, h: float = 1e-6) -> np.ndarray:
    """dM/dtheta by central differences of Eq 7 (M is smooth and even in theta)."""
    return np.diag(_mass_diagonal_derivative(body, theta, h))


def _coriolis_terms(
    body: RigidBody, theta: float, phi_dot: float, theta_dot: float
) -> tuple[float, float]:
    dm_phi, dm_theta = _mass_diagonal_derivative(body, theta)
    return dm_phi * phi_dot * theta_dot, 0.5 * dm_theta * theta_dot**2 - 0.5 * dm_phi * phi_dot**2


def coriolis(body: RigidBody, theta: float, phi_dot: float, theta_dot: float) -> np.ndarray:
    """c(q, q') of Eq 6 as the Christoffel terms of Eq 7's M (so energy is conserved without
    damping and forcing)."""
    return np.array(_coriolis_terms(body, theta, phi_dot, theta_dot))


def paper_coriolis(body: RigidBody, theta: float, phi_dot: float, theta_dot: float) -> np.ndarray:
    """Eq 8 exactly as printed (the I_theta term of M has no theta-dependence, so it drops out),
    with m the mass of Eq 7's translational terms (a tip payload enters them as TIP_OVER_COM^2
    m_p)."""
    L, m = body.arc_length_m, body.translational_mass_kg
    s2, c2 = math.sin(theta / 2), math.cos(theta / 2)
    a = m * L**2 / theta**3 * (theta / 2 * math.sin(theta) - 2 * s2**2)
    b = m * L**2 / theta**5 * (theta * math.sin(theta) - 2 * s2**2 - theta**2 / 2 * c2**2)
    return np.array([a * phi_dot * theta_dot, b * theta_dot**2 - a / 2 * phi_dot**2])


def com_position_m(body: RigidBody, phi: float, theta: float) -> np.ndarray:
    """The body's centre of mass in the base frame: on the chord, d from the base (Eq 6's
    premise)."""
    return np.array(_com_position(body, phi, theta))


def _com_position(body: RigidBody, phi: float, theta: float) -> tuple[float, float, float]:
    d = body.arc_length_m * _chord_factor(theta)
    s, c = math.sin(theta / 2), math.cos(theta / 2)
    return d * (s * math.cos(phi)), d * (s * math.sin(phi)), d * c


def tip_position_m(body: RigidBody, phi: float, theta: float) -> np.ndarray:
    """The arc's end (where a tip payload sits) in the base frame: TIP_OVER_COM p_com."""
    return TIP_OVER_COM * com_position_m(body, phi, theta)


def gravity_force(
    body: RigidBody, phi: float, theta: float, gravity_m_s2: np.ndarray
) -> np.ndarray:
    """G(q) = dU/dq with U = -m g . p_com - m_p g . p_tip (central differences of the exact
    potential)."""
    return np.array(_gravity_terms(body, phi, theta, tuple(float(g) for g in gravity_m_s2)))


def _gravity_terms(
    body: RigidBody, phi: float, theta: float, gravity_m_s2: tuple[float, float, float]
) -> tuple[float, float]:
    """:func:`gravity_force` as floats."""
    gx, gy, gz = gravity_m_s2
    if gx == gy == gz == 0.0:
        return 0.0, 0.0
    m = body.gravity_mass_kg

    def potential(p_: float, t_: float) -> float:
        x, y, z = _com_position(body, p_, t_)
        return -m * (gx * x + gy * y + gz * z)

    h = 1e-7
    return (
        (potential(phi + h, theta) - potential(phi - h, theta)) / (2 * h),
        (potential(phi, theta + h) - potential(phi, theta - h)) / (2 * h),
    )


@dataclass(frozen=True)
class JointModel:
    """Eq 6-12 for n identical-in-motion joints (n = 1: one joint; n = joints per segment: a
    segment).

    ``joints`` are the socket geometries of the joints that bend together
    (mm, from :func:`bvsr_cad.models.kinematics.joint_geometries`); ``rod``
    is one joint's E I / L (N m/rad); ``body`` the moving rigid body.
    """

    joints: tuple[JointGeometry, ...]
    law: SoaForceLaw
    rod_nm_per_rad: float
    body: RigidBody
    gravity_m_s2: np.ndarray = field(default_factory=lambda: np.zeros(3))

    @property
    def n(self) -> int:
        return len(self.joints)

    def __post_init__(self) -> None:
        # Stacked socket centres (n, 5, 3) in m and the rest lengths: evaluated once, not per step.
        object.__setattr__(
            self, "_base_m", units.mm_to_m(np.stack([g.base_mm for g in self.joints]))
        )
        object.__setattr__(
            self, "_moving_m", units.mm_to_m(np.stack([g.moving_mm for g in self.joints]))
        )
        object.__setattr__(
            self, "_rest_m", units.mm_to_m(np.stack([g.rest_lengths_mm for g in self.joints]))
        )
        lengths = {g.length_mm for g in self.joints}
        if len(lengths) != 1:
            raise ValueError(
                f"joints that bend together need one arc length; got {sorted(lengths)} mm"
            )
        object.__setattr__(self, "_arc_m", units.mm_to_m(lengths.pop()))
        object.__setattr__(self, "_gravity", tuple(float(g) for g in self.gravity_m_s2))

    def soa_terms(self, phi: float, theta: float) -> tuple[np.ndarray, np.ndarray]:
        """Per joint: stretch dl (n, 5) in m and dl/dq (n, 5, 2) in m/rad, q = (phi, theta) (Eq
        1)."""
        u, v = theta * math.cos(phi), theta * math.sin(phi)
        length, jac_uv = socket_lengths_and_jacobian(
            self._base_m, self._moving_m, u, v, self._arc_m
        )
        duv = np.array([[-v, math.cos(phi)], [u, math.sin(phi)]])  # d(u, v)/d(phi, theta)
        return length - self._rest_m, jac_uv @ duv

    def generalized_forces(
        self,
        phi: float,
        theta: float,
        phi_dot: float,
        theta_dot: float,
        soa_pa: np.ndarray,
        terms: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> np.ndarray:
        """K(q) - D q' (Eq 10-12) summed over the joints, for gauge pressures (5,) or (n, 5), Pa.

        The joints share q, so their generalised forces add; expressed per joint
        coordinate (each joint turns by theta) the segment's equation is the sum.
        """
        dl, jac = self.soa_terms(phi, theta) if terms is None else terms
        p = np.broadcast_to(np.asarray(soa_pa, float), dl.shape)
        dl_dot = jac @ np.array([phi_dot, theta_dot])  # (n, 5)
        force = self.law.force_n(p, dl, dl_dot)
        q = np.einsum("jsi,js->i", jac, force)
        q[1] -= self.n * self.rod_nm_per_rad * theta
        return q

    def rhs(
        self,
        phi: float,
        theta: float,
        phi_dot: float,
        theta_dot: float,
        soa_pa: np.ndarray,
        terms: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> np.ndarray:
        """(phi'', theta'') of one joint coordinate.

        The body is described on the segment's coordinate Theta = n theta, so its
        inertia and gravity terms per joint coordinate carry the chain rule:
        M_theta scales with n^2 on theta (Theta' = n theta'), gravity with n.
        """
        n = self.n
        big = n * theta
        m_phi, m_theta = _mass_diagonal(self.body, big)
        cor_phi, cor_theta = _coriolis_terms(self.body, big, phi_dot, n * theta_dot)
        grav_phi, grav_theta = _gravity_terms(self.body, phi, big, self._gravity)
        q_phi, q_theta = self.generalized_forces(
            phi, theta, phi_dot, theta_dot, soa_pa, terms
        ).tolist()
        theta_acc = (q_theta - cor_theta * n - grav_theta * n) / (m_theta * n * n)
        if abs(theta) < 1e-9:  # phi is undefined at the straight pose: hold it
            return np.array([0.0, theta_acc])
        return np.array([(q_phi - cor_phi - grav_phi) / m_phi, theta_acc])


@dataclass
class Trajectory:
    """A solved motion: time (s), the joint's phi and theta (rad) and rates, the segment angle."""

    time_s: np.ndarray
    phi_rad: np.ndarray
    theta_rad: np.ndarray
    phi_rate_rad_s: np.ndarray
    theta_rate_rad_s: np.ndarray
    n_joints: int
    pressure_pa: np.ndarray  # (steps, 5) gauge pressure of the joint's SOAs

    @property
    def bend_angle_deg(self) -> np.ndarray:
        """The tilt of the distal panel: n theta."""
        return np.degrees(self.n_joints * self.theta_rad)

    @property
    def bend_rate_deg_s(self) -> np.ndarray:
        return np.degrees(self.n_joints * self.theta_rate_rad_s)

    def peak_velocity_deg_s(self, window_deg: float = VELOCITY_WINDOW_DEG) -> float:
        """Largest bending rate while the angle has not yet passed ``window_deg`` (the paper's
        measure)."""
        angle = np.abs(self.bend_angle_deg)
        passed = np.nonzero(angle > window_deg)[0]
        end = passed[0] if passed.size else angle.size
        return float(np.max(np.abs(self.bend_rate_deg_s[: max(end, 1)])))

    def time_to_deg_s(self, angle_deg: float = VELOCITY_WINDOW_DEG) -> float:
        """First time the bend angle reaches ``angle_deg`` (nan if never): the paper's motion time
        T."""
        idx = np.nonzero(np.abs(self.bend_angle_deg) >= angle_deg)[0]
        if not idx.size:
            return float("nan")
        i = idx[0]
        if i == 0:
            return float(self.time_s[0])
        a0, a1 = np.abs(self.bend_angle_deg[i - 1]), np.abs(self.bend_angle_deg[i])
        return float(
            self.time_s[i - 1]
            + (angle_deg - a0) / (a1 - a0) * (self.time_s[i] - self.time_s[i - 1])
        )


PressureInput = Callable[[float], np.ndarray]  # t (s) -> gauge Pa of the five SOAs


def simulate_joint(
    model: JointModel,
    pressure: PressureInput | None = None,
    seconds: float = 0.3,
    phi0_rad: float = 0.0,
    supply=None,
    sample_s: float = 2.5e-4,
    stop_angle_deg: float | None = None,
) -> Trajectory:
    """Integrate Eq 6 from rest with scipy (LSODA, rtol 1e-6; absolute tolerances per state's unit).

    Exactly one of ``pressure`` (a function of time: the Eq 13 ramp or any
    other trace) and ``supply`` (a :class:`bvsr_cad.models.pneumatics.LineSupply`,
    whose chamber pressures become part of the state) drives the SOAs.
    ``stop_angle_deg`` ends the run once the segment has bent 5 deg past it.
    """
    from scipy.integrate import solve_ivp

    if (pressure is None) == (supply is None):
        raise ValueError("give exactly one of pressure and supply")
    n_p = 0 if supply is None else supply.n_states
    # Start straight with the bending plane phi0 (held while theta = 0, see JointModel.rhs).
    y0 = np.concatenate(
        [[phi0_rad, 0.0, 0.0, 0.0], [] if supply is None else supply.initial_state()]
    )

    def soa_pressures(t: float, y: np.ndarray) -> np.ndarray:
        if supply is None:
            return np.asarray(pressure(t), float)
        return supply.soa_gauge_pa(y[4:])

    def f(t, y):
        phi, theta, dphi, dtheta = y[:4].tolist()
        p = soa_pressures(t, y)
        terms = model.soa_terms(phi, theta)
        acc = model.rhs(phi, theta, dphi, dtheta, p, terms)
        out = [dphi, dtheta, acc[0], acc[1]]
        if supply is not None:
            dl, jac = terms
            dl_dot = jac @ np.array([dphi, dtheta])
            out = np.concatenate([out, supply.state_rates(t, y[4:], dl, dl_dot)])
        return out

    events = None
    if stop_angle_deg is not None:

        def passed(t, y):
            return abs(model.n * y[1]) - math.radians(stop_angle_deg + 5.0)

        passed.terminal = True
        events = [passed]
    t_eval = np.arange(0.0, seconds + 0.5 * sample_s, sample_s)
    scale = np.concatenate([[1e-6, 1e-6, 1e-3, 1e-3], np.full(n_p, 1.0)])  # rad, rad/s, Pa
    sol = solve_ivp(
        f,
        (0.0, seconds),
        y0,
        method="LSODA",
        t_eval=t_eval,
        rtol=1e-6,
        atol=scale,
        max_step=2e-3,
        events=events,
    )
    if sol.status < 0:
        raise RuntimeError(f"Eq 6 integration failed: {sol.message}")
    y = sol.y
    p = np.array([soa_pressures(t, y[:, i]) for i, t in enumerate(sol.t)]).reshape(len(sol.t), -1)
    return Trajectory(sol.t, y[0], y[1], y[2], y[3], model.n, p)


__all__ = [
    "RigidBody",
    "JointModel",
    "Trajectory",
    "simulate_joint",
    "ramp_pa",
    "mass_matrix",
    "coriolis",
    "paper_coriolis",
    "gravity_force",
    "com_position_m",
    "tip_position_m",
    "TIP_OVER_COM",
    "G_M_S2",
    "VELOCITY_WINDOW_DEG",
]
