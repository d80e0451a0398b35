"""Writes the robot descriptions of a tail into an export (``robot/``).

``robot/bvsr.urdf``            URDF (mimic joints; MuJoCo reads its <mujoco> block)
``robot/bvsr.xml``             MJCF, one bending joint per joint, one actuator per SOA
``robot/bvsr_segments.xml``    MJCF, the joints of a segment share theta and phi, one actuator per line
``robot/scene.xml``, ``robot/scene_segments.xml``   menagerie-style scenes that include them
``robot/meshes/*.stl``         visual meshes in metres, in their link's frame
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .. import units
from ..assembly.build import Assembly
from ..assembly.robot import RobotModel, build_robot, chord_joint_value, velocity_limit_rad_s
from .mjcf import ActuationSI, mjcf_tree, scene_tree, write_mjcf
from .robot_meshes import write_robot_meshes
from .urdf import write_urdf


def actuation_si(asm: Assembly) -> ActuationSI:
    spec = asm.spec
    act = spec.actuation
    rod_mat = spec.material(spec.vertebra.material)
    d_m = units.mm_to_m(spec.vertebra.diameter_mm)
    L = units.mm_to_m(spec.joint.gap_mm)
    E = rod_mat.youngs_modulus_mpa * units.PA_PER_MPA
    return ActuationSI(
        area_m2=act.effective_area_mm2 / units.MM_PER_M ** 2,
        stiffness_slope_n_m_per_pa=act.stiffness_slope_n_per_m_per_kpa / units.PA_PER_KPA,
        stiffness_offset_n_m=act.stiffness_offset_n_per_m,
        damping_n_s_m=act.damping_n_s_per_m,
        pressure_min_pa=act.pressure_min_kpa * units.PA_PER_KPA,
        pressure_max_pa=spec.robot.pulse_pressure_max_kpa * units.PA_PER_KPA,
        rod_bending_stiffness_nm_rad=E * math.pi * d_m ** 4 / 64 / L,
        rod_axial_stiffness_n_m=E * math.pi * d_m ** 2 / 4 / L,
        timestep_s=spec.robot.timestep_s,
    )


def robot_for(asm: Assembly, theta_max_rad: list[float]) -> RobotModel:
    spec = asm.spec
    act = actuation_si(asm)
    r_pitch_m = units.mm_to_m(spec.joint.pitch_diameter_mm / 2)
    # Largest torque the five SOAs can put on a joint: all pushing on one side at the pulse pressure.
    effort_nm = 5 * act.pressure_max_pa * act.area_m2 * r_pitch_m
    v = velocity_limit_rad_s(spec.robot.segment_velocity_deg_s, spec.robot.velocity_margin, spec.joints_per_segment)
    return build_robot(asm, theta_max_rad, v, effort_nm, 5 * act.pressure_max_pa * act.area_m2)


def write_robot(asm: Assembly, root: Path, theta_max_rad: list[float],
                progress: Callable[[str], None]) -> dict[str, Any]:
    """Write URDF, MJCF and scenes; returns the manifest's ``robot`` section."""
    progress("robot model (B-rep inertials)")
    robot = robot_for(asm, theta_max_rad)
    folder = root / "robot"
    folder.mkdir(exist_ok=True)  # the fabrication package may have put the rigid twin there
    progress("robot meshes")
    mesh_files = write_robot_meshes(robot, folder / "meshes")
    name = asm.spec.name
    write_urdf(robot, folder / f"{name}.urdf", mesh_files)
    act = actuation_si(asm)
    facts = {}
    for per_segment, stem, scene in ((False, name, "scene.xml"), (True, f"{name}_segments", "scene_segments.xml")):
        tree, facts[stem] = mjcf_tree(robot, mesh_files, act, per_segment)
        write_mjcf(folder / f"{stem}.xml", tree)
        write_mjcf(folder / scene, scene_tree(f"{stem}.xml", stem))
    L = units.mm_to_m(asm.spec.joint.gap_mm)
    urdf_chord_err = max(float(-chord_joint_value(th, L)) for th in theta_max_rad)
    links = []
    for link in robot.links.values():
        I = link.inertial.inertia
        links.append({
            "name": link.name, "role": link.role, "mass_kg": link.inertial.mass_kg,
            "com_m": list(link.inertial.com_m), "inertia_kg_m2": I.tolist(),
            "visuals": [{"mesh": f"robot/meshes/{mesh_files[v.name]}", "material": v.material,
                         "density_g_cm3": v.density_g_cm3} for v in link.visuals],
        })
    return {"robot": {
        "urdf": f"robot/{name}.urdf", "mjcf": "robot/scene.xml", "mjcf_model": f"robot/{name}.xml",
        "mjcf_per_segment": "robot/scene_segments.xml", "mjcf_per_segment_model": f"robot/{name}_segments.xml",
        "units": "SI (m, kg, s, rad); actuator control: gauge pressure in Pa",
        "mass_kg": robot.mass_kg,
        "virtual_link_mass_kg": sum(l.inertial.mass_kg for l in robot.links.values() if l.virtual),
        "bending_joints": [{"name": b.name, "arc_length_m": b.arc_length_m, "urdf_joints": list(b.urdf_joints),
                            "base_link": b.base_link, "tip_link": b.tip_link, "theta_max_rad": b.theta_max_rad,
                            "segment": b.segment, "chord_joint": "value = chord - L (0 at rest); "
                            "bvsr_cad.assembly.robot.chord_joint_value(theta, L)"} for b in robot.bending],
        "joint_limits": {j.name: {"lower": j.lower, "upper": j.upper, "velocity": j.velocity, "effort": j.effort}
                         for j in robot.joints},
        "urdf_chord_max_error_m": urdf_chord_err,
        "mjcf_chord_polynomial_max_error_m": max(f["chord_polynomial_max_error_m"] for f in facts.values()),
        "mjcf_actuators": {stem: f["actuators"] for stem, f in facts.items()},
        "rod_bending_stiffness_nm_rad": act.rod_bending_stiffness_nm_rad,
        "half_angle_hinge_stiffness_nm_rad": 2 * act.rod_bending_stiffness_nm_rad,
        "links": links,
        "soa_actuators": [{"name": s.name, "line": s.line, "rest_length_m": s.rest_length_m} for s in robot.soas],
    }}


def theta_max_from_limits(limits: dict, joints: int) -> list[float]:
    """Minimum over phi of theta_max for each joint, from ``analysis/limits.json``."""
    by_name = {entry["joint"]: entry for entry in limits["joints"]}
    missing = [f"j{k}" for k in range(1, joints + 1) if f"j{k}" not in by_name]
    if missing:
        raise ValueError(f"analysis/limits.json has no limits for {', '.join(missing)}")
    return [float(np.min(by_name[f"j{k}"]["theta_max_rad"])) for k in range(1, joints + 1)]
