"""Writes the robot descriptions of a tail into an export (``robot/``).

- ``robot/bvsr.urdf``: URDF (mimic joints; MuJoCo reads its <mujoco> block);
- ``robot/bvsr_tail.xacro``: the URDF as a xacro macro ``<xacro:bvsr_tail parent xyz rpy/>`` that
  adds the tail to a host's robot description (its meshes: ``robot/meshes/``);
- ``robot/bvsr.xml``: MJCF, reduced chain (two universal joints per bending joint), one actuator
  per SOA;
- ``robot/bvsr_segments.xml``: MJCF, reduced chain, the joints of a segment bend alike, one
  actuator per line;
- ``robot/scene.xml``, ``robot/scene_segments.xml``: menagerie-style scenes that include them;
- ``robot/bvsr_exact.xml``, ``robot/scene_exact.xml``: MJCF with the URDF's exact chain (a 0.2 ms
  step);
- ``robot/bvsr_mount.xml``, ``robot/scene_mount.xml``: MJCF, the mount variant (one universal joint
  per bending joint, the SOAs on fixed tendons): the file ``bvsr mount`` and the quadruped scene
  attach to a host;
- ``robot/scene_cart.xml``: the per-segment tail on the paper's hinged cart (Eq 20-22's
  experiment);
- ``robot/meshes/*.stl``: visual meshes in metres, in their link's frame;
- ``robot/ros2/<name>_description/``: the URDF and meshes as a ROS 2 (ament) package with a
  display launch.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path
from typing import Any

from .. import units
from ..assembly.robot import RobotModel, chord_joint_value
from ..models.kinematics import (
    chain_tip_error_mm,
    joint_transform_chain,
    joint_transform_mount,
    joint_transform_prb,
    mount_order,
)
from .mjcf import cart_scene_tree, mjcf_tree, scene_tree, write_mjcf
from .robot_meshes import write_robot_meshes
from .ros2_package import write_ros2_package
from .urdf import urdf_tree, write_xacro, xacro_name
from .xml import write_tree

#: The export's xacro macro finds its meshes beside it, wherever it is included from.
EXPORT_XACRO_MESH_DIR = "${xacro.abs_filename('meshes')}"


def write_robot(
    robot: RobotModel,
    root: Path,
    progress: Callable[[str], None],
    cart=None,
    mesh_files: dict[str, str] | None = None,
) -> dict[str, Any]:
    """Write the robot model's URDF, MJCF and scenes (with ``cart``, a
    :class:`~bvsr_cad.parameters.tables.CartPlatform`, also ``scene_cart.xml``); returns the
    manifest's ``robot`` section. ``mesh_files``: what :func:`write_robot_meshes` returned where the
    caller has put the meshes in ``robot/meshes`` already (from a build of the same geometry)."""
    folder = root / "robot"
    folder.mkdir(exist_ok=True)  # the fabrication package may have put the rigid twin there
    if mesh_files is None:
        progress("robot meshes")
        mesh_files = write_robot_meshes(robot, folder / "meshes")
    name = robot.name
    urdf = urdf_tree(robot, mesh_files)
    write_tree(urdf, folder / f"{name}.urdf")
    write_xacro(urdf.getroot(), name, folder, EXPORT_XACRO_MESH_DIR)
    progress("ROS 2 description package")
    ros2 = write_ros2_package(folder / f"{name}.urdf", folder / "meshes", folder / "ros2", name)
    facts = _write_mjcf_models(robot, folder, mesh_files)
    error_mm = chain_errors_mm(robot)
    if cart is not None:
        write_mjcf(folder / "scene_cart.xml", cart_scene_tree(robot, mesh_files, cart))
    return {"robot": _robot_section(robot, mesh_files, ros2, facts, error_mm, cart is not None)}


def _write_mjcf_models(
    robot: RobotModel, folder: Path, mesh_files: dict[str, str]
) -> dict[str, dict[str, Any]]:
    """Write the four MJCF models (reduced chain, reduced chain per segment, exact chain, mount
    variant), each with the scene that includes it; returns each model's facts (:func:`mjcf_tree`)
    by file stem."""
    name = robot.name
    facts = {}
    for per_segment, stem, scene, chain in (
        (False, name, "scene.xml", "reduced"),
        (True, f"{name}_segments", "scene_segments.xml", "reduced"),
        (False, f"{name}_exact", "scene_exact.xml", "exact"),
        (False, f"{name}_mount", "scene_mount.xml", "mount"),
    ):
        tree, facts[stem] = mjcf_tree(robot, mesh_files, per_segment, chain=chain)
        write_mjcf(folder / f"{stem}.xml", tree)
        write_mjcf(folder / scene, scene_tree(f"{stem}.xml", stem))
    return facts


def _robot_section(
    robot: RobotModel,
    mesh_files: dict[str, str],
    ros2: dict[str, Any],
    facts: dict[str, dict[str, Any]],
    error_mm: dict[str, float],
    has_cart: bool,
) -> dict[str, Any]:
    """The manifest's ``robot`` section: the files written, each chain's accuracy, the actuation
    and the links."""
    name = robot.name
    act = robot.actuation
    urdf_chord_err = max(
        float(-chord_joint_value(b.theta_max_rad, b.arc_length_m)) for b in robot.bending
    )
    return {
        "urdf": f"robot/{name}.urdf",
        "xacro": f"robot/{xacro_name(name)}.xacro",
        "mjcf": "robot/scene.xml",
        "mjcf_model": f"robot/{name}.xml",
        "ros2_package": {
            "path": f"robot/ros2/{ros2['name']}",
            "urdf": ros2["urdf"],
            "xacro": ros2["xacro"],
            "meshes": ros2["meshes"],
        },
        "mjcf_per_segment": "robot/scene_segments.xml",
        "mjcf_exact": "robot/scene_exact.xml",
        "mjcf_exact_model": f"robot/{name}_exact.xml",
        "mjcf_mount": "robot/scene_mount.xml",
        "mjcf_mount_model": f"robot/{name}_mount.xml",
        "chains": _chain_entries(name, facts, error_mm),
        "mjcf_cart": "robot/scene_cart.xml" if has_cart else None,
        "mjcf_per_segment_model": f"robot/{name}_segments.xml",
        "units": "SI (m, kg, s, rad); actuator control: commanded gauge pressure in Pa (the "
        "chamber "
        "pressure lags it by supply_lag_s)",
        "supply_lag_s": robot.supply_lag_s,
        "mass_kg": robot.mass_kg,
        "virtual_link_mass_kg": sum(l.inertial.mass_kg for l in robot.links.values() if l.virtual),
        "bending_joints": _bending_entries(robot),
        "joint_limits": {
            j.name: {
                "lower": j.lower,
                "upper": j.upper,
                "velocity": j.velocity,
                "effort": j.effort,
            }
            for j in robot.joints
        },
        "urdf_chord_max_error_m": urdf_chord_err,
        "mjcf_chord_polynomial_max_error_m": max(
            f["chord_polynomial_max_error_m"] for f in facts.values()
        ),
        "mjcf_actuators": {stem: f["actuators"] for stem, f in facts.items()},
        "rod_bending_stiffness_nm_rad": act.rod_bending_stiffness_nm_rad,
        "half_angle_hinge_stiffness_nm_rad": 2 * act.rod_bending_stiffness_nm_rad,
        "links": _link_entries(robot, mesh_files),
        "soa_actuators": [
            {"name": s.name, "line": s.line, "rest_length_m": s.rest_length_m} for s in robot.soas
        ],
    }


def _chain_entries(
    name: str, facts: dict[str, dict[str, Any]], error_mm: dict[str, float]
) -> dict[str, dict[str, Any]]:
    """Each model file's chain, its step and its tip's largest distance from Eq 2 over the joint
    range; a reduced chain's bend limit (a polygon of fixed tendons, its largest overshoot past
    theta_max)."""
    return {
        f"robot/{name}.urdf": {"chain": "exact", "tip_error_vs_eq2_mm": error_mm["exact"]},
        **{
            f"robot/{stem}.xml": {
                "chain": f["chain"],
                "timestep_s": f["timestep_s"],
                "tip_error_vs_eq2_mm": error_mm[f["chain"]],
                **({"bend_limit": f["bend_limit"]} if f["bend_limit"] else {}),
            }
            for stem, f in facts.items()
        },
    }


def _bending_entries(robot: RobotModel) -> list[dict[str, Any]]:
    """The manifest's bending joints: each one's arc, the URDF joints that make it, its links and
    how its chord joint's value reads."""
    return [
        {
            "name": b.name,
            "arc_length_m": b.arc_length_m,
            "urdf_joints": list(b.urdf_joints),
            "base_link": b.base_link,
            "tip_link": b.tip_link,
            "theta_max_rad": b.theta_max_rad,
            "segment": b.segment,
            "chord_joint": "value = chord - L (0 at rest); "
            "bvsr_cad.assembly.robot.chord_joint_value(theta, L)",
        }
        for b in robot.bending
    ]


def _link_entries(robot: RobotModel, mesh_files: dict[str, str]) -> list[dict[str, Any]]:
    """The manifest's links: each one's mass, centre of mass, inertia and visual meshes."""
    return [
        {
            "name": link.name,
            "role": link.role,
            "mass_kg": link.inertial.mass_kg,
            "com_m": list(link.inertial.com_m),
            "inertia_kg_m2": link.inertial.inertia.tolist(),
            "visuals": [
                {
                    "mesh": f"robot/meshes/{mesh_files[v.name]}",
                    "material": v.material,
                    "density_g_cm3": v.density_g_cm3,
                }
                for v in link.visuals
            ],
        }
        for link in robot.links.values()
    ]


def chain_errors_mm(robot: RobotModel) -> dict[str, float]:
    """Largest tip distance (mm) from Eq 2 over the joint range of the tail built from each chain
    (:func:`bvsr_cad.models.kinematics.chain_tip_error_mm`); the exact chain's MJCF adds its chord
    polynomial's error (``mjcf_chord_polynomial_max_error_m``)."""
    lengths_mm = [units.m_to_mm(b.arc_length_m) for b in robot.bending]
    thickness_mm = units.m_to_mm(robot.joints[0].T_parent_joint[2][3])
    limits = [b.theta_max_rad for b in robot.bending]
    mount = [
        functools.partial(joint_transform_mount, order=mount_order(k))
        for k in range(1, len(robot.bending) + 1)
    ]
    return {
        chain: chain_tip_error_mm(fn, lengths_mm, thickness_mm, limits)
        for chain, fn in (
            ("reduced", joint_transform_prb),
            ("exact", joint_transform_chain),
            ("mount", mount),
        )
    }
