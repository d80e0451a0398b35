"""The tail on a hinged platform: the paper's two-body model, Eq 20-22, and its cart experiment.

The platform (mass m_r, inertia I_r about its centre of mass, which sits L_r
from the hinge) turns by alpha about the hinge; the tail (m_t, I_t, its
centre of mass L_t from the hinge) turns by beta relative to it. Eq 22,

    (I_r + m_r L_r^2 + I_t + m_t L_t^2) alpha'' - (I_t + m_t L_t^2) beta''
        + m_r g L_r cos(alpha) - m_t g L_t cos(beta - alpha) = 0,

gives the platform's motion for the tail's motion beta(t), which comes from
the tail's own model (:mod:`bvsr_cad.models.dynamics`: the tail's body turns
by half its bending angle, Eq 7's premise). In the cart experiment (Sec. V-B)
the pitch hinge is the rear axle and the cart rests on its front wheel: it
lifts only while Eq 22 drives alpha above 0, and the front end rises by
wheelbase sin(alpha). Steering (waggle) turns the cart about a vertical axis,
where gravity does no work: the same equation with g = 0 and no ground.

While the front wheel is down the ground takes whatever moment would push it
into the floor; the cart lifts once Eq 22's moment about the hinge turns
positive, and lands (without bouncing) when alpha returns to 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .. import units

G_M_S2 = units.STANDARD_GRAVITY_M_S2


@dataclass(frozen=True)
class Platform:
    mass_kg: float  # m_r
    inertia_kg_m2: float  # I_r about its centre of mass
    com_from_hinge_m: float  # L_r
    wheelbase_m: float  # hinge to the front wheel's contact (the lift's lever)


@dataclass(frozen=True)
class TailOnPlatform:
    mass_kg: float  # m_t
    inertia_kg_m2: float  # I_t about its centre of mass
    com_from_hinge_m: float  # L_t


@dataclass
class PlatformMotion:
    time_s: np.ndarray
    alpha_rad: np.ndarray
    beta_rad: np.ndarray

    @property
    def peak_angle_deg(self) -> float:
        return float(np.degrees(np.max(np.abs(self.alpha_rad))))

    def lift_mm(self, wheelbase_m: float) -> float:
        return front_lift_mm(wheelbase_m, self.alpha_rad)


def front_lift_mm(wheelbase_m: float, pitch_rad: np.ndarray) -> float:
    """How high the front wheel rises over a pitch trace (rear axle as hinge; 0 while it rests)."""
    return float(units.m_to_mm(wheelbase_m * np.sin(max(0.0, float(np.max(pitch_rad))))))


def platform_motion(
    platform: Platform,
    tail: TailOnPlatform,
    time_s: np.ndarray,
    beta_rad: np.ndarray,
    gravity: bool = True,
) -> PlatformMotion:
    """Integrate Eq 22 for a given tail motion beta(t) (semi-implicit Euler on the trace's own
    steps, refined 20 times between samples). With ``gravity`` the cart pitches on the ground (alpha
    >= 0); without it, it turns freely about a vertical hinge."""
    from scipy.interpolate import CubicSpline

    t = np.asarray(time_s, float)
    spline = CubicSpline(t, np.asarray(beta_rad, float))
    acc = spline.derivative(2)
    j_t = tail.inertia_kg_m2 + tail.mass_kg * tail.com_from_hinge_m**2
    j_all = platform.inertia_kg_m2 + platform.mass_kg * platform.com_from_hinge_m**2 + j_t
    g = G_M_S2 if gravity else 0.0
    fine = np.linspace(t[0], t[-1], 20 * (len(t) - 1) + 1)
    dt = fine[1] - fine[0]
    alpha, rate = 0.0, 0.0
    out = np.zeros_like(fine)
    betas, accs = spline(fine).tolist(), acc(fine).tolist()  # the spline once, not per step
    for i, (beta, beta_acc) in enumerate(zip(betas, accs)):
        moment = (
            j_t * beta_acc
            - platform.mass_kg * g * platform.com_from_hinge_m * math.cos(alpha)
            + tail.mass_kg * g * tail.com_from_hinge_m * math.cos(beta - alpha)
        )
        a = moment / j_all
        if gravity and alpha <= 0.0 and rate <= 0.0 and a <= 0.0:
            alpha, rate = 0.0, 0.0  # resting on the front wheel: the ground takes the moment
        else:
            rate += a * dt
            alpha += rate * dt
            if gravity and alpha < 0.0:
                alpha, rate = 0.0, 0.0  # lands (no bounce)
        out[i] = alpha
    return PlatformMotion(fine, out, spline(fine))


__all__ = ["Platform", "TailOnPlatform", "PlatformMotion", "platform_motion", "front_lift_mm"]
