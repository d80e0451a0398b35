"""The reduced chain's joint physics: what the MJCF writer's pseudo-rigid-body chain puts on its
hinges and tendons so that it resists bending and shear as the real joint does.

Each reduced joint is two pivots a and b, :data:`~bvsr_cad.models.kinematics.PRB_PIVOT_FRACTION` of
the arc from either end, coupled by an equality; per axis the bend is u = a + b and the shear
s = a - b. The mount variant (the file a host carries) has one universal joint per bending joint,
at mid-arc (:data:`~bvsr_cad.models.kinematics.MOUNT_PIVOT_FRACTION`): no shear mode, and its SOAs
act through their rest lever arms (:class:`MountJoint`). These functions take plain numbers and
socket positions (m, in panel k-1's frame), so the writer only reads them off its robot model
(:mod:`bvsr_cad.exporters.mjcf`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import numpy as np

from .kinematics import PRB_PIVOT_FRACTION


def shear_stiffness_nm_rad(
    n_soas: int,
    stiffness_offset_n_per_m: float,
    area_m2: float,
    rod_bending_stiffness_nm_rad: float,
) -> float:
    """Stiffness (N m/rad) on a reduced joint's shear tendon ``a - b`` (s): the real joint's
    resistance to it.

    In that mode the panel slides sideways by (1 - 2 f) L s / 2 (f = :data:`PRB_PIVOT_FRACTION`)
    without turning, and every column between the panels (the rod and the N SOAs) bends as a
    fixed-guided beam of lateral stiffness 12 E I / L^3: energy (1/2) 3 (1 - 2 f)^2 (E I / L) s^2
    per column. An SOA's own E I / L is its axial spring n_a spread on a thin wall round its
    effective area A (a ring of radius sqrt(A / pi): I / A = A / (2 pi)). The two hinges' 2 E I / L
    already give the rod (1/2) (E I / L) s^2, so the tendon carries the rest. It is zero whenever
    the equalities hold: it adds nothing to the constant-curvature motion, and it holds the mode
    where the rod is soft or absent.

    Args:
        n_soas: the SOAs of a joint (N).
        stiffness_offset_n_per_m: an SOA's axial spring n_a.
        area_m2: an SOA's effective area A.
        rod_bending_stiffness_nm_rad: the rod's E I / L across the gap.
    """
    guided = 3.0 * (1.0 - 2.0 * PRB_PIVOT_FRACTION) ** 2
    soa_ei_over_l = stiffness_offset_n_per_m * area_m2 / (2.0 * np.pi)
    return guided * n_soas * soa_ei_over_l + (guided - 1.0) * rod_bending_stiffness_nm_rad


def soa_bending(per_soa: float, bottoms_m: Sequence[Sequence[float]]) -> float:
    """``per_soa`` N r^2 / 2: a joint's N SOAs (each a spring n_a or damper c along it, its bottom
    socket at ``bottoms_m``) against bending about either axis, r the sockets' mean radius."""
    bottoms = np.asarray(bottoms_m, dtype=float)
    r2 = float(np.mean(np.sum(bottoms[:, :2] ** 2, axis=1)))
    return per_soa * len(bottoms) * r2 / 2


def soa_lever_arms_m(
    bottoms_m: Sequence[Sequence[float]],
    tops_m: Sequence[Sequence[float]],
    pivot_mid_m: Sequence[float],
) -> dict[str, np.ndarray]:
    """Each SOA's stretch per unit bend about X and about Y from rest, m/rad.

    Bending at u' (u' / 2 about each pivot), an SOA's top socket p moves at u' axis x (p - m), m
    the pivots' midpoint, so the SOA stretches at e . (axis x (p - m)) u' (e along it). It is about
    r sin or cos of the SOA's angle round the axis (r the sockets' radius).

    Args:
        bottoms_m: each SOA's bottom socket, at rest.
        tops_m: each SOA's top socket, at rest, in the same frame.
        pivot_mid_m: the pivots' midpoint in that frame.
    """
    m = np.asarray(pivot_mid_m, dtype=float)
    arms: dict[str, list[float]] = {"x": [], "y": []}
    for bottom, top in zip(np.asarray(bottoms_m, float), np.asarray(tops_m, float)):
        e = (top - bottom) / np.linalg.norm(top - bottom)
        for axis, unit in (("x", [1.0, 0.0, 0.0]), ("y", [0.0, 1.0, 0.0])):
            arms[axis].append(float(e @ np.cross(unit, top - m)))
    return {axis: np.array(a) for axis, a in arms.items()}


@dataclasses.dataclass(frozen=True)
class HingeShare:
    """What the default file moves onto a reduced joint's four pivot hinges.

    Per axis, a damping D on each hinge dissipates D (a'^2 + b'^2) = (D / 2) (u'^2 + s'^2), and a
    stiffness K stores (K / 2) (a^2 + b^2) = (K / 4) (u^2 + s^2). The SOA dampers dissipate
    c sum(arm^2) u'^2 (:func:`soa_lever_arms_m`), about c N r^2 / 2, and the shear tendon damps s
    with c N r^2 / 2 (:func:`soa_bending`): D = 2 c sum(arm^2) dissipates both. The shear tendon's
    spring k_s (:func:`shear_stiffness_nm_rad`) on each hinge as 2 k_s stores (k_s / 2) s^2 and as
    much in the bend, which the SOAs' springs give up: their n_a sum(arm^2) u^2 / 2 (about
    n_a N r^2 / 4 u^2) loses k_s u^2 / 2 when n_a is reduced by k_s / sum(arm^2). The SOAs' springs
    cannot give up more than they have: what is left of k_s (a very stiff rod's) stays on the shear
    tendon."""

    damping_nms: dict[str, float]  # on each hinge, about X and about Y
    stiffness_nm_rad: float  # added to each hinge's 2 E I / L
    soa_stiffness_offset_n_per_m: float  # the joint's SOAs' n_a on their actuators
    shear_tendon_nm_rad: float  # left on the shear tendons (0: none written)

    @classmethod
    def of(
        cls,
        arms_m: dict[str, np.ndarray],
        stiffness_offset_n_per_m: float,
        damping_n_s_per_m: float,
        shear_nm_rad: float,
    ) -> HingeShare:
        """The share of a joint whose SOAs have lever arms ``arms_m`` (:func:`soa_lever_arms_m`),
        each a spring n_a and a damper c, and whose shear tendon would carry ``shear_nm_rad``."""
        arms2 = {axis: float(np.sum(a**2)) for axis, a in arms_m.items()}
        mean2 = (arms2["x"] + arms2["y"]) / 2  # the same about both (the SOAs evenly round)
        moved = min(shear_nm_rad, stiffness_offset_n_per_m * mean2)
        return cls(
            damping_nms={axis: 2.0 * damping_n_s_per_m * a2 for axis, a2 in arms2.items()},
            stiffness_nm_rad=2.0 * moved,
            soa_stiffness_offset_n_per_m=stiffness_offset_n_per_m - moved / mean2,
            shear_tendon_nm_rad=shear_nm_rad - moved,
        )


@dataclasses.dataclass(frozen=True)
class MountJoint:
    """What the mount variant puts on a bending joint's one universal joint (hinge angles a about
    X and b about Y, the bend theta with cos theta = cos a cos b, so theta^2 = a^2 + b^2 to fourth
    order).

    - The rod: (1/2) (E I / L) theta^2 is E I / L on each hinge.
    - Each SOA stretches by l - l0 = arm_x a + arm_y b, its rest lever arms about the pivot
      (:func:`soa_lever_arms_m` with the pivot at mid-arc, which is where the default file's pivots'
      midpoint sits): a fixed tendon with those coefficients, so Eq 3-4's force (P A - (m_a P +
      n_a)(l - l0)) acts on both hinges through its first-order geometry. What that leaves out is
      second order in theta: the chord's shortening under the sockets (L theta^2 / 24 against arm
      theta, r about 23 mm, L 37 mm: 3 % of the stretch at theta = 0.5 rad).
    - The SOA dampers: c (arm_x a' + arm_y b')^2 summed over the SOAs is c sum(arm_x^2) a'^2 + c
      sum(arm_y^2) b'^2 (the cross sum vanishes for SOAs evenly round the rod), a damping of c
      sum(arm^2) on each hinge, which MuJoCo's Euler step integrates implicitly."""

    stiffness_nm_rad: float  # on each hinge
    damping_nms: dict[str, float]  # on each hinge, about X and about Y
    arms_m: dict[str, np.ndarray]  # each SOA's tendon coefficients on the two hinges, m/rad

    @classmethod
    def of(
        cls,
        arms_m: dict[str, np.ndarray],
        damping_n_s_per_m: float,
        rod_bending_stiffness_nm_rad: float,
    ) -> MountJoint:
        """The joint whose SOAs have lever arms ``arms_m`` (:func:`soa_lever_arms_m`), each a damper
        c, and whose rod has E I / L = ``rod_bending_stiffness_nm_rad`` across the gap."""
        return cls(
            stiffness_nm_rad=rod_bending_stiffness_nm_rad,
            damping_nms={
                axis: damping_n_s_per_m * float(np.sum(a**2)) for axis, a in arms_m.items()
            },
            arms_m=arms_m,
        )
