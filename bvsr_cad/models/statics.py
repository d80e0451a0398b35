"""Quasi-static model of the tail: Eq 3-5 with the rod moment of Eq 10 and gravity.

Units inside: N, mm, kg, kPa (gauge). An SOA pushes F_i = P_i A - k_i dl_i
(Eq 3) with k_i = m_a P_i + n_a (Eq 4, k in N/m with P in kPa, see
:class:`bvsr_cad.parameters.tables.Actuation`) and dl_i = l_i - l_i(0) from Eq 1.
Generalised forces use the joint's bending vector w = theta (cos phi, sin phi):
the actuators give tau = (dl/dw)^T F (virtual work; the paper's J_a^T F r is
not dimensionally consistent), the rod -E I w / L (Eq 10, I = pi d^4 / 64),
gravity and a tip force their virtual work through the chain.

The equilibrium residual r(w) = -tau_act + (E I / L) w - Q_loads is solved
by damped Newton (central-difference Hessian, vectorised over poses).

Inverse rule (Eq 5): five line pressures for two equations per joint. Each
segment's pose is the bending vector of its first (most loaded) joint; the
pressures are the least-norm gauge pressures (minimum sum of P_i^2, i.e. the
least pressurisation) within [pressure_min, pressure_max] that hold that
joint in equilibrium with its loads; the segment's other joints then settle
where those pressures put them. Without gravity or taper every joint of a
segment has the same pose.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .. import units
from ..parameters.tables import TailSpec
from .actuator import SoaForceLaw, soa_force_law
from .kinematics import (
    TailKinematics,
    soa_lengths_and_jacobian,
    theta_phi_from_uv,
    uv_from_theta_phi,
)
from .rod import joint_rod_stiffness_nmm_per_rad

#: Standard gravity, m/s^2 (N per kg).
G_N_PER_KG = units.STANDARD_GRAVITY_M_S2
#: The paper's motions as the bending-plane angle phi: towards +Y, -Y, +X.
MOTION_PHI_RAD = {"extension": math.pi / 2, "flexion": -math.pi / 2, "waggle": 0.0}
#: Forward statics' Newton keeps a sample's loads' Hessian (gravity, tip force: 2n evaluations of
#: every load) while its steps stay below this and shrink, computing it afresh otherwise: near the
#: solution the Hessian barely changes between steps, and each one costs those 2n evaluations. The
#: poses agree with the Newton that recomputes it at every step far inside the 1e-11 rad step both
#: stop at.
LOAD_HESSIAN_REUSE_BELOW_RAD = 1e-2


@dataclass(frozen=True)
class Actuator:
    """The SOA force law (:mod:`bvsr_cad.models.actuator`) in the statics' units (N, mm, kPa)
    with the pressure bounds of the lines."""

    law: SoaForceLaw
    pressure_min_kpa: float
    pressure_max_kpa: float

    @classmethod
    def from_spec(cls, spec: TailSpec, area_mm2: float | None = None) -> Actuator:
        law = soa_force_law(spec)
        if area_mm2 is not None:
            law = replace(law, area_m2=units.mm2_to_m2(area_mm2))
        return cls(law, spec.actuation.pressure_min_kpa, spec.actuation.pressure_max_kpa)

    @property
    def area_mm2(self) -> float:
        return self.law.area_m2 * units.MM_PER_M**2

    @property
    def newton_per_kpa(self) -> float:
        """P A in N for 1 kPa on A."""
        return float(self.law.force_n(units.PA_PER_KPA, 0.0))

    @property
    def slope_n_per_mm_per_kpa(self) -> float:
        """m_a in N/mm per kPa."""
        return self.law.stiffness_slope_n_per_m_per_pa * units.PA_PER_KPA / units.MM_PER_M

    @property
    def offset_n_per_mm(self) -> float:
        """n_a in N/mm."""
        return self.law.stiffness_offset_n_per_m / units.MM_PER_M

    def force_n(self, pressure_kpa: np.ndarray, dl_mm: np.ndarray) -> np.ndarray:
        """Eq 3: F = P A - (m_a P + n_a) dl."""
        return self.law.force_n(units.kpa_to_pa(pressure_kpa), units.mm_to_m(dl_mm))


@dataclass(frozen=True)
class LumpedMasses:
    """Masses for gravity: panel k at its mid-thickness, joint k (its SOAs and the
    rod in the gap) at the chord midpoint of its arc (the paper's d = (L/theta) sin(theta/2))."""

    panel_kg: np.ndarray  # (n_joints + 1,)
    joint_kg: np.ndarray  # (n_joints,)


@dataclass(frozen=True)
class TailStatics:
    """Equilibrium of the tail for given line pressures, gravity along -Y and a tip force."""

    kin: TailKinematics
    act: Actuator
    rod_nmm_per_rad: float
    masses: LumpedMasses | None = None  # None: no gravity

    @classmethod
    def from_spec(
        cls, spec: TailSpec, masses: LumpedMasses | None = None, area_mm2: float | None = None
    ) -> TailStatics:
        return cls(
            TailKinematics.from_spec(spec),
            Actuator.from_spec(spec, area_mm2),
            joint_rod_stiffness_nmm_per_rad(spec),
            masses,
        )

    def first_segment(self) -> TailStatics:
        """One standalone segment (the paper's Table III specimen): the first three joints."""
        j = self.kin.joints_per_segment
        kin = TailKinematics(self.kin.joints[:j], self.kin.panel_thickness_mm, j)
        m = (
            None
            if self.masses is None
            else LumpedMasses(self.masses.panel_kg[: j + 1], self.masses.joint_kg[:j])
        )
        return TailStatics(kin, self.act, self.rod_nmm_per_rad, m)

    # -- generalised forces -------------------------------------------------
    def _actuator_terms(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """dl (..., n_joints, 5) and dl/dw (..., n_joints, 5, 2)."""
        dls, jacs = [], []
        for k, g in enumerate(self.kin.joints):
            length, jac = soa_lengths_and_jacobian(g, w[..., k, 0], w[..., k, 1])
            dls.append(length - g.rest_lengths_mm)
            jacs.append(jac)
        return np.stack(dls, -2), np.stack(jacs, -3)

    def load_forces(self, w: np.ndarray, tip_force_n: np.ndarray | None) -> np.ndarray:
        """Generalised forces of gravity and the tip force on every joint, (..., n_joints, 2), N
        mm."""
        from .kinematics import joint_transform_and_derivatives

        w = np.asarray(w, float)
        n = self.kin.n_joints
        base, panel = self.kin.frames(w)
        t = self.kin.panel_thickness_mm
        lead = w.shape[:-2]
        # Bodies: forces f (tail frame, N) at points x; suffix sums give what hangs distal of each
        # joint.
        f_panel = np.zeros(lead + (n + 1, 3))
        f_joint = np.zeros(lead + (n, 3))
        f_tip = np.zeros(lead + (3,))
        x_panel = panel[..., :3, 3] + 0.5 * t * panel[..., :3, 2]
        (rot_all, p_all), (dR_u, dR_v, dp_u, dp_v) = joint_transform_and_derivatives(
            w[..., 0], w[..., 1], self.kin.length_mm
        )
        b_rot, b_org = base[..., :3, :3], base[..., :3, 3]
        x_joint = b_org + 0.5 * np.einsum("...ij,...j->...i", b_rot, p_all)
        if self.masses is not None:
            down = np.array([0.0, -G_N_PER_KG, 0.0])
            f_panel = f_panel + self.masses.panel_kg[:, None] * down
            f_joint = f_joint + self.masses.joint_kg[:, None] * down
        if tip_force_n is not None:
            f_tip = f_tip + np.asarray(tip_force_n, float)
        x_tip = panel[..., -1, :3, 3] + t * panel[..., -1, :3, 2]
        # Distal of joint k (0-based): panels k+1.., joint masses k+1.., the tip.
        fs_p = np.flip(
            np.cumsum(np.flip(f_panel[..., 1:, :], -2), -2), -2
        )  # index k: panels k+1..n
        fx_p = np.flip(
            np.cumsum(
                np.flip(
                    np.einsum("...i,...j->...ij", f_panel[..., 1:, :], x_panel[..., 1:, :]), -3
                ),
                -3,
            ),
            -3,
        )
        fj_x = np.einsum("...i,...j->...ij", f_joint, x_joint)
        fs_j = np.flip(np.cumsum(np.flip(f_joint, -2), -2), -2) - f_joint  # joints k+1..n
        fx_j = np.flip(np.cumsum(np.flip(fj_x, -3), -3), -3) - fj_x
        fs = fs_p + fs_j + f_tip[..., None, :]
        fx = fx_p + fx_j + np.einsum("...i,...j->...ij", f_tip, x_tip)[..., None, :, :]
        bt = np.swapaxes(b_rot, -1, -2)
        # G = sum_b g_b y_b^T with g_b = B_R^T f_b, y_b = B_R^T (x_b - B_o) - p.
        g_mat = bt @ (fx - np.einsum("...i,...j->...ij", fs, b_org)) @ b_rot - np.einsum(
            "...i,...j->...ij", np.einsum("...ij,...j->...i", bt, fs), p_all
        )
        gs = np.einsum("...ij,...j->...i", bt, fs)
        own = np.einsum("...ij,...j->...i", bt, f_joint) * 0.5
        rt = np.swapaxes(rot_all, -1, -2)
        q = []
        for d_rot, d_p in ((dR_u, dp_u), (dR_v, dp_v)):
            a_mat = d_rot @ rt
            q.append(np.sum(a_mat * g_mat, (-1, -2)) + np.sum((gs + own) * d_p, -1))
        return np.stack(q, -1)

    def residual(
        self, w: np.ndarray, line_kpa: np.ndarray, tip_force_n: np.ndarray | None = None
    ) -> np.ndarray:
        """dV/dw: zero at equilibrium. ``line_kpa`` (..., n_segments, 5) gauge."""
        w = np.asarray(w, float)
        p_joint = np.repeat(np.asarray(line_kpa, float), self.kin.joints_per_segment, axis=-2)
        return (
            self._actuator_residual(w, p_joint)
            + self.rod_nmm_per_rad * w
            - self.load_forces(w, tip_force_n)
        )

    def _actuator_residual(self, w: np.ndarray, p_joint: np.ndarray) -> np.ndarray:
        """-tau_act (..., n_joints, 2) for per-joint pressures (..., n_joints, 5): joint k's term
        reads w_k only."""
        dl, jac = self._actuator_terms(w)
        return -np.einsum("...si,...s->...i", jac, self.act.force_n(p_joint, dl))

    def _hessian(
        self,
        w: np.ndarray,
        p_joint: np.ndarray,
        tip_force_n: np.ndarray | None,
        q0: np.ndarray,
        h: float = 1e-6,
        loads: np.ndarray | None = None,
    ) -> np.ndarray:
        """d(residual)/dw (m, 2n, 2n) at poses ``w`` (m, n, 2) (rows: residual component), by
        differences that follow the residual's structure: the actuator term of joint k reads w_k
        only, so its 2 x 2 blocks come from perturbing every joint at once along u, then v (central
        differences, 4 evaluations); the rod term is E I / L exactly; the loads (gravity, tip force)
        couple every joint and take forward differences from ``q0`` = their value at ``w`` (2n
        evaluations), or are ``loads`` when given (:meth:`_load_hessian` of nearby poses)."""
        m, n = w.shape[0], self.kin.n_joints
        dirs = (np.eye(2) * h)[None, :, None, :]  # (1, direction, 1, component)
        pj = p_joint[:, None]
        act = (
            self._actuator_residual(w[:, None] + dirs, pj)
            - self._actuator_residual(w[:, None] - dirs, pj)
        ) / (2 * h)  # (m, direction, joint, component)
        hess = np.zeros((m, n, 2, n, 2))
        for k in range(n):
            hess[:, k, :, k, :] = np.swapaxes(act[:, :, k, :], -1, -2)
        hess = hess.reshape((m, 2 * n, 2 * n)) + self.rod_nmm_per_rad * np.eye(2 * n)
        if loads is not None:
            return hess + loads
        if self.masses is not None or tip_force_n is not None:
            hess = hess + self._load_hessian(w, tip_force_n, q0, h)
        return hess

    def _load_hessian(
        self, w: np.ndarray, tip_force_n: np.ndarray | None, q0: np.ndarray, h: float = 1e-6
    ) -> np.ndarray:
        """The loads' part of :meth:`_hessian` (m, 2n, 2n): -d(load forces)/dw by forward
        differences."""
        m, n = w.shape[0], self.kin.n_joints
        pert = (np.eye(2 * n) * h).reshape(2 * n, n, 2)
        fk = (
            tip_force_n[:, None, :]
            if tip_force_n is not None and np.ndim(tip_force_n) > 1
            else tip_force_n
        )
        dq = (self.load_forces(w[:, None] + pert, fk) - q0[:, None]).reshape((m, 2 * n, 2 * n)) / h
        return -np.swapaxes(dq, -1, -2)

    # -- forward map ---------------------------------------------------------
    def forward(
        self,
        line_kpa: np.ndarray,
        tip_force_n: np.ndarray | None = None,
        w0: np.ndarray | None = None,
        fixed: np.ndarray | None = None,
        tol_rad: float = 1e-11,
        max_iter: int = 60,
    ) -> np.ndarray:
        """Equilibrium bending vectors (..., n_joints, 2) for line pressures (..., n_segments, 5).

        Args:
            line_kpa: gauge pressures of every line.
            tip_force_n: force on the tip point (tail frame, N).
            w0: start (and the values of ``fixed`` joints); zeros by default.
            fixed: boolean (n_joints,) of joints held at ``w0``.

        Raises:
            RuntimeError: Newton did not converge (a pressure set beyond the model's range).
        """
        n = self.kin.n_joints
        free = np.ones(2 * n, bool) if fixed is None else ~np.repeat(np.asarray(fixed, bool), 2)
        # Newton on the samples still moving only: one sample's slow convergence costs only itself.
        w, flat_w, flat_p, force, per_sample = self._samples(line_kpa, tip_force_n, w0)
        count = flat_w.shape[0]
        active = np.arange(count)
        last = 0.0
        loaded = self.masses is not None or tip_force_n is not None
        # The loads' Hessian of each sample, kept while its steps are small and shrinking (the loads
        # vary slowly with the pose: the steps after them converge as fast, each without its 2n
        # evaluations).
        loads = np.zeros((count, 2 * n, 2 * n)) if loaded else None
        reuse = np.zeros(count, bool)
        step_was = np.full(count, np.inf)
        for _ in range(max_iter):
            wa, pa = flat_w[active], flat_p[active]
            fa = force[active] if per_sample else force
            pj = np.repeat(pa, self.kin.joints_per_segment, axis=-2)
            q0 = self.load_forces(wa, fa)
            if loaded:
                fresh = np.nonzero(~reuse[active])[0]
                if fresh.size:
                    loads[active[fresh]] = self._load_hessian(
                        wa[fresh], fa[fresh] if per_sample else fa, q0[fresh]
                    )
            step = self._newton_step(wa, pj, fa, q0, free, loads[active] if loaded else None)
            flat_w[active] = wa + step.reshape(wa.shape)
            size = np.max(np.abs(step), -1)
            reuse[active] = (size < LOAD_HESSIAN_REUSE_BELOW_RAD) & (size < step_was[active])
            step_was[active] = size
            moving = size >= tol_rad
            last = float(np.max(np.abs(step))) if step.size else 0.0
            active = active[moving]
            if active.size == 0:
                return flat_w.reshape(w.shape)
        if last < 1e-8:
            return flat_w.reshape(w.shape)
        raise RuntimeError(f"forward statics did not converge (last step {last:.2e} rad)")

    def _samples(
        self, line_kpa: np.ndarray, tip_force_n: np.ndarray | None, w0: np.ndarray | None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None, bool]:
        """The pressure sets (..., n_segments, 5) on one sample axis: the start poses w (...,
        n_joints, 2) from ``w0`` (zeros by default) and their flat view (count, n_joints, 2), the
        pressures (count, n_segments, 5), the tip force (count, 3) and True where it is given per
        sample, else as given and False."""
        line_kpa = np.asarray(line_kpa, float)
        lead = line_kpa.shape[:-2]
        n = self.kin.n_joints
        w = (
            np.zeros(lead + (n, 2))
            if w0 is None
            else np.array(np.broadcast_to(w0, lead + (n, 2)), float)
        )
        count = int(np.prod(lead, dtype=int))
        flat_w = w.reshape((count, n, 2))
        flat_p = np.broadcast_to(line_kpa, lead + line_kpa.shape[-2:]).reshape(
            (count,) + line_kpa.shape[-2:]
        )
        force = None if tip_force_n is None else np.asarray(tip_force_n, float)
        per_sample = force is not None and force.ndim > 1
        if per_sample:
            force = np.broadcast_to(force, lead + (3,)).reshape((count, 3))
        return w, flat_w, flat_p, force, per_sample

    def _newton_step(
        self,
        w: np.ndarray,
        p_joint: np.ndarray,
        tip_force_n: np.ndarray | None,
        q0: np.ndarray,
        free: np.ndarray,
        loads: np.ndarray | None,
    ) -> np.ndarray:
        """One Newton step (m, 2n) of the poses ``w`` (m, n, 2) towards equilibrium, in the
        ``free`` components only (a held one steps 0), at most 0.2 rad in any component. ``q0``:
        the load forces at ``w``; ``loads``: the loads' Hessian where kept (:meth:`_hessian`)."""
        n = self.kin.n_joints
        r = (self._actuator_residual(w, p_joint) + self.rod_nmm_per_rad * w - q0).reshape(
            (w.shape[0], 2 * n)
        )
        hess = self._hessian(w, p_joint, tip_force_n, q0, loads=loads)
        hess = 0.5 * (hess + np.swapaxes(hess, -1, -2))  # a Hessian: symmetric up to rounding
        hess = np.where(free[:, None] & free[None, :], hess, np.eye(2 * n))
        r = np.where(free, r, 0.0)
        step = -np.linalg.solve(hess, r[..., None])[..., 0]
        big = np.max(np.abs(step), -1, keepdims=True)
        return step * np.minimum(1.0, 0.2 / np.maximum(big, 1e-300))  # at most 0.2 rad per step

    def forward_theta_phi(
        self, line_kpa: np.ndarray, tip_force_n: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """(theta, phi) of every joint at equilibrium, each (..., n_joints)."""
        return theta_phi_from_uv(self.forward(line_kpa, tip_force_n))

    # -- inverse map (Eq 5) --------------------------------------------------
    def joint_pressure_system(
        self, w: np.ndarray, tip_force_n: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray]:
        """Eq 5 as linear equations M P = b per joint: M (..., n_joints, 2, 5), b (..., n_joints,
        2).

        From -J^T [P (A - m_a dl) - n_a dl] + K w - Q = 0.
        """
        dl, jac = self._actuator_terms(w)
        coef = self.act.newton_per_kpa - self.act.slope_n_per_mm_per_kpa * dl
        m = np.swapaxes(jac, -1, -2) * coef[..., None, :]
        b = (
            self.rod_nmm_per_rad * w
            - self.load_forces(w, tip_force_n)
            + np.einsum("...si,...s->...i", jac, self.act.offset_n_per_mm * dl)
        )
        return m, b

    def inverse(
        self,
        w_segment: np.ndarray,
        tip_force_n: np.ndarray | None = None,
        tol_kpa: float = 1e-10,
        max_iter: int = 100,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Line pressures that put each segment's first joint at ``w_segment`` (..., n_segments, 2).

        Returns:
            (line_kpa (..., n_segments, 5) gauge, NaN where no pressures within the
            bounds reach the pose; w (..., n_joints, 2), the whole tail at equilibrium).
        """
        w_segment = np.asarray(w_segment, float)
        lead = w_segment.shape[:-2]
        j = self.kin.joints_per_segment
        ref = np.zeros(self.kin.n_joints, bool)
        ref[::j] = True
        w = self.kin.expand_segments(w_segment)
        p = np.zeros(lead + (self.kin.n_segments, 5))
        for _ in range(max_iter):
            m, b = self.joint_pressure_system(w, tip_force_n)
            p_new, ok = least_norm_in_box(
                m[..., ref, :, :],
                b[..., ref, :],
                self.act.pressure_min_kpa,
                self.act.pressure_max_kpa,
            )
            p_new = np.where(ok[..., None], p_new, 0.0)
            if self.masses is None and tip_force_n is None and j == 1:
                p = p_new
                break
            w = self.forward(p_new, tip_force_n, w0=w, fixed=ref)
            change = np.max(np.abs(p_new - p)) if p.size else 0.0
            p = p_new
            if change < tol_kpa:
                break
        return np.where(ok[..., None], p, np.nan), w


def least_norm_in_box(
    m: np.ndarray, b: np.ndarray, lo: float, hi: float, max_iter: int = 100
) -> tuple[np.ndarray, np.ndarray]:
    """min |P|^2 s.t. M P = b, lo <= P <= hi, batched: M (..., 2, 5), b (..., 2).

    Solved in the dual: P = clip(M^T lam), lam maximises the concave dual
    b.lam - 1/2 |clip(M^T lam)|^2 - ... by semismooth Newton with backtracking.

    Returns:
        (P (..., 5), feasible (...,) bool).
    """
    lam = np.zeros(b.shape)
    mt = np.swapaxes(m, -1, -2)

    def primal(lam_: np.ndarray) -> np.ndarray:
        return np.clip(np.einsum("...ij,...j->...i", mt, lam_), lo, hi)

    def dual(lam_: np.ndarray) -> np.ndarray:
        p_ = primal(lam_)
        return (
            np.sum(lam_ * b, -1)
            - np.sum(lam_ * np.einsum("...ij,...j->...i", m, p_), -1)
            + 0.5 * np.sum(p_ * p_, -1)
        )

    for _ in range(max_iter):
        p = primal(lam)
        grad = b - np.einsum("...ij,...j->...i", m, p)
        if np.max(np.abs(grad)) < 1e-10 * (1.0 + np.max(np.abs(b))):
            break
        active = (np.einsum("...ij,...j->...i", mt, lam) > lo) & (
            np.einsum("...ij,...j->...i", mt, lam) < hi
        )
        hmat = np.einsum("...ik,...k,...jk->...ij", m, active.astype(float), m) + 1e-12 * np.eye(2)
        step = np.linalg.solve(hmat, grad[..., None])[..., 0]
        d0 = dual(lam)
        alpha = np.ones(b.shape[:-1])
        for _ in range(30):
            trial = lam + alpha[..., None] * step
            better = dual(trial) >= d0 - 1e-12 * (1.0 + np.abs(d0))  # the dual is concave: ascend
            if np.all(better):
                break
            alpha = np.where(better, alpha, alpha / 2)
        lam = lam + alpha[..., None] * step
    p = primal(lam)
    res = np.max(np.abs(np.einsum("...ij,...j->...i", m, p) - b), -1)
    return p, res < 1e-6 * (1.0 + np.max(np.abs(b), -1))


def pressure_pattern_kpa(phi_rad: float, low_kpa: float, high_kpa: float) -> np.ndarray:
    """Bend towards phi: SOAs on that side evacuated, the opposite side pressurised,
    SOAs on the bending axis (|cos| < 1e-9) inactive."""
    from ..parameters.layout import soa_angles_deg

    c = np.cos(np.radians(soa_angles_deg()) - phi_rad)
    return np.where(c > 1e-9, low_kpa, np.where(c < -1e-9, high_kpa, 0.0))


def segment_bend_angle_rad(kin: TailKinematics, w: np.ndarray) -> np.ndarray:
    """Angle between the axes of the first and the last panel: the segment's bending angle."""
    _, panel = kin.frames(w)
    z0, z1 = panel[..., 0, :3, 2], panel[..., -1, :3, 2]
    return np.arccos(np.clip(np.sum(z0 * z1, -1), -1.0, 1.0))


@dataclass(frozen=True)
class QuasiStatic:
    """Table III for one motion: the free bending angle and the blocked tip force at the pressure
    limits, and the line pressures (kPa gauge) that produce them."""

    motion: str
    max_angle_deg: float
    blocked_force_n: float
    line_kpa: tuple[float, ...]


#: The blocked-force equations' largest residual accepted as a root: moments over the rod's
#: stiffness (rad) and the tip's offset (mm).
BLOCKED_RESIDUAL_TOL = 1e-9


def quasi_static_segment(seg: TailStatics, motion: str) -> QuasiStatic:
    """One segment at the pressure limits: free bending angle and the blocked tip force.

    The blocked force is the reaction at the tip point held at its rest
    position (the joints may still flex inside the segment), as a force
    sensor touching the tip would measure.
    """
    from scipy.optimize import root

    phi = MOTION_PHI_RAD[motion]
    p_line = pressure_pattern_kpa(phi, seg.act.pressure_min_kpa, seg.act.pressure_max_kpa)[None, :]
    w = seg.forward(p_line)
    angle = float(np.degrees(segment_bend_angle_rad(seg.kin, w)))
    n = seg.kin.n_joints
    tip0 = seg.kin.rest_tip_mm()
    scale = (
        seg.rod_nmm_per_rad or 1.0e3
    )  # N mm/rad, the residual's scale only (no rod: any positive value)

    def equations(x: np.ndarray) -> np.ndarray:
        wx = x[: 2 * n].reshape(n, 2)
        # The tip is held sideways only: along the axis an inextensible segment
        # is at its longest when straight, so the axial reaction is not defined.
        force = np.array([x[2 * n], x[2 * n + 1], 0.0])
        r = seg.residual(wx, p_line, force).ravel() / scale
        return np.concatenate([r, (seg.kin.tip_point_mm(wx) - tip0)[:2]])

    sol = root(equations, np.zeros(2 * n + 2), method="hybr", options={"xtol": 1e-12})
    # MINPACK may stop "not making good progress" at a root it cannot polish further: a one-joint
    # segment in extension ends with every equation within 2e-16 of zero (rounding); judge the root.
    if not sol.success and not np.max(np.abs(equations(sol.x))) < BLOCKED_RESIDUAL_TOL:
        raise RuntimeError(f"blocked force for {motion}: {sol.message}")
    reaction = sol.x[2 * n :]
    return QuasiStatic(
        motion, angle, float(np.linalg.norm(reaction)), tuple(float(v) for v in p_line[0])
    )


def lateral_stiffness_n_per_mm(seg: TailStatics, force_n: float = 0.5) -> float:
    """Passive lateral stiffness of the tail ``seg`` at its tip, lines open (0 kPa gauge): the
    paper's Fig. 3(d) test, a sideways force on the distal panel over the tip's displacement.

    A force of +-``force_n`` along X (perpendicular to gravity, which is along -Y) is applied at the
    tip point and the stiffness is the central difference 2 F / (x(+F) - x(-F)), so the sag under
    gravity cancels and the figure is the tangent stiffness at the loaded rest pose.
    """
    lines = np.zeros((2, seg.kin.n_segments, 5))
    forces = np.array([[force_n, 0.0, 0.0], [-force_n, 0.0, 0.0]])
    w = seg.forward(lines, forces)
    x = seg.kin.tip_point_mm(w)[:, 0]
    return float(2.0 * force_n / (x[0] - x[1]))


__all__ = [
    "Actuator",
    "LumpedMasses",
    "TailStatics",
    "QuasiStatic",
    "least_norm_in_box",
    "pressure_pattern_kpa",
    "quasi_static_segment",
    "segment_bend_angle_rad",
    "lateral_stiffness_n_per_mm",
    "uv_from_theta_phi",
    "MOTION_PHI_RAD",
    "G_N_PER_KG",
]
