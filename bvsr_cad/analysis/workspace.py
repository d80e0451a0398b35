"""The paper's workspace protocol (Sec. IV-A-4) on the static model.

Each of the 5 x n_segments lines is, with equal probability, pressurised
(uniform from atmospheric to the protocol's maximum), depressurised (uniform
from the minimum to atmospheric) or inactive (atmospheric); the tail is
mounted horizontally (gravity along -Y). The forward statics give every
joint's pose and the tip point (centre of the tip panel's distal face).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .. import units
from ..assembly.assemble import Assembly
from ..models.rod import rod_section
from ..models.statics import Actuator, LumpedMasses, TailStatics, quasi_static_segment
from ..parameters.layout import N_SOA
from ..parameters.tables import TailSpec
from .limits import UselessResultError

Progress = Callable[[str], None]


def lumped_masses(asm: Assembly) -> LumpedMasses:
    """Panel masses (with the rod inside them) and joint masses (its SOAs and the rod in the gap),
    kg."""
    spec = asm.spec
    rod = rod_section(spec)
    t = spec.joint.panel_thickness_mm
    panel_g = np.array(
        [asm.mass_g(asm.instance(f"panel{k}").part) for k in range(spec.panels)]
    ) + rod.mass_g(t)
    joint_g = np.array(
        [
            sum(asm.mass_g(i.part) for i in asm.soas_of_joint(k)) + rod.mass_g(spec.joint.gap_mm)
            for k in range(1, spec.joints + 1)
        ]
    )
    return LumpedMasses(panel_g / units.G_PER_KG, joint_g / units.G_PER_KG)


def sample_line_pressures_kpa(spec: TailSpec, n: int, rng: np.random.Generator) -> np.ndarray:
    """Gauge pressures (n, n_segments, 5) drawn by the paper's protocol."""
    a = spec.actuation
    shape = (n, spec.segments, N_SOA)
    state = rng.integers(0, 3, size=shape)  # 0 inactive, 1 pressurised, 2 depressurised
    up = rng.uniform(a.atmospheric_kpa, a.workspace_pressurised_max_kpa_abs, size=shape)
    down = rng.uniform(a.workspace_depressurised_min_kpa_abs, a.atmospheric_kpa, size=shape)
    absolute = np.where(state == 1, up, np.where(state == 2, down, a.atmospheric_kpa))
    return absolute - a.atmospheric_kpa


@dataclass(frozen=True)
class Workspace:
    samples: int
    seed: int
    tip_mm: np.ndarray  # (n, 3)
    w: np.ndarray  # (n, n_joints, 2)
    line_kpa: np.ndarray  # (n, n_segments, 5)

    def extent_mm(self) -> dict[str, list[float]]:
        return {
            ax: [float(self.tip_mm[:, i].min()), float(self.tip_mm[:, i].max())]
            for i, ax in enumerate("xyz")
        }

    @property
    def max_theta_rad(self) -> float:
        return float(np.max(np.hypot(self.w[..., 0], self.w[..., 1])))

    def summary(self) -> dict:
        """What `bvsr workspace` prints: the samples, the seed, the tip's extent along each axis
        (mm) and the largest joint bend (rad)."""
        return {
            "samples": self.samples,
            "seed": self.seed,
            "tip_extent_mm": self.extent_mm(),
            "max_theta_rad": self.max_theta_rad,
        }


def unsolved_problems(spec: TailSpec, line_kpa: np.ndarray, why: str) -> list[str]:
    """The protocol's pressures for which the forward statics find no equilibrium (Newton's steps do
    not shrink: the SOAs' force law, k = m_a P + n_a, leaves the straight tail no stiffness under
    vacuum), with the stiffness at the lowest gauge pressure drawn."""
    a = spec.actuation
    low = float(np.min(line_kpa))
    k = a.stiffness_slope_n_per_m_per_kpa * low + a.stiffness_offset_n_per_m
    return [
        f"actuation.stiffness_slope_n_per_m_per_kpa = {a.stiffness_slope_n_per_m_per_kpa!r}, "
        f"actuation.stiffness_offset_n_per_m = {a.stiffness_offset_n_per_m!r}: the forward statics "
        "find no "
        f"equilibrium for the workspace protocol's pressures ({why}); an SOA's k = m_a P + n_a is "
        f"{k:.0f} N/m "
        f"at the lowest gauge pressure drawn, {low:.1f} kPa "
        "(actuation.workspace_depressurised_min_kpa_abs = "
        f"{a.workspace_depressurised_min_kpa_abs!r}); allowed: a force law stiff enough at that "
        "pressure (the "
        "paper's fit: m_a = 9.4, n_a = 2918) or a shallower vacuum"
    ]


def empty_problems(ws: Workspace, spec: TailSpec) -> list[str]:
    """A workspace in which no sample bends any joint (every line at atmospheric, or forces that
    cannot bend the tail): what the protocol keys that drew it allow (``bvsr_cad.parameters.load``
    refuses the protocol that draws no pressure at load)."""
    if ws.samples == 0 or ws.max_theta_rad > 0.0:
        return []
    a = spec.actuation
    return [
        f"actuation.workspace_pressurised_max_kpa_abs = {a.workspace_pressurised_max_kpa_abs!r}, "
        "actuation.workspace_depressurised_min_kpa_abs = "
        f"{a.workspace_depressurised_min_kpa_abs!r}: none of "
        f"the {ws.samples} workspace samples bends a joint (the workspace is the straight tail's "
        "tip alone); "
        "allowed: a protocol that draws pressures other than actuation.atmospheric_kpa = "
        f"{a.atmospheric_kpa!r} "
        "and an SOA force that bends the tail"
    ]


def tail_statics(asm: Assembly, gravity: bool = True, spec: TailSpec | None = None) -> TailStatics:
    """The statics of the assembled tail; ``spec`` (default the assembly's, same geometry) may carry
    fitted values or another workspace protocol."""
    return TailStatics.from_spec(spec or asm.spec, lumped_masses(asm) if gravity else None)


def run_workspace(
    asm: Assembly,
    samples: int,
    seed: int,
    progress: Progress | None = None,
    chunk: int = 2000,
    spec: TailSpec | None = None,
) -> Workspace:
    """Sample the protocol and solve the forward statics of every sample (``spec``: see
    :func:`tail_statics`)."""
    say = progress or (lambda _m: None)
    spec = spec or asm.spec
    st = tail_statics(asm, spec=spec)
    rng = np.random.default_rng(seed)
    p = sample_line_pressures_kpa(spec, samples, rng)
    ws = []
    for i in range(0, samples, chunk):
        say(f"workspace: forward statics {i}..{min(samples, i + chunk)} of {samples}")
        try:
            ws.append(st.forward(p[i : i + chunk]))
        except RuntimeError as exc:
            raise UselessResultError(
                f"tail {spec.name!r}", unsolved_problems(spec, p[i : i + chunk], str(exc))
            ) from exc
    w = np.concatenate(ws)
    return Workspace(samples, seed, st.kin.tip_point_mm(w), w, p)


def quasi_static_table(asm: Assembly, area_scale: tuple[float, ...] = (1.0,)) -> list[dict]:
    """Table III from the model: one segment at the pressure limits (with gravity, mounted
    horizontally)."""
    rows = []
    for scale in area_scale:
        st = TailStatics.from_spec(
            asm.spec, lumped_masses(asm), area_mm2=Actuator.from_spec(asm.spec).area_mm2 * scale
        ).first_segment()
        for motion in ("extension", "flexion", "waggle"):
            q = quasi_static_segment(st, motion)
            rows.append(
                {
                    "motion": motion,
                    "area_mm2": st.act.area_mm2,
                    "max_angle_deg": q.max_angle_deg,
                    "blocked_force_n": q.blocked_force_n,
                    "line_kpa": list(q.line_kpa),
                }
            )
    return rows
