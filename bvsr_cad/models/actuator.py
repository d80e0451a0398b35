"""The SOA force law (Eq 3-4 with the damper of Eq 11): its one home, in SI.

    F = P A - (m_a P + n_a) dl - c dl/dt

with P the gauge pressure (Pa), dl the SOA's stretch from its rest length (m)
and k = m_a P + n_a its stiffness (Eq 4). The paper's fit k = 9.4 P + 2918 is
read with P in kPa and k in N/m (see :class:`bvsr_cad.parameters.tables.Actuation`),
so m_a here is 9.4e-3 N/m per Pa. The statics (N, mm, kPa) and the MJCF
actuators (SI) both evaluate this law; neither writes it again.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .. import units
from ..parameters.tables import TailSpec


@dataclass(frozen=True)
class SoaForceLaw:
    area_m2: float  # A
    stiffness_slope_n_per_m_per_pa: float  # m_a
    stiffness_offset_n_per_m: float  # n_a
    damping_n_s_per_m: float  # c

    def stiffness_n_per_m(self, pressure_pa):
        """Eq 4: k = m_a P + n_a."""
        return (
            self.stiffness_slope_n_per_m_per_pa * np.asarray(pressure_pa, float)
            + self.stiffness_offset_n_per_m
        )

    def force_n(self, pressure_pa, stretch_m, stretch_rate_m_s=0.0):
        """Eq 3 with the damper: F = P A - k(P) dl - c dl/dt (N, pushing the sockets apart)."""
        p = np.asarray(pressure_pa, float)
        return (
            p * self.area_m2
            - self.stiffness_n_per_m(p) * stretch_m
            - self.damping_n_s_per_m * stretch_rate_m_s
        )

    def scaled_area(self, factor: float) -> SoaForceLaw:
        return replace(self, area_m2=self.area_m2 * factor)


def soa_force_law(spec: TailSpec) -> SoaForceLaw:
    """The law of one SOA from the parameter file's ``[actuation]``, with the area and damping
    that `bvsr calibrate` fitted where the file carries them (``[calibration.fitted]``)."""
    a = spec.actuation
    return SoaForceLaw(
        area_m2=units.mm2_to_m2(spec.fitted("effective_area_mm2", a.effective_area_mm2)),
        stiffness_slope_n_per_m_per_pa=a.stiffness_slope_n_per_m_per_kpa / units.PA_PER_KPA,
        stiffness_offset_n_per_m=a.stiffness_offset_n_per_m,
        damping_n_s_per_m=spec.fitted("damping_n_s_per_m", a.damping_n_s_per_m),
    )
