"""The ROS 2 description package: valid files, self-contained meshes, the URDF unchanged but for
mesh URIs."""

from __future__ import annotations

import ast
import re
import shutil
import subprocess
import sys
import types
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from bvsr_cad.exporters.ros2_package import write_ros2_package

from .conftest import PARAMS

NAME = "bvsr"
PACKAGE = f"{NAME}_description"
PREFIX = f"package://{PACKAGE}/meshes/"


@pytest.fixture(scope="module")
def source(tmp_path_factory) -> Path:
    """An export's ``robot/`` folder: the URDF and its meshes, written by the existing writers."""
    from bvsr_cad.assembly.assemble import build_assembly
    from bvsr_cad.assembly.robot import robot_model
    from bvsr_cad.exporters.robot_meshes import write_robot_meshes
    from bvsr_cad.exporters.urdf import write_urdf
    from bvsr_cad.parameters.load import load_spec

    spec = load_spec(PARAMS / "bvsr.toml")
    robot = robot_model(build_assembly(spec), [0.5] * spec.joints)
    assert robot.name == NAME
    folder = tmp_path_factory.mktemp("exp") / "robot"
    mesh_files = write_robot_meshes(robot, folder / "meshes")
    write_urdf(robot, folder / f"{NAME}.urdf", mesh_files)
    return folder


@pytest.fixture(scope="module")
def written(source) -> tuple[dict, Path]:
    info = write_ros2_package(source / f"{NAME}.urdf", source / "meshes", source / "ros2", NAME)
    return info, Path(info["path"])


def _urdf(pkg: Path) -> ET.Element:
    return ET.parse(pkg / "urdf" / f"{NAME}.urdf").getroot()


def test_manifest_lists_exactly_the_files(written, source):
    info, pkg = written
    assert pkg == source / "ros2" / PACKAGE and pkg.is_dir()
    assert info["name"] == PACKAGE and info["urdf"] == f"urdf/{NAME}.urdf"
    assert info["xacro"] == f"urdf/{NAME}_tail.xacro"
    on_disk = sorted(p.relative_to(pkg).as_posix() for p in pkg.rglob("*") if p.is_file())
    assert info["files"] == on_disk
    assert {
        "package.xml",
        "CMakeLists.txt",
        f"urdf/{NAME}.urdf",
        f"urdf/{NAME}_tail.xacro",
        "launch/display.launch.py",
        "rviz/display.rviz",
        "README.md",
    } <= set(on_disk)
    assert info["meshes"] == len(list((pkg / "meshes").iterdir())) > 0
    # nothing but the package is left in out_dir (no temporary folder)
    assert [p.name for p in (source / "ros2").iterdir()] == [PACKAGE]


def test_package_xml_and_cmake_agree(written):
    _, pkg = written
    root = ET.parse(pkg / "package.xml").getroot()
    assert root.tag == "package" and root.get("format") == "3"
    assert root.findtext("name") == PACKAGE == pkg.name
    assert re.fullmatch(r"\d+\.\d+\.\d+", root.findtext("version"))
    assert root.findtext("license") == "MIT"
    assert "tail" in root.findtext("description")
    assert root.find("maintainer").get("email")
    assert [e.text for e in root.findall("buildtool_depend")] == ["ament_cmake"]
    assert {"robot_state_publisher", "joint_state_publisher_gui", "rviz2"} <= {
        e.text for e in root.findall("exec_depend")
    }
    assert root.findtext("export/build_type") == "ament_cmake"

    cmake = (pkg / "CMakeLists.txt").read_text()
    assert re.search(r"cmake_minimum_required\(VERSION 3\.8\)", cmake)
    assert re.findall(r"^project\((\w+)\)", cmake, re.M) == [PACKAGE]
    assert "find_package(ament_cmake REQUIRED)" in cmake
    install = re.search(
        r"install\(DIRECTORY ([\w ]+) DESTINATION share/\$\{PROJECT_NAME\}\)", cmake
    )
    assert install and set(install.group(1).split()) == {"urdf", "meshes", "launch", "rviz"}
    assert all((pkg / d).is_dir() for d in install.group(1).split())
    assert cmake.rstrip().endswith("ament_package()")


def test_every_mesh_uri_resolves_and_no_mesh_is_extra(written):
    _, pkg = written
    uris = [m.get("filename") for m in _urdf(pkg).iter("mesh")]
    assert uris and all(u.startswith(PREFIX) for u in uris)
    referenced = {u.removeprefix(PREFIX) for u in uris}
    for file in referenced:
        path = pkg / "meshes" / file
        assert path.is_file() and path.resolve().parent == (pkg / "meshes").resolve()
    assert referenced == {p.name for p in (pkg / "meshes").iterdir()}


def test_meshes_are_byte_copies(written, source):
    _, pkg = written
    for path in (pkg / "meshes").iterdir():
        assert path.read_bytes() == (source / "meshes" / path.name).read_bytes()


def _canonical(el: ET.Element, mesh_name) -> tuple:
    attrib = dict(el.attrib)
    if el.tag == "mesh":
        attrib["filename"] = mesh_name(attrib["filename"])
    return (
        el.tag,
        sorted(attrib.items()),
        (el.text or "").strip(),
        [_canonical(c, mesh_name) for c in el],
    )


def test_urdf_unchanged_but_for_mesh_uris(written, source):
    _, pkg = written
    src_text = (source / f"{NAME}.urdf").read_text()
    pkg_text = (pkg / "urdf" / f"{NAME}.urdf").read_text()
    assert pkg_text.startswith("<?xml")  # the declaration is kept
    src, out = ET.fromstring(src_text.encode()), ET.fromstring(pkg_text.encode())
    assert _canonical(src, lambda f: f.removeprefix("meshes/")) == _canonical(
        out, lambda f: f.removeprefix(PREFIX)
    )
    # the same things, spelled out
    for tag in ("link", "joint", "material"):
        assert [e.get("name") for e in src.findall(tag)] == [
            e.get("name") for e in out.findall(tag)
        ]
    assert {
        l.get("name"): float(l.find("inertial/mass").get("value")) for l in src.findall("link")
    } == {l.get("name"): float(l.find("inertial/mass").get("value")) for l in out.findall("link")}
    assert len(list(out.iter("mesh"))) == len(list(src.iter("mesh"))) > 0


def test_launch_file_compiles_and_launches_the_package(written, monkeypatch):
    _, pkg = written
    path = pkg / "launch" / "display.launch.py"
    code = compile(path.read_text(), str(path), "exec")
    tree = ast.parse(path.read_text())
    assert "generate_launch_description" in {
        n.name for n in tree.body if isinstance(n, ast.FunctionDef)
    }

    # Run it against stand-ins of launch, launch_ros and ament_index_python: the share folder of an
    # installed package has the source package's layout, so the package folder stands in for it.
    shares = []

    def get_package_share_directory(name):
        shares.append(name)
        return str(pkg)

    class Node:
        def __init__(self, **kw):
            self.kw = kw

    class LaunchDescription:
        def __init__(self, entities):
            self.entities = entities

    stubs = {
        "ament_index_python": types.ModuleType("ament_index_python"),
        "ament_index_python.packages": types.ModuleType("ament_index_python.packages"),
        "launch": types.ModuleType("launch"),
        "launch_ros": types.ModuleType("launch_ros"),
        "launch_ros.actions": types.ModuleType("launch_ros.actions"),
    }
    stubs["ament_index_python.packages"].get_package_share_directory = get_package_share_directory
    stubs["launch"].LaunchDescription = LaunchDescription
    stubs["launch_ros.actions"].Node = Node
    for mod, stub in stubs.items():
        monkeypatch.setitem(sys.modules, mod, stub)
    namespace: dict = {"__name__": "display_launch", "__file__": str(path)}
    exec(code, namespace)
    ld = namespace["generate_launch_description"]()

    assert shares == [PACKAGE]
    nodes = {n.kw["package"]: n.kw for n in ld.entities}
    assert set(nodes) == {"robot_state_publisher", "joint_state_publisher_gui", "rviz2"}
    [params] = nodes["robot_state_publisher"]["parameters"]
    assert params["robot_description"] == (pkg / "urdf" / f"{NAME}.urdf").read_text()
    args = nodes["rviz2"]["arguments"]
    assert args[0] == "-d" and Path(args[1]) == pkg / "rviz" / "display.rviz"


def test_rviz_config_fixes_the_root_link(written):
    yaml = pytest.importorskip("yaml")
    _, pkg = written
    cfg = yaml.safe_load((pkg / "rviz" / "display.rviz").read_text())
    vm = cfg["Visualization Manager"]
    root = _urdf(pkg)
    children = {c.get("link") for c in root.iterfind("joint/child")}
    roots = [l.get("name") for l in root.findall("link") if l.get("name") not in children]
    assert roots == ["panel0"]
    assert vm["Global Options"]["Fixed Frame"] == "panel0"
    displays = {d["Class"]: d for d in vm["Displays"]}
    assert {"rviz_default_plugins/Grid", "rviz_default_plugins/RobotModel"} <= set(displays)
    model = displays["rviz_default_plugins/RobotModel"]
    assert (
        model["Description Source"] == "Topic"
        and model["Description Topic"]["Value"] == "/robot_description"
    )
    assert all(d["Enabled"] for d in displays.values())


def test_readme_says_how_to_launch(written):
    _, pkg = written
    text = (pkg / "README.md").read_text()
    assert "colcon build" in text and f"ros2 launch {PACKAGE} display.launch.py" in text


def test_check_urdf_accepts_the_package_urdf(written):
    exe = shutil.which("check_urdf")
    if exe is None:
        pytest.skip("check_urdf (Debian liburdfdom-tools) is not installed")
    _, pkg = written
    run = subprocess.run(
        [exe, str(pkg / "urdf" / f"{NAME}.urdf")], capture_output=True, text=True, timeout=60
    )
    assert run.returncode == 0, run.stdout + run.stderr
    assert "root Link: panel0" in run.stdout


def test_a_second_write_replaces_the_package(source, tmp_path):
    out = tmp_path / "ros2"
    first = write_ros2_package(source / f"{NAME}.urdf", source / "meshes", out, NAME)
    pkg = Path(first["path"])
    (pkg / "stale.txt").write_text("left over")
    (pkg / "meshes" / "stale.stl").write_bytes(b"solid")
    second = write_ros2_package(source / f"{NAME}.urdf", source / "meshes", out, NAME)
    assert second == first
    assert not (pkg / "stale.txt").exists() and not (pkg / "meshes" / "stale.stl").exists()
    assert (
        sorted(p.relative_to(pkg).as_posix() for p in pkg.rglob("*") if p.is_file())
        == second["files"]
    )
    assert [p.name for p in out.iterdir()] == [PACKAGE]


def test_a_missing_mesh_raises_and_writes_nothing(source, tmp_path):
    text = (source / f"{NAME}.urdf").read_text()
    assert text.count('filename="meshes/panel0.stl"') >= 1
    broken = tmp_path / "broken.urdf"
    broken.write_text(
        text.replace('filename="meshes/panel0.stl"', 'filename="meshes/missing_panel.stl"', 1)
    )
    out = tmp_path / "ros2"
    with pytest.raises(FileNotFoundError, match=r"missing_panel\.stl") as err:
        write_ros2_package(broken, source / "meshes", out, NAME)
    assert "'panel0'" in str(err.value)  # the link
    assert not out.exists() or list(out.iterdir()) == []

    # over an existing package: the old package is left as it was, and no temporary folder stays
    good = write_ros2_package(source / f"{NAME}.urdf", source / "meshes", out, NAME)
    with pytest.raises(FileNotFoundError, match=r"missing_panel\.stl"):
        write_ros2_package(broken, source / "meshes", out, NAME)
    assert [p.name for p in out.iterdir()] == [PACKAGE]
    pkg = Path(good["path"])
    assert (
        sorted(p.relative_to(pkg).as_posix() for p in pkg.rglob("*") if p.is_file())
        == good["files"]
    )


def test_an_invalid_package_name_is_refused(source, tmp_path):
    with pytest.raises(ValueError, match="package name"):
        write_ros2_package(source / f"{NAME}.urdf", source / "meshes", tmp_path, "BVSR-tail")
    assert list(tmp_path.iterdir()) == []


def test_a_failure_while_writing_leaves_the_old_package_and_no_temporary_folder(
    source, tmp_path, monkeypatch
):
    import bvsr_cad.exporters.ros2_package as mod

    out = tmp_path / "ros2"
    good = write_ros2_package(source / f"{NAME}.urdf", source / "meshes", out, NAME)
    copies = []
    copyfile = shutil.copyfile

    def failing_copy(src, dst):
        copies.append(dst)
        if len(copies) == 3:
            raise OSError("disk full")
        return copyfile(src, dst)

    monkeypatch.setattr(mod.shutil, "copyfile", failing_copy)
    with pytest.raises(OSError, match="disk full"):
        write_ros2_package(source / f"{NAME}.urdf", source / "meshes", out, NAME)
    assert len(copies) == 3 and all(Path(c).parent.parent.name.endswith(".tmp") for c in copies)
    assert [p.name for p in out.iterdir()] == [PACKAGE]
    pkg = Path(good["path"])
    assert (
        sorted(p.relative_to(pkg).as_posix() for p in pkg.rglob("*") if p.is_file())
        == good["files"]
    )


def test_xacro_macro_expands_onto_a_host_and_check_urdf_accepts(written, tmp_path):
    """The package's macro on a host description: the ``xacro`` package expands it, check_urdf
    accepts the robot (the host's link the root, the tail's root link its child through the mount
    joint), the links are the package URDF's with the prefix, and every mesh is a package URI of a
    file the package holds."""
    xacro = pytest.importorskip("xacro")
    exe = shutil.which("check_urdf")
    if exe is None:
        pytest.skip("check_urdf (Debian liburdfdom-tools) is not installed")
    _, pkg = written
    host = tmp_path / "host.urdf.xacro"
    host.write_text(
        '<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="host">'
        f'<xacro:include filename="{pkg / "urdf" / f"{NAME}_tail.xacro"}"/>'
        '<link name="base_link"/>'
        f'<xacro:{NAME}_tail parent="base_link" xyz="-0.24 0 0" rpy="1.5708 0 -1.5708" '
        'prefix="rear_"/></robot>'
    )
    out = tmp_path / "host.urdf"
    out.write_text(xacro.process_file(str(host)).toprettyxml(indent="  "))
    run = subprocess.run([exe, str(out)], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stdout + run.stderr
    assert (
        "root Link: base_link has 1 child(ren)" in run.stdout
        and "child(1):  rear_panel0" in run.stdout
    )
    robot = ET.parse(out).getroot()
    links = {l.get("name") for l in robot.findall("link")}
    assert links == {"base_link"} | {f"rear_{l.get('name')}" for l in _urdf(pkg).findall("link")}
    mount = robot.find(f"joint[@name='rear_{NAME}_mount']")
    assert mount.find("origin").attrib == {"xyz": "-0.24 0 0", "rpy": "1.5708 0 -1.5708"}
    meshes = [m.get("filename") for m in robot.iter("mesh")]
    assert meshes and all(m.startswith(PREFIX) for m in meshes)
    assert all((pkg / "meshes" / m[len(PREFIX) :]).is_file() for m in meshes)
