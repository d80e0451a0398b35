"""Eq 1-2 and the tail chain: closed forms and two independent computations."""

from __future__ import annotations

import numpy as np
import pytest

from bvsr_cad.models.kinematics import (
    TailKinematics,
    joint_rotation_translation,
    joint_transform,
    joint_transform_and_derivatives,
    joint_transform_chain,
    joint_transform_derivatives,
    soa_lengths_and_jacobian,
    soa_lengths_mm,
    uv_from_theta_phi,
)

L = 36.51


def test_eq2_equals_the_urdf_chain_including_the_straight_limit():
    rng = np.random.default_rng(0)
    theta = np.r_[0.0, 1e-12, 1e-6, 5e-3, rng.uniform(0, 1.5, 200)]
    phi = rng.uniform(-np.pi, np.pi, theta.size)
    assert (
        np.abs(joint_transform(theta, phi, L) - joint_transform_chain(theta, phi, L)).max() < 1e-12
    )


def test_eq2_closed_form_entries():
    th, ph = 0.7, 0.4
    t = joint_transform(th, ph, L)
    c, s = np.cos(ph), np.sin(ph)
    assert t[0, 0] == pytest.approx(c * c * np.cos(th) + s * s, abs=1e-14)
    assert t[0, 3] == pytest.approx(L * c * (1 - np.cos(th)) / th, abs=1e-12)
    assert t[2, 3] == pytest.approx(L * np.sin(th) / th, abs=1e-12)
    np.testing.assert_allclose(
        joint_transform(0.0, 1.0, L),
        np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, L], [0, 0, 0, 1.0]]),
        atol=1e-15,
    )


def test_eq2_derivatives_match_differences_and_the_shared_path_gives_the_same_numbers():
    """dR/dw, dp/dw against central differences of Eq 2 on both sides of the series' switch (theta
    1e-2), and joint_transform_and_derivatives (one twist for both) equal to the two separate calls,
    bit for bit, on arrays and on scalars."""
    rng = np.random.default_rng(3)
    u = np.r_[0.0, 3e-3, -7e-3, rng.uniform(-1.2, 1.2, 40)]
    v = np.r_[0.0, 4e-3, 6e-3, rng.uniform(-1.2, 1.2, 40)]
    h = 1e-6
    dR_u, dR_v, dp_u, dp_v = joint_transform_derivatives(u, v, L)
    for d_rot, d_p, du, dv in ((dR_u, dp_u, h, 0.0), (dR_v, dp_v, 0.0, h)):
        (r1, p1), (r0, p0) = (
            joint_rotation_translation(u + du, v + dv, L),
            joint_rotation_translation(u - du, v - dv, L),
        )
        np.testing.assert_allclose(d_rot, (r1 - r0) / (2 * h), atol=1e-8)
        np.testing.assert_allclose(d_p, (p1 - p0) / (2 * h), atol=1e-7)
    for uu, vv in ((u, v), (np.array(0.31), np.array(-0.2)), (np.array(0.0), np.array(0.0))):
        (rot, trans), derivs = joint_transform_and_derivatives(uu, vv, L)
        # Against the URDF's chain of rotations and a slide (computed without the series or Omega).
        chain = joint_transform_chain(np.hypot(uu, vv), np.arctan2(vv, uu), L)
        np.testing.assert_allclose(rot, chain[..., :3, :3], atol=1e-12)
        np.testing.assert_allclose(trans, chain[..., :3, 3], atol=1e-12)
        alone = joint_rotation_translation(uu, vv, L) + joint_transform_derivatives(uu, vv, L)
        assert all(
            a.tobytes() == b.tobytes() and a.shape == b.shape
            for a, b in zip((rot, trans) + derivs, alone)
        )


@pytest.mark.parametrize("taper_offset_deg", [0.0, -0.05])
def test_one_bending_vector_gives_the_array_paths_lengths_and_jacobian(taper_offset_deg):
    """:func:`socket_lengths_and_jacobian` at one bending vector (0-d u and v: Eq 2 written out
    entry by entry, one product for every socket) against the array path at the same vector (the
    twist's products and einsums), on both sides of the series' switch, at zero, for one joint's
    sockets and a segment's, and its Jacobian against central differences of its own lengths; on the
    default tail and on a cone 0.05 deg narrower (any geometry that loads must pass: the tolerances
    come from the arithmetic).

    The two paths sum the same products in other orders: a length's rounding is a few ulps of its
    largest term (|base| + |moving| + L, about 80 mm) per operation, absolute, whatever the length
    (sockets of bends beyond any limit come within 0.2 mm). The bound 64 eps (|base| + |moving| +
    L), 1.2e-12 mm, allows some tens of such operations; measured worst 2.1e-14 mm over cones within
    0.1 deg of the default, where the relative rounding reaches 1.9e-14 (no relative bound near
    1e-14 holds)."""
    import math

    from bvsr_cad.models.kinematics import (
        SERIES_BELOW_RAD,
        joint_geometries,
        socket_lengths_and_jacobian,
    )
    from bvsr_cad.parameters.layout import half_angle_rad, replace_taper
    from bvsr_cad.parameters.load import load_spec

    spec = load_spec("params/bvsr.toml")
    if taper_offset_deg:
        spec = replace_taper(spec, math.degrees(half_angle_rad(spec)) + taper_offset_deg)
    geoms = joint_geometries(spec)
    base, moving = np.stack([g.base_mm for g in geoms]), np.stack([g.moving_mm for g in geoms])
    atol_mm = 64 * np.finfo(float).eps * (np.abs(base).max() + np.abs(moving).max() + L)
    rng = np.random.default_rng(21)
    vectors = [(0.0, 0.0), (1e-12, -3e-13), (3e-3, -4e-3), (SERIES_BELOW_RAD, 0.0), (0.0, -1.2)]
    vectors += [tuple(rng.uniform(-1.2, 1.2, 2)) for _ in range(100)]
    for u, v in vectors:
        for b, m in ((base[0], moving[0]), (base[:3], moving[:3]), (base, moving)):
            length, jac = socket_lengths_and_jacobian(b, m, np.array(u), np.array(v), L)
            lead = b.shape[:-2] or (1,)  # the same vector for every joint, as an array
            ref_len, ref_jac = socket_lengths_and_jacobian(
                b, m, np.full(lead, u), np.full(lead, v), L
            )
            assert length.shape == b.shape[:-1] and jac.shape == b.shape[:-1] + (2,)
            np.testing.assert_allclose(length, ref_len.reshape(length.shape), rtol=0, atol=atol_mm)
            np.testing.assert_allclose(
                jac, ref_jac.reshape(jac.shape), rtol=0, atol=1e-13 * np.abs(ref_jac).max()
            )
    h, (u, v) = 1e-6, (0.41, -0.27)
    _, jac = socket_lengths_and_jacobian(base, moving, u, v, L)
    for k, (du, dv) in enumerate(((h, 0.0), (0.0, h))):
        ahead = socket_lengths_and_jacobian(base, moving, u + du, v + dv, L)[0]
        behind = socket_lengths_and_jacobian(base, moving, u - du, v - dv, L)[0]
        np.testing.assert_allclose(jac[..., k], (ahead - behind) / (2 * h), atol=1e-7)


def test_one_angle_gives_the_array_path_bits():
    """The series coefficients of one angle (Python floats, what a joint's dynamics asks ~21,000
    times a build) are the bits the array path gives for an array of one, on both sides of the
    series' switch, at the switch, at zero and for 0-d and (1,) inputs, and the same array types and
    shapes."""
    from bvsr_cad.models.kinematics import (
        SERIES_BELOW_RAD,
        _series_coefficients,
        _series_coefficients_array,
    )

    rng = np.random.default_rng(11)
    angles = np.r_[
        0.0,
        1e-300,
        1e-12,
        1e-6,
        SERIES_BELOW_RAD,
        np.nextafter(SERIES_BELOW_RAD, 0.0),
        rng.uniform(0.0, 2e-2, 3000),
        rng.uniform(0.0, 1.6, 3000),
        np.abs(rng.normal(0.0, 1e-3, 1000)),
        np.pi,
        3.0,
    ]
    for a in angles:
        for shape in ((), (1,)):
            t = np.full(shape, a)
            one, ref = _series_coefficients(t), _series_coefficients_array(t)
            assert all(
                x.shape == y.shape == shape and x.dtype == y.dtype and x.tobytes() == y.tobytes()
                for x, y in zip(one, ref)
            ), a
    # Arrays of several take the array path itself.
    many = angles[:50]
    assert all(
        x.tobytes() == y.tobytes()
        for x, y in zip(_series_coefficients(many), _series_coefficients_array(many))
    )


def test_soa_lengths_and_jacobian(bvsr_spec):
    kin = TailKinematics.from_spec(bvsr_spec)
    g = kin.joints[-1]
    # At rest: H_a + 2 pocket depths along z plus the taper's radial step.
    dz = L + 2 * 0.545
    dr = np.linalg.norm(g.moving_mm[0, :2]) - np.linalg.norm(g.base_mm[0, :2])
    np.testing.assert_allclose(g.rest_lengths_mm, np.hypot(dz, dr), rtol=1e-12)
    u, v, h = 0.21, -0.13, 1e-6
    _, jac = soa_lengths_and_jacobian(g, np.array(u), np.array(v))
    fd_u = (
        (
            soa_lengths_mm(g, np.array(u + h), np.array(v))
            - soa_lengths_mm(g, np.array(u - h), np.array(v))
        )
        / 2
        / h
    )
    fd_v = (
        (
            soa_lengths_mm(g, np.array(u), np.array(v + h))
            - soa_lengths_mm(g, np.array(u), np.array(v - h))
        )
        / 2
        / h
    )
    np.testing.assert_allclose(jac, np.stack([fd_u, fd_v], -1), atol=1e-7)


def test_tail_tip_uniform_bend_closed_form(bvsr_spec):
    kin = TailKinematics.from_spec(bvsr_spec)
    n, t = 6, 42.51 - L  # Table I: six joints, panels H_j - H_a thick
    assert kin.n_joints == n and kin.rest_tip_mm() == pytest.approx([0, 0, n * L + (n + 1) * t])
    # Every joint bent by theta in the YZ plane: the tip is a planar chain of arcs and slabs.
    th = 0.1
    w = np.tile(uv_from_theta_phi(th, np.pi / 2), (n, 1))
    pos, ang = np.zeros(2), 0.0  # (y, z), angle of the local z axis from +Z towards +Y
    for _ in range(n):
        pos = pos + t * np.array([np.sin(ang), np.cos(ang)])
        chord = 2 * L * np.sin(th / 2) / th
        pos = pos + chord * np.array([np.sin(ang + th / 2), np.cos(ang + th / 2)])
        ang += th
    pos = pos + t * np.array([np.sin(ang), np.cos(ang)])
    tip = kin.tip_point_mm(w)
    assert tip == pytest.approx([0.0, pos[0], pos[1]], abs=1e-9)
    # Batched poses give the same as one by one.
    batch = np.stack([w, 0.5 * w])
    np.testing.assert_allclose(kin.tip_point_mm(batch)[0], tip, atol=1e-12)
