"""The tip payload in ``bvsr simulate``: the model the command runs carries it as a point mass on
the tip, its share of the root wrench checked by hand under a known angular acceleration (the Eq
6-12 model's payload is pinned in ``tests/test_models_dynamics.py``)."""

from __future__ import annotations

import functools
import json

import mujoco
import numpy as np
import pytest

from .conftest import PARAMS

THETA_MAX = 0.5  # a fixed joint limit: the payload test does not depend on the clearance analysis


def test_simulate_carries_the_payload_as_a_point_mass(tmp_path, capsys, monkeypatch, bvsr_data):
    """``bvsr simulate --payload-g 100``: the tail model it runs holds a 100 g body on the tip, and
    that body's share of the root sensor's force and torque is a point mass's under a known angular
    acceleration.

    The model is the one the command's run compiled (captured as it is written). At rest, without
    gravity, one hinge at a time is given an angular acceleration alpha about its axis e through its
    anchor a (read from MuJoCo), every other joint none: the payload (the simulator's 20 mm sphere
    resting on the tip face, its centre 10 mm beyond it) moves at alpha e x (r - a), so by hand it
    adds F = m alpha e x (r - a) to the root force and (r - r_root) x F + I alpha e to the root
    torque (I = 0.4 m (10 mm)^2, a solid sphere), expressed in the root site's frame (the tail's).
    The share is the model's wrench less the same model with the payload's mass and inertia set to
    zero; relative 1e-9: rounding only."""
    import bvsr_cad.simulation.sim as sim
    from bvsr_cad.cli import main

    compiled = []
    real_model_xml = sim._model_xml

    def capture(spec, theta_max_rad, folder, payload_g):
        path, lines = real_model_xml(spec, theta_max_rad, folder, payload_g)
        compiled.append((spec.segments, mujoco.MjModel.from_xml_path(str(path))))
        return path, lines

    monkeypatch.setattr(sim, "_model_xml", capture)
    # What the payload does not enter is left out, to keep the run short: the clearance analysis
    # (fixed limits), the standalone segment's run (no payload) and the collision shapes (mass-less
    # geoms).
    monkeypatch.setattr(sim, "joint_limits_rad", lambda spec, *a, **k: [THETA_MAX] * spec.joints)
    monkeypatch.setattr(
        sim, "segment_extension", lambda *a, **k: (np.zeros(2), np.zeros(2), np.zeros(2), 0.0)
    )
    monkeypatch.setattr(sim, "robot_model", functools.partial(sim.robot_model, collisions=False))
    assert (
        main(
            [
                "simulate",
                str(PARAMS / "bvsr.toml"),
                "--payload-g",
                "100",
                "--supply",
                "ramp",
                "--json",
                "-o",
                str(tmp_path),
            ]
        )
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert out["payload_g"] == 100
    tails = [m for segments, m in compiled if segments == bvsr_data["segments"]]
    assert len(tails) == 1, "the whole tail's model is compiled once per run"
    m = tails[0]
    d = mujoco.MjData(m)
    payload = m.body("payload").id
    mass_kg, r_sphere_m = 0.1, 0.010
    assert m.body_mass[payload] == pytest.approx(mass_kg, rel=1e-12)
    m.opt.gravity[:] = 0.0
    mujoco.mj_forward(m, d)
    site = m.site("root_ft").id
    rot = d.site_xmat[site].reshape(3, 3)  # columns: the site's (the tail's) axes in the world
    r_root = d.site_xpos[site].copy()
    r_payload = d.xipos[payload].copy()
    # The sphere's centre on the tail's axis, 10 mm beyond the tip face: n H_a + (n + 1) t from the
    # root face.
    j, n = bvsr_data["joint"], bvsr_data["segments"] * bvsr_data["joints_per_segment"]
    tail_length_mm = n * j["gap_mm"] + (n + 1) * (j["joint_height_mm"] - j["gap_mm"])
    np.testing.assert_allclose(
        rot.T @ (r_payload - r_root), [0, 0, (tail_length_mm + 10.0) / 1e3], atol=1e-9
    )

    def root_wrench(hinge: int, alpha: float):
        d.qvel[:] = 0.0
        d.qacc[:] = 0.0
        d.qacc[m.jnt_dofadr[hinge]] = alpha
        mujoco.mj_inverse(m, d)
        return d.sensor("root_force").data.copy(), d.sensor("root_torque").data.copy()

    alpha = 10.0
    hinges = [i for i in range(m.njnt) if m.jnt_type[i] == mujoco.mjtJoint.mjJNT_HINGE][
        :2
    ]  # two axes
    assert len(hinges) == 2
    with_payload = [root_wrench(h, alpha) for h in hinges]
    m.body_mass[payload] = 0.0
    m.body_inertia[payload] = 0.0
    without = [root_wrench(h, alpha) for h in hinges]
    i_sphere = 0.4 * mass_kg * r_sphere_m**2
    for h, (f1, t1), (f0, t0) in zip(hinges, with_payload, without):
        e, a = d.xaxis[h], d.xanchor[h]
        force = mass_kg * alpha * np.cross(e, r_payload - a)
        torque = np.cross(r_payload - r_root, force) + i_sphere * alpha * e
        assert (
            np.linalg.norm(force) > 0.1 * mass_kg * alpha
        )  # the payload is well off the hinge's axis
        np.testing.assert_allclose(f1 - f0, rot.T @ force, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(t1 - t0, rot.T @ torque, rtol=1e-9, atol=1e-12)
