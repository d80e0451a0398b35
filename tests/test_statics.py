"""Eq 3-5: forward and inverse maps, symmetry, straight at zero pressure."""

from __future__ import annotations

import numpy as np
import pytest

from bvsr_cad.models.statics import LumpedMasses, TailStatics, least_norm_in_box


@pytest.fixture(scope="module")
def statics(bvsr_spec):
    n = bvsr_spec.joints
    return TailStatics.from_spec(bvsr_spec, LumpedMasses(np.full(n + 1, 0.018), np.full(n, 0.0155)))


def _workspace_pressures(spec, n, seed=0):
    from bvsr_cad.analysis.workspace import sample_line_pressures_kpa

    return sample_line_pressures_kpa(spec, n, np.random.default_rng(seed))


def test_zero_pressure_without_gravity_is_straight(bvsr_spec):
    st = TailStatics.from_spec(bvsr_spec)
    w = st.forward(np.zeros((1, bvsr_spec.segments, 5)))
    assert np.abs(w).max() < 1e-12


def test_forward_of_inverse_returns_the_pose(bvsr_spec, statics):
    p = _workspace_pressures(bvsr_spec, 60)
    w = statics.forward(p)
    p_inv, _ = statics.inverse(w[:, ::bvsr_spec.joints_per_segment])
    assert not np.isnan(p_inv).any()
    assert (p_inv >= statics.act.pressure_min_kpa - 1e-9).all() and (p_inv <= statics.act.pressure_max_kpa + 1e-9).all()
    w2 = statics.forward(p_inv)
    assert np.abs(w2 - w)[:, ::bvsr_spec.joints_per_segment].max() < 1e-6
    # Least norm: no pressure set that holds the same pose has a smaller norm than the inverse's.
    assert (np.linalg.norm(p_inv, axis=-1) <= np.linalg.norm(p, axis=-1) + 1e-9).all()


def test_mirrored_pressures_give_mirrored_poses(bvsr_spec):
    st = TailStatics.from_spec(bvsr_spec)  # gravity along -Y keeps the YZ mirror symmetry; checked without it too
    p = _workspace_pressures(bvsr_spec, 40, 1)
    mirror = p[..., [0, 4, 3, 2, 1]]  # soa2 <-> soa5, soa3 <-> soa4 (x -> -x)
    w, wm = st.forward(p), st.forward(mirror)
    np.testing.assert_allclose(wm[..., 0], -w[..., 0], atol=1e-9)
    np.testing.assert_allclose(wm[..., 1], w[..., 1], atol=1e-9)


def test_least_norm_in_box_closed_form():
    m = np.array([[1.0, 1, 1, 1, 1], [0, 1, 0, 0, 0]])
    b = np.array([5.0, 0.0])
    p, ok = least_norm_in_box(m, b, -10, 10)
    assert ok and p == pytest.approx([1.25, 0, 1.25, 1.25, 1.25], abs=1e-9)
    p, ok = least_norm_in_box(m, b, -10, 1.5)
    assert ok and p == pytest.approx([1.25, 0, 1.25, 1.25, 1.25], abs=1e-9)
    _, ok = least_norm_in_box(m, np.array([50.0, 0.0]), -10, 10)
    assert not ok
