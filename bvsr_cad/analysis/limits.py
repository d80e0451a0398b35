"""Collision-free bending limit theta_max(phi) of every joint (the others straight).

For each joint and bending-plane angle, bisection on theta in [0, 1 rad]: a
pose is free when every pair keeps the required clearance; the stage-1 bound
of :mod:`bvsr_cad.analysis.clearance` clears most pairs, exact mesh distances
decide the rest.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .clearance import PosedTail


@dataclass(frozen=True)
class JointLimits:
    joint: str
    phi_rad: list[float]
    theta_max_rad: list[float]
    limiting_pair: list[list[str]]


def _pose(pt: PosedTail, joint: int, theta: float, phi: float) -> np.ndarray:
    w = np.zeros((pt.kin.n_joints, 2))
    w[joint] = (theta * np.cos(phi), theta * np.sin(phi))
    return w


def _worst(pt: PosedTail, w: np.ndarray, need_mm: float, joint: int) -> tuple[float, int]:
    lb = pt.lower_bounds(w[None])[0]
    # Only pairs that feel this joint move; the others keep their rest clearance (>= their bound).
    check = np.flatnonzero((lb < need_mm) & pt.span[:, joint])
    if len(check) == 0:
        return float(lb.min()), int(lb.argmin())
    ex = pt.exact(w, check)
    return float(ex.min()), int(check[ex.argmin()])


def joint_limits(pt: PosedTail, need_mm: float, n_phi: int = 12, theta_hi_rad: float = 1.0,
                 steps: int = 10) -> list[JointLimits]:
    """theta_max(phi) of every joint, to theta_hi / 2^steps (1 mrad by default)."""
    out = []
    phis = np.linspace(-np.pi, np.pi, n_phi, endpoint=False)
    for k in range(pt.kin.n_joints):
        th_max, pairs = [], []
        for phi in phis:
            d, p = _worst(pt, _pose(pt, k, theta_hi_rad, phi), need_mm, k)
            if d >= need_mm:
                th_max.append(theta_hi_rad)
                pairs.append([])
                continue
            lo, hi, hit = 0.0, theta_hi_rad, p
            for _ in range(steps):
                mid = 0.5 * (lo + hi)
                d, p = _worst(pt, _pose(pt, k, mid, phi), need_mm, k)
                if d >= need_mm:
                    lo = mid
                else:
                    hi, hit = mid, p
            th_max.append(lo)
            a, b = pt.pairs[hit]
            pairs.append([pt.names[a], pt.names[b]])
        out.append(JointLimits(f"j{k + 1}", [float(v) for v in phis], [float(v) for v in th_max], pairs))
    return out


def joint_limits_bound(pt: PosedTail, need_mm: float, n_phi: int = 36, theta_hi_rad: float = 1.0,
                       n_theta: int = 1001) -> list[JointLimits]:
    """Conservative theta_max(phi) from the stage-1 bound alone (vectorised; what `bvsr build` saves):
    the exact limit is never below it (at theta_hi / (n_theta - 1) resolution)."""
    phis = np.linspace(-np.pi, np.pi, n_phi, endpoint=False)
    th = np.linspace(0.0, theta_hi_rad, n_theta)
    tt, pp = np.meshgrid(th, phis, indexing="ij")
    out = []
    for k in range(pt.kin.n_joints):
        w = np.zeros((tt.size, pt.kin.n_joints, 2))
        w[:, k, 0] = (tt * np.cos(pp)).ravel()
        w[:, k, 1] = (tt * np.sin(pp)).ravel()
        lb = pt.lower_bounds(w)[:, pt.span[:, k]].reshape(n_theta, n_phi, -1)
        ids = np.flatnonzero(pt.span[:, k])
        bad = lb.min(-1) < need_mm  # (theta, phi)
        first = np.where(bad.any(0), bad.argmax(0), n_theta)
        th_max, pairs = [], []
        for j in range(n_phi):
            if first[j] >= n_theta:
                th_max.append(float(theta_hi_rad))
                pairs.append([])
                continue
            th_max.append(float(th[max(first[j] - 1, 0)]))
            a, b = pt.pairs[ids[lb[first[j], j].argmin()]]
            pairs.append([pt.names[a], pt.names[b]])
        out.append(JointLimits(f"j{k + 1}", [float(v) for v in phis], th_max, pairs))
    return out
