"""A ROS 2 (ament_cmake) description package of a tail, next to its URDF.

:func:`write_ros2_package` turns the export's URDF (``robot/<name>.urdf``, meshes in
``robot/meshes/`` named by relative paths) into a self-contained package
``<out_dir>/<name>_description/``::

    package.xml                 format 3, ament_cmake, exec_depends of the launch file
    CMakeLists.txt              installs urdf/ meshes/ launch/ rviz/ into share/<name>_description
    urdf/<name>.urdf            the URDF, every mesh as package://<name>_description/meshes/<file>
    urdf/<name>_tail.xacro      the URDF as the macro <xacro:<name>_tail parent xyz rpy/> for a
                                host's description (exporters/urdf.py: xacro_tree)
    meshes/                     exactly the meshes the URDF references
    launch/display.launch.py    robot_state_publisher + joint_state_publisher_gui + rviz2
    rviz/display.rviz           Grid and RobotModel (/robot_description), fixed frame: root link
    README.md

Use it by copying (or symlinking) the folder into a colcon workspace's ``src/``::

    colcon build --packages-select <name>_description && source install/setup.bash
    ros2 launch <name>_description display.launch.py

The package is written into a temporary sibling folder and renamed into place,
so a failure never leaves a half-written package, and a second write replaces
the previous package whole. Units are those of the URDF (SI: m, kg, s, rad).
"""

from __future__ import annotations

import json
import re
import shutil
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path, PurePosixPath
from typing import Any

from .. import __version__
from .urdf import write_xacro, xacro_name

#: REP 144: a package name is lower case letters, digits and underscores, starting with a letter.
_PACKAGE_NAME = re.compile(r"^[a-z][a-z0-9_]*$")
_VERSION = re.compile(r"^\d+\.\d+\.\d+$")
#: package.xml format 3 needs a maintainer with an e-mail address; the generator stands in for one.
_MAINTAINER = "bvsr_cad generator"
_MAINTAINER_EMAIL = "bvsr-cad@example.invalid"
#: Initial RViz orbit distance, about twice the length of the default tail.
_VIEW_DISTANCE_M = 0.6


def write_ros2_package(urdf_file: Path, mesh_dir: Path, out_dir: Path, name: str) -> dict[str, Any]:
    """Write the ROS 2 description package ``out_dir/<name>_description/``.

    Args:
        urdf_file: an existing URDF whose ``<mesh filename>`` are relative paths
            (``meshes/panel0.stl``); a mesh is looked up in ``mesh_dir`` by its file name.
        mesh_dir: the folder holding the mesh files.
        out_dir: the folder that receives the package (created if missing).
        name: the robot name; the package is ``<name>_description`` and its URDF
            ``urdf/<name>.urdf``.

    Returns:
        A manifest fragment: ``name``, ``path`` (the package folder), ``urdf`` (relative to the
        package), ``meshes`` (how many) and ``files`` (every file, relative to the package, sorted).

    Raises:
        ValueError: ``name`` is not a valid ROS package name, or the URDF has no single root link,
            or two different mesh paths share a file name.
        FileNotFoundError: a mesh the URDF references is missing from ``mesh_dir`` (the message
            names the link and the file).
    """
    urdf_file, mesh_dir, out_dir = Path(urdf_file), Path(mesh_dir), Path(out_dir)
    package = f"{name}_description"
    if not _PACKAGE_NAME.match(package):
        raise ValueError(
            f"{package!r} is not a valid ROS package name (lower case letters, digits, '_')"
        )

    # Read and check everything before creating anything.
    tree = _parse_keeping_comments(urdf_file)
    root_link = _root_link(tree.getroot(), urdf_file)
    meshes = _rewrite_meshes(tree.getroot(), mesh_dir, package, urdf_file)

    out_dir.mkdir(parents=True, exist_ok=True)
    package_dir = out_dir / package
    tmp = Path(tempfile.mkdtemp(prefix=f".{package}.", suffix=".tmp", dir=out_dir))
    try:
        _write_contents(tmp, tree, meshes, package, name, root_link)
        files = sorted(p.relative_to(tmp).as_posix() for p in tmp.rglob("*") if p.is_file())
        _replace_dir(tmp, package_dir)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return {
        "name": package,
        "path": str(package_dir),
        "urdf": f"urdf/{name}.urdf",
        "xacro": f"urdf/{xacro_name(name)}.xacro",
        "meshes": len(meshes),
        "files": files,
    }


def _parse_keeping_comments(path: Path) -> ET.ElementTree:
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    return ET.parse(path, parser)


def _root_link(robot: ET.Element, urdf_file: Path) -> str:
    """The URDF's root: the one link that is no joint's child."""
    links = [l.get("name") for l in robot.findall("link")]
    children = {c.get("link") for c in robot.iterfind("joint/child")}
    roots = [l for l in links if l not in children]
    if len(roots) != 1:
        raise ValueError(f"{urdf_file}: expected one root link (no joint's child), found {roots}")
    return str(roots[0])


def _rewrite_meshes(
    robot: ET.Element, mesh_dir: Path, package: str, urdf_file: Path
) -> dict[str, Path]:
    """Point every ``<mesh filename>`` at ``package://<package>/meshes/<file>``; returns file ->
    source."""
    meshes: dict[str, Path] = {}
    origin: dict[str, str] = {}
    for link in robot.iter("link"):
        for mesh in link.iter("mesh"):
            ref = mesh.get("filename", "")
            file = PurePosixPath(
                ref.split("://", 1)[-1]
            ).name  # also accepts package:// and file:// URIs
            if not file:
                raise ValueError(
                    f"{urdf_file}: link {link.get('name')!r} has a mesh without a filename"
                )
            if file in origin and origin[file] != ref:
                raise ValueError(
                    f"{urdf_file}: meshes {origin[file]!r} and {ref!r} share the file name {file!r}"
                )
            source = mesh_dir / file
            if not source.is_file():
                raise FileNotFoundError(
                    f"{urdf_file}: link {link.get('name')!r} references mesh {ref!r}, "
                    f"but {file!r} is not in {mesh_dir}"
                )
            origin[file] = ref
            meshes[file] = source
            mesh.set("filename", f"package://{package}/meshes/{file}")
    return meshes


def _write_contents(
    folder: Path,
    tree: ET.ElementTree,
    meshes: dict[str, Path],
    package: str,
    name: str,
    root_link: str,
) -> None:
    for sub in ("urdf", "meshes", "launch", "rviz"):
        (folder / sub).mkdir()
    tree.write(folder / "urdf" / f"{name}.urdf", encoding="utf-8", xml_declaration=True)
    write_xacro(tree.getroot(), name, folder / "urdf", f"package://{package}/meshes")
    for file, source in meshes.items():
        shutil.copyfile(source, folder / "meshes" / file)
    (folder / "package.xml").write_text(_package_xml(package, name), encoding="utf-8")
    (folder / "CMakeLists.txt").write_text(_cmakelists(package), encoding="utf-8")
    (folder / "launch" / "display.launch.py").write_text(
        _launch_py(package, name), encoding="utf-8"
    )
    (folder / "rviz" / "display.rviz").write_text(_rviz(root_link), encoding="utf-8")
    (folder / "README.md").write_text(_readme(package, name), encoding="utf-8")


def _replace_dir(new: Path, target: Path) -> None:
    """Rename ``new`` to ``target``; an existing ``target`` is renamed away first and deleted
    last."""
    if not target.exists():
        new.rename(target)
        return
    old = Path(tempfile.mkdtemp(prefix=f".{target.name}.", suffix=".old", dir=target.parent))
    old.rmdir()
    target.rename(old)
    try:
        new.rename(target)
    except BaseException:
        old.rename(target)
        raise
    shutil.rmtree(old, ignore_errors=True)


def _package_xml(package: str, name: str) -> str:
    version = __version__ if _VERSION.match(__version__) else "0.1.0"
    root = ET.Element("package", format="3")
    ET.SubElement(root, "name").text = package
    ET.SubElement(root, "version").text = version
    ET.SubElement(root, "description").text = (
        f"URDF description of the {name} Biomimetic Vertebraic Soft Robotic (BVSR) tail: meshes, "
        "an RViz configuration and a display launch file. Generated by bvsr_cad."
    )
    ET.SubElement(root, "maintainer", email=_MAINTAINER_EMAIL).text = _MAINTAINER
    ET.SubElement(root, "license").text = "MIT"
    ET.SubElement(root, "buildtool_depend").text = "ament_cmake"
    for dep in (
        "ament_index_python",
        "launch",
        "launch_ros",
        "robot_state_publisher",
        "joint_state_publisher_gui",
        "rviz2",
    ):
        ET.SubElement(root, "exec_depend").text = dep
    ET.SubElement(ET.SubElement(root, "export"), "build_type").text = "ament_cmake"
    ET.indent(root)
    schema = (
        '<?xml-model href="http://download.ros.org/schema/package_format3.xsd" '
        'schematypens="http://www.w3.org/2001/XMLSchema"?>\n'
    )
    return '<?xml version="1.0"?>\n' + schema + ET.tostring(root, encoding="unicode") + "\n"


def _cmakelists(package: str) -> str:
    return f"""cmake_minimum_required(VERSION 3.8)
project({package})

find_package(ament_cmake REQUIRED)

install(DIRECTORY urdf meshes launch rviz DESTINATION share/${{PROJECT_NAME}})

ament_package()
"""


def _launch_py(package: str, name: str) -> str:
    return f'''"""Show the {name} tail in RViz 2 with a joint slider GUI (generated by bvsr_cad)."""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch_ros.actions import Node

PACKAGE = {package!r}
URDF = {f"{name}.urdf"!r}


def generate_launch_description():
    share = get_package_share_directory(PACKAGE)
    with open(os.path.join(share, "urdf", URDF), encoding="utf-8") as f:
        robot_description = f.read()
    return LaunchDescription([
        Node(
            package="robot_state_publisher",
            executable="robot_state_publisher",
            output="screen",
            parameters=[{{"robot_description": robot_description}}],
        ),
        Node(
            package="joint_state_publisher_gui",
            executable="joint_state_publisher_gui",
        ),
        Node(
            package="rviz2",
            executable="rviz2",
            output="screen",
            arguments=["-d", os.path.join(share, "rviz", "display.rviz")],
        ),
    ])
'''


#: The RViz 2 configuration: a grid and the robot model from ``/robot_description``, seen from an
#: orbit ``{distance_m}`` away, in the fixed frame ``{frame}`` (a YAML scalar).
_RVIZ_CONFIG = """Panels:
  - Class: rviz_common/Displays
    Name: Displays
  - Class: rviz_common/Views
    Name: Views
Visualization Manager:
  Class: ""
  Displays:
    - Alpha: 0.5
      Cell Size: 0.05
      Class: rviz_default_plugins/Grid
      Color: 160; 160; 164
      Enabled: true
      Line Style:
        Line Width: 0.03
        Value: Lines
      Name: Grid
      Normal Cell Count: 0
      Offset:
        X: 0
        Y: 0
        Z: 0
      Plane: XY
      Plane Cell Count: 20
      Reference Frame: <Fixed Frame>
      Value: true
    - Alpha: 1
      Class: rviz_default_plugins/RobotModel
      Collision Enabled: false
      Description File: ""
      Description Source: Topic
      Description Topic:
        Depth: 5
        Durability Policy: Transient Local
        History Policy: Keep Last
        Reliability Policy: Reliable
        Value: /robot_description
      Enabled: true
      Name: RobotModel
      TF Prefix: ""
      Update Interval: 0
      Value: true
      Visual Enabled: true
  Enabled: true
  Global Options:
    Background Color: 48; 48; 48
    Fixed Frame: {frame}
    Frame Rate: 30
  Name: root
  Tools:
    - Class: rviz_default_plugins/Interact
      Hide Inactive Objects: true
    - Class: rviz_default_plugins/MoveCamera
    - Class: rviz_default_plugins/Select
  Value: true
  Views:
    Current:
      Class: rviz_default_plugins/Orbit
      Distance: {distance_m}
      Enable Stereo Rendering:
        Stereo Eye Separation: 0.06
        Stereo Focal Distance: 1
        Swap Stereo Eyes: false
        Value: false
      Focal Point:
        X: 0
        Y: 0
        Z: 0
      Focal Shape Fixed Size: true
      Focal Shape Size: 0.05
      Invert Z Axis: false
      Name: Current View
      Near Clip Distance: 0.01
      Pitch: 0.5
      Target Frame: <Fixed Frame>
      Value: Orbit (rviz_default_plugins)
      Yaw: 0.8
    Saved: ~
Window Geometry:
  Height: 800
  Width: 1200
"""


def _rviz(root_link: str) -> str:
    frame = json.dumps(root_link)  # a JSON string is a YAML double-quoted scalar
    return _RVIZ_CONFIG.format(frame=frame, distance_m=_VIEW_DISTANCE_M)


def _readme(package: str, name: str) -> str:
    return f"""# {package}

ROS 2 description package of the {name} BVSR tail, generated by bvsr_cad: `urdf/{name}.urdf`
(SI units, mimic joints), its meshes, an RViz 2 configuration and a display launch file.

Copy (or symlink) this folder into the `src/` of a colcon workspace, then:

```sh
colcon build --packages-select {package}
source install/setup.bash
ros2 launch {package} display.launch.py
```

RViz shows the tail with `robot_state_publisher`; move the joints with the \
`joint_state_publisher_gui`
sliders (mimic joints follow their leaders). Regenerate the package with bvsr_cad rather than \
editing it.

To add the tail to a robot's description, include its macro and call it with the host link and \
the pose of the tail's mount frame (the centre of the root panel's robot face, Z along the tail; \
`xyz` in m, `rpy` in rad; `prefix` goes before every tail name):

```xml
<xacro:include filename="$(find {package})/urdf/{name}_tail.xacro"/>
<xacro:{name}_tail parent="base_link" xyz="-0.24 0 0" rpy="1.5708 0 -1.5708" prefix=""/>
```
"""
