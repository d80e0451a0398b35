"""Constant-curvature kinematics of the BVSR joints and of the whole tail (mm).

Eq 2 of the paper, T_s(theta, phi), is evaluated through the bending vector
w = (u, v) = theta (cos phi, sin phi): the rotation is exp of the skew matrix
of (-v, u, 0) and every entry is a smooth function of (u, v), so theta -> 0
needs no special case beyond the series of sin(theta)/theta and
(1 - cos theta)/theta^2 (and their derivatives) near zero. The solvers of
:mod:`bvsr_cad.models.statics` work in w for the same reason: phi is undefined
at a straight joint, w is not.

Frames: Z along the tail, Y dorsal, X lateral. Joint k
(1-based) runs from the upper face centre of panel k-1 (its base frame) to
the lower face centre of panel k (its moving frame) along an arc of length
L = H_a; the panels are rigid slabs of thickness H_j - H_a. Everything is
vectorised over leading axes: a pose batch has shape (n_poses, n_joints).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..parameters.layout import half_angle_rad, panel_layout, soa_angles_deg
from ..parameters.tables import TailSpec

#: Below this bending angle the closed forms lose digits; the series are exact to ~1e-17.
SERIES_BELOW_RAD = 1e-2


def _series_coefficients(
    theta: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """S = sin t / t, C = (1 - cos t) / t^2, S1 = S'(t) / t, C1 = C'(t) / t."""
    t = np.asarray(theta, float)
    if t.size == 1:
        one = _series_coefficients_one(float(t.reshape(())))
        return (
            tuple(np.array(x) for x in one)
            if t.ndim == 0
            else tuple(np.full(t.shape, x) for x in one)
        )
    return _series_coefficients_array(t)


def _series_coefficients_array(
    t: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_series_coefficients` of an array of angles."""
    t2 = t * t
    small = t < SERIES_BELOW_RAD
    ts = np.where(small, 1.0, t)  # keeps the closed forms finite where the series is used
    s, c = np.sin(ts), np.cos(ts)
    S = np.where(small, 1 - t2 / 6 + t2 * t2 / 120 - t2**3 / 5040, s / ts)
    C = np.where(small, 0.5 - t2 / 24 + t2 * t2 / 720 - t2**3 / 40320, (1 - c) / ts**2)
    S1 = np.where(small, -1 / 3 + t2 / 30 - t2 * t2 / 840, (ts * c - s) / ts**3)
    C1 = np.where(small, -1 / 12 + t2 / 180 - t2 * t2 / 6720, (ts * s - 2 * (1 - c)) / ts**4)
    return S, C, S1, C1


def _series_coefficients_one(t: float) -> tuple[float, float, float, float]:
    """:func:`_series_coefficients` of one angle, the bits :func:`_series_coefficients_array` gives
    for an array of one: the same operations in the same order on Python floats, with numpy's sin,
    cos and power (the loops an array of one runs through) and ``t * t`` where numpy squares
    (tests/test_kinematics.py compares the two bit for bit). A joint's dynamics and statics ask for
    one angle at a time, many thousands of times in a build's analyses, where the array path's
    numpy calls cost far more than the arithmetic of one angle."""
    t2 = t * t
    if t < SERIES_BELOW_RAD:
        t6 = float(np.power(t2, 3.0))
        return (
            1 - t2 / 6 + t2 * t2 / 120 - t6 / 5040,
            0.5 - t2 / 24 + t2 * t2 / 720 - t6 / 40320,
            -1 / 3 + t2 / 30 - t2 * t2 / 840,
            -1 / 12 + t2 / 180 - t2 * t2 / 6720,
        )
    s, c = float(np.sin(t)), float(np.cos(t))
    return (
        s / t,
        (1 - c) / t2,
        (t * c - s) / float(np.power(t, 3.0)),
        (t * s - 2 * (1 - c)) / float(np.power(t, 4.0)),
    )


def _hat(x: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    x, y, z = np.broadcast_arrays(np.asarray(x, float), np.asarray(y, float), np.asarray(z, float))
    out = np.zeros(x.shape + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -z, y
    out[..., 1, 0], out[..., 1, 2] = z, -x
    out[..., 2, 0], out[..., 2, 1] = -y, x
    return out


def _bending_hat(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """hat(-v, u, 0), the bending vector's skew matrix (Eq 2's Omega)."""
    out = np.zeros(u.shape + (3, 3))
    out[..., 0, 1] = -0.0  # -z of hat(x, y, z), z = 0: the same signed zeros as _hat
    out[..., 0, 2], out[..., 1, 2] = u, v
    out[..., 2, 0], out[..., 2, 1] = -u, -v
    return out


@dataclass(frozen=True)
class _Twist:
    """What Eq 2 and its derivatives share at bending vectors (u, v): computed once per call."""

    u: np.ndarray
    v: np.ndarray
    S: np.ndarray
    C: np.ndarray
    S1: np.ndarray
    C1: np.ndarray
    om: np.ndarray  # Omega (..., 3, 3)
    om2: np.ndarray  # Omega @ Omega

    @classmethod
    def at(cls, u: np.ndarray, v: np.ndarray) -> _Twist:
        u, v = np.broadcast_arrays(np.asarray(u, float), np.asarray(v, float))
        S, C, S1, C1 = _series_coefficients(np.hypot(u, v))
        om = _bending_hat(u, v)
        return cls(u, v, S, C, S1, C1, om, om @ om)

    def rotation_translation(self, length_mm: float) -> tuple[np.ndarray, np.ndarray]:
        S, C = self.S, self.C
        rot = np.eye(3) + S[..., None, None] * self.om + C[..., None, None] * self.om2
        trans = length_mm * np.stack([self.u * C, self.v * C, S], -1)
        return rot, trans

    def derivatives(
        self, length_mm: float
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        u, v, S, C, S1, C1, om, om2 = (
            self.u,
            self.v,
            self.S,
            self.C,
            self.S1,
            self.C1,
            self.om,
            self.om2,
        )
        e = (..., None, None)
        # d(Omega)/du = hat(0, 1, 0), d(Omega)/dv = hat(-1, 0, 0).
        d_om_u, d_om_v = _EY, -_EX
        dR_u = (
            (S1 * u)[e] * om
            + S[e] * d_om_u
            + (C1 * u)[e] * om2
            + C[e] * (d_om_u @ om + om @ d_om_u)
        )
        dR_v = (
            (S1 * v)[e] * om
            + S[e] * d_om_v
            + (C1 * v)[e] * om2
            + C[e] * (d_om_v @ om + om @ d_om_v)
        )
        dp_u = length_mm * np.stack([C + u * u * C1, u * v * C1, u * S1], -1)
        dp_v = length_mm * np.stack([u * v * C1, C + v * v * C1, v * S1], -1)
        return dR_u, dR_v, dp_u, dp_v


_EX = _hat(np.array(1.0), np.array(0.0), np.array(0.0))
_EY = _hat(np.array(0.0), np.array(1.0), np.array(0.0))


def joint_rotation_translation(
    u: np.ndarray, v: np.ndarray, length_mm: float
) -> tuple[np.ndarray, np.ndarray]:
    """Rotation (..., 3, 3) and translation (..., 3) of Eq 2 at bending vector (u, v)."""
    return _Twist.at(u, v).rotation_translation(length_mm)


def joint_transform_uv(u: np.ndarray, v: np.ndarray, length_mm: float) -> np.ndarray:
    """Eq 2 as a (..., 4, 4) homogeneous transform, base frame -> moving frame."""
    rot, trans = joint_rotation_translation(u, v, length_mm)
    out = np.zeros(rot.shape[:-2] + (4, 4))
    out[..., :3, :3] = rot
    out[..., :3, 3] = trans
    out[..., 3, 3] = 1.0
    return out


def joint_transform(theta_rad: np.ndarray, phi_rad: np.ndarray, length_mm: float) -> np.ndarray:
    """Eq 2, T_s(theta, phi): the moving frame of a joint in its base frame."""
    theta_rad = np.asarray(theta_rad, float)
    return joint_transform_uv(theta_rad * np.cos(phi_rad), theta_rad * np.sin(phi_rad), length_mm)


def joint_transform_derivatives(
    u: np.ndarray, v: np.ndarray, length_mm: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """dR/du, dR/dv (..., 3, 3) and dp/du, dp/dv (..., 3), analytic."""
    return _Twist.at(u, v).derivatives(length_mm)


def joint_transform_and_derivatives(
    u: np.ndarray, v: np.ndarray, length_mm: float
) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, ...]]:
    """(:func:`joint_rotation_translation`, :func:`joint_transform_derivatives`) at once: the series
    coefficients and Omega computed once (the same numbers as the two calls)."""
    twist = _Twist.at(u, v)
    return twist.rotation_translation(length_mm), twist.derivatives(length_mm)


def _rz(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    m = np.zeros(np.shape(a) + (4, 4))
    m[..., 0, 0], m[..., 0, 1], m[..., 1, 0], m[..., 1, 1] = c, -s, s, c
    m[..., 2, 2] = m[..., 3, 3] = 1.0
    return m


def _ry(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    m = np.zeros(np.shape(a) + (4, 4))
    m[..., 0, 0], m[..., 0, 2], m[..., 2, 0], m[..., 2, 2] = c, s, -s, c
    m[..., 1, 1] = m[..., 3, 3] = 1.0
    return m


def chord_length_mm(theta_rad: np.ndarray, length_mm: float) -> np.ndarray:
    """c = 2 L sin(theta/2) / theta, the arc's chord (L at theta = 0; even in theta, any length
    unit).

    The one home of the chord: the kinematics, the robot model and its MJCF chord fit call it."""
    S, _, _, _ = _series_coefficients(np.abs(np.asarray(theta_rad, float)) / 2)
    return length_mm * S


def joint_transform_chain(
    theta_rad: np.ndarray, phi_rad: np.ndarray, length_mm: float
) -> np.ndarray:
    """Rz(phi) Ry(theta/2) Tz(c) Ry(theta/2) Rz(-phi): the URDF realisation of Eq 2."""
    theta_rad = np.asarray(theta_rad, float)
    phi_rad = np.broadcast_to(np.asarray(phi_rad, float), theta_rad.shape)
    tz = np.zeros(theta_rad.shape + (4, 4))
    tz[...] = np.eye(4)
    tz[..., 2, 3] = chord_length_mm(theta_rad, length_mm)
    return _rz(phi_rad) @ _ry(theta_rad / 2) @ tz @ _ry(theta_rad / 2) @ _rz(-phi_rad)


@dataclass(frozen=True)
class JointGeometry:
    """One joint: arc length and the SOA socket centres (Eq 1), taper included.

    ``base_mm`` are the centres of the SOAs' lower flange seats in the joint's
    base frame (upper face centre of panel k-1, so z = -pocket depth),
    ``moving_mm`` the upper seats in the moving frame (z = +pocket depth).
    """

    index: int  # 1-based joint number
    length_mm: float
    base_mm: np.ndarray  # (5, 3)
    moving_mm: np.ndarray  # (5, 3)

    @property
    def rest_lengths_mm(self) -> np.ndarray:
        return soa_lengths_mm(self, np.zeros(1), np.zeros(1))[0]


def joint_geometries(spec: TailSpec) -> tuple[JointGeometry, ...]:
    """Socket centres of every joint from the panel layout (pitch radii of the cone, pocket
    depth)."""
    beta = half_angle_rad(spec)
    lays = [panel_layout(spec, k, beta) for k in range(spec.panels)]
    a = np.radians(soa_angles_deg())
    out = []
    for k in range(1, spec.panels):
        lo, hi = lays[k - 1], lays[k]
        r_b, r_m = lo.pitch_radius_upper_mm, hi.pitch_radius_lower_mm
        base = np.stack([r_b * np.cos(a), r_b * np.sin(a), np.full(5, -lo.pocket_depth_mm)], -1)
        moving = np.stack([r_m * np.cos(a), r_m * np.sin(a), np.full(5, hi.pocket_depth_mm)], -1)
        out.append(JointGeometry(k, spec.joint.gap_mm, base, moving))
    return tuple(out)


def soa_lengths_mm(geom: JointGeometry, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Eq 1: l_i = |T_s m_i - b_i| for the five SOAs, shape (..., 5)."""
    rot, trans = joint_rotation_translation(u, v, geom.length_mm)
    d = np.einsum("...ij,sj->...si", rot, geom.moving_mm) + trans[..., None, :] - geom.base_mm
    return np.linalg.norm(d, axis=-1)


def socket_lengths_and_jacobian(
    base: np.ndarray, moving: np.ndarray, u: np.ndarray, v: np.ndarray, length: float
) -> tuple[np.ndarray, np.ndarray]:
    """Eq 1 and its derivative for socket centres ``base``/``moving`` (..., 5, 3), broadcast against
    the bending vectors (u, v) (...,): (l (..., 5), dl/dw (..., 5, 2)), in the sockets' length unit.

    One bending vector (0-d ``u`` and ``v``: a joint's dynamics and statics, many thousands of calls
    in a build's analyses) takes :func:`_one_twist_sockets`: the same quantities from Eq 2's
    entries in closed form, to rounding (tests/test_kinematics.py compares the two)."""
    if np.ndim(u) == 0 and np.ndim(v) == 0:
        return _one_twist_sockets(
            np.asarray(base, float), np.asarray(moving, float), float(u), float(v), length
        )
    (rot, trans), (dR_u, dR_v, dp_u, dp_v) = joint_transform_and_derivatives(u, v, length)
    d = np.einsum("...ij,...sj->...si", rot, moving) + trans[..., None, :] - base
    lengths = np.linalg.norm(d, axis=-1)
    e = d / lengths[..., None]
    dd_u = np.einsum("...ij,...sj->...si", dR_u, moving) + dp_u[..., None, :]
    dd_v = np.einsum("...ij,...sj->...si", dR_v, moving) + dp_v[..., None, :]
    jac = np.stack([np.sum(e * dd_u, -1), np.sum(e * dd_v, -1)], -1)
    return lengths, jac


def _one_twist_sockets(
    base: np.ndarray, moving: np.ndarray, u: float, v: float, length: float
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`socket_lengths_and_jacobian` at one bending vector (u, v): R, dR/du, dR/dv written out
    entry by entry (Omega = hat(-v, u, 0), Omega^2 = -[[uu, uv, 0], [uv, vv, 0], [0, 0, uu + vv]]
    and their derivatives, see :class:`_Twist`) as the rows of one (9, 3) matrix, and p, dp/du,
    dp/dv as its offsets, so that every socket's d = R m + p - b and dd/du, dd/dv come from one
    product instead of the twist's 3 x 3 products and three einsums, whose numpy call overheads
    outweigh the arithmetic on 15 sockets."""
    S, C, S1, C1 = _series_coefficients_one(math.hypot(u, v))
    uu, uv, vv, ww = u * u, u * v, v * v, u * u + v * v
    su, sv, cu, cv = S1 * u, S1 * v, C1 * u, C1 * v  # dS/du, dS/dv, dC/du, dC/dv
    rows = np.array(
        [
            [1.0 - C * uu, -C * uv, S * u],  # R
            [-C * uv, 1.0 - C * vv, S * v],
            [-S * u, -S * v, 1.0 - C * ww],
            [-cu * uu - 2.0 * C * u, -cu * uv - C * v, su * u + S],  # dR/du
            [-cu * uv - C * v, -cu * vv, su * v],
            [-su * u - S, -su * v, -cu * ww - 2.0 * C * u],
            [-cv * uu, -cv * uv - C * u, sv * u],  # dR/dv
            [-cv * uv - C * u, -cv * vv - 2.0 * C * v, sv * v + S],
            [-sv * u, -sv * v - S, -cv * ww - 2.0 * C * v],
        ]
    )
    offsets = length * np.array(
        [u * C, v * C, S, C + uu * C1, uv * C1, u * S1, uv * C1, C + vv * C1, v * S1]
    )
    dd = moving @ rows.T + offsets  # (..., 5, 9): d + b, dd/du, dd/dv
    d = dd[..., :3] - base
    lengths = np.sqrt(np.einsum("...i,...i->...", d, d))
    jac = (
        np.einsum("...i,...ki->...k", d, dd[..., 3:].reshape(dd.shape[:-1] + (2, 3)))
        / lengths[..., None]
    )
    return lengths, jac


def soa_lengths_and_jacobian(
    geom: JointGeometry, u: np.ndarray, v: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(l (..., 5), dl/dw (..., 5, 2)) with w = (u, v)."""
    return socket_lengths_and_jacobian(geom.base_mm, geom.moving_mm, u, v, geom.length_mm)


def uv_from_theta_phi(theta_rad: np.ndarray, phi_rad: np.ndarray) -> np.ndarray:
    """Bending vectors (..., 2) from (theta, phi)."""
    theta_rad = np.asarray(theta_rad, float)
    return np.stack([theta_rad * np.cos(phi_rad), theta_rad * np.sin(phi_rad)], -1)


def theta_phi_from_uv(w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(theta, phi) from bending vectors (..., 2); phi = 0 where theta = 0."""
    w = np.asarray(w, float)
    return np.hypot(w[..., 0], w[..., 1]), np.arctan2(w[..., 1], w[..., 0])


@dataclass(frozen=True)
class TailKinematics:
    """The chain of rigid panels and constant-curvature joints of one tail."""

    joints: tuple[JointGeometry, ...]
    panel_thickness_mm: float
    joints_per_segment: int

    @classmethod
    def from_spec(cls, spec: TailSpec) -> TailKinematics:
        return cls(joint_geometries(spec), spec.joint.panel_thickness_mm, spec.joints_per_segment)

    @property
    def n_joints(self) -> int:
        return len(self.joints)

    @property
    def n_segments(self) -> int:
        return self.n_joints // self.joints_per_segment

    @property
    def length_mm(self) -> float:
        return self.joints[0].length_mm

    def segment_of_joint(self) -> np.ndarray:
        """0-based segment index of every joint."""
        return np.arange(self.n_joints) // self.joints_per_segment

    def expand_segments(self, w_segment: np.ndarray) -> np.ndarray:
        """Per-segment bending vectors (..., n_segments, 2) -> per joint (..., n_joints, 2)."""
        return np.repeat(np.asarray(w_segment, float), self.joints_per_segment, axis=-2)

    def frames(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Base frames of every joint and lower-face frames of every panel.

        Args:
            w: bending vectors, shape (..., n_joints, 2).

        Returns:
            (base (..., n_joints, 4, 4): upper face of panel k-1 for joint k,
            panel (..., n_joints + 1, 4, 4): lower face of panel k), tail frame, mm.
        """
        w = np.asarray(w, float)
        lead = w.shape[:-2]
        tz = np.eye(4)
        tz[2, 3] = self.panel_thickness_mm
        panel = np.empty(lead + (self.n_joints + 1, 4, 4))
        base = np.empty(lead + (self.n_joints, 4, 4))
        panel[..., 0, :, :] = np.eye(4)
        for k, g in enumerate(self.joints):
            base[..., k, :, :] = panel[..., k, :, :] @ tz
            panel[..., k + 1, :, :] = base[..., k, :, :] @ joint_transform_uv(
                w[..., k, 0], w[..., k, 1], g.length_mm
            )
        return base, panel

    def tip_point_mm(self, w: np.ndarray) -> np.ndarray:
        """Centre of the tip panel's distal face in the root frame, (..., 3)."""
        _, panel = self.frames(w)
        tip = panel[..., -1, :, :]
        return tip[..., :3, 3] + self.panel_thickness_mm * tip[..., :3, 2]

    def tip_point_theta_phi_mm(self, theta_rad: np.ndarray, phi_rad: np.ndarray) -> np.ndarray:
        """Tip point from per-joint (theta, phi) arrays of shape (..., n_joints)."""
        return self.tip_point_mm(uv_from_theta_phi(theta_rad, phi_rad))

    def rest_tip_mm(self) -> np.ndarray:
        return self.tip_point_mm(np.zeros((self.n_joints, 2)))


#: The reduced (pseudo-rigid-body) joint of the default MJCF: two universal joints on the arc's
#: axis, each at L/6 from an end, joined by a rigid link of 2L/3. Bent by theta/2 each, the
#: pivots put the arc's end at (2L/3 + (L/3) cos(theta/2)) along the chord, which matches the
#: chord 2 L sin(theta/2) / theta to theta^2 (the residual is 3.5e-4 L theta^4, 10 um at 0.95 rad).
PRB_PIVOT_FRACTION = 1.0 / 6.0


def prb_angles(theta_rad: np.ndarray, phi_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hinge angles (about X, then about Y) of each universal joint of the reduced joint at (theta,
    phi).

    The first pivot turns Rx(a) Ry(b), the second Ry(b) Rx(a); their product Rx(a) Ry(2b) Rx(a)
    has no twist and equals Eq 2's rotation exactly when sin b = sin(theta/2) cos phi and
    tan a = -sin(theta/2) sin phi / cos(theta/2)."""
    half = np.asarray(theta_rad, float) / 2
    return (
        np.arctan2(-np.sin(half) * np.sin(phi_rad), np.cos(half)),
        np.arcsin(np.sin(half) * np.cos(phi_rad)),
    )


def prb_bend_angle(a_rad: np.ndarray, b_rad: np.ndarray) -> np.ndarray:
    """The reduced joint's bend theta from a pivot's hinge angles (the inverse of
    :func:`prb_angles`): cos(theta/2) = cos a cos b (from sin b = sin(theta/2) cos phi, tan a =
    -tan(theta/2) sin phi)."""
    return 2.0 * np.arccos(np.clip(np.cos(a_rad) * np.cos(b_rad), -1.0, 1.0))


@dataclass(frozen=True)
class PrbLimitPolygon:
    """The reduced joint's bend limit theta <= theta_max as faces in a pivot's hinge angles (a, b).

    The exact limit, cos a cos b >= cos(theta_max / 2) (:func:`prb_bend_angle`), is a convex region
    (log cos a + log cos b is concave), nearly the disc of radius theta_max / 2. Face i bounds
    cos(phi_i) a + sin(phi_i) b <= half_width_rad[i] on both sides, phi_i = 180 i / n deg for the n
    directions (2 n faces), and touches the region at ``touch_ab[i]`` (the support function, in
    closed form), so the polygon circumscribes it. Along a face theta is largest at its ends
    (-log(cos a cos b) is convex), so the largest bend the polygon allows is at a vertex
    (``vertex_ab``, between faces i and i + 1 of the 2 n): ``overshoot`` = theta / theta_max - 1
    there; the smallest is theta_max, where a face touches."""

    theta_max_rad: float
    direction_rad: np.ndarray  # (n,)
    half_width_rad: np.ndarray  # (n,)
    touch_ab: np.ndarray  # (n, 2)
    vertex_ab: np.ndarray  # (2 n, 2)
    overshoot: float

    @classmethod
    def make(cls, theta_max_rad: float, directions: int) -> PrbLimitPolygon:
        if directions < 2:
            raise ValueError(f"PrbLimitPolygon: directions={directions} must be >= 2 (4 faces)")
        phi = np.arange(directions) * np.pi / directions
        # Support of {cos a cos b >= C}: the Lagrange condition tan b / tan a = tan phi with
        # (1 + tan^2 a)(1 + tan^2 b) = 1 / C^2 = 1 + T gives tan^2 a = 2 cos^2 phi T / w,
        # tan^2 b = 2 sin^2 phi T / w, w = 1 + sqrt(1 + 4 sin^2 phi cos^2 phi T).
        big_t = np.tan(theta_max_rad / 2) ** 2
        c2, s2 = np.cos(phi) ** 2, np.sin(phi) ** 2
        w = 1.0 + np.sqrt(1.0 + 4.0 * s2 * c2 * big_t)
        touch = np.stack(
            [
                np.sign(np.cos(phi).round(15)) * np.arctan(np.sqrt(2 * c2 * big_t / w)),
                np.arctan(np.sqrt(2 * s2 * big_t / w)),
            ],
            axis=1,
        )
        half = np.cos(phi) * touch[:, 0] + np.sin(phi) * touch[:, 1]
        normal = np.concatenate([phi, phi + np.pi])  # faces phi and phi + pi (i.e. -half along phi)
        width = np.concatenate([half, half])
        n1 = np.stack([np.cos(normal), np.sin(normal)], axis=1)
        vertex = np.array(
            [
                np.linalg.solve(
                    np.stack([n1[k], n1[(k + 1) % len(normal)]]),
                    [width[k], width[(k + 1) % len(normal)]],
                )
                for k in range(len(normal))
            ]
        )
        worst = float(prb_bend_angle(vertex[:, 0], vertex[:, 1]).max())
        return cls(theta_max_rad, phi, half, touch, vertex, worst / theta_max_rad - 1.0)


def joint_transform_prb(theta_rad: np.ndarray, phi_rad: np.ndarray, length_mm: float) -> np.ndarray:
    """Tz(d) Rx(a) Ry(b) Tz(L - 2d) Ry(b) Rx(a) Tz(d), d = L/6: the reduced joint's end frame."""
    a, b = prb_angles(theta_rad, phi_rad)
    d = PRB_PIVOT_FRACTION * length_mm
    tz = np.eye(4)
    tz[2, 3] = d
    mid = np.eye(4)
    mid[2, 3] = length_mm - 2 * d
    return tz @ _rx(a) @ _ry(b) @ mid @ _ry(b) @ _rx(a) @ tz


#: The mount variant's joint (the tail file a host carries): one universal joint per bending joint
#: on the arc's axis at mid-arc, L/2 from either end. Each panel keeps Eq 2's normal exactly; the
#: arc's end lies on the chord's line, short of it by L (2 sin(theta/2) / theta - cos(theta/2))
#: (:func:`mount_chord_error`), and the panel turns about its normal by a twist that a two-hinge
#: joint cannot avoid off its hinge planes (:func:`mount_twist_rad`). Half-way is the one place
#: without a first-order error: a pivot at p from the base and q = L - p from the end puts the arc's
#: end (p - q) sin(theta/2) off the chord's line.
MOUNT_PIVOT_FRACTION = 0.5
#: The mount variant's hinge order on joint k (1-based): Rx then Ry on odd joints, Ry then Rx on
#: even ones, so that the twists of two neighbours bent alike cancel to second order instead of
#: adding up along the tail.
MOUNT_ORDERS = ("xy", "yx")


def mount_order(k: int) -> str:
    """The hinge order of the mount variant's joint k (1-based): :data:`MOUNT_ORDERS`."""
    return MOUNT_ORDERS[(k - 1) % 2]


def mount_angles(
    theta_rad: np.ndarray, phi_rad: np.ndarray, order: str = "xy"
) -> tuple[np.ndarray, np.ndarray]:
    """Hinge angles (about X, about Y) of the mount variant's universal joint that give the panel
    Eq 2's normal (sin theta cos phi, sin theta sin phi, cos theta) at (theta, phi).

    Rx(a) Ry(b) turns Z to (sin b, -sin a cos b, cos a cos b): sin b = sin theta cos phi, tan a =
    -tan theta sin phi. Ry(b) Rx(a) turns it to (cos a sin b, -sin a, cos a cos b): sin a = -sin
    theta sin phi, tan b = tan theta cos phi. Either way cos theta = cos a cos b."""
    theta_rad = np.asarray(theta_rad, float)
    s, c = np.sin(theta_rad), np.cos(theta_rad)
    if order == "xy":
        return np.arctan2(-s * np.sin(phi_rad), c), np.arcsin(s * np.cos(phi_rad))
    if order == "yx":
        return -np.arcsin(s * np.sin(phi_rad)), np.arctan2(s * np.cos(phi_rad), c)
    raise ValueError(f"mount_angles: order {order!r}, allowed {', '.join(MOUNT_ORDERS)}")


def joint_transform_mount(
    theta_rad: np.ndarray, phi_rad: np.ndarray, length_mm: float, order: str = "xy"
) -> np.ndarray:
    """Tz(L/2) Rx(a) Ry(b) Tz(L/2) (order ``yx``: Ry(b) Rx(a)): the mount variant's end frame at
    (theta, phi) (:func:`mount_angles`)."""
    a, b = mount_angles(theta_rad, phi_rad, order)
    half = np.eye(4)
    half[2, 3] = MOUNT_PIVOT_FRACTION * length_mm
    turn = _rx(a) @ _ry(b) if order == "xy" else _ry(b) @ _rx(a)
    return half @ turn @ half


def mount_chord_error(theta_rad: np.ndarray, length: float) -> np.ndarray:
    """How far the mount variant's joint end falls short of the arc's end, along the chord (the
    unit of ``length``): 2 r cos(theta/2) - 2 L sin(theta/2) / theta with r = L/2, as a positive
    shortfall L (2 sin(theta/2) / theta - cos(theta/2)) = L (theta^2 / 12 - theta^4 / 480 + ...).

    Both arms of the pivot are L/2, so the end lies on the bisector of the base and end normals,
    the chord's direction, whatever the twist."""
    half = np.abs(np.asarray(theta_rad, float)) / 2
    return chord_length_mm(2 * half, length) - length * np.cos(half)


def mount_twist_rad(a_rad: np.ndarray, b_rad: np.ndarray) -> np.ndarray:
    """The twist about the panel's normal of the universal joint Rx(a) Ry(b), against Eq 2's
    twist-free rotation with the same normal: 2 atan(tan(a/2) tan(b/2)) (the quaternion (cos a/2
    cos b/2, sin a/2 cos b/2, cos a/2 sin b/2, sin a/2 sin b/2) split into a swing and a twist
    about Z); about -ab/2 for Ry(b) Rx(a). Zero in the hinges' planes (a = 0 or b = 0)."""
    return 2.0 * np.arctan(np.tan(np.asarray(a_rad) / 2) * np.tan(np.asarray(b_rad) / 2))


def _rx(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a), np.sin(a)
    m = np.zeros(np.shape(a) + (4, 4))
    m[..., 1, 1], m[..., 1, 2], m[..., 2, 1], m[..., 2, 2] = c, -s, s, c
    m[..., 0, 0] = m[..., 3, 3] = 1.0
    return m


def chain_tip_error_mm(
    joint_fn, lengths_mm, panel_thickness_mm: float, theta_max_rad, poses: int = 2000, seed: int = 0
) -> float:
    """Largest distance (mm) between the tip of a tail whose joints are ``joint_fn(theta, phi, L)``
    (4x4 end frames, e.g. :func:`joint_transform_prb`; or a sequence of one such function per
    joint) and Eq 2's tip, over the joint range: ``poses`` random poses (theta uniform up to each
    joint's limit, phi uniform) and every joint at its limit in one common plane (24 planes), where
    the errors add. The tip is the centre of the last panel's distal face; ``lengths_mm`` and
    ``theta_max_rad`` are per joint."""
    rng = np.random.default_rng(seed)
    lim = np.asarray(theta_max_rad, float)
    n = len(lim)
    theta = np.concatenate([rng.uniform(0, 1, (poses, n)) * lim, np.tile(lim, (24, 1))])
    phi = np.concatenate(
        [
            rng.uniform(-np.pi, np.pi, (poses, n)),
            np.repeat(np.linspace(-np.pi, np.pi, 24, endpoint=False)[:, None], n, 1),
        ]
    )
    tz = np.eye(4)
    tz[2, 3] = panel_thickness_mm
    tips = []
    fns = list(joint_fn) if isinstance(joint_fn, (list, tuple)) else [joint_fn] * n
    for chain in (fns, [joint_transform] * n):
        T = np.broadcast_to(np.eye(4), theta.shape[:1] + (4, 4))
        for k, length in enumerate(lengths_mm):
            T = T @ tz @ chain[k](theta[:, k], phi[:, k], length)
        tips.append(T[:, :3, 3] + panel_thickness_mm * T[:, :3, 2])
    return float(np.max(np.linalg.norm(tips[0] - tips[1], axis=-1)))
