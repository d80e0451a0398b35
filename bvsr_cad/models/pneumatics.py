"""The pneumatic supply of a line: valve (ISO 6358), tube, SOA chambers, polytropic air.

The alternative to the paper's Eq 13 ramp: the pressure in a line's SOAs
rises only as fast as the valve lets air in. Per pressurised line, with the
line's absolute pressure p as the state,

    q_m = C rho_0 p_u sqrt(T_0 / T_u) phi(p_d / p_u)                (ISO 6358-1, Eq 1-2)
    phi(r) = 1                                    r <= b (choked)
           = sqrt(1 - ((r - b) / (1 - b))^2)       b < r < 0.999
           -> 0 linearly                           0.999 <= r <= 1 (laminar end)
    dp/dt = n / V (R T_s q_m - p dV/dt)                            (polytropic filling)
    V = V_tube + sum over the line's SOAs of (V_soa + A dl)

C is the valve's sonic conductance (catalogue unit dm^3/(s bar), converted
here to m^3/(s Pa)), b its critical pressure ratio, rho_0 = 1.185 kg/m^3 and
T_0 = 293.15 K the ISO 8778 reference, R = 287.05 J/(kg K), n the polytropic
index (1: isothermal, 1.4: adiabatic). The tube enters as volume (its length
from the BOM's tube route, its bore); its flow resistance is not modelled
(a 2.5 mm bore passes about 10 times the flow of a small solenoid valve's
orifice, so the valve dominates). V_soa is the SOA's air space from the
B-rep; it grows by A dl as the SOA stretches (A the effective area of Eq 3).

A line with the valve shut stays at atmospheric pressure in this model (the
experiments pressurise some lines and leave the others open).

:func:`first_order_time_constant_s` reduces the supply to the first-order lag
that the MJCF's actuators carry (MuJoCo ``dyntype="filter"``), so the
exported model keeps working in plain MuJoCo.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

#: Specific gas constant of dry air, J/(kg K).
R_AIR_J_KG_K = 287.05
#: ISO 8778 reference atmosphere: density (kg/m^3) and temperature (K).
RHO_0_KG_M3 = 1.185
T_0_K = 293.15
#: Catalogue unit of C: 1 dm^3/(s bar) in m^3/(s Pa).
M3_S_PA_PER_L_S_BAR = 1e-3 / 1e5


def iso6358_mass_flow_kg_s(
    p_up_pa: np.ndarray | float,
    p_down_pa: np.ndarray | float,
    conductance_m3_s_pa: float,
    critical_ratio: float,
    temperature_k: float = T_0_K,
) -> np.ndarray:
    """Mass flow through a valve from p_up to p_down (absolute Pa, broadcast); negative when it
    flows back: :func:`_mass_flow_one_kg_s`, the law's one home, at every pair of pressures."""
    up, down = np.broadcast_arrays(np.asarray(p_up_pa, float), np.asarray(p_down_pa, float))
    flows = [
        _mass_flow_one_kg_s(u, d, conductance_m3_s_pa, critical_ratio, temperature_k)
        for u, d in zip(up.ravel().tolist(), down.ravel().tolist())
    ]
    return np.array(flows, float).reshape(up.shape)[()]


def _mass_flow_one_kg_s(
    p_up_pa: float,
    p_down_pa: float,
    conductance_m3_s_pa: float,
    critical_ratio: float,
    temperature_k: float,
) -> float:
    """The ISO 6358 mass flow of one valve on floats (a line's filling asks for it at every step of
    its integration: no arrays per call)."""
    sign = 1.0 if p_up_pa >= p_down_pa else -1.0
    hi, lo = max(p_up_pa, p_down_pa), min(p_up_pa, p_down_pa)
    r = lo / max(hi, 1e-9)

    def subsonic(x: float) -> float:
        return math.sqrt(
            min(max(1.0 - ((x - critical_ratio) / (1.0 - critical_ratio)) ** 2, 0.0), 1.0)
        )

    # Near r = 1 the ellipse's slope is infinite (no flow law has that): below a 0.1 % drop the flow
    # falls linearly to zero, the laminar end of ISO 6358-3, which keeps the integrators' steps
    # sane.
    r_lam = 0.999
    if r <= critical_ratio:
        phi = 1.0
    elif r < r_lam:
        phi = subsonic(r)
    else:
        phi = subsonic(r_lam) * (1.0 - r) / (1.0 - r_lam)
    return sign * conductance_m3_s_pa * RHO_0_KG_M3 * hi * math.sqrt(T_0_K / temperature_k) * phi


@dataclass(frozen=True)
class Valve:
    """A valve's ISO 6358 flow rating."""

    conductance_m3_s_pa: float  # C
    critical_ratio: float  # b

    @classmethod
    def from_catalogue(cls, conductance_l_s_bar: float, critical_ratio: float) -> Valve:
        return cls(conductance_l_s_bar * M3_S_PA_PER_L_S_BAR, critical_ratio)


@dataclass(frozen=True)
class LineSupply:
    """The pressurised lines of one experiment, each feeding its SOAs through its own valve.

    ``lines`` gives, for each of the joint's five SOA places, the index of the
    line state that feeds it, or -1 for an SOA left at atmospheric pressure.
    Each line feeds ``soas_per_line`` SOAs (one per joint of the segment),
    which all stretch alike in the segment model.
    """

    valve: Valve
    source_pa_abs: float
    atmospheric_pa: float
    tube_volume_m3: Sequence[float]  # per line state
    soa_volume_m3: float  # one SOA's air space at rest
    soa_area_m2: float  # dV/dl of one SOA
    soas_per_line: int
    lines: tuple[int, ...]  # per SOA place: line state index or -1
    polytropic_index: float = 1.2
    temperature_k: float = T_0_K

    @property
    def n_states(self) -> int:
        return len(self.tube_volume_m3)

    def initial_state(self) -> np.ndarray:
        return np.full(self.n_states, self.atmospheric_pa)

    def soa_gauge_pa(self, state: np.ndarray) -> np.ndarray:
        """Gauge pressure of the five SOA places."""
        out = np.zeros(len(self.lines))
        for place, line in enumerate(self.lines):
            if line >= 0:
                out[place] = state[line] - self.atmospheric_pa
        return out

    def volumes_m3(
        self, dl_m: np.ndarray, dl_rate_m_s: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """(V, dV/dt) of every line state; dl (n_joints, 5) of the SOAs in the joints that bend
        together.

        The joints carry one SOA of each line; in the segment model they all
        stretch alike, so the line's SOAs are ``soas_per_line`` copies of the
        mean stretch over the given joints.
        """
        v, dv = self._volumes(dl_m, dl_rate_m_s)
        return np.array(v), np.array(dv)

    def _volumes(
        self, dl_m: np.ndarray, dl_rate_m_s: np.ndarray
    ) -> tuple[list[float], list[float]]:
        v = [float(x) for x in self.tube_volume_m3]
        dv = [0.0] * self.n_states
        dl_m, dl_rate_m_s = np.atleast_2d(dl_m), np.atleast_2d(dl_rate_m_s)
        mean_dl = (
            dl_m.sum(0) / dl_m.shape[0]
        ).tolist()  # np.mean's sum and division, without its checks
        mean_rate = (dl_rate_m_s.sum(0) / dl_rate_m_s.shape[0]).tolist()
        for place, line in enumerate(self.lines):
            if line >= 0:
                v[line] += self.soas_per_line * (
                    self.soa_volume_m3 + self.soa_area_m2 * mean_dl[place]
                )
                dv[line] += self.soas_per_line * self.soa_area_m2 * mean_rate[place]
        return v, dv

    def state_rates(
        self, t_s: float, state: np.ndarray, dl_m: np.ndarray, dl_rate_m_s: np.ndarray
    ) -> np.ndarray:
        """dp/dt of every line (the valve opens at t = 0)."""
        v, dv = self._volumes(dl_m, dl_rate_m_s)
        rt = R_AIR_J_KG_K * self.temperature_k
        out = []
        for line, p in enumerate(np.asarray(state, float).tolist()):
            q = (
                _mass_flow_one_kg_s(
                    self.source_pa_abs,
                    p,
                    self.valve.conductance_m3_s_pa,
                    self.valve.critical_ratio,
                    self.temperature_k,
                )
                if t_s >= 0
                else 0.0
            )
            out.append(self.polytropic_index / v[line] * (rt * q - p * dv[line]))
        return np.array(out)


def fill_curve(
    supply: LineSupply, seconds: float, samples: int = 2000
) -> tuple[np.ndarray, np.ndarray]:
    """Gauge pressure of line 0 filling its SOAs held at rest length: (time s, gauge Pa)."""
    from scipy.integrate import solve_ivp

    zeros = np.zeros((1, len(supply.lines)))

    def f(t, y):
        return supply.state_rates(t, y, zeros, zeros)

    t = np.linspace(0.0, seconds, samples)
    sol = solve_ivp(
        f, (0.0, seconds), supply.initial_state(), t_eval=t, rtol=1e-7, atol=1.0, method="RK45"
    )
    return sol.t, sol.y[0] - supply.atmospheric_pa


def first_order_time_constant_s(supply: LineSupply) -> float:
    """The lag tau of p' = (P0 - p) / tau fitted to the supply filling its SOAs at rest: least
    squares of P0 (1 - exp(-t / tau)) against the fill curve up to 95 % of P0 (the MJCF actuators'
    ``dynprm``).

    At rest every SOA place stretches alike (not at all), so which places a line feeds does not
    change its fill."""
    from scipy.optimize import minimize_scalar

    p0 = supply.source_pa_abs - supply.atmospheric_pa
    horizon = 0.05
    for _ in range(12):
        t, p = fill_curve(supply, horizon)
        if p[-1] >= 0.95 * p0:
            break
        horizon *= 2
    end = int(np.argmax(p >= 0.95 * p0)) + 1 if p[-1] >= 0.95 * p0 else p.size
    t, p = t[:end], p[:end]
    t63 = float(t[int(np.argmax(p >= (1 - math.exp(-1)) * p0))])

    def rms(tau: float) -> float:
        return float(np.sqrt(np.mean((p0 * (1 - np.exp(-t / tau)) - p) ** 2)))

    return float(
        minimize_scalar(
            rms, bounds=(0.3 * t63, 3.0 * t63), method="bounded", options={"xatol": 1e-4 * t63}
        ).x
    )


__all__ = [
    "Valve",
    "LineSupply",
    "iso6358_mass_flow_kg_s",
    "fill_curve",
    "first_order_time_constant_s",
    "M3_S_PA_PER_L_S_BAR",
    "R_AIR_J_KG_K",
    "RHO_0_KG_M3",
    "T_0_K",
]
