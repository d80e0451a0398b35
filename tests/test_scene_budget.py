"""The default simulation scene's budget for batched stepping: the counts that set what a MuJoCo
Warp step costs every world stay at or below what the scene has. A change to the writer that adds
tendons, DoFs or constraint rows to the default scene fails here, not in a benchmark someone forgot
to run (``benchmarks/sim_bench.py`` measures what they cost; figures in benchmarks/RESULTS.md).

Each ceiling is per bending joint of the tail (``segments`` x ``joints_per_segment`` of the
parameters: 6 in the default tail) and is the default scene's own count, as
``benchmarks/sim_bench.py`` measured it:

- DoFs: 4 per joint, the two pivot hinges of the pseudo-rigid-body chain about each of the two
  bending axes;
- tendons: 12 per joint, one spatial tendon per SOA (5) and a bend-limit tendon per direction of
  the limit polygon (7); the shear springs and all the dampers are on the hinges;
- constraint rows: 2 per joint, the most in any step of 0.3 s of any held pressure pattern from
  rest (:func:`sim_bench.held_patterns`), all of them the two pivots' equalities: held pressures
  bend the tail to at most 38 % of its limits, so no limit row appears.
"""

from __future__ import annotations

import mujoco
import pytest

from bvsr_cad.simulation import sim_gpu

from .conftest import benchmark_script

DOFS_PER_JOINT = 4
TENDONS_PER_JOINT = 12
ROWS_PER_JOINT = 2


@pytest.fixture(scope="module")
def budget(bvsr_export, bvsr_spec):
    """The default scene, its counts and the tail's number of bending joints."""
    model = mujoco.MjModel.from_xml_path(str(sim_gpu.scene_path(bvsr_export)))
    counts = benchmark_script("sim_bench").scene_counts(model)
    return model, counts, bvsr_spec.segments * bvsr_spec.joints_per_segment


def test_default_scene_dofs_within_budget(budget):
    model, _, joints = budget
    assert model.nv <= DOFS_PER_JOINT * joints


def test_default_scene_tendons_within_budget(budget):
    model, _, joints = budget
    assert model.ntendon <= TENDONS_PER_JOINT * joints


def test_default_scene_constraint_rows_within_budget(budget):
    """The most rows under any held pattern, which the rows of the scene's equalities (one a joint
    equality, all active from rest) bound from below: the count sees every row."""
    model, counts, joints = budget
    rows = counts["rows"]
    equality_rows = sum(
        {mujoco.mjtEq.mjEQ_JOINT: 1, mujoco.mjtEq.mjEQ_CONNECT: 3, mujoco.mjtEq.mjEQ_WELD: 6}[t]
        for t in map(mujoco.mjtEq, model.eq_type)
    )
    assert counts["warnings"] == []
    assert rows["equality"] == equality_rows
    assert equality_rows <= rows["all"] <= ROWS_PER_JOINT * joints


@pytest.fixture(scope="module")
def written_model(bvsr_spec):
    """The default tail's model file as a build writes it (robot/bvsr.xml, the reduced chain that
    robot/scene.xml includes), made in memory from the assembly in seconds instead of a whole
    build: without collision shapes and meshes (neither adds a DoF, a tendon or an equality) and
    with a fixed joint limit (its value sets no count).
    :func:`test_the_model_made_in_memory_counts_as_the_exported_scene` holds it to the export."""
    import xml.etree.ElementTree as ET

    from bvsr_cad.assembly.assemble import build_assembly
    from bvsr_cad.assembly.robot import robot_model
    from bvsr_cad.exporters.mjcf import mjcf_tree

    asm = build_assembly(bvsr_spec)
    robot = robot_model(asm, [0.5] * asm.spec.joints, collisions=False)
    meshes = {v.name: f"{v.name}.stl" for link in robot.links.values() for v in link.visuals}
    root = mjcf_tree(robot, meshes, False, chain="reduced")[0].getroot()
    for parent in list(root.iter()):
        for child in list(parent):
            if child.tag == "mesh" or child.get("mesh") is not None:
                parent.remove(child)
    model = mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))
    return model, bvsr_spec.segments * bvsr_spec.joints_per_segment


def test_the_written_models_dofs_within_budget(written_model):
    model, joints = written_model
    assert model.nv <= DOFS_PER_JOINT * joints


def test_the_written_models_tendons_within_budget(written_model):
    """tools/mutate.py's mjcf_idle_tendon_per_joint (a tendon per joint that does nothing) fails
    here in seconds, as in :func:`test_default_scene_tendons_within_budget` after a whole build."""
    model, joints = written_model
    assert model.ntendon <= TENDONS_PER_JOINT * joints


def test_the_model_made_in_memory_counts_as_the_exported_scene(written_model, budget):
    """The in-memory model has the exported scene's DoFs, tendons, actuators and equalities: the
    fast tests above see what the scene has."""
    made, _ = written_model
    exported, _, _ = budget
    counts = ("nv", "ntendon", "nu", "neq", "njnt")
    assert {c: getattr(made, c) for c in counts} == {c: getattr(exported, c) for c in counts}
