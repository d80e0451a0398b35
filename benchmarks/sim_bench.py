"""Simulation cost of an exported tail's scene, in one run:

- counts: DoFs, joints, tendons by kind (fixed, spatial; how many carry damping, stiffness,
  limits), equality constraints, and the most constraint rows (all; from limits, equalities,
  contacts) CPU MuJoCo has in any step of 0.3 s of each held pressure pattern from rest
  (:func:`held_patterns`);
- CPU, one core (the process pinned to one CPU): CPU MuJoCo's steps/s and real-time factor at the
  exported time step, and MuJoCo Warp's steps/s on the CPU at a small batch; with ``--baseline
  OTHER/scene.xml`` the same for that scene, the two alternated over ``--rounds`` rounds (the
  order flips each round), and the scene's ratio to the baseline;
- batches: MuJoCo Warp, with and without CUDA-graph capture, and MJX at batch 1, 1024 and 8192 on
  a CUDA GPU, hinge stiffness, damping and tip payload varied per world; each batch's world 0 is
  checked against CPU MuJoCo stepping world 0's model;
- stages: where a MuJoCo Warp step's time goes at the largest batch (tendon, collision,
  constraint, passive, integrator), from the event scopes MuJoCo Warp wraps its stages in: GPU time
  from CUDA events on a GPU (the step replayed as a CUDA graph), host wall time on a CPU device; on
  a GPU also the GPU time of the kernels named after tendons (Warp's kernel timing).

Without a CUDA GPU it says so, runs tiny batches on the CPU backends (``--cpu-batches``) to prove
the code path (their rates say nothing about a GPU) and skips CUDA-graph capture with a line
saying so. MJX and Warp come with the extra ``.[gpu]`` (MJX on an NVIDIA GPU also needs
``jax[cuda12]``).

    python benchmarks/sim_bench.py EXPORT_DIR --baseline OLD_EXPORT/robot/scene.xml --no-mjx
    python benchmarks/sim_bench.py EXPORT_DIR --json out.json    # every figure, machine-readable
    python benchmarks/sim_bench.py EXPORT_DIR --gpu-batches 8192,65536 --profile   # per kernel

``--profile`` adds every stage's time and, on CUDA, MuJoCo Warp's slowest kernels at the largest
batch in GPU ms per step, from steps launched one by one under Warp's kernel timing.
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import os
import shutil
import statistics
import sys
import time
from pathlib import Path
from typing import NamedTuple

os.environ.setdefault("XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false")  # polite on a shared CPU

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from bvsr_cad.simulation import sim_gpu  # noqa: E402

GPU_BATCHES = (1, 1024, 8192)
COUNT_SECONDS = 0.3  # the accuracy goals' held-pattern length
#: A step's event scopes (MuJoCo Warp's function names) by stage; a scope inside one already
#: counted is not counted again. The tendons' passive forces and damping derivative run inside
#: ``passive`` and ``implicit``: on CUDA the kernel timing gives the tendons' whole share.
STAGES = {
    "tendon": ("tendon", "tendon_armature", "tendon_bias"),
    "collision": ("collision",),
    "constraint": ("make_constraint", "solve"),
    "passive": ("passive",),
    "integrator": ("euler", "implicit", "rungekutta4"),
}


class Scene(NamedTuple):
    label: str
    path: Path
    model: mujoco.MjModel
    ctrl: np.ndarray  # the held pressure the rates are measured under


# --- counts ------------------------------------------------------------------------------------


def actuator_moments(model: mujoco.MjModel) -> np.ndarray:
    """Each actuator's generalised-force direction at the rest pose, (nu, nv)."""
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    dense = np.zeros((model.nu, model.nv))
    mujoco.mju_sparse2dense(
        dense, data.actuator_moment, data.moment_rownnz, data.moment_rowadr, data.moment_colind
    )
    return dense


def held_patterns(model: mujoco.MjModel) -> list[tuple[str, np.ndarray]]:
    """Held pressure patterns ``(name, ctrl)``, every pressurised actuator at the top of its range.

    Actuators are named ``<joint>_<line>``. A joint's *side* is the actuators that bend it the way
    its first one does (a positive dot product of their moments at rest). The patterns: rest; all
    lines; all lines at the bottom of the range (vacuum); the first line's side in every joint; the
    other side; the two sides alternating from joint to joint (an S-bend); each line alone."""
    limited = model.actuator_ctrllimited.astype(bool)
    top = np.where(limited, model.actuator_ctrlrange[:, 1], 0.0)
    bottom = np.where(limited, model.actuator_ctrlrange[:, 0], 0.0)
    names = [model.actuator(i).name for i in range(model.nu)]
    joint = [n.rsplit("_", 1)[0] for n in names]
    line = np.array([n.rsplit("_", 1)[-1] for n in names])
    joints = list(dict.fromkeys(joint))
    moment = actuator_moments(model)
    side = np.zeros(model.nu, bool)
    for j in joints:
        members = [i for i in range(model.nu) if joint[i] == j]
        side[members] = moment[members] @ moment[members[0]] > 0
    even = np.array([joints.index(j) % 2 == 0 for j in joint])
    first = line[0] if model.nu else ""
    patterns = [
        ("rest", np.zeros(model.nu)),
        ("all lines", top),
        ("all lines, vacuum", bottom),
        (f"{first}'s side", np.where(side, top, 0.0)),
        (f"opposite {first}'s side", np.where(~side, top, 0.0)),
        ("sides alternating", np.where(side == even, top, 0.0)),
    ]
    return patterns + [(f"{g} alone", np.where(line == g, top, 0.0)) for g in dict.fromkeys(line)]


def _is_fixed(model: mujoco.MjModel, tendon: int) -> bool:
    adr, num = model.tendon_adr[tendon], model.tendon_num[tendon]
    return bool((model.wrap_type[adr : adr + num] == mujoco.mjtWrap.mjWRAP_JOINT).all())


def scene_counts(model: mujoco.MjModel, seconds: float = COUNT_SECONDS) -> dict:
    """The scene's sizes, and the most constraint rows of each kind CPU MuJoCo has in any step of
    ``seconds`` of each :func:`held_patterns` from rest (``rows``; ``rows_by_pattern``: all
    rows)."""
    joint_types = {
        name.removeprefix("mjJNT_").lower(): int(t)
        for name, t in mujoco.mjtJoint.__members__.items()
    }
    fixed = [_is_fixed(model, t) for t in range(model.ntendon)]
    counts = {
        "timestep_s": float(model.opt.timestep),
        "nq": model.nq,
        "nv": model.nv,
        "nu": model.nu,
        "joints": {name: int((model.jnt_type == t).sum()) for name, t in joint_types.items()},
        "limited_joints": int(model.jnt_limited.sum()),
        "stiff_joints": int((model.jnt_stiffness > 0).sum()),
        "damped_dofs": int((model.dof_damping > 0).sum()),
        "tendons": model.ntendon,
        "fixed_tendons": int(sum(fixed)),
        "spatial_tendons": int(model.ntendon - sum(fixed)),
        "damped_tendons": int((model.tendon_damping > 0).sum()),
        "stiff_tendons": int((model.tendon_stiffness > 0).sum()),
        "limited_tendons": int(model.tendon_limited.sum()),
        "equalities": model.neq,
        "limit_rows_possible": int(model.jnt_limited.sum() + model.tendon_limited.sum()),
    }
    c = mujoco.mjtConstraint
    kinds = {
        "limit": (int(c.mjCNSTR_LIMIT_JOINT), int(c.mjCNSTR_LIMIT_TENDON)),
        "equality": (int(c.mjCNSTR_EQUALITY),),
        "friction": (int(c.mjCNSTR_FRICTION_DOF), int(c.mjCNSTR_FRICTION_TENDON)),
        "contact": tuple(
            int(k)
            for k in (
                c.mjCNSTR_CONTACT_FRICTIONLESS,
                c.mjCNSTR_CONTACT_PYRAMIDAL,
                c.mjCNSTR_CONTACT_ELLIPTIC,
            )
        ),
    }
    most = dict.fromkeys(["all", *kinds], 0)
    by_pattern, warned = {}, set()
    data = mujoco.MjData(model)
    for name, ctrl in held_patterns(model):
        mujoco.mj_resetData(model, data)
        data.ctrl[:] = ctrl
        seen = 0
        for _ in range(max(1, round(seconds / model.opt.timestep))):
            mujoco.mj_step(model, data)
            types = data.efc_type[: data.nefc]
            seen = max(seen, data.nefc)
            for kind, members in kinds.items():
                most[kind] = max(most[kind], int(np.isin(types, members).sum()))
        warned |= {mujoco.mjtWarning(i).name for i, w in enumerate(data.warning) if w.number}
        by_pattern[name] = int(seen)
        most["all"] = max(most["all"], int(seen))
    worst = [name for name, rows in by_pattern.items() if rows == most["all"]]
    counts["rows"] = most | {"patterns": worst, "seconds": seconds}
    counts["rows_by_pattern"] = by_pattern
    counts["warnings"] = sorted(warned)
    return counts


COUNT_ROWS = (  # (label, how to read it from scene_counts)
    ("DoFs (nv)", lambda c: c["nv"]),
    ("joints: hinge / ball", lambda c: f"{c['joints']['hinge']} / {c['joints']['ball']}"),
    ("  limited / with stiffness", lambda c: f"{c['limited_joints']} / {c['stiff_joints']}"),
    ("  DoFs with damping", lambda c: c["damped_dofs"]),
    ("tendons", lambda c: c["tendons"]),
    ("  fixed / spatial", lambda c: f"{c['fixed_tendons']} / {c['spatial_tendons']}"),
    (
        "  damped / stiff / limited",
        lambda c: f"{c['damped_tendons']} / {c['stiff_tendons']} / {c['limited_tendons']}",
    ),
    ("equality constraints", lambda c: c["equalities"]),
    ("limits (rows at most)", lambda c: c["limit_rows_possible"]),
    ("constraint rows, most", lambda c: c["rows"]["all"]),
    ("  of them limit rows", lambda c: c["rows"]["limit"]),
    ("  equality rows", lambda c: c["rows"]["equality"]),
    ("  contact rows", lambda c: c["rows"]["contact"]),
    ("  most under", lambda c: _patterns(c["rows"]["patterns"], len(c["rows_by_pattern"]))),
)


def _patterns(names: list[str], of: int) -> str:
    if len(names) == of:
        return f"all {of} patterns"
    return names[0] + (f" and {len(names) - 1} more" if len(names) > 1 else "")


def counts_table(scenes: list[Scene], counts: dict[str, dict]) -> str:
    head = f"{'':28s}" + "".join(f"{s.label:>24s}" for s in scenes)
    lines = [head]
    for label, read in COUNT_ROWS:
        lines.append(f"{label:28s}" + "".join(f"{str(read(counts[s.label])):>24s}" for s in scenes))
    return "\n".join(lines)


# --- CPU, one core -------------------------------------------------------------------------------


def cpu_rate(
    model: mujoco.MjModel, ctrl: np.ndarray, seconds: float
) -> tuple[float, float, list[str]]:
    """Steps of one CPU MuJoCo per wall second and per CPU second of this process, stepping for
    about ``seconds``, and its warnings. On a shared machine the wall rate is the CPU share the
    process got; the CPU rate is the step's own cost."""
    data = mujoco.MjData(model)
    data.ctrl[:] = ctrl
    steps, start, cpu = 0, time.perf_counter(), time.process_time()
    while time.perf_counter() - start < seconds:
        for _ in range(500):
            mujoco.mj_step(model, data)
        steps += 500
    wall, cpu = time.perf_counter() - start, time.process_time() - cpu
    warned = [mujoco.mjtWarning(i).name for i, w in enumerate(data.warning) if w.number]
    return steps / wall, steps / cpu, warned


@contextlib.contextmanager
def one_core(cpu: int | None):
    """The process pinned to CPU ``cpu`` (the lowest it may use when None) inside the block; yields
    a line saying where it runs."""
    if not hasattr(os, "sched_setaffinity"):
        yield "not pinned (no sched_setaffinity here)"
        return
    allowed = os.sched_getaffinity(0)
    chosen = min(allowed) if cpu is None else cpu
    if chosen not in allowed:
        raise ValueError(f"--pin-cpu {cpu}: this process may use CPUs {sorted(allowed)}")
    os.sched_setaffinity(0, {chosen})
    try:
        yield f"pinned to CPU {chosen} of {len(allowed)}"
    finally:
        os.sched_setaffinity(0, allowed)


def compare_cpu(scenes: list[Scene], args) -> dict:
    """Steps per wall second and per CPU second of CPU MuJoCo and of MuJoCo Warp's CPU batch, for
    each scene on one core, the scenes alternated over ``args.rounds`` rounds (the order flips
    each round): ``rates[series][scene label]``, one figure a round."""
    series = ["mujoco", "mujoco_cpu"]
    batches = {}
    result = {"rounds": args.rounds, "warnings": {}}
    with one_core(args.pin_cpu) as where:
        result["where"] = where
        if args.warp_cpu_batch:
            try:
                sim_gpu.import_warp()
                for s in scenes:
                    fields = sim_gpu.randomised_fields(s.model, args.warp_cpu_batch)
                    buffers = sim_gpu.constraint_buffers(s.model)
                    batch = sim_gpu.warp_batch(s.model, s.ctrl, fields, buffers, "cpu", graph=False)
                    batch.step(1)  # compiles
                    batches[s.label] = batch
                series += ["warp", "warp_cpu"]
            except ImportError as exc:
                result["warp_skipped"] = str(exc)
        rates = {key: {s.label: [] for s in scenes} for key in series}
        for r in range(args.rounds):
            order = scenes if r % 2 == 0 else scenes[::-1]
            for s in order:
                wall, cpu, warned = cpu_rate(s.model, s.ctrl, args.cpu_seconds)
                rates["mujoco"][s.label].append(wall)
                rates["mujoco_cpu"][s.label].append(cpu)
                if warned:
                    result["warnings"][s.label] = warned
            for s in order if batches else ():
                start, cpu = time.perf_counter(), time.process_time()
                batches[s.label].step(args.warp_cpu_steps)
                steps = args.warp_cpu_batch * args.warp_cpu_steps
                rates["warp"][s.label].append(steps / (time.perf_counter() - start))
                rates["warp_cpu"][s.label].append(steps / (time.process_time() - cpu))
        for s in scenes if batches else ():
            problems = batches[s.label].check()
            if problems:
                result["warnings"].setdefault(s.label, []).extend(problems)
    return result | {"rates": rates}


def _spread(rates: list[float], scale: float = 1.0) -> str:
    rates = [r * scale for r in rates]
    med = statistics.median(rates)
    fmt = (lambda x: f"{x:,.4g}") if med < 100 else (lambda x: f"{x:,.0f}")
    return fmt(med) if len(rates) == 1 else f"{fmt(med)} [{fmt(min(rates))}-{fmt(max(rates))}]"


def cpu_table(scenes: list[Scene], cpu: dict, args) -> tuple[str, dict]:
    """The CPU comparison as lines (median [range] of the rounds), and the scene's ratios to the
    baseline, of the medians: ``<series>`` of the steps, ``<series>_simulated`` of the simulated
    seconds (the same unless the time steps differ)."""
    rows = [  # (label, series, simulated seconds rather than steps)
        (f"CPU MuJoCo {mujoco.__version__}: steps per wall s", "mujoco", False),
        ("  steps per CPU s", "mujoco_cpu", False),
        ("  real-time factor", "mujoco", True),
        ("  real-time factor per CPU s", "mujoco_cpu", True),
        (f"MuJoCo Warp CPU, batch {args.warp_cpu_batch}: steps per wall s", "warp", False),
        ("  steps per CPU s", "warp_cpu", False),
        ("  simulated s per wall s", "warp", True),
        ("  simulated s per CPU s", "warp_cpu", True),
    ]
    dt = {s.label: s.model.opt.timestep for s in scenes}
    base = scenes[1].label if len(scenes) > 1 else None
    lines = [
        f"CPU, one core ({cpu['where']}), {cpu['rounds']} round(s) alternated, median [range]:",
        f"{'':40s}"
        + "".join(f"{s.label:>24s}" for s in scenes)
        + (f"{scenes[0].label + ' / ' + base:>20s}" if base else ""),
    ]
    ratios = {}
    for label, key, simulated in rows:
        if key not in cpu["rates"]:
            continue
        rates = cpu["rates"][key]
        scale = {s.label: dt[s.label] if simulated else 1.0 for s in scenes}
        line = f"{label:40s}" + "".join(
            f"{_spread(rates[s.label], scale[s.label]):>24s}" for s in scenes
        )
        if base:
            ratio = (statistics.median(rates[scenes[0].label]) * scale[scenes[0].label]) / (
                statistics.median(rates[base]) * scale[base]
            )
            ratios[key + ("_simulated" if simulated else "")] = ratio
            line += f"{ratio:>20.2f}"
        lines.append(line)
    if "warp_skipped" in cpu:
        lines.append(f"MuJoCo Warp CPU skipped: {cpu['warp_skipped']}")
    for label, warned in cpu["warnings"].items():
        lines.append(f"  {label} WARNINGS: {warned}")
    return "\n".join(lines), ratios


# --- batches -------------------------------------------------------------------------------------


def cuda_present() -> str | None:
    """A line naming the CUDA GPU, or None."""
    if shutil.which("nvidia-smi") is None:
        return None
    try:
        wp, _ = sim_gpu.import_warp()
        if not wp.get_cuda_device_count():
            return None
        return f"{wp.get_cuda_device_count()} CUDA device(s): {wp.get_device('cuda:0').name}"
    except ImportError:
        return "nvidia-smi found (install the .[gpu] extra to use it)"


def batch_row(
    make, scene: Scene, nworld: int, steps: int, rand: sim_gpu.Randomisation, label: str
) -> tuple[str, dict]:
    """Build a batch of ``nworld`` randomised worlds with ``make(fields)``, time ``steps`` steps
    after a warm-up step, check world 0 against CPU MuJoCo. A printed line and its figures."""
    model, ctrl = scene.model, scene.ctrl
    fields = sim_gpu.randomised_fields(model, nworld, rand)
    start = time.perf_counter()
    batch = make(fields)
    batch.step(1)  # compiles
    first = time.perf_counter() - start
    start = time.perf_counter()
    batch.step(steps)
    wall = time.perf_counter() - start
    rate = nworld * steps / wall
    diff = sim_gpu.world_difference(batch, model, ctrl, fields, steps + 1, world=0)
    problems = batch.check()
    row = {
        "scene": scene.label,
        "engine": label,
        "nworld": nworld,
        "steps_per_s": rate,
        "simulated_s_per_s": rate * model.opt.timestep,
        "first_step_s": first,
        "world0_max_dqpos": diff,
        "problems": problems,
    }
    line = (
        f"  {scene.label:>10s} {label:15s} batch {nworld:5d}: {rate:12,.0f} steps/s = "
        f"{rate * model.opt.timestep:10.4g} simulated s/s (first step incl. compile "
        f"{first:6.1f} s); "
        f"world 0 vs CPU MuJoCo max|dqpos| {diff:.1e}"
        + (f"  PROBLEMS: {problems}" if problems else "")
    )
    return line, row


# --- stages --------------------------------------------------------------------------------------


class _HostEvents:
    """Warp as MuJoCo Warp's event scopes see it, with host-clock events: Warp launches CPU kernels
    synchronously, so the wall time between two records is the stages' time (plus the scopes' own
    Python overhead). CUDA events exist only on CUDA devices."""

    class Event:
        def __init__(self, device=None, enable_timing=False, **_):
            self.t = 0.0

    def __init__(self, wp):
        self._wp = wp

    def __getattr__(self, name):
        return getattr(self._wp, name)

    @staticmethod
    def record_event(event=None, external=False):
        event.t = time.perf_counter()
        return event

    @staticmethod
    def get_event_elapsed_time(start_event, end_event, synchronize=True):
        return (end_event.t - start_event.t) * 1e3  # ms, as CUDA events give it


@contextlib.contextmanager
def _host_clock(warp_util):
    real = warp_util.wp
    warp_util.wp = _HostEvents(real)
    try:
        yield
    finally:
        warp_util.wp = real


def _add_trace(total: dict, trace: dict, path: tuple = ()) -> None:
    """Sum an EventTracer trace ``{name: (elapsed ms per call, sub-trace)}`` into ``total``."""
    for name, (elapsed, sub) in trace.items():
        key = (*path, name)
        total[key] = total.get(key, 0.0) + float(sum(elapsed))
        _add_trace(total, sub, key)


def stage_times(
    model: mujoco.MjModel,
    ctrl: np.ndarray,
    fields: dict[str, np.ndarray],
    buffers: sim_gpu.ConstraintBuffers,
    device: str,
    steps: int,
    graph: bool,
) -> dict[tuple[str, ...], float]:
    """Milliseconds per step (all worlds) of each of MuJoCo Warp's event scopes, keyed by its path
    (``("step", "forward", "fwd_position", ...)``), over ``steps`` steps after one that compiles.

    With ``graph`` the step is captured once as a CUDA graph, events included (as MuJoCo Warp's
    ``testspeed --event_trace`` does), and replayed; without, each step is launched one by one. On
    a CPU device the events are host-clock readings (:class:`_HostEvents`)."""
    wp, mjw = sim_gpu.import_warp()
    from mujoco_warp._src import warp_util

    cuda = wp.get_device(device).is_cuda
    if graph and not cuda:
        raise ValueError(f"CUDA-graph capture needs a CUDA device; {device!r} is not one")
    total: dict[tuple[str, ...], float] = {}
    with wp.ScopedDevice(device), contextlib.nullcontext() if cuda else _host_clock(warp_util):
        mw, dw = sim_gpu._warp_model_data(model, ctrl, fields, buffers)
        mjw.step(mw, dw)  # compiles outside the timing and the capture
        wp.synchronize_device(device)
        if graph:
            with warp_util.EventTracer() as tracer:
                with wp.ScopedCapture() as capture:
                    mjw.step(mw, dw)
                for _ in range(steps):
                    wp.capture_launch(capture.graph)
                    wp.synchronize_device(device)
                    _add_trace(total, tracer.trace())
        else:
            for _ in range(steps):
                with warp_util.EventTracer() as tracer:
                    mjw.step(mw, dw)
                    wp.synchronize_device(device)
                    _add_trace(total, tracer.trace())
    return {path: ms / steps for path, ms in total.items()}


def stage_summary(times: dict[tuple[str, ...], float]) -> dict[str, float]:
    """The step's time (ms per step) by :data:`STAGES`, the rest as ``other``, and ``step``."""
    group_of = {scope: stage for stage, scopes in STAGES.items() for scope in scopes}
    out = dict.fromkeys(STAGES, 0.0)
    for path, ms in times.items():
        if path[-1] in group_of and not any(p in group_of for p in path[:-1]):
            out[group_of[path[-1]]] += ms
    step = times.get(("step",), 0.0)
    return out | {"other": step - sum(out.values()), "step": step}


def stage_lines(scenes, summaries: dict[str, dict], clock: str, nworld: int) -> str:
    lines = [f"MuJoCo Warp's stages at batch {nworld}, ms per step ({clock}):"]
    lines.append(f"{'':16s}" + "".join(f"{s.label:>22s}" for s in scenes if s.label in summaries))
    for stage in (*STAGES, "other", "step"):
        cells = []
        for s in scenes:
            if s.label not in summaries:
                continue
            ms, step = summaries[s.label][stage], summaries[s.label]["step"]
            cells.append(f"{ms:10.4f} {ms / step if step else 0:6.1%}")
        lines.append(f"  {stage:14s}" + "".join(f"{c:>22s}" for c in cells))
    return "\n".join(lines)


def tree_lines(times: dict[tuple[str, ...], float]) -> str:
    return "\n".join(
        f"  {'  ' * (len(p) - 1)}{p[-1]:{40 - 2 * len(p)}s} {ms:10.4f}" for p, ms in times.items()
    )


def profile_lines(times: list[sim_gpu.KernelTime], nworld: int, rows: int) -> str:
    """MuJoCo Warp's slowest kernels at batch ``nworld`` (GPU ms per step), as printed lines."""
    total = sum(k.ms_per_step for k in times)
    launches = sum(k.launches_per_step for k in times)
    lines = [
        f"MuJoCo Warp kernels at batch {nworld}: {launches:.0f} launches and {total:.3f} ms of GPU "
        f"time per step (launched one by one); the slowest {rows}:"
    ]
    lines += [
        f"  {k.ms_per_step:8.4f} ms {k.ms_per_step / total:6.1%}  "
        f"x{k.launches_per_step:<3g} {k.name}"
        for k in times[:rows]
    ]
    return "\n".join(lines)


def tendon_kernels_ms(times: list[sim_gpu.KernelTime]) -> float:
    return sum(k.ms_per_step for k in times if "tendon" in k.name)


# --- the run -------------------------------------------------------------------------------------


def _sizes(text: str) -> tuple[int, ...]:
    """Batch sizes from ``1,1024,8192``."""
    try:
        sizes = tuple(int(b) for b in text.split(","))
    except ValueError:
        sizes = ()
    if not sizes or min(sizes) < 1:
        raise ValueError(f"batch sizes must be positive integers separated by commas, got {text!r}")
    return sizes


def parse(argv) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("export", type=Path)
    ap.add_argument("--scene", help="MJCF inside the export (default: the manifest's robot.mjcf)")
    ap.add_argument(
        "--baseline", type=Path, help="another scene's MJCF file, measured beside the export's"
    )
    ap.add_argument("--steps", type=int, default=100, help="timed steps per batch")
    ap.add_argument("--cpu-seconds", type=float, default=3.0, help="CPU MuJoCo seconds per round")
    ap.add_argument("--rounds", type=int, default=3, help="alternated rounds of the CPU comparison")
    ap.add_argument("--pin-cpu", type=int, help="the CPU to pin to (default: the lowest allowed)")
    ap.add_argument(
        "--warp-cpu-batch", type=int, default=4, help="MuJoCo Warp CPU batch; 0 skips it"
    )
    ap.add_argument("--warp-cpu-steps", type=int, default=50, help="its timed steps per round")
    ap.add_argument("--stage-steps", type=int, default=20, help="steps the stage times average")
    ap.add_argument(
        "--pressure-fraction",
        type=float,
        default=0.6,
        help="held pressure for the rates, fraction of the range's top",
    )
    ap.add_argument(
        "--cpu-batches", default="1,4", help="batch sizes on the CPU backends without a GPU"
    )
    ap.add_argument("--gpu-batches", default=",".join(map(str, GPU_BATCHES)), help="on a CUDA GPU")
    ap.add_argument(
        "--profile",
        action="store_true",
        help="end with every stage's time and, on CUDA, MuJoCo Warp's slowest kernels",
    )
    ap.add_argument("--profile-rows", type=int, default=15, help="kernels --profile lists")
    ap.add_argument(
        "--no-mjx",
        action="store_true",
        help="skip MJX (its CPU compile takes tens of seconds a batch)",
    )
    ap.add_argument("--json", type=Path, help="also write every figure to this JSON file")
    args = ap.parse_args(argv)
    try:
        args.gpu_sizes, args.cpu_sizes = _sizes(args.gpu_batches), _sizes(args.cpu_batches)
    except ValueError as exc:
        ap.error(str(exc))
    for key in ("profile_rows", "rounds", "steps", "stage_steps", "warp_cpu_steps"):
        if getattr(args, key) < 1:
            ap.error(f"--{key.replace('_', '-')} must be at least 1, got {getattr(args, key)}")
    if args.baseline is not None and not args.baseline.is_file():
        ap.error(f"--baseline {args.baseline}: no such MJCF file")
    if args.warp_cpu_batch < 0:
        ap.error(f"--warp-cpu-batch must be 0 (skip) or more, got {args.warp_cpu_batch}")
    return args


def versions() -> dict[str, str]:
    out = {"mujoco": mujoco.__version__}
    try:
        wp, mjw = sim_gpu.import_warp()
        out |= {"warp": wp.__version__, "mujoco_warp": getattr(mjw, "__version__", "?")}
    except ImportError:
        pass
    return out


def load_scene(label: str, path: Path, fraction: float) -> Scene:
    model = mujoco.MjModel.from_xml_path(str(path))
    return Scene(label, path, model, fraction * model.actuator_ctrlrange[:, 1])


def main(argv=None) -> int:
    args = parse(argv)
    path = args.export / args.scene if args.scene else sim_gpu.scene_path(args.export)
    scenes = [load_scene("scene", path, args.pressure_fraction)]
    if args.baseline:
        scenes.append(load_scene("baseline", args.baseline, args.pressure_fraction))
    report: dict = {"versions": versions(), "scenes": {}}
    for s in scenes:
        m = s.model
        print(
            f"{s.label}: {s.path}: nq {m.nq}, nv {m.nv}, nu {m.nu}, neq {m.neq}, ntendon "
            f"{m.ntendon}, time step {m.opt.timestep * 1e3:g} ms, held pressure "
            f"{args.pressure_fraction:.0%} of {m.actuator_ctrlrange[0, 1]:g} Pa"
        )
        report["scenes"][s.label] = {"path": str(s.path), "counts": scene_counts(m)}
    counts = {label: entry["counts"] for label, entry in report["scenes"].items()}
    print(
        f"\ncounts (constraint rows: the most in a step of {COUNT_SECONDS} s of each held pattern):"
    )
    print(counts_table(scenes, counts))
    for s in scenes:
        if counts[s.label]["warnings"]:
            print(f"  {s.label} WARNINGS under the held patterns: {counts[s.label]['warnings']}")

    cpu = compare_cpu(scenes, args)
    text, ratios = cpu_table(scenes, cpu, args)
    print("\n" + text)
    report["cpu"] = cpu | {"ratios": ratios, "warp_batch": args.warp_cpu_batch}

    gpu = cuda_present()
    if gpu:
        print(f"\nGPU: {gpu}")
        batches, device = args.gpu_sizes, "cuda:0"
    else:
        batches, device = args.cpu_sizes, "cpu"
        print(
            f"\nno CUDA GPU here: tiny batches {batches} on the CPU backends prove the code path "
            "(their rates are not GPU figures); CUDA-graph capture needs a CUDA device: skipped"
        )
    report["device"] = gpu or "cpu"
    report["batches"] = batch_section(scenes, args, device, batches)
    report.update(stage_section(scenes, args, device, max(batches)))
    if args.json:
        args.json.write_text(json.dumps(report, indent=1, default=str) + "\n")
        print(f"\nfigures written to {args.json}")
    return 0


def batch_section(scenes: list[Scene], args, device: str, batches) -> list[dict]:
    rand = sim_gpu.Randomisation()
    print(
        f"per world: hinge stiffness x U{rand.stiffness_scale}, damping x U{rand.damping_scale}, "
        f"tip payload U{rand.payload_kg} kg"
    )
    for s in scenes:
        print(f"  {s.label} constraint buffers: {sim_gpu.constraint_buffers(s.model).line()}")
    engines = []
    try:
        wp, mjw = sim_gpu.import_warp()
        cuda = wp.get_device(device).is_cuda

        def warp(graph):
            return lambda s, f: sim_gpu.warp_batch(
                s.model, s.ctrl, f, sim_gpu.constraint_buffers(s.model), device=device, graph=graph
            )

        if cuda:  # the step captured as a CUDA graph and replayed, and launched kernel by kernel
            engines += [("warp graph", warp(True), scenes), ("warp launches", warp(False), scenes)]
        else:
            engines.append(("warp", warp(False), scenes))
    except ImportError as exc:
        print(f"MuJoCo Warp skipped: {exc}")
    if not args.no_mjx:
        try:
            jax, _ = sim_gpu.import_mjx()
            if device != "cpu" and not any(d.platform == "gpu" for d in jax.devices()):
                print(
                    "MJX: JAX sees no GPU (pip install 'jax[cuda12]==0.10.2'); MJX runs on "
                    "JAX's CPU backend"
                )
            engines.append(("mjx", lambda s, f: sim_gpu.mjx_batch(s.model, s.ctrl, f), scenes[:1]))
        except ImportError as exc:
            print(f"MJX skipped: {exc}")
    rows = []
    for label, make, which in engines:
        for nworld in batches:
            for s in which:
                line, row = batch_row(
                    lambda f, s=s, make=make: make(s, f), s, nworld, args.steps, rand, label
                )
                print(line, flush=True)
                rows.append(row)
    if len(scenes) > 1:
        print(ratio_line(rows, scenes))
    return rows


def ratio_line(rows: list[dict], scenes: list[Scene]) -> str:
    """The scene's steps/s over the baseline's, for each engine and batch both ran."""
    rate = {(r["scene"], r["engine"], r["nworld"]): r["steps_per_s"] for r in rows}
    pairs = [
        f"{engine} {nworld}: {rate[key] / rate[(scenes[1].label, engine, nworld)]:.2f}"
        for key in rate
        for label, engine, nworld in [key]
        if label == scenes[0].label and (scenes[1].label, engine, nworld) in rate
    ]
    return f"  {scenes[0].label} / {scenes[1].label} steps/s: " + ", ".join(pairs)


def stage_section(scenes: list[Scene], args, device: str, nworld: int) -> dict:
    try:
        wp, _ = sim_gpu.import_warp()
    except ImportError as exc:
        print(f"stages skipped: {exc}")
        return {}
    cuda = wp.get_device(device).is_cuda
    clock = (
        "GPU time from CUDA events, the step replayed as a CUDA graph"
        if cuda
        else f"host wall time on {device}, scopes' Python overhead included: not GPU figures"
    )
    rand = sim_gpu.Randomisation()
    out = {"stages": {}, "kernels": {}}
    summaries, trees = {}, {}
    for s in scenes:
        fields = sim_gpu.randomised_fields(s.model, nworld, rand)
        buffers = sim_gpu.constraint_buffers(s.model)
        times = stage_times(s.model, s.ctrl, fields, buffers, device, args.stage_steps, graph=cuda)
        summaries[s.label], trees[s.label] = stage_summary(times), times
        out["stages"][s.label] = {
            "nworld": nworld,
            "clock": clock,
            "summary_ms": summaries[s.label],
            "ms_per_step": {".".join(p): ms for p, ms in times.items()},
        }
        if cuda:
            kernels = sim_gpu.warp_kernel_profile(s.model, s.ctrl, fields, buffers, device)
            out["kernels"][s.label] = [dataclasses.asdict(k) for k in kernels]
            summaries[s.label]["tendon kernels"] = tendon_kernels_ms(kernels)
    print("\n" + stage_lines(scenes, summaries, clock, nworld))
    for s in scenes:
        summary = summaries[s.label]
        step_us_per_world = summary["step"] * 1e3 / nworld
        line = f"  {s.label}: {step_us_per_world * 1e3:,.0f} ns per world-step"
        if "tendon kernels" in summary:
            line += (
                f"; kernels named after tendons (launched one by one): "
                f"{summary['tendon kernels']:.4f} ms per step"
            )
        print(line)
    if not cuda:
        print("  kernels named after tendons: Warp times kernels on CUDA devices only: skipped")
    if args.profile:
        for s in scenes:
            print(f"\n{s.label}: every stage, ms per step ({clock}):")
            print(tree_lines(trees[s.label]))
            if cuda:
                kernels = [sim_gpu.KernelTime(**k) for k in out["kernels"][s.label]]
                print(profile_lines(kernels, nworld, args.profile_rows))
        if not cuda:
            print("--profile: per-kernel times need MuJoCo Warp on a CUDA GPU; skipped")
    return out


if __name__ == "__main__":
    sys.exit(main())
