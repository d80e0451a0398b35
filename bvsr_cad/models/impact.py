"""The balls of the paper's disturbance test (Sec. IV-D, Fig. 17) and how they roll and give.

The paper gives each ball's size and mass and the ramp (1.35 m at 45 deg). What
it does not give is taken from the rules the balls are made to: a size 5 and
a size 7 basketball's circumference (FIBA: 69-71 cm and 74.9-78 cm, the
middles here), the inflation its makers print (7.5-8.5 psi, 55 kPa here) and
the rebound FIBA asks for (1.2-1.4 m from 1.8 m: e = sqrt(1.3 / 1.8) = 0.85).

An inflated ball gives like a spring: pressed by delta, its shell flattens on
a disc of radius a, a^2 = 2 r delta, and the air pushes back on it,
F = p pi a^2 = 2 pi r p delta, so k = 2 pi r p (the shell's own bending
neglected); its losses are the damping that returns ``restitution`` of the
speed (a damped spring's half period).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..units import STANDARD_GRAVITY_M_S2

#: The paper's ramp (Sec. IV-D, Fig. 17c): the ball is released at its top.
RAMP_LENGTH_M = 1.35
RAMP_ANGLE_DEG = 45.0
#: A thin shell's moment of inertia over m r^2 (a basketball is a rubber shell).
SHELL_INERTIA_RATIO = 2.0 / 3.0


@dataclass(frozen=True)
class Ball:
    name: str
    mass_kg: float
    circumference_m: float
    gauge_pressure_pa: float
    restitution: float

    @property
    def radius_m(self) -> float:
        return self.circumference_m / (2.0 * math.pi)

    @property
    def stiffness_n_per_m(self) -> float:
        """k = 2 pi r p: the flattened cap's area times the inflation pressure, per unit press."""
        return 2.0 * math.pi * self.radius_m * self.gauge_pressure_pa

    def damping_n_s_per_m(self, mass_kg: float | None = None) -> float:
        """c = 2 zeta sqrt(k m) of the damped spring whose bounce returns ``restitution`` of the
        speed."""
        ln_e = math.log(self.restitution)
        zeta = -ln_e / math.sqrt(math.pi**2 + ln_e**2)
        return 2.0 * zeta * math.sqrt(self.stiffness_n_per_m * (mass_kg or self.mass_kg))

    @property
    def contact_time_s(self) -> float:
        """Half period of the ball's mass on its own stiffness: how long a bounce on a wall
        lasts."""
        return math.pi * math.sqrt(self.mass_kg / self.stiffness_n_per_m)


#: The paper's two balls (masses from Sec. IV-D; sizes, pressure and rebound as above).
BALLS = {
    "size5": Ball("size 5 ball (500 g)", 0.500, 0.700, 55e3, 0.85),
    "size7": Ball("size 7 ball (650 g)", 0.650, 0.765, 55e3, 0.85),
}


def rolling_speed_m_s(drop_m: float, inertia_ratio: float = SHELL_INERTIA_RATIO) -> float:
    """Speed of a ball rolling without slipping from rest after a drop of ``drop_m``:
    m g h = (1/2)(1 + I / (m r^2)) m v^2."""
    return math.sqrt(2.0 * STANDARD_GRAVITY_M_S2 * drop_m / (1.0 + inertia_ratio))
