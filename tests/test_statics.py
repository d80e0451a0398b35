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
    p_inv, _ = statics.inverse(w[:, :: bvsr_spec.joints_per_segment])
    assert not np.isnan(p_inv).any()
    assert (p_inv >= statics.act.pressure_min_kpa - 1e-9).all() and (
        p_inv <= statics.act.pressure_max_kpa + 1e-9
    ).all()
    w2 = statics.forward(p_inv)
    assert np.abs(w2 - w)[:, :: bvsr_spec.joints_per_segment].max() < 1e-6
    # Least norm: no pressure set that holds the same pose has a smaller norm than the inverse's.
    assert (np.linalg.norm(p_inv, axis=-1) <= np.linalg.norm(p, axis=-1) + 1e-9).all()


def test_mirrored_pressures_give_mirrored_poses(bvsr_spec):
    st = TailStatics.from_spec(
        bvsr_spec
    )  # gravity along -Y keeps the YZ mirror symmetry; checked without it too
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


def _central_hessian(st, w, p, tip, h=1e-6):
    """d(residual)/dw by central differences over every variable at once (the solver's former
    Hessian)."""
    n = st.kin.n_joints
    pert = (np.eye(2 * n) * h).reshape(2 * n, n, 2)
    lk, fk = p[:, None], tip
    d = (st.residual(w[:, None] + pert, lk, fk) - st.residual(w[:, None] - pert, lk, fk)) / (2 * h)
    return np.swapaxes(d.reshape(len(w), 2 * n, 2 * n), -1, -2)


def test_structured_hessian_equals_central_differences(bvsr_spec, statics):
    """The solver's Hessian (actuator blocks per joint, the rod exact, the loads by forward
    differences) against central differences of the whole residual at bent poses under gravity and a
    tip force."""
    p = _workspace_pressures(bvsr_spec, 8, 2)
    tip = np.array([0.3, -0.2, 0.1])
    w = statics.forward(p, tip)
    p_joint = np.repeat(p, bvsr_spec.joints_per_segment, axis=-2)
    fast = statics._hessian(w, p_joint, tip, statics.load_forces(w, tip))
    ref = _central_hessian(statics, w, p, tip)
    scale = np.abs(ref).max()
    assert (
        np.abs(fast - ref).max() < 1e-6 * scale
    )  # forward differences of the loads: O(h) of a 1e-6 step


@pytest.mark.parametrize("tip_force", [None, (0.3, -0.2, 0.1), "per sample"])
def test_keeping_the_loads_hessian_converges_to_the_same_poses(
    bvsr_spec, statics, monkeypatch, tip_force
):
    """Newton that keeps a sample's loads' Hessian while its steps are small and shrinking lands on
    the poses of Newton that recomputes it at every step (never kept: a threshold of 0), to 1e-12
    rad, under gravity alone, a tip force and a force per sample; and it does keep it (fewer
    evaluations)."""
    from bvsr_cad.models import statics as module

    p = _workspace_pressures(bvsr_spec, 40, 4)
    force = (
        np.random.default_rng(5).normal(0.0, 0.3, (40, 3))
        if tip_force == "per sample"
        else None
        if tip_force is None
        else np.array(tip_force)
    )
    counted: list[int] = []
    real = TailStatics._load_hessian

    def counting(self, w, *args, **kw):
        counted.append(len(w))
        return real(self, w, *args, **kw)

    monkeypatch.setattr(TailStatics, "_load_hessian", counting)
    kept = statics.forward(p, force)
    kept_evaluations = sum(counted)
    counted.clear()
    monkeypatch.setattr(module, "LOAD_HESSIAN_REUSE_BELOW_RAD", 0.0)
    fresh = statics.forward(p, force)
    assert np.abs(kept - fresh).max() < 1e-12
    assert kept_evaluations < sum(counted)
    assert np.abs(statics.residual(kept, p, force)).max() < 1e-8  # N mm: at equilibrium


def test_forward_matches_an_independent_root_finder(bvsr_spec, statics):
    """The converged poses equal scipy's hybrid root finder on the same residual to 1e-9 rad."""
    from scipy.optimize import root

    p = _workspace_pressures(bvsr_spec, 6, 3)
    w = statics.forward(p)
    n = bvsr_spec.joints
    for k in range(len(p)):
        sol = root(
            lambda x, k=k: statics.residual(x.reshape(n, 2), p[k]).ravel(),
            np.zeros(2 * n),
            method="hybr",
            options={"xtol": 1e-13},
        )
        assert (
            np.abs(sol.fun).max() < 1e-8
        )  # N mm: equilibrium (hybr may stop at its own xtol floor)
        assert np.abs(sol.x.reshape(n, 2) - w[k]).max() < 1e-9


def test_a_one_joint_segment_has_a_blocked_force_in_every_motion(bvsr_spec):
    """MINPACK stopped a one-joint segment's extension at a root whose equations were all within
    2e-16 of zero ("not making good progress") and the analyses crashed; a root within the tolerance
    is one. The force balances the moment of the lines' pressures: flexion and extension differ by
    the lines' asymmetry only (a few percent), as for the three-joint segment."""
    import dataclasses

    from bvsr_cad.models.statics import quasi_static_segment

    one = dataclasses.replace(
        bvsr_spec, joints_per_segment=1
    )  # refused at load (its rigid twin), fine here
    seg = TailStatics.from_spec(one).first_segment()
    assert seg.kin.n_joints == 1
    forces = {
        m: quasi_static_segment(seg, m).blocked_force_n for m in ("extension", "flexion", "waggle")
    }
    assert all(np.isfinite(f) and f > 0 for f in forces.values()), forces
    assert forces["extension"] == pytest.approx(forces["flexion"], rel=0.05)


def test_the_horizontal_tail_sags_towards_minus_y_as_hand_statics_give(bvsr_spec, bvsr_data):
    """Gravity's sign and lever arms: the tail horizontal, no pressure, the SOAs' springs taken out
    (n_a = m_a = 0: no force at zero pressure), so that only the rod holds each joint, K = E I / H_a
    with I = pi d^4 / 64 from the parameter file. Small masses (grams) keep every angle below 1e-2
    rad, where the linear hand statics hold: a body at height z above the root face, distal of joint
    k, moves across by v_k (z - c_k) when joint k bends by v_k towards +Y, c_k being the middle of
    the joint's arc (the arc's end moves L v / 2, then the panel turns by v); joint k's own mass, on
    its chord's midpoint, moves L v_k / 4. Gravity along -Y then bends joint k by v_k = -g sum(m_b
    arm_bk) / K, towards -Y, and puts the tip (the last panel's distal face) at y = sum_k v_k (z_tip
    - c_k) < 0. The hand statics leave out terms of relative order Theta^2 (Theta the tip's angle,
    sum of the v_k): that is the tolerance."""
    from dataclasses import replace

    from bvsr_cad.analysis.calibrate import uncalibrated

    j, d_rod = bvsr_data["joint"], bvsr_data["vertebra"]["diameter_mm"]
    e_mpa = bvsr_data["materials"][bvsr_data["vertebra"]["material"]]["youngs_modulus_mpa"]
    h_j, gap = j["joint_height_mm"], j["gap_mm"]
    t = h_j - gap
    n = bvsr_data["segments"] * bvsr_data["joints_per_segment"]
    k_nmm = e_mpa * np.pi * d_rod**4 / 64 / gap
    g = 9.80665  # standard gravity, N/kg
    panel_kg = 1e-3 * (
        1.0 + 0.1 * np.arange(n + 1)
    )  # distinct, so that a body counted at the wrong joint shows
    joint_kg = 0.5e-3 * (1.0 + 0.05 * np.arange(n))
    st = TailStatics.from_spec(
        uncalibrated(bvsr_spec), LumpedMasses(panel_kg, joint_kg)
    )  # the table's E
    st = replace(
        st,
        act=replace(
            st.act,
            law=replace(
                st.act.law, stiffness_slope_n_per_m_per_pa=0.0, stiffness_offset_n_per_m=0.0
            ),
        ),
    )
    w = st.forward(np.zeros((bvsr_spec.segments, 5)))

    z_panel = np.arange(n + 1) * h_j + t / 2  # mid-thickness of panel 0..n
    z_base = np.arange(n) * h_j + t  # joint k's base face (k = 1..n as 0..n-1)
    c = z_base + gap / 2
    z_joint = z_base + gap / 2  # the chord's midpoint at rest
    v = np.empty(n)
    for k in range(n):
        moment = (
            np.sum(panel_kg[k + 1 :] * (z_panel[k + 1 :] - c[k]))
            + np.sum(joint_kg[k + 1 :] * (z_joint[k + 1 :] - c[k]))
            + joint_kg[k] * gap / 4
        )
        v[k] = -g * moment / k_nmm
    theta_tip = abs(v.sum())
    assert theta_tip < 1e-2
    rtol = theta_tip**2
    np.testing.assert_allclose(w[:, 0], 0.0, atol=1e-12)  # no lateral (X) bend: gravity is along Y
    np.testing.assert_allclose(w[:, 1], v, rtol=rtol)
    assert (w[:, 1] < 0).all()
    _, panel = st.kin.frames(w)
    tip = panel[-1, :3, 3] + t * panel[-1, :3, 2]
    y_tip = np.sum(v * (n * h_j + t - c))
    assert y_tip < -0.1  # mm: a sag well above the tolerance
    assert tip[1] == pytest.approx(y_tip, rel=rtol)
