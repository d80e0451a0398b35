"""Batched simulation of an exported MJCF scene under MJX (JAX) and MuJoCo Warp.

Shared by the tests (``tests/test_sim_gpu.py``) and the benchmark (``benchmarks/sim_bench.py``):

- :func:`constraint_buffers`: MuJoCo Warp allocates a fixed number of constraint rows (``njmax``)
  and contacts (``nconmax``) per world; too few and the solver drops rows and the state goes NaN
  (the per-segment scene overflowed the default 64). The buffers are sized from CPU MuJoCo probe
  runs of the same model under held pressures, with a margin, plus a row for every limit (which held
  pressures do not reach).
- :func:`randomised_fields`: domain randomisation as a learning team needs it: per world, the
  hinges' spring stiffness (the rod's bending stiffness; in the default scene also the shear
  springs) and damping (in the default scene the SOAs' damping) scaled, and a tip payload (a
  point mass at the tip body's centre of mass, so its centre of mass and rotational inertia are
  unchanged and only ``body_mass`` and the ancestors' ``body_subtreemass`` change).
- :func:`mjx_batch` / :func:`warp_batch`: the batched model (those fields with one row per world)
  and data, with a step function; :func:`world_model` is the CPU MuJoCo model of one world, the
  reference each batch's world is checked against.
- :func:`exclude_for_mjx`: MJX has no cylinder-box collision, so its ``put_model`` refuses the tail
  mounted on a host with a box body (its panels against the Go1's trunk): the body pairs that hold
  such geom pairs (:func:`mjx_uncollidable`) are excluded, and each exclusion is named.
- :func:`warp_kernel_profile`: where a MuJoCo Warp step's GPU time goes, per kernel (CUDA only;
  ``benchmarks/sim_bench.py --profile``).

MJX, JAX and MuJoCo Warp come with the optional extra ``.[gpu]``; they are imported inside the
functions that use them, so the base install never needs them.
"""

from __future__ import annotations

import copy
import json
import re
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from ..extras import install_line, require

GPU_EXTRA = f"the optional extra 'gpu' ({install_line('gpu')})"

#: The model fields :func:`randomised_fields` gives one row per world.
RANDOMISED_FIELDS = ("jnt_stiffness", "dof_damping", "body_mass", "body_subtreemass")


def import_mjx():
    """``(jax, mujoco.mjx)``, or an ImportError naming the extra that installs them."""
    require("gpu", "MJX")
    import jax
    from mujoco import mjx

    return jax, mjx


#: XLA options for compiling MJX's step on JAX's CPU backend (DebugOptions fields, passed per
#: function through ``jax.jit(compiler_options=...)``, so nothing else in the process changes).
#: XLA:CPU's loop fusion copies the step's long chains of dependent arithmetic (the tail is 14
#: bodies and 24 hinges deep) into every consumer, so its kernels nest thousands of calls deep and
#: one step's compile takes minutes of CPU, and its first step minutes more. Without fusion each
#: operation is its own kernel: the step compiles in a fraction of that and runs in milliseconds;
#: XLA's backend optimisation level 0 and LLVM's expensive passes off shorten the compile further,
#: at the cost of slower steps, which matters little: MJX on a CPU is for trying and testing (CPU
#: MuJoCo is the fast path there). A GPU's fusion is what makes it fast: these are for CPU devices
#: only (:func:`compiler_options`). The compile times behind this are in benchmarks/RESULTS.md.
CPU_COMPILER_OPTIONS = {
    "xla_disable_hlo_passes": "fusion",
    "xla_backend_optimization_level": 0,
    "xla_llvm_disable_expensive_passes": True,
}


def compiler_options(device=None) -> dict:
    """The XLA options :func:`mjx_batch` compiles with on ``device`` (JAX's default device when
    None)."""
    jax, _ = import_mjx()
    platform = (device if device is not None else jax.devices()[0]).platform
    return dict(CPU_COMPILER_OPTIONS) if platform == "cpu" else {}


def mjx_uncollidable(model: mujoco.MjModel) -> list[tuple[int, int]]:
    """The geom pairs of ``model`` that MJX would collide (its candidate pairs: contype and
    conaffinity, welded and parent bodies, ``<exclude>`` and ``<pair>``, as CPU MuJoCo filters them)
    but has no collision function for, so that its ``put_model`` refuses the model: on the tail
    mounted on a legged host, the panels' cylinders against a box of the host's."""
    import_mjx()
    from mujoco.mjx._src import collision_driver, types  # MJX's own table of geom-type pairs

    return [
        (int(g1), int(g2))
        for g1, g2, _ in collision_driver.geom_pairs(model)
        if not collision_driver.has_collision_fn(
            types.GeomType(model.geom_type[g1]), types.GeomType(model.geom_type[g2])
        )
    ]


def exclude_for_mjx(spec: mujoco.MjSpec) -> list[str]:
    """Adds to ``spec`` an ``<exclude>`` for each body pair that holds a geom pair MJX cannot
    collide (:func:`mjx_uncollidable`), so that MJX takes the compiled model; returns one line per
    body pair, naming the geoms and their types. The model compiled from ``spec`` then lacks those
    contacts on CPU MuJoCo too: a batch is compared with CPU MuJoCo on the same model. An
    ``<exclude>`` acts on two bodies, MuJoCo's finest contact filter short of explicit ``<pair>``
    lists, so any other geom pair of the same two bodies goes as well."""
    model = spec.compile()
    by_bodies: dict[tuple[int, int], list[tuple[int, int]]] = {}
    for g1, g2 in mjx_uncollidable(model):
        pair = tuple(sorted((int(model.geom_bodyid[g1]), int(model.geom_bodyid[g2]))))
        by_bodies.setdefault(pair, []).append((g1, g2))

    def geom(g: int) -> str:
        kind = mujoco.mjtGeom(model.geom_type[g]).name.removeprefix("mjGEOM_").lower()
        name = model.geom(g).name or f"geom {g} of {model.body(model.geom_bodyid[g]).name}"
        return f"{name} ({kind})"

    lines = []
    for (b1, b2), pairs in by_bodies.items():
        names = model.body(b1).name, model.body(b2).name
        spec.add_exclude(bodyname1=names[0], bodyname2=names[1])
        lines.append(
            f"MJX: contacts between bodies {names[0]} and {names[1]} excluded (no MJX collision "
            f"function for {', '.join(f'{geom(g1)} - {geom(g2)}' for g1, g2 in pairs)})"
        )
    return lines


def import_warp():
    """``(warp, mujoco_warp)`` with Warp's per-kernel messages off, or an ImportError naming the
    extra."""
    require("gpu", "MuJoCo Warp")
    import warp

    warp.config.quiet = True  # before mujoco_warp's import initialises Warp
    import mujoco_warp

    return warp, mujoco_warp


def scene_path(export_dir: str | Path) -> Path:
    """The default MJCF scene of an export (the manifest's ``robot.mjcf``)."""
    root = Path(export_dir)
    return root / json.loads((root / "manifest.json").read_text())["robot"]["mjcf"]


# --- constraint buffers --------------------------------------------------------------------------


def probe_controls(model: mujoco.MjModel) -> list[np.ndarray]:
    """Held pressure patterns that exercise the scene's constraints: none, every actuator at the top
    and at the bottom of its range, and each actuator group alone at the top. Actuators are named
    ``<joint or segment>_<line>``; a group is one line in every joint (the same name after the last
    underscore), the pattern that bends the tail furthest into its joint limits."""
    lo, hi = model.actuator_ctrlrange[:, 0], model.actuator_ctrlrange[:, 1]
    limited = model.actuator_ctrllimited.astype(bool)
    top = np.where(limited, hi, 0.0)
    names = [model.actuator(i).name.rsplit("_", 1)[-1] for i in range(model.nu)]
    groups = sorted(set(names))
    patterns = [np.zeros(model.nu), top, np.where(limited, lo, 0.0)]
    patterns += [np.where([n == g for n in names], top, 0.0) for g in groups]
    return patterns


@dataclass(frozen=True)
class ConstraintBuffers:
    nefc_seen: int  # the most constraint rows one CPU MuJoCo probe step had
    ncon_seen: int  # the most contacts
    njmax: int  # rows allocated per world
    nconmax: int  # contacts allocated per world
    limit_rows: int = 0  # of njmax, reserved for the joint and tendon limits (one row each at most)

    def line(self) -> str:
        return (
            f"njmax {self.njmax} (probe saw nefc <= {self.nefc_seen}; {self.limit_rows} reserved "
            "for limits), "
            f"nconmax {self.nconmax} (probe saw ncon <= {self.ncon_seen})"
        )


def constraint_buffers(
    model: mujoco.MjModel,
    seconds: float = 0.3,
    margin: float = 2.0,
    controls: list[np.ndarray] | None = None,
) -> ConstraintBuffers:
    """Per-world buffer sizes for MuJoCo Warp from CPU MuJoCo: ``seconds`` of each held pattern of
    :func:`probe_controls` from rest, the largest ``nefc`` and ``ncon`` of any step, times
    ``margin`` (at least 16 rows and 8 contacts more than seen: randomised worlds bend further), and
    one row more per limited joint and tendon: MuJoCo makes at most one row per limit, and held
    pressures bend the default tail to at most 38 % of its joint limits, so the probe never sees
    them, but a load (a contact, an impact) does: the reduced chain's bend limits are 8 fixed
    tendons per joint."""
    if margin < 1.0:
        raise ValueError(
            f"constraint_buffers: margin={margin} must be >= 1 (a multiple of what the probe saw)"
        )
    data = mujoco.MjData(model)
    nefc = ncon = 0
    for ctrl in controls if controls is not None else probe_controls(model):
        mujoco.mj_resetData(model, data)
        data.ctrl[:] = ctrl
        for _ in range(max(1, round(seconds / model.opt.timestep))):
            mujoco.mj_step(model, data)
            nefc, ncon = max(nefc, data.nefc), max(ncon, data.ncon)
    limits = int(model.jnt_limited.sum() + model.tendon_limited.sum())
    return ConstraintBuffers(
        nefc,
        ncon,
        max(int(np.ceil(nefc * margin)), nefc + 16) + limits,
        max(int(np.ceil(ncon * margin)), ncon + 8),
        limits,
    )


# --- domain randomisation ------------------------------------------------------------------------


@dataclass(frozen=True)
class Randomisation:
    """Uniform ranges, per world: scale factors on the hinges' stiffness and damping, tip payload
    (kg)."""

    stiffness_scale: tuple[float, float] = (0.8, 1.2)
    damping_scale: tuple[float, float] = (0.5, 2.0)
    payload_kg: tuple[float, float] = (0.0, 0.05)
    seed: int = 0

    def __post_init__(self):
        for key in ("stiffness_scale", "damping_scale", "payload_kg"):
            lo, hi = getattr(self, key)
            if not 0.0 <= lo <= hi:
                raise ValueError(f"Randomisation.{key}=({lo}, {hi}): needs 0 <= low <= high")


def tip_body(model: mujoco.MjModel) -> int:
    """The body furthest down the kinematic tree (the last panel of the tail)."""
    depth = np.zeros(model.nbody, int)
    for b in range(1, model.nbody):
        depth[b] = depth[model.body_parentid[b]] + 1
    return int(np.flatnonzero(depth == depth.max())[-1])


def randomised_fields(
    model: mujoco.MjModel, nworld: int, rand: Randomisation = Randomisation()
) -> dict[str, np.ndarray]:
    """The :data:`RANDOMISED_FIELDS`, each with a leading axis of ``nworld`` rows (world 0
    included)."""
    if nworld < 1:
        raise ValueError(f"randomised_fields: nworld={nworld} must be >= 1")
    rng = np.random.default_rng(rand.seed)
    hinge = model.jnt_type == mujoco.mjtJoint.mjJNT_HINGE
    fields = {name: np.tile(getattr(model, name), (nworld, 1)) for name in RANDOMISED_FIELDS}
    fields["jnt_stiffness"][:, hinge] *= rng.uniform(*rand.stiffness_scale, (nworld, 1))
    fields["dof_damping"][:, model.jnt_dofadr[hinge]] *= rng.uniform(
        *rand.damping_scale, (nworld, 1)
    )
    payload = rng.uniform(*rand.payload_kg, nworld)
    body = tip_body(model)
    fields["body_mass"][:, body] += payload
    while body > 0:
        fields["body_subtreemass"][:, body] += payload
        body = model.body_parentid[body]
    fields["body_subtreemass"][:, 0] += payload
    return fields


def world_model(model: mujoco.MjModel, fields: dict[str, np.ndarray], world: int) -> mujoco.MjModel:
    """A CPU MuJoCo copy of ``model`` with world ``world``'s row of each randomised field."""
    out = copy.deepcopy(model)
    for name, rows in fields.items():
        getattr(out, name)[:] = rows[world]
    return out


# --- batches
# ---------------------------------------------------------------------------------------


@dataclass
class Batch:
    """A batched model and data, and ``step(n)``: advance every world ``n`` time steps."""

    engine: str
    nworld: int
    step: Callable[[int], None]
    qpos: Callable[[], np.ndarray]  # (nworld, nq) on the host
    check: Callable[[], list[str]]  # problems (overflow, NaN) so far; empty when none


def mjx_batch(
    model: mujoco.MjModel, ctrl: np.ndarray, fields: dict[str, np.ndarray], device=None
) -> Batch:
    """MJX: ``jax.vmap`` of ``mjx.step`` over a model whose randomised fields carry a world axis
    (MuJoCo Playground's pattern), the data broadcast to every world; ``n`` steps run in one jitted
    ``fori_loop``, compiled with :func:`compiler_options`. Uses JAX's default device unless
    ``device`` is given."""
    jax, mjx = import_mjx()
    import jax.numpy as jnp

    nworld = len(next(iter(fields.values())))
    data = mujoco.MjData(model)
    data.ctrl[:] = ctrl
    mx = mjx.put_model(model, device=device)
    axes = jax.tree.map(lambda _: None, mx).tree_replace({name: 0 for name in fields})
    mx = mx.tree_replace(
        {name: jax.device_put(jnp.asarray(rows), device) for name, rows in fields.items()}
    )
    dx = jax.tree.map(
        lambda x: jnp.broadcast_to(x, (nworld, *x.shape)), mjx.put_data(model, data, device=device)
    )

    def one(m, d):  # mjx.step returns some integer fields wider than put_data made them
        return jax.tree.map(lambda new, old: new.astype(old.dtype), mjx.step(m, d), d)

    batched = jax.vmap(one, in_axes=(axes, 0))
    run = jax.jit(
        lambda m, d, n: jax.lax.fori_loop(0, n, lambda _, dd: batched(m, dd), d),
        compiler_options=compiler_options(device),
    )
    state = {"d": dx}

    def step(n: int) -> None:
        state["d"] = run(mx, state["d"], n)
        state["d"].qpos.block_until_ready()

    def check() -> list[str]:
        bad = ~np.isfinite(np.asarray(state["d"].qpos)).all(axis=1)
        return [f"MJX: {bad.sum()} of {nworld} worlds have a non-finite qpos"] if bad.any() else []

    return Batch("mjx", nworld, step, lambda: np.asarray(state["d"].qpos), check)


def _warp_model_data(
    model: mujoco.MjModel,
    ctrl: np.ndarray,
    fields: dict[str, np.ndarray],
    buffers: ConstraintBuffers,
):
    """MuJoCo Warp's batched model and data on Warp's current device (:func:`warp_batch`)."""
    _, mjw = import_warp()
    nworld = len(next(iter(fields.values())))
    data = mujoco.MjData(model)
    data.ctrl[:] = ctrl
    mw = mjw.put_model(model, batch_sizes={name: nworld for name in fields})
    for name, rows in fields.items():
        getattr(mw, name).assign(rows)
    return mw, mjw.put_data(
        model, data, nworld=nworld, nconmax=buffers.nconmax, njmax=buffers.njmax
    )


def warp_batch(
    model: mujoco.MjModel,
    ctrl: np.ndarray,
    fields: dict[str, np.ndarray],
    buffers: ConstraintBuffers,
    device: str = "cpu",
    graph: bool | None = None,
) -> Batch:
    """MuJoCo Warp: ``put_model`` with ``batch_sizes`` giving the randomised fields one row per
    world, filled from ``fields``; ``put_data`` with ``nworld`` and the constraint buffers. On a
    CUDA device one step is captured as a CUDA graph (``graph`` overrides) and replayed."""
    wp, mjw = import_warp()
    nworld = len(next(iter(fields.values())))
    with wp.ScopedDevice(device):
        mw, dw = _warp_model_data(model, ctrl, fields, buffers)
        captured = None
        if graph if graph is not None else wp.get_device(device).is_cuda:
            mjw.step(mw, dw)  # compile outside the capture
            with wp.ScopedCapture() as capture:
                mjw.step(mw, dw)
            captured = capture.graph
            mjw.reset_data(mw, dw)
            dw.ctrl.assign(np.tile(ctrl, (nworld, 1)))

    def step(n: int) -> None:
        with wp.ScopedDevice(device):
            for _ in range(n):
                if captured is None:
                    mjw.step(mw, dw)
                else:
                    wp.capture_launch(captured)
            wp.synchronize_device(device)

    overflow = mjw.OverflowType
    buffer_bits = (
        overflow.NEFC
        | overflow.NJMAX_NNZ
        | overflow.BROADPHASE
        | overflow.NARROWPHASE
        | overflow.CCD
    )

    def check() -> list[str]:
        problems = []
        flags = dw.overflow.numpy() & int(buffer_bits)
        if flags.any():
            problems.append(
                f"MuJoCo Warp: {int((flags != 0).sum())} of {nworld} worlds overflowed their "
                "buffers "
                f"({overflow(int(np.bitwise_or.reduce(flags))).name}; {buffers.line()})"
            )
        if (dw.nefc.numpy() > buffers.njmax).any():
            problems.append(
                f"MuJoCo Warp: nefc {int(dw.nefc.numpy().max())} > njmax {buffers.njmax}"
            )
        bad = ~np.isfinite(dw.qpos.numpy()).all(axis=1)
        if bad.any():
            problems.append(f"MuJoCo Warp: {bad.sum()} of {nworld} worlds have a non-finite qpos")
        return problems

    return Batch("warp", nworld, step, lambda: dw.qpos.numpy(), check)


def cpu_reference(
    model: mujoco.MjModel, ctrl: np.ndarray, steps: int
) -> tuple[np.ndarray, list[str]]:
    """CPU MuJoCo's ``qpos`` after ``steps`` steps from rest under ``ctrl``, and the warnings it
    raised."""
    data = mujoco.MjData(model)
    data.ctrl[:] = ctrl
    for _ in range(steps):
        mujoco.mj_step(model, data)
    warned = [mujoco.mjtWarning(i).name for i, w in enumerate(data.warning) if w.number]
    return data.qpos.copy(), warned


@dataclass(frozen=True)
class KernelTime:
    """One GPU kernel of a MuJoCo Warp step: its time and launches per step, over every world."""

    name: str
    ms_per_step: float
    launches_per_step: float


def kernel_label(name: str) -> str:
    """A Warp timing name without Warp's decorations: ``forward kernel _spring_damper_tendon_passive
    __locals__kernel_1c3d22e2`` -> ``_spring_damper_tendon_passive`` (the module hash and the
    closure's ``__locals__`` suffix differ between builds of the same kernel)."""
    name = re.sub(r"^(forward|backward) kernel ", "", name)
    return re.sub(r"(__locals__\w*?)?_[0-9a-f]{8}$", "", name)


def kernel_times(results, steps: int) -> list[KernelTime]:
    """Warp's timing results (objects with ``name`` and ``elapsed`` in ms) of ``steps`` steps,
    summed per kernel, slowest first."""
    total: dict[str, list[float]] = {}
    for r in results:
        entry = total.setdefault(kernel_label(r.name), [0.0, 0])
        entry[0] += r.elapsed
        entry[1] += 1
    rows = [KernelTime(name, ms / steps, count / steps) for name, (ms, count) in total.items()]
    return sorted(rows, key=lambda k: -k.ms_per_step)


def warp_kernel_profile(
    model: mujoco.MjModel,
    ctrl: np.ndarray,
    fields: dict[str, np.ndarray],
    buffers: ConstraintBuffers,
    device: str = "cuda:0",
    steps: int = 5,
) -> list[KernelTime]:
    """Where a MuJoCo Warp step of this batch spends its GPU time: ``steps`` steps launched one by
    one (not as a graph) under Warp's CUDA kernel timing, after a step that compiles. Slowest kernel
    first.

    Raises:
        ValueError: ``device`` is not a CUDA device (Warp times only CUDA kernels), or ``steps`` <
            1.
    """
    if steps < 1:
        raise ValueError(f"steps must be at least 1, got {steps}")
    wp, mjw = import_warp()
    if not wp.get_device(device).is_cuda:
        raise ValueError(f"per-kernel times need a CUDA device; {device!r} is not one")
    with wp.ScopedDevice(device):
        mw, dw = _warp_model_data(model, ctrl, fields, buffers)
        mjw.step(mw, dw)
        wp.synchronize_device(device)
        wp.timing_begin(cuda_filter=wp.TIMING_KERNEL)
        for _ in range(steps):
            mjw.step(mw, dw)
        results = wp.timing_end()
    return kernel_times(results, steps)


def world_difference(
    batch: Batch,
    model: mujoco.MjModel,
    ctrl: np.ndarray,
    fields: dict[str, np.ndarray],
    steps: int,
    world: int = 0,
) -> float:
    """The largest ``|qpos|`` difference between ``batch``'s world and CPU MuJoCo stepping that
    world's model (the batch must have stepped ``steps`` times from rest under ``ctrl``)."""
    ref, warned = cpu_reference(world_model(model, fields, world), ctrl, steps)
    if warned:
        raise RuntimeError(f"CPU MuJoCo warned on world {world}: {warned}")
    return float(np.abs(batch.qpos()[world] - ref).max())
