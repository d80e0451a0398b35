"""The figures a design study records for one tail, computed from the models, not from an export.

A study (`bvsr sweep`) asks for metric *groups*; each group builds only what it
needs: ``mass`` the assembly's B-rep masses, ``statics`` the quasi-static model
(Table III and the paper's lateral stiffness test, Fig. 3 d-f), ``workspace`` the
random-pressure protocol, ``dynamics`` the Eq 6-12 pulses with the spec's supply,
``clearance`` the certified clearance over the workspace's poses, ``limits`` the
exact joint limits. The ``checks`` group (a full export and every check) is run by
the study engine (:mod:`bvsr_cad.studies.sweep`), which sits above the pipeline.

Every metric's name carries its unit. :data:`METRICS` lists them by group with a
line of documentation; :func:`model_metrics` computes the groups asked for.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .. import units
from ..assembly.assemble import Assembly, build_assembly
from ..models.rod import rod_section
from ..models.statics import lateral_stiffness_n_per_mm
from ..parameters.measurements import MOTIONS
from ..parameters.tables import TailSpec
from .predict import Predictor
from .workspace import run_workspace, tail_statics

Progress = Callable[[str], None]


@dataclass(frozen=True)
class Conditions:
    """Where the dynamic metrics are taken: a pulse of ``pressure_bar`` (gauge) for ``motion``, with
    ``payload_g`` at the tip for the whole tail's root wrench."""

    pressure_bar: float = 6.0
    motion: str = "extension"
    payload_g: float = 0.0


#: group -> {metric: what it is}. Names carry units; ``_ok`` metrics are booleans.
METRICS: dict[str, dict[str, str]] = {
    "mass": {
        "mass_g": "modelled mass of the tail: panels, SOAs and rods (B-rep volumes x densities)",
        "length_mm": "tail length, root face to tip face",
        "rod_flexural_rigidity_n_mm2": "the vertebra's E I as the models use it (fitted ratio "
        "applied; 0: no rod)",
    },
    "statics": {
        "lateral_stiffness_n_per_mm": "one segment's passive tip stiffness sideways, lines open "
        "(Fig. 3 d)",
        **{
            f"blocked_force_{m}_n": f"one segment's blocked tip force in {m} at the pressure "
            "limits (Fig. 3 e)"
            for m in MOTIONS
        },
        **{
            f"max_angle_{m}_deg": f"one segment's free bending angle in {m} at the pressure limits "
            "(Fig. 3 f)"
            for m in MOTIONS
        },
    },
    "workspace": {
        **{
            f"workspace_{a}_{e}_mm": f"tip workspace, {e} {a} (tail frame, random protocol)"
            for a in "xy"
            for e in ("min", "max")
        },
        "workspace_radius_mm": "largest lateral distance of the tip from its rest point",
    },
    "dynamics": {
        "peak_velocity_deg_s": "one segment's peak bending rate before 38 deg after a pulse",
        "root_peak_torque_nm": "the whole tail's peak root torque after a pulse",
        "root_peak_force_n": "the whole tail's peak root force after a pulse",
        "root_torque_per_mass_nm_per_kg": "root_peak_torque_nm per kg of tail (needs mass)",
    },
    "clearance": {
        "min_clearance_mm": "certified minimum clearance between solids that must not touch, over "
        "the workspace's poses",
        "clearance_margin_mm": "min_clearance_mm minus analysis.min_clearance_mm (>= 0: the "
        "required clearance holds)",
    },
    "limits": {
        "joint_limit_min_deg": "smallest theta_max over every joint and bending plane (exact "
        "clearance limits)",
        "joint_limit_max_deg": "largest theta_max over every joint and bending plane",
    },
}

#: Groups a group needs computed first (its figures read theirs).
REQUIRES = {"dynamics": ("mass",), "clearance": ("workspace",)}


def group_of(metric: str) -> str | None:
    for group, names in METRICS.items():
        if metric in names:
            return group
    return None


def calibration_metrics(spec: TailSpec) -> dict[str, float]:
    """The base file's fitted values (``fitted_<name>``), recorded with every variant."""
    return {f"fitted_{k}": float(v) for k, v in sorted(spec.calibration.fitted.items())}


def model_metrics(
    spec: TailSpec,
    groups: list[str],
    conditions: Conditions = Conditions(),
    progress: Progress | None = None,
    asm: Assembly | None = None,
) -> dict[str, float | bool]:
    """The metrics of ``groups`` (keys of :data:`METRICS`) for ``spec``, with the seconds each took
    (``seconds_<group>``) and the calibration's fitted values."""
    say = progress or (lambda _m: None)
    wanted = list(dict.fromkeys(g for group in groups for g in (*REQUIRES.get(group, ()), group)))
    unknown = [g for g in wanted if g not in METRICS]
    if unknown:
        raise ValueError(f"unknown metric groups {unknown}; allowed: {', '.join(METRICS)}")
    out: dict[str, float | bool] = dict(calibration_metrics(spec))
    t0 = time.perf_counter()
    asm = asm or build_assembly(spec)
    out["seconds_assembly"] = time.perf_counter() - t0
    pred = Predictor(asm, spec)
    ws = None
    posed = []  # the clearance model of the tail, built once for clearance and limits

    def posed_tail_once():
        from .clearance import posed_tail

        if not posed:
            posed.append(posed_tail(asm))
        return posed[0]

    for group in wanted:
        t = time.perf_counter()
        say(f"metrics: {group}")
        if group == "mass":
            out["mass_g"] = float(sum(asm.mass_g(i.part) for i in asm.instances))
            out["length_mm"] = float(spec.length_mm)
            out["rod_flexural_rigidity_n_mm2"] = float(rod_section(spec).flexural_rigidity_n_mm2)
        elif group == "statics":
            seg = tail_statics(asm, spec=spec).first_segment()
            out["lateral_stiffness_n_per_mm"] = lateral_stiffness_n_per_mm(seg)
            for m in MOTIONS:
                qs = pred.quasi_static(m)
                out[f"blocked_force_{m}_n"] = qs.blocked_force_n
                out[f"max_angle_{m}_deg"] = qs.max_angle_deg
        elif group == "workspace":
            cfg = spec.analysis
            ws = run_workspace(asm, cfg.build_workspace_samples, cfg.seed, spec=spec)
            st = tail_statics(asm, spec=spec)
            rest = st.kin.tip_point_mm(st.forward(np.zeros((spec.segments, 5))))
            for i, a in enumerate("xy"):
                out[f"workspace_{a}_min_mm"] = float(ws.tip_mm[:, i].min())
                out[f"workspace_{a}_max_mm"] = float(ws.tip_mm[:, i].max())
            out["workspace_radius_mm"] = float(
                np.max(np.hypot(ws.tip_mm[:, 0] - rest[0], ws.tip_mm[:, 1] - rest[1]))
            )
        elif group == "dynamics":
            c = conditions
            out["peak_velocity_deg_s"] = pred.segment_peak_velocity(c.motion, c.pressure_bar)
            force_n, torque_nm = pred.root_wrench(c.motion, c.pressure_bar, c.payload_g)
            out["root_peak_torque_nm"] = torque_nm
            out["root_peak_force_n"] = force_n
            out["root_torque_per_mass_nm_per_kg"] = torque_nm / units.g_to_kg(out["mass_g"])
        elif group == "clearance":
            from .clearance import clearance_over

            rng = np.random.default_rng(spec.analysis.seed)
            idx = rng.integers(0, ws.samples, spec.analysis.build_clearance_poses)
            res = clearance_over(posed_tail_once(), ws.w[idx])
            out["min_clearance_mm"] = float(res.min_clearance_mm)
            out["clearance_margin_mm"] = float(
                res.min_clearance_mm - spec.analysis.min_clearance_mm
            )
        elif group == "limits":
            from .limits import build_joint_limits

            lims = build_joint_limits(posed_tail_once(), spec)
            theta = np.concatenate([lim.theta_max_rad for lim in lims])
            out["joint_limit_min_deg"] = float(np.degrees(theta.min()))
            out["joint_limit_max_deg"] = float(np.degrees(theta.max()))
        out[f"seconds_{group}"] = time.perf_counter() - t
    return out


__all__ = ["METRICS", "Conditions", "model_metrics", "group_of", "calibration_metrics"]
