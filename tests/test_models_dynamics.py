"""The Eq 6-12 dynamics, the ISO 6358 supply, the platform of Eq 20-22 and the measurement files:
each against a closed form, a second method or the paper's printed equation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from bvsr_cad.models import dynamics as dyn
from bvsr_cad.models import pneumatics as pn
from bvsr_cad.models.actuator import soa_force_law
from bvsr_cad.models.kinematics import joint_geometries
from bvsr_cad.models.platform import Platform, TailOnPlatform, platform_motion
from bvsr_cad.models.rod import rod_section
from bvsr_cad.models.statics import TailStatics, pressure_pattern_kpa

BODY = dyn.RigidBody(
    mass_kg=0.1, inertia_phi_kg_m2=5e-5, inertia_theta_kg_m2=1.6e-4, arc_length_m=0.13
)


def test_mass_matrix_closed_forms():
    """Eq 7 at the straight pose by hand: CoM at L/2 turning at theta'/2 -> I/4 + m L^2 / 16; M_phi
    = I_phi + m L^2 / 4."""
    m = dyn.mass_matrix(BODY, 0.0)
    assert m[1, 1] == pytest.approx(1.6e-4 / 4 + 0.1 * 0.13**2 / 16, rel=1e-12)
    assert m[0, 0] == pytest.approx(5e-5 + 0.1 * 0.13**2 / 4, rel=1e-12)
    # Away from 0: the kinetic energy of the chord-midpoint body, |dp/dtheta|^2, by finite
    # differences.
    th, h = 0.9, 1e-6
    p = lambda t: np.array(dyn.com_position_m(BODY, 0.0, t))  # noqa: E731
    v2 = float(np.sum(((p(th + h) - p(th - h)) / (2 * h)) ** 2))
    assert dyn.mass_matrix(BODY, th)[1, 1] == pytest.approx(1.6e-4 / 4 + 0.1 * v2, rel=1e-7)
    # The series branch meets the closed form.
    assert dyn.mass_matrix(BODY, 0.0199)[1, 1] == pytest.approx(
        dyn.mass_matrix(BODY, 0.0201)[1, 1], rel=1e-6
    )


@pytest.mark.parametrize("theta", [0.2, 0.7, 1.3])
def test_coriolis_is_eq8_as_printed(theta):
    """The Christoffel terms of Eq 7's M are the paper's Eq 8."""
    ours = dyn.coriolis(BODY, theta, 0.7, 1.3)
    paper = dyn.paper_coriolis(BODY, theta, 0.7, 1.3)
    assert ours == pytest.approx(paper, rel=1e-4)  # finite differences of M against the closed form


def test_gravity_is_the_potential_gradient_by_hand():
    """Tail horizontal, gravity -Y: U = m g d sin(theta/2) sin(phi), d = L sin(theta/2) / theta."""
    g = np.array([0.0, -dyn.G_M_S2, 0.0])
    phi, th = 1.1, 0.6
    dU_dth = (
        BODY.mass_kg
        * dyn.G_M_S2
        * BODY.arc_length_m
        * math.sin(phi)
        * (math.sin(th) / (2 * th) - (1 - math.cos(th)) / (2 * th**2))
    )
    assert dyn.gravity_force(BODY, phi, th, g)[1] == pytest.approx(dU_dth, rel=1e-6)


def test_equilibrium_of_eq6_is_the_statics(bvsr_spec):
    spec = bvsr_spec
    """A held pressure: Eq 6 settles where the quasi-static model (a second method: Newton on the
    potential's gradient, models/statics.py) puts the joint; one joint, no gravity."""
    geom = joint_geometries(spec)[:1]
    law = soa_force_law(spec)
    rod = rod_section(spec).bending_stiffness_nm_per_rad(spec.joint.gap_mm)
    model = dyn.JointModel(
        geom, law, rod, dyn.RigidBody(0.03, 2e-5, 1.5e-5, spec.joint.gap_mm / 1e3)
    )
    pat = pressure_pattern_kpa(math.pi / 2, -95.0, 150.0)
    tr = dyn.simulate_joint(model, lambda t: pat * 1e3, seconds=0.6, phi0_rad=math.pi / 2)
    st = TailStatics.from_spec(spec)
    kin = st.kin
    one = TailStatics(
        type(kin)(kin.joints[:1], kin.panel_thickness_mm, 1), st.act, st.rod_nmm_per_rad
    )
    w = one.forward(pat[None, :])[0]
    assert tr.theta_rad[-1] == pytest.approx(float(np.hypot(*w)), rel=1e-4)
    assert abs(tr.theta_rate_rad_s[-1]) < 1e-3


def test_iso6358_flow_by_hand():
    c, b = 0.5 * pn.M3_S_PA_PER_L_S_BAR, 0.4
    q = pn.iso6358_mass_flow_kg_s(7e5, 1e5, c, b)  # r = 0.14 < b: choked
    assert q == pytest.approx(c * pn.RHO_0_KG_M3 * 7e5, rel=1e-12)
    # Subsonic: phi = sqrt(1 - ((0.7 - 0.4) / 0.6)^2) = sqrt(0.75)
    assert pn.iso6358_mass_flow_kg_s(1e6, 7e5, c, b) == pytest.approx(
        c * pn.RHO_0_KG_M3 * 1e6 * math.sqrt(0.75)
    )
    assert pn.iso6358_mass_flow_kg_s(1e5, 1e5, c, b) == 0.0
    assert pn.iso6358_mass_flow_kg_s(1e5, 7e5, c, b) == pytest.approx(-q)  # reverses


def test_one_valve_on_floats_is_the_array_law_to_the_bit():
    """A line's filling takes the valve's flow on floats (``_mass_flow_one_kg_s``, the law's one
    home, every step of an integration); :func:`iso6358_mass_flow_kg_s` applies it to arrays: the
    same bits for the same pressures (choked, subsonic, in the laminar end, at equal pressures and
    flowing back, at two temperatures), the laminar end by hand, and its broadcasting."""
    c, b = 0.08 * pn.M3_S_PA_PER_L_S_BAR, 0.4
    rng = np.random.default_rng(5)
    down = np.r_[
        1e5,
        2.8e5,
        6.99e5,
        6.9999e5,
        7e5,
        7.0001e5,
        9e5,
        rng.uniform(0.5e5, 9e5, 400),
        7e5 * (1 - rng.uniform(0, 2e-3, 100)),
    ]
    for temperature in (pn.T_0_K, 310.0):
        ref = pn.iso6358_mass_flow_kg_s(7e5, down, c, b, temperature)
        one = [pn._mass_flow_one_kg_s(7e5, float(p), c, b, temperature) for p in down]
        assert np.array(one).tobytes() == ref.tobytes()
    assert {np.sign(x) for x in ref} == {-1.0, 0.0, 1.0}
    # The laminar end by hand: a 0.05 % drop, half the way from the ellipse's value at 0.999 to
    # zero.
    r = 1 - 5e-4
    ellipse = math.sqrt(1 - ((0.999 - b) / (1 - b)) ** 2)
    assert pn.iso6358_mass_flow_kg_s(7e5, 7e5 * r, c, b) == pytest.approx(
        c * pn.RHO_0_KG_M3 * 7e5 * ellipse * 0.5, rel=1e-9
    )
    # Broadcast: one pressure against a (2, 3) grid gives a (2, 3) grid; two scalars a scalar.
    grid = pn.iso6358_mass_flow_kg_s(np.full((2, 1), 7e5), np.array([1e5, 5e5, 7e5]), c, b)
    assert grid.shape == (2, 3) and grid[1, 2] == 0.0
    assert np.ndim(pn.iso6358_mass_flow_kg_s(7e5, 1e5, c, b)) == 0


def test_the_joint_models_right_hand_side_is_eq6_from_the_public_terms(bvsr_spec):
    """:meth:`JointModel.rhs` (its terms on floats, the sockets' lengths and Jacobian from one
    twist) against Eq 6 put together from the public functions: ``mass_matrix``, ``coriolis``,
    ``gravity_force`` (gravity with two components) and ``generalized_forces`` on the array path of
    :func:`socket_lengths_and_jacobian`, for a segment of three joints, at the straight pose too."""
    from bvsr_cad.models.kinematics import socket_lengths_and_jacobian

    spec = bvsr_spec
    geom = joint_geometries(spec)[:3]
    law = soa_force_law(spec)
    rod = rod_section(spec).bending_stiffness_nm_per_rad(spec.joint.gap_mm)
    g = np.array([0.0, -6.0, -7.6])
    model = dyn.JointModel(
        geom, law, rod, dyn.RigidBody(0.05, 3e-5, 4e-5, 3 * spec.joint.gap_mm / 1e3), g
    )
    rng = np.random.default_rng(9)
    states = [(0.3, 0.0, 0.0, 0.0)] + [
        tuple(rng.uniform([-3, -0.4, -20, -20], [3, 0.4, 20, 20])) for _ in range(60)
    ]
    worst = 0.0
    for phi, theta, dphi, dtheta in states:
        p = rng.uniform(-9e4, 5e5, 5)
        u, v = theta * math.cos(phi), theta * math.sin(phi)
        length, jac_uv = socket_lengths_and_jacobian(
            model._base_m, model._moving_m, np.full(3, u), np.full(3, v), model._arc_m
        )
        duv = np.array([[-v, math.cos(phi)], [u, math.sin(phi)]])
        terms = (length - model._rest_m, jac_uv @ duv)
        n = model.n
        m = dyn.mass_matrix(model.body, n * theta)
        m_q = np.array([m[0, 0], m[1, 1] * n * n])
        cor = dyn.coriolis(model.body, n * theta, dphi, n * dtheta) * np.array([1.0, n])
        grav = dyn.gravity_force(model.body, phi, n * theta, g) * np.array([1.0, n])
        want = (model.generalized_forces(phi, theta, dphi, dtheta, p, terms) - cor - grav) / m_q
        if theta == 0.0:
            want[0] = 0.0
        got = model.rhs(phi, theta, dphi, dtheta, p)
        worst = max(worst, float(np.max(np.abs(got - want) / np.maximum(np.abs(want), 1.0))))
    assert worst < 1e-9


def test_isothermal_choked_filling_rises_linearly():
    """n = 1, closed rigid volume, choked inflow: dp/dt = R T C rho_0 p_s / V (constant)."""
    c = 0.2 * pn.M3_S_PA_PER_L_S_BAR
    sup = pn.LineSupply(
        pn.Valve(c, 0.5),
        7.01e5,
        1.01e5,
        (2e-6,),
        4e-6,
        1e-4,
        3,
        (-1, -1, 0, -1, -1),
        polytropic_index=1.0,
    )
    volume = 2e-6 + 3 * 4e-6
    slope = pn.R_AIR_J_KG_K * pn.T_0_K * c * pn.RHO_0_KG_M3 * 7.01e5 / volume
    t, p = pn.fill_curve(sup, 0.004, samples=81)
    assert np.all(p + 1.01e5 < 0.5 * 7.01e5)  # still choked
    assert p[-1] == pytest.approx(slope * t[-1], rel=1e-5)
    tau = pn.first_order_time_constant_s(sup)
    assert 0 < tau < 0.5


def test_a_lines_lag_is_the_same_whichever_places_it_feeds():
    """:func:`bvsr_cad.models.pneumatics.first_order_time_constant_s`: at rest every place stretches
    alike, so the lag of a line feeding place 1 or place 4 (or two lines in either order) is the
    same to the bit; a wider tube fills more slowly."""
    import dataclasses

    c = 0.08 * pn.M3_S_PA_PER_L_S_BAR
    base = pn.LineSupply(
        pn.Valve(c, 0.4), 7.01e5, 1.01e5, (2e-6,), 4e-6, 1e-4, 3, (0, -1, -1, -1, -1)
    )
    lag = pn.first_order_time_constant_s
    places = [(-1, -1, -1, 0, -1), (0, -1, -1, -1, -1), (-1, 0, -1, -1, -1)]
    assert len({lag(dataclasses.replace(base, lines=lines)) for lines in places}) == 1
    two = dataclasses.replace(base, tube_volume_m3=(2e-6, 3e-6), lines=(-1, 1, -1, 0, -1))
    assert lag(two) == lag(dataclasses.replace(two, lines=(1, -1, -1, -1, 0)))
    assert lag(dataclasses.replace(base, tube_volume_m3=(3e-6,))) > lag(base)


def test_platform_conserves_angular_momentum_without_gravity():
    """Eq 22 with g = 0 from rest: (I_r + m_r L_r^2 + J_t) alpha = J_t beta, J_t = I_t + m_t
    L_t^2."""
    plat = Platform(0.7, 2e-3, 0.1, 0.2)
    tail = TailOnPlatform(0.2, 1e-3, 0.12)
    t = np.linspace(0, 0.2, 201)
    beta = 0.5 * (1 - np.cos(np.pi * t / 0.2))
    res = platform_motion(plat, tail, t, beta, gravity=False)
    j_t = 1e-3 + 0.2 * 0.12**2
    assert beta[-1] == pytest.approx(1.0)
    assert res.alpha_rad[-1] == pytest.approx(j_t / (2e-3 + 0.7 * 0.01 + j_t) * beta[-1], rel=2e-3)


def test_platform_on_the_ground_stays_down_for_a_slow_tail():
    plat = Platform(0.7, 2e-3, 0.1, 0.2)
    tail = TailOnPlatform(0.2, 1e-3, 0.12)
    t = np.linspace(0, 2.0, 201)
    res = platform_motion(plat, tail, t, 0.3 * t / 2.0, gravity=True)
    assert res.lift_mm(0.2) == 0.0


# -- the tip payload
# ---------------------------------------------------------------------------------
def _arc_end_m(L: float, phi: float, theta: float) -> np.ndarray:
    """The end of a constant-curvature arc of length L bent by theta in the plane phi, by hand."""
    r = L * (1 - math.cos(theta)) / theta if theta else 0.0
    z = L * math.sin(theta) / theta if theta else L
    return np.array([r * math.cos(phi), r * math.sin(phi), z])


def test_a_tip_payload_is_a_point_mass_at_the_arcs_end():
    """A payload m_p at the end of the body's arc: the body keeps its mass and inertias and the
    payload adds its own kinetic and potential energy, with its position from the arc by hand (not
    from the model's centre of mass).

    M_theta grows by m_p |dp_tip/dtheta|^2 (finite differences, h = 1e-6: rel 1e-7 as for the body
    above); straight, the tip moves across at L / 2 per unit theta: m_p L^2 / 4. Eq 7's M_phi
    carries the body as m d^2 with d its distance from the base along the chord; the payload's
    distance is the whole chord 2 L sin(theta / 2) / theta, so M_phi grows by m_p chord^2. Gravity
    (-Y) grows by the gradient of U_p = m_p g y_tip (y_tip by hand, differentiated by hand)."""
    m_p, L = 0.1, BODY.arc_length_m
    body = BODY.with_tip_mass(m_p)
    assert (body.mass_kg, body.inertia_phi_kg_m2, body.inertia_theta_kg_m2, body.arc_length_m) == (
        BODY.mass_kg,
        BODY.inertia_phi_kg_m2,
        BODY.inertia_theta_kg_m2,
        BODY.arc_length_m,
    )
    assert body.tip_mass_kg == m_p and body.total_mass_kg == pytest.approx(0.2, rel=1e-15)
    assert BODY.with_tip_mass(0.0) is BODY and BODY.tip_mass_kg == 0.0
    with pytest.raises(ValueError, match="mass_kg = -0.1"):
        BODY.with_tip_mass(-0.1)

    straight = dyn.mass_matrix(body, 0.0) - dyn.mass_matrix(BODY, 0.0)
    assert straight[1, 1] == pytest.approx(m_p * L**2 / 4, rel=1e-12)
    assert straight[0, 0] == pytest.approx(m_p * L**2, rel=1e-12)
    th, h = 0.9, 1e-6
    v2 = float(np.sum(((_arc_end_m(L, 0.0, th + h) - _arc_end_m(L, 0.0, th - h)) / (2 * h)) ** 2))
    bent = dyn.mass_matrix(body, th) - dyn.mass_matrix(BODY, th)
    assert bent[1, 1] == pytest.approx(m_p * v2, rel=1e-7)
    assert bent[0, 0] == pytest.approx(m_p * (2 * L * math.sin(th / 2) / th) ** 2, rel=1e-12)
    np.testing.assert_allclose(
        dyn.tip_position_m(body, 1.1, th), _arc_end_m(L, 1.1, th), rtol=1e-14, atol=1e-17
    )

    g = np.array([0.0, -dyn.G_M_S2, 0.0])
    phi = 1.1
    r = L * (1 - math.cos(th)) / th
    dU_dphi = m_p * dyn.G_M_S2 * r * math.cos(phi)
    dU_dth = m_p * dyn.G_M_S2 * L * math.sin(phi) * (math.sin(th) / th - (1 - math.cos(th)) / th**2)
    extra = dyn.gravity_force(body, phi, th, g) - dyn.gravity_force(BODY, phi, th, g)
    assert extra == pytest.approx([dU_dphi, dU_dth], rel=1e-6)  # central differences, h = 1e-7


@pytest.mark.parametrize("payload_kg", [0.0, 0.1])
def test_without_damping_and_forcing_the_model_conserves_energy(payload_kg):
    """Eq 6 with only M, c and G (no actuators, rod or damper): M q'' = -c - G from the public
    terms, integrated (DOP853, rtol 1e-10) for 0.1 s of the tail, bent down and turning about its
    axis, falling further under gravity (-Y). The energy q'^T M q' / 2 + U, with U = -m g . p_com -
    m_p g . p_tip (the tip by hand), stays put to 1e-7 of the kinetic energy's swing: the
    integration and the terms' central differences err by about 1e-8 of it here (measured), while a
    payload weighed at the centre of mass instead of the tip drifts by half the swing. (The bend
    stays above 0.3 rad: near straight, Eq 7's closed form cancels to a few digits and the central
    differences of M are noisier, at about 1e-6.)"""
    from scipy.integrate import solve_ivp

    body = BODY.with_tip_mass(payload_kg)
    g = np.array([0.0, -dyn.G_M_S2, 0.0])

    def f(t, y):
        phi, th, dphi, dth = y
        rhs = -dyn.coriolis(body, th, dphi, dth) - dyn.gravity_force(body, phi, th, g)
        return [dphi, dth, *np.linalg.solve(dyn.mass_matrix(body, th), rhs)]

    def energy(y):
        phi, th, dphi, dth = y
        qd = np.array([dphi, dth])
        kinetic = 0.5 * qd @ dyn.mass_matrix(body, th) @ qd
        tip = _arc_end_m(BODY.arc_length_m, phi, th)
        return kinetic, kinetic - BODY.mass_kg * g @ dyn.com_position_m(
            BODY, phi, th
        ) - payload_kg * g @ tip

    sol = solve_ivp(
        f,
        (0.0, 0.1),
        [-1.2, 0.6, 1.5, 0.0],
        method="DOP853",
        rtol=1e-10,
        atol=1e-12,
        dense_output=True,
    )
    assert sol.status == 0
    states = sol.sol(np.linspace(0.0, 0.1, 201)).T
    kinetic, total = np.array([energy(y) for y in states]).T
    assert 0.3 < states[:, 1].min() and states[:, 1].max() > 1.2  # it fell a long way
    swing = kinetic.max() - kinetic.min()
    assert swing > 0.5 * kinetic.max()
    assert np.max(np.abs(total - total[0])) < 1e-7 * swing, (
        np.max(np.abs(total - total[0])),
        swing,
    )


def _constant_acceleration(n_joints: int, accel_rad_s2: float) -> dyn.Trajectory:
    """The segment bending from rest at a constant angular acceleration in extension (phi = +90
    deg): the segment angle n theta = A t^2 / 2 over 2 ms."""
    t = np.linspace(0.0, 2e-3, 81)
    big = 0.5 * accel_rad_s2 * t**2
    return dyn.Trajectory(
        t,
        np.full_like(t, math.pi / 2),
        big / n_joints,
        np.zeros_like(t),
        accel_rad_s2 * t / n_joints,
        n_joints,
        np.zeros((t.size, 5)),
    )


def test_root_wrench_with_a_tip_payload_under_a_known_angular_acceleration(bvsr_spec, bvsr_data):
    """The predicted root force and torque of the whole tail with and without a 100 g tip payload,
    the tail bending from rest at a known angular acceleration A (the segment angle Theta = A t^2 /
    2).

    By hand, at rest (terms of second order in Theta left out): the body turns by half the angle, so
    at A / 2, and its centre of mass, on the chord midpoint L / 2 from the base face (the model's
    premise, Eq 7), moves across at (L / 2)(A / 2) = L A / 4. The payload, a point mass on the arc's
    end, sits at L (1 - cos Theta) / Theta ~ L Theta / 2 across and L along the axis: it moves
    across at L A / 2, twice as fast. Force F = (m L / 4 + m_p L / 2) A; torque about the root
    panel's proximal face, t below the base face: (L / 2 + t) m L A / 4 + I_theta A / 2 + (L + t)
    m_p L A / 2, with L = n H_j (the last panel's distal face). np.gradient's central differences
    are exact on the quadratic (its one-sided ends give less, never the peak). With A = 200 rad/s^2
    over 2 ms, Theta <= 4e-4 rad; the left-out terms (the centre of mass and the tip drawn in along
    the axis, at order A^2 t^2 of their lateral lever) are of relative order (2 Theta)^2 = 6.4e-7:
    rel 1e-6."""
    from bvsr_cad.analysis.predict import Predictor
    from bvsr_cad.assembly.bodies import moving_body

    pred = Predictor.from_spec(bvsr_spec)
    n = bvsr_spec.joints
    h_j, gap = bvsr_data["joint"]["joint_height_mm"] / 1e3, bvsr_data["joint"]["gap_mm"] / 1e3
    t_panel, A = h_j - gap, 200.0
    body = moving_body(pred.asm, 1, n)
    m, L = body.mass_kg, body.arc_length_m
    assert L == pytest.approx(
        n * h_j, rel=1e-12
    )  # the segment's arc ends on the last panel's distal face
    for payload_g in (0.0, 100.0):
        m_p = payload_g / 1e3
        model = pred.joint_model(1, n, payload_g)
        tr = _constant_acceleration(n, A)
        pred.tail_pulse = lambda motion, bar, grams, model=model, tr=tr: (model, tr)
        force_n, torque_nm = pred.root_wrench("extension", 6.0, payload_g)
        f = (m * L / 4 + m_p * L / 2) * A
        torque = (
            (L / 2 + t_panel) * m * L * A / 4
            + body.inertia_theta_kg_m2 * A / 2
            + (L + t_panel) * m_p * L * A / 2
        )
        assert force_n == pytest.approx(f, rel=1e-6), payload_g
        assert torque_nm == pytest.approx(torque, rel=1e-6), payload_g


def test_the_predictions_tail_sags_towards_minus_y_without_pressure(bvsr_spec):
    """The predictions' Eq 6-12 model of the whole tail is mounted as the paper's experiments mount
    it: horizontal, dorsal (+Y) up, so gravity is along the tail frame's -Y. From rest, straight,
    with no pressure, it bends towards -Y (theta sin(phi) < 0, started in the +Y plane) by a visible
    sag (more than 0.1 deg per joint), and gravity alone does it: without gravity it stays
    straight."""
    import dataclasses

    from bvsr_cad.analysis.predict import Predictor

    pred = Predictor.from_spec(bvsr_spec)
    model = pred.joint_model(1, bvsr_spec.joints)
    np.testing.assert_allclose(
        model.gravity_m_s2, [0.0, -9.80665, 0.0], rtol=1e-12
    )  # standard gravity, -Y
    tr = dyn.simulate_joint(model, lambda t: np.zeros(5), seconds=0.3, phi0_rad=math.pi / 2)
    v = tr.theta_rad[-1] * math.sin(tr.phi_rad[-1])
    assert v < -math.radians(0.1), math.degrees(v)
    still = dyn.simulate_joint(
        dataclasses.replace(model, gravity_m_s2=np.zeros(3)),
        lambda t: np.zeros(5),
        seconds=0.3,
        phi0_rad=math.pi / 2,
    )
    assert np.abs(still.theta_rad).max() < 1e-9
