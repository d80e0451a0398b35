"""Simulation throughput of an exported tail, in one run:

- CPU MuJoCo on one core: steps/s and real-time factor (simulated s per wall s) at the exported time
  step;
- MJX (``jax.vmap`` over a model with per-world fields) and MuJoCo Warp (batched model) at batch 1,
  1024 and 8192 on a CUDA GPU, constraint buffers sized from the model, stiffness, damping and tip
  payload varied per world; each batch's world 0 is checked against CPU MuJoCo stepping world 0's
  model.

Without a CUDA GPU it says so and runs tiny batches on the CPU backends (``--cpu-batches``) to prove
the code path; their rates say nothing about a GPU. MJX and Warp come with the extra ``.[gpu]``
(MJX on an NVIDIA GPU also needs ``jax[cuda12]``).

    python benchmarks/sim_bench.py EXPORT_DIR [--scene robot/scene.xml] [--steps 100]
    python benchmarks/sim_bench.py /tmp/x --cpu-batches 1,4 --no-mjx  # without MJX's CPU compile
    python benchmarks/sim_bench.py /tmp/x --gpu-batches 8192,65536 --profile  # Warp's GPU time

``--profile`` (CUDA only) ends with MuJoCo Warp's slowest kernels at the largest batch, in GPU ms
per step, from steps launched one by one under Warp's kernel timing.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import time
from pathlib import Path

os.environ.setdefault("XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false")  # polite on a shared CPU

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

from bvsr_cad.simulation import sim_gpu  # noqa: E402

GPU_BATCHES = (1, 1024, 8192)


def cpu_rate(model: mujoco.MjModel, ctrl: np.ndarray, seconds: float) -> tuple[float, list[str]]:
    """Steps per wall second of one CPU MuJoCo, stepping for about ``seconds``, and its warnings."""
    data = mujoco.MjData(model)
    data.ctrl[:] = ctrl
    steps, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        for _ in range(500):
            mujoco.mj_step(model, data)
        steps += 500
    rate = steps / (time.perf_counter() - start)
    return rate, [mujoco.mjtWarning(i).name for i, w in enumerate(data.warning) if w.number]


def cuda_present() -> str | None:
    """A line naming the CUDA GPU, or None."""
    if shutil.which("nvidia-smi") is None:
        return None
    try:
        wp, _ = sim_gpu.import_warp()
        return (
            f"{wp.get_cuda_device_count()} CUDA device(s): {wp.get_device('cuda:0').name}"
            if wp.get_cuda_device_count()
            else None
        )
    except ImportError:
        return "nvidia-smi found (install the .[gpu] extra to use it)"


def batch_row(make, model, ctrl, nworld: int, steps: int, rand: sim_gpu.Randomisation) -> str:
    """Build a batch of ``nworld`` randomised worlds, time ``steps`` steps after a warm-up step,
    check world 0."""
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
    return (
        f"  {batch.engine:5s} batch {nworld:5d}: {rate:12,.0f} steps/s = "
        f"{rate * model.opt.timestep:10.3g} "
        f"simulated s/s (first step incl. compile {first:6.1f} s); world 0 vs CPU MuJoCo "
        "max|dqpos| "
        f"{diff:.1e}" + (f"  PROBLEMS: {problems}" if problems else "")
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("export", type=Path)
    ap.add_argument("--scene", help="MJCF inside the export (default: the manifest's robot.mjcf)")
    ap.add_argument("--steps", type=int, default=100, help="timed steps per batch")
    ap.add_argument("--cpu-seconds", type=float, default=3.0)
    ap.add_argument(
        "--pressure-fraction",
        type=float,
        default=0.6,
        help="held pressure, fraction of the range's top",
    )
    ap.add_argument(
        "--cpu-batches", default="1,4", help="batch sizes on the CPU backends when there is no GPU"
    )
    ap.add_argument(
        "--gpu-batches", default=",".join(map(str, GPU_BATCHES)), help="batch sizes on a CUDA GPU"
    )
    ap.add_argument(
        "--profile",
        action="store_true",
        help="on a CUDA GPU, end with MuJoCo Warp's slowest kernels at the largest batch",
    )
    ap.add_argument("--profile-rows", type=int, default=15, help="kernels --profile lists")
    ap.add_argument(
        "--no-mjx",
        action="store_true",
        help="skip MJX (its CPU compile of the tail takes 25-40 s per batch size)",
    )
    args = ap.parse_args(argv)
    try:
        gpu_batches, cpu_batches = _sizes(args.gpu_batches), _sizes(args.cpu_batches)
    except ValueError as exc:
        ap.error(str(exc))
    if args.profile_rows < 1:
        ap.error(f"--profile-rows must be at least 1, got {args.profile_rows}")

    path = args.export / args.scene if args.scene else sim_gpu.scene_path(args.export)
    model = mujoco.MjModel.from_xml_path(str(path))
    ctrl = args.pressure_fraction * model.actuator_ctrlrange[:, 1]
    dt = model.opt.timestep
    print(
        f"{path}: nq {model.nq}, nv {model.nv}, nu {model.nu}, neq {model.neq}, time step "
        f"{dt * 1e3:g} ms, "
        f"held pressure {args.pressure_fraction:.0%} of {model.actuator_ctrlrange[0, 1]:g} Pa"
    )

    rate, warned = cpu_rate(model, ctrl, args.cpu_seconds)
    print(
        f"CPU MuJoCo {mujoco.__version__}, one core: {rate:,.0f} steps/s, real-time factor "
        f"{rate * dt:.2f}" + (f"  WARNINGS: {warned}" if warned else "")
    )

    buffers = sim_gpu.constraint_buffers(model)
    rand = sim_gpu.Randomisation()
    print(f"constraint buffers from the model: {buffers.line()}")
    print(
        f"per world: hinge stiffness x U{rand.stiffness_scale}, damping x U{rand.damping_scale}, "
        f"tip payload U{rand.payload_kg} kg"
    )

    gpu = cuda_present()
    if gpu:
        print(f"GPU: {gpu}")
        batches, device = gpu_batches, "cuda:0"
    else:
        batches, device = cpu_batches, "cpu"
        print(
            f"no CUDA GPU here: tiny batches {batches} on the CPU backends prove the code path "
            "(their rates are not GPU figures)"
        )

    engines = []

    def warp_engine(f):
        return sim_gpu.warp_batch(model, ctrl, f, buffers, device=device)

    try:
        sim_gpu.import_warp()
        engines.append(warp_engine)
    except ImportError as exc:
        print(f"MuJoCo Warp skipped: {exc}")
    if not args.no_mjx:
        try:
            jax, _ = sim_gpu.import_mjx()
            if gpu and not any(d.platform == "gpu" for d in jax.devices()):
                print(
                    "MJX: JAX sees no GPU (pip install 'jax[cuda12]==0.10.2'); MJX runs on JAX's "
                    "CPU backend"
                )
            engines.append(lambda f: sim_gpu.mjx_batch(model, ctrl, f))
        except ImportError as exc:
            print(f"MJX skipped: {exc}")
    for make in engines:
        for nworld in batches:
            print(batch_row(make, model, ctrl, nworld, args.steps, rand), flush=True)
    if args.profile:
        if not gpu or not engines or engines[0] is not warp_engine:
            print("--profile: per-kernel times need MuJoCo Warp on a CUDA GPU; skipped")
        else:
            print(profile_lines(model, ctrl, max(batches), buffers, rand, args.profile_rows))
    return 0


def _sizes(text: str) -> tuple[int, ...]:
    """Batch sizes from ``1,1024,8192``."""
    try:
        sizes = tuple(int(b) for b in text.split(","))
    except ValueError:
        sizes = ()
    if not sizes or min(sizes) < 1:
        raise ValueError(f"batch sizes must be positive integers separated by commas, got {text!r}")
    return sizes


def profile_lines(model, ctrl, nworld: int, buffers, rand, rows: int) -> str:
    """MuJoCo Warp's slowest kernels at batch ``nworld`` (GPU ms per step), as printed lines."""
    fields = sim_gpu.randomised_fields(model, nworld, rand)
    times = sim_gpu.warp_kernel_profile(model, ctrl, fields, buffers)
    total = sum(k.ms_per_step for k in times)
    lines = [
        f"MuJoCo Warp kernels at batch {nworld}: {sum(k.launches_per_step for k in times):.0f} "
        "launches "
        f"and {total:.3f} ms of GPU time per step (launched one by one); the slowest {rows}:"
    ]
    lines += [
        f"  {k.ms_per_step:8.4f} ms {k.ms_per_step / total:6.1%}  x{k.launches_per_step:<3g} "
        f"{k.name}"
        for k in times[:rows]
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
