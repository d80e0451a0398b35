"""Workspace protocol, the clearance bound (never above the exact distance), CLI exit codes."""

from __future__ import annotations

import numpy as np
import pytest

from bvsr_cad.cli import main

from .conftest import PARAMS


@pytest.fixture(scope="module")
def asm(bvsr_spec):
    from bvsr_cad.assembly.build import build_assembly

    return build_assembly(bvsr_spec)


def test_protocol_pressures_in_range(bvsr_spec):
    from bvsr_cad.analysis.workspace import sample_line_pressures_kpa

    p = sample_line_pressures_kpa(bvsr_spec, 3000, np.random.default_rng(0))
    assert p.min() >= 50 - 101 and p.max() <= 150 - 101
    frac = [(p > 0).mean(), (p < 0).mean(), (p == 0).mean()]
    assert frac == pytest.approx([1 / 3] * 3, abs=0.03)


def test_bound_is_conservative_and_exact_at_rest(asm):
    from bvsr_cad.analysis.clearance import posed_tail

    pt = posed_tail(asm)
    n = pt.kin.n_joints
    everything = np.arange(len(pt.pairs))
    np.testing.assert_allclose(pt.exact(np.zeros((n, 2)), everything), pt.rest_mm, atol=1e-9)
    rng = np.random.default_rng(5)
    w = rng.normal(size=(2, n, 2)) * 0.3
    lb = pt.lower_bounds(w)
    for k in range(len(w)):
        assert (pt.exact(w[k], everything) >= lb[k] - 1e-9).all()
    # Flanges seated in one panel move rigidly: their clearance does not change with the pose.
    i = int(np.argmin(pt.rest_mm))
    assert pt.exact(w[0], np.array([i]))[0] == pytest.approx(pt.rest_mm[i], abs=1e-3)


def test_cli_bad_input_exit_2(capsys):
    assert main(["clearance", str(PARAMS / "bvsr.toml"), "--poses", "0"]) == 2
    assert main(["workspace", str(PARAMS / "nope.toml")]) == 2
