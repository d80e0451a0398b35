"""The paper's workspace experiment run in time (bvsr_cad.simulation.sim.workspace_protocol): the
exported MJCF driven by a new random pressure per line every cycle, as Sec. IV-A-5 drives the real
tail.

Two independent models meet here: where the tail has settled at the end of each 1 s cycle,
MuJoCo's reduced chain must put the tip where the quasi-static model of the analyses puts it for
the same pressures (models/statics, solved by Newton's method, no time)."""

from __future__ import annotations

import numpy as np
import pytest

from bvsr_cad.analysis.predict import NeedsSimulator, Predictor
from bvsr_cad.analysis.workspace import sample_line_pressures_kpa, tail_statics
from bvsr_cad.assembly.assemble import build_assembly
from bvsr_cad.simulation import sim

CYCLES = 40
#: Joint limits beyond any bend of this protocol (0.5 bar): the run does not need the clearance
#: analysis.
FREE_LIMITS_RAD = 0.9


@pytest.fixture(scope="module")
def asm(bvsr_spec):
    return build_assembly(bvsr_spec)


@pytest.fixture(scope="module")
def run(asm, bvsr_spec):
    return sim.workspace_protocol(
        asm, bvsr_spec, [FREE_LIMITS_RAD] * bvsr_spec.joints, cycles=CYCLES
    )


def test_settled_tip_is_where_the_statics_put_it(run, asm, bvsr_spec):
    """Each cycle's settled tip, lateral to the tail's axis, against the statics' for the same
    pressures: within 5 mm, median within 3 mm (lateral excursions 4-50 mm).

    The difference is the two models' gravity: the statics lump it (each panel at its
    mid-thickness, each joint's SOAs and rod at its arc's chord midpoint), MuJoCo applies it to
    each link's own inertia. Measured on the default tail: largest 4.0 mm, median 2.5; with gravity
    off in both, 2.2 mm and 0.7 (within 7 % of the excursion: the SOAs, the rod and the chain
    agree). The run adds little: cycles held 3 s instead of 1 s give 4.2 mm (the tail has
    settled), a 0.5 ms step instead of the exported 2 ms 3.8 mm. The limits sit a quarter above the
    measured figures: a change that moves the settled tip by a millimetre more (a wrong lever arm,
    stiffness or mass) trips them."""
    assert run.warnings == 0
    assert run.settled_mm.shape == (CYCLES, 3)
    st = tail_statics(asm, spec=bvsr_spec)
    draws = sample_line_pressures_kpa(
        bvsr_spec, CYCLES, np.random.default_rng(bvsr_spec.analysis.seed)
    )
    tips = st.kin.tip_point_mm(st.forward(draws))
    rest = st.kin.tip_point_mm(st.forward(np.zeros((bvsr_spec.segments, 5))))
    statics = np.hypot(tips[:, 0] - rest[0], tips[:, 1] - rest[1])
    mujoco = run.lateral_mm(run.settled_mm)
    assert statics.max() > 30.0  # the draws do bend the tail: the comparison means something
    assert np.max(np.abs(mujoco - statics)) < 5.0
    assert np.median(np.abs(mujoco - statics)) < 3.0


def test_path_is_sampled_through_every_cycle(run, bvsr_spec):
    per_cycle = round(bvsr_spec.actuation.workspace_cycle_s / sim.PROTOCOL_SAMPLE_S)
    assert run.tip_mm.shape == (CYCLES * per_cycle, 3)
    # The last sample of each cycle is the settled point.
    np.testing.assert_allclose(run.tip_mm[per_cycle - 1 :: per_cycle], run.settled_mm, atol=1e-9)
    assert run.radius_mm >= run.settled_radius_mm
    assert np.linalg.norm(run.axis) == pytest.approx(1.0)


def test_workspace_row_needs_the_simulator(asm, bvsr_spec):
    with pytest.raises(NeedsSimulator, match="workspace_sim"):
        Predictor(asm, bvsr_spec).tip_workspace_radius(2, 150.0, 50.0)


def test_dropping_the_geoms_changes_nothing(asm, bvsr_spec):
    """The protocol's model drops its geoms (none can touch another in this scene): the same run as
    with them, to the last bit."""
    limits = [FREE_LIMITS_RAD] * bvsr_spec.joints
    assert sim.protocol_model(asm, bvsr_spec, limits, "panel0")[0].ngeom == 0
    assert sim.protocol_model(asm, bvsr_spec, limits, "panel0", keep_geoms=True)[0].ngeom > 0
    lean = sim.workspace_protocol(asm, bvsr_spec, limits, cycles=4)
    full = sim.workspace_protocol(asm, bvsr_spec, limits, cycles=4, keep_geoms=True)
    np.testing.assert_array_equal(full.tip_mm, lean.tip_mm)
    np.testing.assert_array_equal(full.rest_mm, lean.rest_mm)
