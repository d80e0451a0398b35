"""URDF writer (element tree, SI units) for the robot model.

Mimic joints couple each bending joint's second half-angle to the first (x1)
and the counter-rotation to phi (x-1). The chord joint mimics ``jk_theta_a``
with multiplier 0: it stays at the rest chord L in tools that enforce mimic
(MuJoCo turns mimic into equality constraints, so nothing slides), an error of
L - chord(theta) = L theta^2 / 24 + O(theta^4) at most at the joint limit
(reported in the manifest). Kinematic users who want the exact arc set it
with :func:`bvsr_cad.assembly.robot.chord_joint_value`.

The collision shapes are for contacts with the world. Neighbouring panels' halves of an SOA or rod
column meet (and overlap by the column's tilt) at mid-gap in every pose; URDF cannot exclude a pair
of links, and MuJoCo's import collides every two links but a parent and its child (pybullet and
Gazebo leave self-collision off unless asked). In MuJoCo use the MJCF, which turns the tail's
self-contacts off, or set the imported geoms' ``conaffinity`` to 0 as ``bvsr check`` does.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from ..assembly.robot import RobotModel
from .mjcf import collision_mesh_name
from .xml import num as _f
from .xml import origin_attrs, write_tree
from .xml import vec as _vec


def mujoco_compiler(robot_el: ET.Element) -> None:
    """The URDF's ``<mujoco>`` block: MuJoCo keeps the inertias, visuals, bodies and mesh paths as
    written."""
    ET.SubElement(
        ET.SubElement(robot_el, "mujoco"),
        "compiler",
        balanceinertia="false",
        discardvisual="false",
        fusestatic="false",
        strippath="false",
    )


def inertial_element(link_el: ET.Element, inertial) -> None:
    """A link's ``<inertial>``: centre of mass, mass and inertia about the centre of mass (SI)."""
    el = ET.SubElement(link_el, "inertial")
    ET.SubElement(el, "origin", xyz=_vec(inertial.com), rpy="0 0 0")
    ET.SubElement(el, "mass", value=_f(inertial.mass_kg))
    I = inertial.inertia
    ET.SubElement(
        el,
        "inertia",
        ixx=_f(I[0, 0]),
        ixy=_f(I[0, 1]),
        ixz=_f(I[0, 2]),
        iyy=_f(I[1, 1]),
        iyz=_f(I[1, 2]),
        izz=_f(I[2, 2]),
    )


def urdf_tree(
    robot: RobotModel, mesh_files: dict[str, str], mesh_prefix: str = "meshes/"
) -> ET.ElementTree:
    root = ET.Element("robot", name=robot.name)
    mujoco_compiler(root)
    materials = {}
    for link in robot.links.values():
        for vis in link.visuals:
            materials.setdefault(vis.material, vis.rgba)
    for name, rgba in materials.items():
        m = ET.SubElement(root, "material", name=name)
        ET.SubElement(m, "color", rgba=_vec(rgba))
    for link in robot.links.values():
        el = ET.SubElement(root, "link", name=link.name)
        inertial_element(el, link.inertial)
        for vis in link.visuals:
            v = ET.SubElement(el, "visual", name=vis.name)
            ET.SubElement(v, "origin", xyz="0 0 0", rpy="0 0 0")
            g = ET.SubElement(v, "geometry")
            ET.SubElement(g, "mesh", filename=mesh_prefix + mesh_files[vis.name])
            ET.SubElement(v, "material", name=vis.material)
        for col in link.collisions:
            c = ET.SubElement(el, "collision", name=f"{col.name}_collision")
            ET.SubElement(c, "origin", **origin_attrs(col.T_link_geom))
            g = ET.SubElement(c, "geometry")
            if col.kind == "mesh":
                ET.SubElement(
                    g, "mesh", filename=mesh_prefix + mesh_files[collision_mesh_name(col)]
                )
            else:
                ET.SubElement(g, "cylinder", radius=_f(col.radius_m), length=_f(col.length_m))
    for j in robot.joints:
        el = ET.SubElement(root, "joint", name=j.name, type=j.type)
        ET.SubElement(el, "origin", **origin_attrs(j.T_parent_joint))
        ET.SubElement(el, "parent", link=j.parent)
        ET.SubElement(el, "child", link=j.child)
        ET.SubElement(el, "axis", xyz=_vec(j.axis))
        lim = {"effort": _f(j.effort or 0.0), "velocity": _f(j.velocity or 0.0)}
        if j.type != "continuous":
            lim.update(lower=_f(j.lower), upper=_f(j.upper))
        ET.SubElement(el, "limit", **lim)
        if j.damping:
            ET.SubElement(el, "dynamics", damping=_f(j.damping))
        if j.mimic is not None:
            ET.SubElement(
                el,
                "mimic",
                joint=j.mimic.joint,
                multiplier=_f(j.mimic.multiplier),
                offset=_f(j.mimic.offset),
            )
    ET.indent(root)
    return ET.ElementTree(root)


def write_urdf(
    robot: RobotModel, path: Path, mesh_files: dict[str, str], mesh_prefix: str = "meshes/"
) -> None:
    write_tree(urdf_tree(robot, mesh_files, mesh_prefix), path)


#: The xacro namespace of a macro file.
XACRO_NS = "http://www.ros.org/wiki/xacro"


def xacro_name(robot_name: str) -> str:
    """The macro's name (and its file's stem): ``bvsr`` -> ``bvsr_tail``."""
    return f"{robot_name}_tail"


def xacro_tree(urdf: ET.Element, robot_name: str, mesh_dir: str) -> ET.ElementTree:
    """The tail's URDF as a xacro macro a host's robot description calls to add the tail::

        <xacro:include filename="bvsr_tail.xacro"/>
        <xacro:bvsr_tail parent="base_link" xyz="-0.24 0 0" rpy="1.5708 0 -1.5708"/>

    A fixed joint ``${prefix}<name>_mount`` puts the tail's root link (its frame is the mount
    frame: the root panel's robot face, Z along the tail) at ``xyz`` (m) and fixed-axis ``rpy``
    (rad) in ``parent``; every link, joint and material name of the URDF gets ``prefix`` (default
    none), every mesh is ``${mesh_dir}/<file>``. The URDF's ``<mujoco>`` block stays out: it is
    the host's to give.

    Args:
        urdf: the tail's URDF (:func:`urdf_tree`'s root, or a file's).
        robot_name: the tail's name; the macro is :func:`xacro_name` of it.
        mesh_dir: the default of the macro's ``mesh_dir`` (evaluated where the file is included:
            ``${xacro.abs_filename('meshes')}`` is the ``meshes`` folder beside it).

    Returns:
        The macro file's tree.
    """
    import copy

    ET.register_namespace("xacro", XACRO_NS)
    x = f"{{{XACRO_NS}}}"
    macro = xacro_name(robot_name)
    children = {c.get("link") for c in urdf.iterfind("joint/child")}
    root_link = next(l.get("name") for l in urdf.findall("link") if l.get("name") not in children)
    out = ET.Element("robot", name=macro)
    default = f"{macro}_mesh_dir"
    ET.SubElement(out, x + "property", name=default, value=mesh_dir, lazy_eval="false")
    body = ET.SubElement(
        out,
        x + "macro",
        name=macro,
        params=f"parent xyz:='0 0 0' rpy:='0 0 0' prefix:='' mesh_dir:=${{{default}}}",
    )
    joint = ET.SubElement(body, "joint", name=f"${{prefix}}{robot_name}_mount", type="fixed")
    ET.SubElement(joint, "parent", link="${parent}")
    ET.SubElement(joint, "child", link=f"${{prefix}}{root_link}")
    ET.SubElement(joint, "origin", xyz="${xyz}", rpy="${rpy}")
    for el in urdf:
        if el.tag in ("link", "joint", "material"):
            body.append(_prefixed(copy.deepcopy(el)))
    ET.indent(out)
    return ET.ElementTree(out)


def _prefixed(el: ET.Element) -> ET.Element:
    """A URDF link, joint or material with ``${prefix}`` on every name it gives or refers to and
    ``${mesh_dir}`` before every mesh file's name."""
    for sub in el.iter():
        if (sub is el and sub.tag in ("link", "joint")) or sub.tag == "material":
            sub.set("name", "${prefix}" + sub.get("name"))
        elif sub.tag in ("parent", "child"):
            sub.set("link", "${prefix}" + sub.get("link"))
        elif sub.tag == "mimic":
            sub.set("joint", "${prefix}" + sub.get("joint"))
        elif sub.tag == "mesh":
            sub.set("filename", "${mesh_dir}/" + sub.get("filename").rsplit("/", 1)[-1])
    return el


def write_xacro(urdf: ET.Element, robot_name: str, folder: Path, mesh_dir: str) -> str:
    """Write :func:`xacro_tree` as ``folder/<macro>.xacro``; returns the file's name."""
    name = f"{xacro_name(robot_name)}.xacro"
    write_tree(xacro_tree(urdf, robot_name, mesh_dir), folder / name)
    return name
