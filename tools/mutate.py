#!/usr/bin/env python
"""Mutation check of the core numbers: do the tests catch a wrong answer?

Each fault in :data:`FAULTS` is one deliberate mistake, written as an exact
text substitution in one file of the working tree (a bore of 2 mm, d^3 in
E I, a swapped axis, a wrong density, a dropped SOA, ...). For each fault
this script

1. checks that the old snippet occurs exactly once in its file (otherwise the
   list has rotted: it stops and names the fault),
2. keeps the file's bytes in ``<file>.mutate-orig``, writes the mutated file,
3. runs the fast test suite (``python -m pytest -x -q -m "not slow"``) with a
   timeout,
4. restores the file byte for byte in a ``finally`` (also on Ctrl-C, SIGTERM
   and SIGHUP), and removes the backup,
5. records *caught* (the suite failed; the first failing test is named) or
   *SURVIVED* (the suite passed with the fault in place).

It prints a table and exits 1 if any fault survived (or timed out), 2 on a
usage problem (a rotten snippet, a leftover backup, a failing baseline).

If a run is killed hard (SIGKILL, power loss), the backup stays behind; the
next run refuses to start until ``--restore`` has put the original back.

Each fault also names its *catchers*, the tests written to catch it. ``--targeted`` (what CI runs)
applies each fault in a private copy of the tree (``--jobs`` copies side by side; the working tree
is never touched) and runs its catchers alone: the fault is caught only if every one of them fails,
so a test that stops catching its fault fails the run (PARTIAL). All the catchers first run once on
the unmutated copies and must pass, so a failure under a fault is the fault's.
``tests/test_mutate_faults.py`` checks that every fault applies and names catchers that exist.

Usage (from the repository root)::

    .venv/bin/python tools/mutate.py --targeted      # every fault against its catchers (CI)
    .venv/bin/python tools/mutate.py                 # every fault against the fast suite (by hand)
    .venv/bin/python tools/mutate.py --list          # the faults, whether each applies, catchers
    .venv/bin/python tools/mutate.py --only rod_bore_2mm --only ei_d_cubed
    .venv/bin/python tools/mutate.py --json          # one JSON object on stdout
    .venv/bin/python tools/mutate.py --restore       # after a killed run

The tree is shared: while a fault is applied, the file is wrong for anyone
else importing it. Runs are short (one fault at a time, restored at once),
and a restore never overwrites someone else's edit: if the file changed while
the fault was in place, the fault alone is reversed in the current text.

By default the suite's files are given explicitly, ``tests/test_truth*.py``
first, so a caught fault usually fails within seconds; ``--plain-order``
runs the suite in pytest's own order. After a caught fault the failing test
is run again on the restored tree and must pass (else the fault is reported
UNCONFIRMED; ``--no-confirm`` skips that), so a failure is the fault's and
not the tree's. ``--baseline`` also runs the whole unmutated suite first and
stops if it fails.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BACKUP_SUFFIX = ".mutate-orig"
STATE_FILE = Path("tools") / ".mutate-state.json"
#: The test that every fault applies (``tests/test_mutate_faults.py``) fails under any applied
#: fault, whose snippet is then gone: it would "catch" them all, so the suite run for a fault leaves
#: it out.
SELF_TEST = "tests/test_mutate_faults.py"
PYTEST_ARGS = [
    "-m",
    "pytest",
    "-x",
    "-q",
    "-m",
    "not slow",
    "-p",
    "no:cacheprovider",
    "-rfE",
    "--no-header",
    "-W",
    "ignore::DeprecationWarning",
    f"--ignore={SELF_TEST}",
]
#: ``--targeted``: a fault's catchers alone, each run to its end (every one must fail, so no -x),
#: whether marked slow or not (they are named).
TARGETED_ARGS = [
    "-m",
    "pytest",
    "-q",
    "-p",
    "no:cacheprovider",
    "-rfE",
    "--no-header",
    "-W",
    "ignore::DeprecationWarning",
]


@dataclass(frozen=True)
class Fault:
    name: str
    file: str  # relative to the repository root
    old: str  # must occur exactly once in the file
    new: str
    description: str
    #: pytest node ids (a parametrised test's id without its [...] stands for all its cases) that
    #: must each fail under this fault: ``--targeted`` runs these alone.
    catchers: tuple[str, ...] = ()


# Every fault is a physically wrong answer that still imports, builds and runs.
FAULTS: list[Fault] = [
    # -- the four faults of the review ---------------------------------------------------------
    Fault(
        "rod_bore_2mm",
        "bvsr_cad/parameters/layout.py",
        "def rod_bore_mm(spec: TailSpec) -> float:\n    thread = rod_thread(spec)\n",
        "def rod_bore_mm(spec: TailSpec) -> float:\n"
        "    return 2.0\n    thread = rod_thread(spec)\n",
        "the panels' rod bore is 2 mm for a 6 mm rod",
        catchers=(
            "tests/test_truth.py::test_rod_bore_is_the_iso_tap_drill_or_the_rod_with_clearance",
        ),
    ),
    Fault(
        "ei_d_cubed",
        "bvsr_cad/models/rod.py",
        "return math.pi * self.diameter_mm**4 / 64.0",
        "return math.pi * self.diameter_mm**3 / 64.0",
        "the rod's second moment of area is pi d^3 / 64 instead of pi d^4 / 64",
        catchers=(
            "tests/test_truth.py::test_rod_section_is_the_closed_form_with_the_tables_material",
        ),
    ),
    Fault(
        "robot_ei_x1.5",
        "bvsr_cad/assembly/robot.py",
        "rod_bending_stiffness_nm_rad=rod.bending_stiffness_nm_per_rad(L_mm),",
        "rod_bending_stiffness_nm_rad=1.5 * rod.bending_stiffness_nm_per_rad(L_mm),",
        "the robot model's rod E I / L is 1.5 times the rod's",
        catchers=("tests/test_truth.py::test_robot_rod_stiffness_is_ei_over_l_in_si",),
    ),
    Fault(
        "rod_panel_material",
        "bvsr_cad/models/rod.py",
        "table = _table_section(spec, v.material, v.diameter_mm)",
        "table = _table_section(spec, spec.use.panel, v.diameter_mm)",
        "the rod's section (E, density) takes the panel's material",
        catchers=(
            "tests/test_truth.py::test_rod_section_is_the_closed_form_with_the_tables_material",
        ),
    ),
    # -- more faults in the core numbers ------------------------------------------------------
    Fault(
        "rod_part_panel_material",
        "bvsr_cad/assembly/assemble.py",
        'kind="rod",\n                material=spec.vertebra.material,',
        'kind="rod",\n                material=spec.use.panel,',
        "the rod part (its mass, its BOM line) is made of the panel's material",
        catchers=("tests/test_truth.py::test_parts_are_made_of_their_tables_material",),
    ),
    Fault(
        "tap_drill_m6",
        "bvsr_cad/parameters/data/iso_metric.toml",
        "pitch_mm = 1.0\ntap_drill_mm = 5.0\n",
        "pitch_mm = 1.0\ntap_drill_mm = 5.5\n",
        "the M6 tap drill is 5.5 mm (ISO 2306: 5.0 mm)",
        catchers=(
            "tests/test_truth.py::test_rod_bore_is_the_iso_tap_drill_or_the_rod_with_clearance[6.0-threaded]",
        ),
    ),
    Fault(
        "set_screw_bore_no_clearance",
        "bvsr_cad/parameters/layout.py",
        "return hole_d(spec, spec.vertebra.diameter_mm + spec.socket.rod_clearance_mm)",
        "return hole_d(spec, spec.vertebra.diameter_mm - spec.socket.rod_clearance_mm)",
        "the set-screw bore is smaller than the rod (clearance subtracted)",
        catchers=(
            "tests/test_truth.py::test_rod_bore_is_the_iso_tap_drill_or_the_rod_with_clearance[6.0-set_screw]",
        ),
    ),
    Fault(
        "polar_cos_sin_swapped",
        "bvsr_cad/parameters/layout.py",
        "return (radius_mm * math.cos(a), radius_mm * math.sin(a))",
        "return (radius_mm * math.sin(a), radius_mm * math.cos(a))",
        "x and y swapped in the pentagon's polar(): SOA 1 lateral instead of dorsal",
        catchers=("tests/test_truth.py::test_soas_sit_on_the_pentagon",),
    ),
    Fault(
        "pentagon_clockwise",
        "bvsr_cad/parameters/layout.py",
        "return 90.0 + 72.0 * np.arange(N_SOA)",
        "return 90.0 - 72.0 * np.arange(N_SOA)",
        "the SOAs are numbered clockwise (soa2 at 18 deg instead of 162 deg)",
        catchers=("tests/test_truth.py::test_soas_sit_on_the_pentagon",),
    ),
    Fault(
        "dropped_soa",
        "bvsr_cad/assembly/assemble.py",
        "for i, a in enumerate(soa_angles_deg(), start=1):",
        "for i, a in enumerate(soa_angles_deg()[:4], start=1):",
        "each joint places 4 SOAs instead of N_SOA = 5",
        catchers=("tests/test_truth.py::test_soas_sit_on_the_pentagon",),
    ),
    Fault(
        "soa_stiffness_sign",
        "bvsr_cad/models/actuator.py",
        "p * self.area_m2\n            - self.stiffness_n_per_m(p) * stretch_m",
        "p * self.area_m2\n            + self.stiffness_n_per_m(p) * stretch_m",
        "the SOA's spring pushes with its stretch instead of against it (Eq 3 sign)",
        catchers=("tests/test_truth.py::test_soa_force_law_by_hand",),
    ),
    Fault(
        "soa_slope_kpa_as_pa",
        "bvsr_cad/models/actuator.py",
        "stiffness_slope_n_per_m_per_pa=a.stiffness_slope_n_per_m_per_kpa / units.PA_PER_KPA,",
        "stiffness_slope_n_per_m_per_pa=a.stiffness_slope_n_per_m_per_kpa,",
        "m_a of Eq 4 given per kPa is used per Pa (1000 times too stiff under pressure)",
        catchers=("tests/test_truth.py::test_soa_force_law_by_hand",),
    ),
    Fault(
        "chord_full_angle",
        "bvsr_cad/models/kinematics.py",
        "S, _, _, _ = _series_coefficients(np.abs(np.asarray(theta_rad, float)) / 2)",
        "S, _, _, _ = _series_coefficients(np.abs(np.asarray(theta_rad, float)))",
        "the chord is L sin(theta) / theta instead of 2 L sin(theta / 2) / theta",
        catchers=("tests/test_truth.py::test_chord_is_two_l_sin_half_theta_over_theta",),
    ),
    Fault(
        "parallel_axis_sign",
        "bvsr_cad/assembly/inertia.py",
        "I += i.inertia + i.mass_kg * (np.dot(d, d) * np.eye(3) - np.outer(d, d))",
        "I += i.inertia + i.mass_kg * (np.dot(d, d) * np.eye(3) + np.outer(d, d))",
        "the parallel-axis term of compose() adds d d^T instead of subtracting it",
        catchers=("tests/test_truth.py::test_composed_inertia_by_hand",),
    ),
    Fault(
        "density_mm3_per_cm3",
        "bvsr_cad/units.py",
        "MM3_PER_CM3 = 1000.0",
        "MM3_PER_CM3 = 100.0",
        "1 cm^3 = 100 mm^3: every mass from a density is 10 times too large",
        catchers=("tests/test_truth.py::test_unit_conversions_by_hand",),
    ),
    Fault(
        "density_kg_m3_factor",
        "bvsr_cad/units.py",
        "return value_g_cm3 * 1000.0",
        "return value_g_cm3 * 100.0",
        "g/cm^3 -> kg/m^3 by 100 instead of 1000",
        catchers=("tests/test_truth.py::test_unit_conversions_by_hand",),
    ),
    Fault(
        "inertia_mm2_to_m2",
        "bvsr_cad/units.py",
        "return value_g_mm2 / G_PER_KG / (MM_PER_M * MM_PER_M)",
        "return value_g_mm2 / G_PER_KG / MM_PER_M",
        "g mm^2 -> kg m^2 divides by 1e6 instead of 1e9",
        catchers=("tests/test_truth.py::test_unit_conversions_by_hand",),
    ),
    Fault(
        "panel_thickness",
        "bvsr_cad/parameters/tables.py",
        "return self.joint_height_mm - self.gap_mm\n",
        "return self.joint_height_mm - self.gap_mm + 0.2\n",
        "the panel thickness is H_j - H_a + 0.2 mm (still a valid parameter file)",
        catchers=("tests/test_truth.py::test_panels_sit_every_h_j_and_are_h_j_minus_h_a_thick",),
    ),
    Fault(
        "taper_upper_rim",
        "bvsr_cad/parameters/layout.py",
        "r_rim_hi = j.panel_diameter_mm / 2 - (z0 + t) * tan_b",
        "r_rim_hi = j.panel_diameter_mm / 2 - z0 * tan_b",
        "the rim does not follow the cone across a panel's thickness",
        catchers=("tests/test_truth.py::test_rims_and_pitch_circles_follow_one_cone",),
    ),
    Fault(
        "flange_thickness",
        "bvsr_cad/parameters/tables.py",
        "return (self.height_mm - self.origami_height_mm) / 2.0",
        "return (self.height_mm - self.origami_height_mm) / 2.5",
        "each SOA flange is (H - H_o) / 2.5 thick instead of (H - H_o) / 2",
        catchers=("tests/test_truth.py::test_soa_body_height_and_pocket_depth",),
    ),
    Fault(
        "mold_shrinkage_scale",
        "bvsr_cad/parameters/molds.py",
        "k = 1.0 + c.shrinkage_percent / 100.0",
        "k = 1.0 + c.shrinkage_percent / 10.0",
        "the mold cavity scales by 1 + shrinkage / 10 instead of 1 + shrinkage / 100",
        catchers=("tests/test_truth.py::test_mold_cast_is_the_soa_grown_by_the_shrinkage",),
    ),
    Fault(
        "twin_pin_hole",
        "bvsr_cad/parameters/twin.py",
        "return fp.pin_diameter_mm + fp.pin_hole_clearance_mm",
        "return fp.pin_diameter_mm - fp.pin_hole_clearance_mm",
        "the rigid twin's dowel holes are smaller than the dowel",
        catchers=("tests/test_truth.py::test_rigid_twin_dowel_holes",),
    ),
    Fault(
        "robot_rod_panel_material",
        "bvsr_cad/assembly/robot.py",
        "rod_mat = spec.materials.get(spec.vertebra.material)  # None: no rod (no rod pieces "
        "either)",
        "rod_mat = spec.materials.get(spec.use.panel)  # None: no rod (no rod pieces either)",
        "the robot model's rod pieces (links' mass and inertia) take the panel's density",
        catchers=("tests/test_truth.py::test_robot_mass_by_hand",),
    ),
    Fault(
        "robot_theta_about_x",
        "bvsr_cad/assembly/robot.py",
        "names[1],\n            _as_tuple(np.eye(4)),\n            (0, 1, 0),",
        "names[1],\n            _as_tuple(np.eye(4)),\n            (1, 0, 0),",
        "the first half-angle joint turns about X instead of Y (swapped axis in the chain)",
        catchers=("tests/test_truth.py::test_mujoco_bent_joint_is_eq2_by_hand",),
    ),
    Fault(
        "robot_phi_origin_in_mm",
        "bvsr_cad/assembly/robot.py",
        "_as_tuple(translation_m(z=t)),\n            (0, 0, 1),",
        "_as_tuple(translation_m(z=t_mm)),\n            (0, 0, 1),",
        "each joint's chain starts t millimetres written as metres above its panel (mm -> m)",
        catchers=("tests/test_truth.py::test_mujoco_rest_pose_is_the_straight_tail",),
    ),
    Fault(
        "robot_top_site_frame",
        "bvsr_cad/assembly/robot.py",
        "(top_mm - [0, 0, hi.z0_mm])",
        "(top_mm - [0, 0, lo.z0_mm])",
        "an SOA's top socket is placed in the lower panel's frame",
        catchers=("tests/test_truth.py::test_mujoco_sockets_on_the_pentagon",),
    ),
    Fault(
        "robot_velocity_not_shared",
        "bvsr_cad/assembly/robot.py",
        "return units.deg_s_to_rad_s(segment_deg_s) / joints_per_segment * margin",
        "return units.deg_s_to_rad_s(segment_deg_s) * margin",
        "a joint's velocity limit is the whole segment's rate (not shared by its joints)",
        catchers=("tests/test_truth.py::test_robot_limits_by_hand",),
    ),
    Fault(
        "robot_effort_on_diameter",
        "bvsr_cad/assembly/robot.py",
        "effort_limit_nm = push_n * units.mm_to_m(spec.joint.pitch_diameter_mm / 2)",
        "effort_limit_nm = push_n * units.mm_to_m(spec.joint.pitch_diameter_mm)",
        "the SOAs' torque limit uses the pitch diameter as the lever arm",
        catchers=("tests/test_truth.py::test_robot_limits_by_hand",),
    ),
    Fault(
        "mjcf_soa_spring_sign",
        "bvsr_cad/exporters/mjcf.py",
        "biasprm=_vec((n_a * l0_m, -n_a, -c))",
        "biasprm=_vec((-n_a * l0_m, n_a, -c))",
        "the MJCF actuator's SOA spring pushes with the stretch (Eq 3 sign in MuJoCo)",
        catchers=("tests/test_truth.py::test_mujoco_soa_actuator_is_eq3_by_hand",),
    ),
    Fault(
        "mjcf_hinge_damping_halved",
        "bvsr_cad/models/reduced_chain.py",
        "axis: 2.0 * damping_n_s_per_m * a2 for axis, a2 in arms2.items()",
        "axis: 1.0 * damping_n_s_per_m * a2 for axis, a2 in arms2.items()",
        "the default MJCF's pivot hinges carry half the SOAs' damping",
        catchers=("tests/test_robot.py::test_default_mjcf_hinges_carry_the_soa_dampers_and_shear",),
    ),
    Fault(
        "mjcf_hinge_damping_lever_from_arc_start",
        "bvsr_cad/exporters/mjcf.py",
        "pivot_mid_m=[0.0, 0.0, t_m + b.arc_length_m / 2],",
        "pivot_mid_m=[0.0, 0.0, t_m],",
        "the SOAs' lever arms for the hinges' share taken about the arc's start, not the pivots' "
        "midpoint",
        catchers=("tests/test_robot.py::test_default_mjcf_hinges_carry_the_soa_dampers_and_shear",),
    ),
    Fault(
        "mjcf_shear_spring_counted_twice_in_the_bend",
        "bvsr_cad/models/reduced_chain.py",
        "soa_stiffness_offset_n_per_m=stiffness_offset_n_per_m - moved / mean2,",
        "soa_stiffness_offset_n_per_m=stiffness_offset_n_per_m,",
        "the shear spring moved onto the default MJCF's hinges stiffens the bend too (the SOAs' "
        "springs keep all of n_a)",
        catchers=("tests/test_robot.py::test_default_mjcf_hinges_carry_the_soa_dampers_and_shear",),
    ),
    Fault(
        "mount_pivot_at_a_third",
        "bvsr_cad/models/kinematics.py",
        "MOUNT_PIVOT_FRACTION = 0.5",
        "MOUNT_PIVOT_FRACTION = 1.0 / 3.0",
        "the mount variant's universal joint a third of the arc from its start, not at mid-arc",
        catchers=("tests/test_robot.py::test_mount_variant_joint_error_is_its_closed_form",),
    ),
    Fault(
        "mount_hinge_stiffness_doubled",
        "bvsr_cad/models/reduced_chain.py",
        "stiffness_nm_rad=rod_bending_stiffness_nm_rad,",
        "stiffness_nm_rad=2.0 * rod_bending_stiffness_nm_rad,",
        "the mount variant's hinges carry the default file's 2 E I / L (its two pivots' share), "
        "not the one pivot's E I / L",
        catchers=("tests/test_robot.py::test_mount_variant_follows_the_exact_chain",),
    ),
    Fault(
        "kinematics_xy_swapped",
        "bvsr_cad/models/kinematics.py",
        "trans = length_mm * np.stack([self.u * C, self.v * C, S], -1)",
        "trans = length_mm * np.stack([self.v * C, self.u * C, S], -1)",
        "X and Y swapped in the translation of Eq 2",
        catchers=("tests/test_truth.py::test_linearised_equilibrium_of_one_pressurised_soa",),
    ),
    Fault(
        "mid_angles_off_1deg",
        "bvsr_cad/parameters/layout.py",
        "return soa_angles_deg() + 36.0",
        "return soa_angles_deg() + 35.0",
        "the features between the pockets (lightening, tubes, inserts) are 1 deg off the "
        "mid-angles",
        catchers=("tests/test_truth.py::test_features_between_the_pockets_sit_on_the_mid_angles",),
    ),
    Fault(
        "pocket_clearance_sign",
        "bvsr_cad/parameters/layout.py",
        "return spec.joint.base_diameter_mm + spec.fabrication.pocket_clearance_mm",
        "return spec.joint.base_diameter_mm - spec.fabrication.pocket_clearance_mm",
        "a flange pocket is smaller than the D_b flange (clearance subtracted)",
        catchers=("tests/test_truth.py::test_flange_pockets_are_d_b_plus_clearance",),
    ),
    Fault(
        "m3_nut_across_flats",
        "bvsr_cad/parameters/data/iso_metric.toml",
        "tap_drill_mm = 2.5\nnut_af_mm = 5.5\n",
        "tap_drill_mm = 2.5\nnut_af_mm = 5.0\n",
        "the M3 nut is 5.0 mm across flats (ISO 4032: 5.5 mm): the twin's nut pockets are too "
        "small",
        catchers=("tests/test_truth.py::test_rigid_twin_tie_rod_and_nut_pocket",),
    ),
    # -- the directions of the physics: payload, gravity, taper, density
    # -----------------------------
    Fault(
        "payload_ignored_in_simulate",
        "bvsr_cad/simulation/sim.py",
        'tail_xml = _model_xml(spec, theta_max_rad, folder / "tail", payload_g)',
        'tail_xml = _model_xml(spec, theta_max_rad, folder / "tail", 0.0)',
        "bvsr simulate --payload-g runs the tail without its payload",
        catchers=(
            "tests/test_simulate_payload.py::test_simulate_carries_the_payload_as_a_point_mass",
        ),
    ),
    Fault(
        "payload_left_out_of_dynamics",
        "bvsr_cad/models/dynamics.py",
        "return replace(self, tip_mass_kg=self.tip_mass_kg + mass_kg)",
        "return replace(self, tip_mass_kg=self.tip_mass_kg)",
        "RigidBody.with_tip_mass ignores the payload (the Eq 6-12 model runs without it)",
        catchers=(
            "tests/test_models_dynamics.py::test_a_tip_payload_is_a_point_mass_at_the_arcs_end",
            "tests/test_models_dynamics.py::test_root_wrench_with_a_tip_payload_under_a_known_angular_acceleration",
        ),
    ),
    Fault(
        "payload_not_passed_to_the_model",
        "bvsr_cad/analysis/predict.py",
        "body = body.with_tip_mass(units.g_to_kg(payload_g))",
        "body = body.with_tip_mass(0.0)",
        "the predictions' joint model leaves the tip payload out",
        catchers=(
            "tests/test_models_dynamics.py::test_root_wrench_with_a_tip_payload_under_a_known_angular_acceleration",
        ),
    ),
    Fault(
        "payload_offset_from_the_base",
        "bvsr_cad/models/dynamics.py",
        "TIP_OVER_COM = 2.0",
        "TIP_OVER_COM = 1.0",
        "the payload rides at the body's centre of mass (the chord midpoint, half-way from the "
        "base) instead "
        "of at the arc's end",
        catchers=(
            "tests/test_models_dynamics.py::test_a_tip_payload_is_a_point_mass_at_the_arcs_end",
            "tests/test_models_dynamics.py::test_root_wrench_with_a_tip_payload_under_a_known_angular_acceleration",
        ),
    ),
    Fault(
        "payload_weighed_at_the_centre_of_mass",
        "bvsr_cad/models/dynamics.py",
        "return self.mass_kg + TIP_OVER_COM * self.tip_mass_kg",
        "return self.mass_kg + self.tip_mass_kg",
        "gravity pulls the tip payload as if it sat at the body's centre of mass",
        catchers=(
            "tests/test_models_dynamics.py::test_a_tip_payload_is_a_point_mass_at_the_arcs_end",
            "tests/test_models_dynamics.py::test_without_damping_and_forcing_the_model_conserves_energy[0.1]",
        ),
    ),
    Fault(
        "root_torque_lever_without_panel",
        "bvsr_cad/analysis/predict.py",
        "face = np.array([0.0, 0.0, units.mm_to_m(self.spec.joint.panel_thickness_mm)])",
        "face = np.zeros(3)",
        "the predicted root torque is taken about the body's base face, not the root sensor's face",
        catchers=(
            "tests/test_models_dynamics.py::test_root_wrench_with_a_tip_payload_under_a_known_angular_acceleration",
        ),
    ),
    Fault(
        "statics_gravity_sign",
        "bvsr_cad/models/statics.py",
        "down = np.array([0.0, -G_N_PER_KG, 0.0])",
        "down = np.array([0.0, G_N_PER_KG, 0.0])",
        "gravity points along +Y in the statics (the horizontal tail sags upwards)",
        catchers=(
            "tests/test_statics.py::test_the_horizontal_tail_sags_towards_minus_y_as_hand_statics_give",
        ),
    ),
    Fault(
        "dynamics_gravity_sign",
        "bvsr_cad/analysis/predict.py",
        "GRAVITY_M_S2 = np.array([0.0, -G_M_S2, 0.0])",
        "GRAVITY_M_S2 = np.array([0.0, G_M_S2, 0.0])",
        "gravity points along +Y in the predictions' Eq 6-12 model",
        catchers=(
            "tests/test_models_dynamics.py::test_the_predictions_tail_sags_towards_minus_y_without_pressure",
        ),
    ),
    Fault(
        "taper_sign",
        "bvsr_cad/parameters/layout.py",
        "        return math.radians(max_feasible_taper_deg(spec))\n",
        "        return -math.radians(max_feasible_taper_deg(spec))\n",
        "the cone opens the wrong way: panels grow from the root to the tip",
        catchers=("tests/test_truth.py::test_panels_narrow_from_root_to_tip_on_the_b_rep",),
    ),
    Fault(
        "soa_density",
        "bvsr_cad/defaults/params/bvsr.toml",
        'name = "cast polyurethane rubber, Shore 75-80A"\ndensity_g_cm3 = 1.05\n',
        'name = "cast polyurethane rubber, Shore 75-80A"\ndensity_g_cm3 = 1.15\n',
        "the SOA's polyurethane is 1.15 g/cm^3 (datasheets: 1.04-1.06): every SOA 10 % heavier",
        catchers=("tests/test_truth.py::test_soa_and_tail_masses_within_the_datasheets_densities",),
    ),
    # -- the memo: a step is reused only for the same inputs and file bytes ---------------------
    Fault(
        "memo_ignores_file_bytes",
        "bvsr_cad/pipeline/runner.py",
        "for f in files] if cache else []",
        "for f in files][:0] if cache else []",
        "a writer's cached step (the report's pictures, the 3MF layouts) is reused after the files "
        "it reads changed",
        catchers=(
            "tests/test_cache.py::test_a_writers_step_follows_its_inputs_and_the_bytes_of_its_files",
        ),
    ),
    Fault(
        "check_memo_ignores_file_bytes",
        "bvsr_cad/checks/memo.py",
        '{"read_files": [(rel, self._sha[rel]) for rel in files], "values": values},',
        '{"read_files": list(files), "values": values},',
        "a check group's verdicts are reused after the files it reads changed",
        catchers=(
            "tests/test_cache.py::test_check_verdicts_follow_the_bytes_of_the_files_they_read",
        ),
    ),
    Fault(
        "early_checks_ignore_their_reads",
        "bvsr_cad/memo.py",
        "if kept is not None and kept[0] == inputs:",
        "if kept is not None:",
        "a check group a build ran early keeps its verdicts after a file it read changed (the "
        "in-memory memo gives a name's value again whatever its inputs)",
        catchers=(
            "tests/test_cache.py::test_the_in_memory_memo_gives_a_value_again_only_for_the_same_inputs",
        ),
    ),
    # -- the simulation scene's cost -----------------------------------------------------------
    Fault(
        "mjcf_idle_tendon_per_joint",
        "bvsr_cad/exporters/mjcf.py",
        '            ET.SubElement(fixed, "joint", joint=f"{b.name}_b{axis}", coef="-1")\n'
        "    if per_segment:\n",
        '            ET.SubElement(fixed, "joint", joint=f"{b.name}_b{axis}", coef="-1")\n'
        '        idle = ET.SubElement(tendon, "fixed", name=f"{b.name}_idle")\n'
        '        ET.SubElement(idle, "joint", joint=f"{b.name}_ax", coef="1")\n'
        "    if per_segment:\n",
        "the writer adds a tendon per joint that does nothing: the same physics, one more tendon "
        "for every world of a batch to pass over each step",
        catchers=("tests/test_scene_budget.py::test_the_written_models_tendons_within_budget",),
    ),
    # -- the tail on a host: the mount transform -----------------------------------------------
    Fault(
        "mount_rpy_intrinsic",
        "bvsr_cad/exporters/mount.py",
        "    T[:3, :3] = yaw @ pitch @ roll  # about the fixed X, then Y, then Z\n",
        "    T[:3, :3] = roll @ pitch @ yaw  # about the fixed X, then Y, then Z\n",
        "the mount pose's roll-pitch-yaw read about moving axes, not URDF's fixed ones: the tail "
        "points elsewhere than the pose and the xacro macro say",
        catchers=("tests/test_mount.py::test_box_host_at_a_body",),
    ),
    Fault(
        "mount_site_order",
        "bvsr_cad/exporters/mount.py",
        "    return parent, T_site @ pose\n",
        "    return parent, pose @ T_site\n",
        "a site's pose applied in the body's frame instead of the site's",
        catchers=("tests/test_mount.py::test_box_host_at_a_site_written_and_loaded_elsewhere",),
    ),
    Fault(
        "xacro_mount_rpy_dropped",
        "bvsr_cad/exporters/urdf.py",
        '    ET.SubElement(joint, "origin", xyz="${xyz}", rpy="${rpy}")\n',
        '    ET.SubElement(joint, "origin", xyz="${xyz}", rpy="0 0 0")\n',
        "the xacro macro's mount joint ignores rpy: the tail points along the parent link's Z "
        "whatever the call asks",
        catchers=(
            "tests/test_mount.py::test_xacro_macro_on_a_host_expands_and_check_urdf_accepts",
            "tests/test_ros2_package.py::test_xacro_macro_expands_onto_a_host_and_check_urdf_accepts",
        ),
    ),
    # -- the tail on a quadruped (simulation/quadruped.py) -------------------------------------
    Fault(
        "quadruped_payload_half_mass",
        "bvsr_cad/simulation/quadruped.py",
        "    m = units.g_to_kg(payload_g)\n",
        "    m = units.g_to_kg(payload_g) / 2\n",
        "the tip payload of Fig. 18 weighs half what it is said to: the root carries too little",
        catchers=("tests/test_quadruped.py::test_a_payload_adds_its_weight_at_the_root",),
    ),
    Fault(
        "quadruped_ball_impulse_sign",
        "bvsr_cad/simulation/quadruped.py",
        "            f_ball = f if c.geom2 == self.ball else -f\n",
        "            f_ball = -f if c.geom2 == self.ball else f\n",
        "the contact force on the ball taken as the force on the other geom: Fig. 17's impulse "
        "into the tail has the wrong sign and no longer balances the ball's momentum change",
        catchers=("tests/test_quadruped.py::test_fig17_ball_momentum_and_soft_below_rigid",),
    ),
    Fault(
        "quadruped_stance_pd_sign",
        "bvsr_cad/simulation/quadruped.py",
        "    torque = sc.kp * (sc.stance_q - q) - sc.kd * qd\n",
        "    torque = sc.kp * (q - sc.stance_q) - sc.kd * qd\n",
        "the stance's PD pushes the joints away from the standing pose: the robot falls",
        catchers=("tests/test_quadruped.py::test_stands_5_s_at_rest_and_waggling_at_6_bar",),
    ),
    Fault(
        "quadruped_attitude_quat_order",
        "bvsr_cad/simulation/quadruped.py",
        '    return np.degrees(Rotation.from_quat([x, y, z, w]).as_euler("xyz"))\n',
        '    return np.degrees(Rotation.from_quat([w, x, y, z]).as_euler("xyz"))\n',
        "MuJoCo's w-first quaternion read as SciPy's w-last: the torso's roll, pitch and yaw are "
        "wrong (a level robot reads tilted by 180 deg)",
        catchers=("tests/test_quadruped.py::test_stands_5_s_at_rest_and_waggling_at_6_bar",),
    ),
    Fault(
        "quadruped_fig17_verdict_inverted",
        "bvsr_cad/simulation/quadruped.py",
        'all(v["torso_speed"] < 1.0 for v in ratios.values())',
        'all(v["torso_speed"] > 1.0 for v in ratios.values())',
        "Fig. 17's verdict reads a higher torso response behind the soft tail as agreeing with "
        "the paper",
        catchers=("tests/test_quadruped.py::test_fig17_ball_momentum_and_soft_below_rigid",),
    ),
]


# -- file handling ------------------------------------------------------------------------------
def _backup(path: Path) -> Path:
    return path.with_name(path.name + BACKUP_SUFFIX)


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _leftovers(root: Path) -> list[Path]:
    out = []
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames[:] = [
            d
            for d in dirnames
            if d not in (".git", ".venv", "node_modules", "exports", "__pycache__")
        ]
        out += [Path(dirpath) / f for f in filenames if f.endswith(BACKUP_SUFFIX)]
    return sorted(out)


def _atomic_write(path: Path, data: bytes) -> None:
    tmp = path.with_name(path.name + ".mutate-tmp")
    tmp.write_bytes(data)
    try:
        os.chmod(tmp, path.stat().st_mode & 0o7777)
    except OSError:
        pass
    os.replace(tmp, path)


_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class _SignalsHeld:
    """Signals wait while a file is being mutated or restored (then arrive at once)."""

    def __enter__(self):
        signal.pthread_sigmask(signal.SIG_BLOCK, _SIGNALS)

    def __exit__(self, *exc):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, _SIGNALS)
        return False


class Mutation:
    """One fault applied to one file; :meth:`restore` undoes it exactly once."""

    def __init__(self, root: Path, fault: Fault):
        self.root = root
        self.fault = fault
        self.path = root / fault.file
        self.backup = _backup(self.path)
        self.original: bytes | None = None
        self.mutated: bytes | None = None

    def apply(self) -> None:
        with _SignalsHeld():
            self._apply()

    def _apply(self) -> None:
        original = self.path.read_bytes()
        text = original.decode("utf-8")
        n = text.count(self.fault.old)
        if n != 1:
            raise SnippetError(self.fault, n)
        mutated = text.replace(self.fault.old, self.fault.new, 1).encode("utf-8")
        # Backup first (fsynced), state second, mutation last: a kill at any point is recoverable.
        with open(self.backup, "wb") as fh:
            fh.write(original)
            fh.flush()
            os.fsync(fh.fileno())
        _write_state(
            self.root,
            {
                "fault": self.fault.name,
                "file": self.fault.file,
                "original_sha256": _sha(original),
                "mutated_sha256": _sha(mutated),
                "pid": os.getpid(),
                "started": time.time(),
            },
        )
        self.original, self.mutated = original, mutated
        _atomic_write(self.path, mutated)

    def restore(self) -> str:
        """Put the original back; returns '' or a warning (the file was edited meanwhile)."""
        with _SignalsHeld():
            return self._restore()

    def _restore(self) -> str:
        if self.original is None:
            return ""
        warning = _restore_file(self.path, self.original, self.mutated, self.fault)
        self.original = None
        try:
            self.backup.unlink()
        except FileNotFoundError:
            pass
        _clear_state(self.root)
        return warning


def _restore_file(path: Path, original: bytes, mutated: bytes | None, fault: Fault | None) -> str:
    """Original bytes back unless someone edited the mutated file: then reverse the fault only."""
    current = path.read_bytes() if path.exists() else None
    if current == original:
        return ""
    if current is None or mutated is None or current == mutated:
        _atomic_write(path, original)
        return ""
    # Edited while the fault was in place (a colleague saved over it): never overwrite that edit.
    text = current.decode("utf-8", errors="surrogateescape")
    if fault is not None and text.count(fault.new) == 1 and text.count(fault.old) == 0:
        _atomic_write(
            path, text.replace(fault.new, fault.old, 1).encode("utf-8", errors="surrogateescape")
        )
        return (
            f"{path}: edited while fault {fault.name} was applied; reversed the fault in the "
            "edited text"
        )
    return (
        f"{path}: edited while fault {fault.name if fault else '?'} was applied and the fault's "
        "text is gone; "
        "left as it is (check it by hand)"
    )


def _state_path(root: Path) -> Path:
    return root / STATE_FILE


def _write_state(root: Path, state: dict) -> None:
    p = _state_path(root)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(json.dumps(state, indent=1))


def _clear_state(root: Path) -> None:
    try:
        _state_path(root).unlink()
    except FileNotFoundError:
        pass


def restore_leftovers(root: Path) -> list[str]:
    """After a killed run: put every ``*.mutate-orig`` back (reversing only the fault if the file
    was edited)."""
    state = {}
    if _state_path(root).exists():
        try:
            state = json.loads(_state_path(root).read_text())
        except ValueError:
            state = {}
    fault = next((f for f in FAULTS if f.name == state.get("fault")), None)
    messages = []
    pgid = state.get("pytest_pgid")
    if pgid:  # the killed run's pytest (its own session) may still be running on the mutated file
        try:
            cmd = Path(f"/proc/{pgid}/cmdline").read_bytes().replace(b"\0", b" ")
            if b"pytest" in cmd and os.getpgid(pgid) == pgid:
                os.killpg(pgid, signal.SIGTERM)
                messages.append(f"stopped the killed run's pytest (process group {pgid})")
        except (OSError, ProcessLookupError):
            pass
    for backup in _leftovers(root):
        target = backup.with_name(backup.name[: -len(BACKUP_SUFFIX)])
        original = backup.read_bytes()
        mutated = None
        f = fault if fault is not None and (root / fault.file) == target else None
        if f is not None and target.exists():
            cur = target.read_bytes()
            if _sha(cur) == state.get("mutated_sha256"):
                mutated = cur
        if f is None or mutated is not None or not target.exists():
            _atomic_write(target, original)
            messages.append(f"restored {target.relative_to(root)} from {backup.name}")
        else:
            messages.append(
                _restore_file(target, original, None if mutated is None else mutated, f)
                or f"restored {target.relative_to(root)}"
            )
        backup.unlink()
    _clear_state(root)
    return messages


class SnippetError(Exception):
    def __init__(self, fault: Fault, count: int):
        where = (
            "not found"
            if count == 0
            else "behind a link out of the tree"
            if count < 0
            else f"found {count} times"
        )
        super().__init__(
            f"fault {fault.name}: its snippet is {where} in {fault.file} "
            f"(it must occur exactly once; update FAULTS in tools/mutate.py):\n    {fault.old!r}"
        )
        self.fault = fault


def snippet_problems(root: Path, faults: list[Fault]) -> list[str]:
    out = []
    for f in faults:
        p = root / f.file
        if not p.is_file():
            out.append(f"fault {f.name}: {f.file} does not exist")
            continue
        n = p.read_text().count(f.old)
        if n != 1:
            out.append(str(SnippetError(f, n)))
        elif f.old == f.new:
            out.append(f"fault {f.name}: the new text equals the old")
    return out


# -- running the suite --------------------------------------------------------------------------
class Interrupted(Exception):
    pass


#: The pytest runs under way (one, or one per job of ``--targeted --jobs``), each in its own
#: session.
_CHILDREN: set[subprocess.Popen] = set()
_CHILDREN_LOCK = threading.Lock()


def _on_signal(signum, _frame):
    raise Interrupted(signal.Signals(signum).name)


def _stop(child: subprocess.Popen) -> None:
    if child.poll() is None:
        try:
            os.killpg(child.pid, signal.SIGTERM)
            try:
                child.wait(10)
            except subprocess.TimeoutExpired:
                os.killpg(child.pid, signal.SIGKILL)
                child.wait()
        except ProcessLookupError:
            pass
    with _CHILDREN_LOCK:
        _CHILDREN.discard(child)


def _kill_child() -> None:
    """Stop every pytest run this process started that is still going."""
    with _CHILDREN_LOCK:
        children = list(_CHILDREN)
    for child in children:
        _stop(child)
    with _CHILDREN_LOCK:
        servers = list(_SERVERS.values())
    for server in servers:
        server.stop_run()


#: ``--targeted``: the libraries a catcher's run imports before any code of bvsr_cad (a catcher
#: run is mostly these imports: 4 to 5 CPU s of a trivial catcher's 7). Each copy of the tree has a
#: server (:class:`_ForkServer`) that imports them once and forks a pytest run per fault: bvsr_cad
#: itself, its tests and conftest are imported in the forked child, from the copy, as it is now.
PRELOADED = (
    "numpy",
    "scipy.linalg",
    "scipy.optimize",
    "scipy.spatial",
    "scipy.integrate",
    "scipy.interpolate",
    "networkx",
    "shapely",
    "trimesh",
    "manifold3d",
    "mujoco",
    "OCP",
    "build123d",
    "hypothesis",
    "pytest",
)

_SERVER = r"""
import importlib, json, os, sys
for name in sys.argv[1:]:
    try:
        importlib.import_module(name)
    except Exception:  # a library missing here is imported (and fails) in the run instead
        pass
import pytest
ours = ("bvsr_cad", "tests")
assert not any(m.split(".")[0] in ours for m in sys.modules)
answer = os.fdopen(os.dup(1), "w")
null = os.open(os.devnull, os.O_RDWR)
for line in sys.stdin:
    request = json.loads(line)
    pid = os.fork()
    if pid == 0:
        os.setsid()
        out = os.open(request["out"], os.O_WRONLY | os.O_CREAT | os.O_TRUNC)
        os.dup2(null, 0)
        os.dup2(out, 1)
        os.dup2(out, 2)
        code = 3
        try:
            code = int(pytest.main(request["args"]))
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(code)
    answer.write(json.dumps({"pid": pid}) + "\n")
    answer.flush()
    _, status = os.waitpid(pid, 0)
    answer.write(json.dumps({"rc": os.waitstatus_to_exitcode(status)}) + "\n")
    answer.flush()
"""


class _ForkServer:
    """A Python process in ``root`` (a private copy of the tree) that has imported
    :data:`PRELOADED` and forks one pytest run (``pytest.main``) per request, in a session of its
    own, its output into a file. Started with the environment :func:`run_suite` gives a run."""

    def __init__(self, root: Path, python: str, env: dict[str, str]):
        self.out = Path(tempfile.mkstemp(prefix="bvsr-mutate-run-", suffix=".txt")[1])
        env = {**env, "OPENBLAS_NUM_THREADS": env.get("OPENBLAS_NUM_THREADS", "1")}  # no threads
        self.proc = subprocess.Popen(
            [python, "-c", _SERVER, *PRELOADED],
            cwd=root,
            env=env,
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            start_new_session=True,
        )
        self.pid: int | None = None  # the run under way

    def run(self, args: list[str], timeout_s: float) -> tuple[int | None, str]:
        """(pytest's exit code, or None after ``timeout_s``; its output)."""
        import select

        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(json.dumps({"args": args, "out": str(self.out)}) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError("the fork server ended")
        self.pid = json.loads(line)["pid"]
        ready, _, _ = select.select([self.proc.stdout], [], [], timeout_s)
        if not ready:
            self.stop_run()
        line = self.proc.stdout.readline()
        self.pid = None
        if not line:
            raise RuntimeError("the fork server ended")
        rc = json.loads(line)["rc"]
        return (rc if ready else None), self.out.read_text(errors="replace")

    def stop_run(self) -> None:
        pid = self.pid
        if pid is not None:
            try:
                os.killpg(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass

    def close(self) -> None:
        self.stop_run()
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        self.out.unlink(missing_ok=True)


#: The fork servers of ``--targeted`` (one per private copy), by the copy's path; none with
#: ``--fresh-interpreters``.
_SERVERS: dict[Path, _ForkServer] = {}
_USE_SERVERS = hasattr(os, "fork")


def _close_servers() -> None:
    with _CHILDREN_LOCK:
        servers = list(_SERVERS.values())
        _SERVERS.clear()
    for server in servers:
        server.close()


_FAIL_RE = re.compile(r"^(FAILED|ERROR) (.+?)(?: - (.*))?$", re.M)


def failure_reason(output: str) -> str:
    """'FAILED' (an assertion) or 'ERROR' (setup, e.g. the parameter file no longer loads), with
    pytest's one-line message."""
    m = _FAIL_RE.search(output)
    if not m:
        return ""
    return f"{m.group(1)}: {(m.group(3) or '').strip()[:160]}"


def first_failure(output: str) -> str:
    m = _FAIL_RE.search(output)
    if m:
        return m.group(2)
    if "no tests ran" in output:
        return "(no tests ran)"
    for line in output.splitlines():
        if "Error" in line or "error" in line:
            return line.strip()[:120]
    return "(see output)"


def test_args(root: Path, plain_order: bool) -> list[str]:
    """Test files in the order to run: ``tests/test_truth*.py`` first, then the rest (pytest keeps
    the order of explicit file arguments; given a folder it would sort them)."""
    if plain_order:
        return []
    files = sorted(
        str(p.relative_to(root))
        for p in (root / "tests").glob("test_*.py")
        if p.relative_to(root).as_posix() != SELF_TEST
    )
    first = [f for f in files if Path(f).name.startswith("test_truth")]
    return first + [f for f in files if f not in first]


def failed_ids(output: str) -> set[str]:
    """Node ids pytest's short summary names as FAILED or ERROR."""
    return {m.group(2) for m in _FAIL_RE.finditer(output)}


def missed_catchers(catchers: tuple[str, ...], failed: set[str]) -> list[str]:
    """The catchers that did not fail (an id without [...] fails when any of its cases does)."""
    return [
        c
        for c in catchers
        if not any(f == c or (f.startswith(c + "[") and "[" not in c) for f in failed)
    ]


def run_suite(
    root: Path,
    timeout_s: float,
    extra: list[str],
    python: str,
    base: list[str] | None = None,
    tail_chars: int = 3000,
) -> tuple[str, str, float, str]:
    """(status: passed/failed/timeout, first failing test, seconds, output tail: the last
    ``tail_chars`` characters). ``base``: pytest's arguments before ``extra`` (default: the fast
    suite's)."""
    env = dict(os.environ)
    if base is TARGETED_ARGS:
        # No third-party plugin (pytest-xdist, ...) is loaded: a second less per fault. The
        # catchers' baseline runs the same way, so a catcher that needs one fails there, never
        # passes for a fault.
        env["PYTEST_DISABLE_PLUGIN_AUTOLOAD"] = "1"
    env["COLUMNS"] = "250"  # pytest's short summary keeps whole node ids
    env["PYTHONDONTWRITEBYTECODE"] = "1"  # no stale bytecode of a mutated module can outlive it
    env["PYTHONPATH"] = str(root) + (
        os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else ""
    )
    t0 = time.monotonic()
    if base is TARGETED_ARGS and _USE_SERVERS:
        with _CHILDREN_LOCK:
            server = _SERVERS.get(root)
            if server is None:
                server = _SERVERS[root] = _ForkServer(root, python, env)
        rc, out = server.run([*base[2:], *extra], timeout_s)  # base: -m pytest ARGS
        if rc is None:
            return "timeout", f"(over {timeout_s:g} s)", time.monotonic() - t0, ""
        return _outcome(rc, out, time.monotonic() - t0, tail_chars)
    child = subprocess.Popen(
        [python, *(PYTEST_ARGS if base is None else base), *extra],
        cwd=root,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    with _CHILDREN_LOCK:
        _CHILDREN.add(child)
    state = _state_path(root)
    if state.exists():  # a fault is applied: --restore can stop this run's pytest if we are killed
        try:
            _write_state(root, {**json.loads(state.read_text()), "pytest_pgid": child.pid})
        except ValueError:
            pass
    try:
        out, _ = child.communicate(timeout=timeout_s)
        rc = child.returncode
    except subprocess.TimeoutExpired:
        _stop(child)
        return "timeout", f"(over {timeout_s:g} s)", time.monotonic() - t0, ""
    finally:
        if child.poll() is not None:
            with _CHILDREN_LOCK:
                _CHILDREN.discard(child)
    return _outcome(rc, out, time.monotonic() - t0, tail_chars)


def _outcome(rc: int, out: str, dt: float, tail_chars: int) -> tuple[str, str, float, str]:
    """:func:`run_suite`'s answer from pytest's exit code and output."""
    tail = out[-tail_chars:]
    if rc == 0:
        return "passed", "", dt, tail
    if rc == 5:
        return "failed", "(no tests collected)", dt, tail
    if rc == 4:  # a usage error: in a targeted run, a catcher that does not exist
        return (
            "failed",
            "(pytest usage error: " + (out.strip().splitlines() or ["?"])[-1][:200] + ")",
            dt,
            tail,
        )
    return "failed", first_failure(out), dt, tail


def _python(root: Path) -> str:
    venv = root / ".venv" / "bin" / "python"
    return str(venv) if venv.exists() else sys.executable


# -- main ---------------------------------------------------------------------------------------
def _table(rows: list[dict]) -> str:
    heads = ("fault", "file", "result", "first failing test", "s")
    data = [
        (
            r["name"],
            r["file"],
            r["result"] + (" (setup error)" if r.get("how", "").startswith("ERROR") else ""),
            r["first_failure"] or "-",
            f"{r['seconds']:.0f}",
        )
        for r in rows
    ]
    widths = [
        max(len(h), *(len(d[i]) for d in data)) if data else len(h) for i, h in enumerate(heads)
    ]
    line = "  ".join(h.ljust(w) for h, w in zip(heads, widths))
    out = [line, "  ".join("-" * w for w in widths)]
    out += ["  ".join(c.ljust(w) for c, w in zip(d, widths)) for d in data]
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument(
        "--only", action="append", metavar="NAME", help="run only this fault (repeatable)"
    )
    ap.add_argument(
        "--list", action="store_true", help="list the faults and whether each snippet applies"
    )
    ap.add_argument(
        "--json", action="store_true", help="print one JSON object instead of the table"
    )
    ap.add_argument(
        "--restore",
        action="store_true",
        help="restore files left mutated by a killed run, then exit",
    )
    ap.add_argument(
        "--targeted",
        action="store_true",
        help="run each fault against its catchers alone (each must fail), after one run of all the "
        "catchers on the unmutated tree (which must pass)",
    )
    ap.add_argument(
        "--fresh-interpreters",
        action="store_true",
        help="--targeted: each run in a new interpreter (default: forked from one that imported "
        "the libraries, PRELOADED)",
    )
    ap.add_argument(
        "--no-baseline", action="store_true", help="--targeted: skip the catchers' unmutated run"
    )
    ap.add_argument(
        "--jobs",
        type=int,
        default=2,
        metavar="N",
        help="--targeted: faults run side by side, each in its own copy of the tree (default 2)",
    )
    ap.add_argument(
        "--timeout",
        type=float,
        default=None,
        help="seconds allowed per pytest run (default 900; --targeted: 120)",
    )
    ap.add_argument(
        "--baseline", action="store_true", help="first run the unmutated suite; stop if it fails"
    )
    ap.add_argument(
        "--no-confirm",
        action="store_true",
        help="skip re-running a caught fault's failing test on the restored tree",
    )
    ap.add_argument(
        "--plain-order", action="store_true", help="run the suite in pytest's own file order"
    )
    ap.add_argument(
        "--root", type=Path, default=ROOT, help="repository to mutate (default: this one)"
    )
    ap.add_argument(
        "--pytest-arg",
        action="append",
        default=[],
        metavar="ARG",
        help="one more argument for pytest, e.g. --pytest-arg=--deselect=tests/test_x.py::test_y",
    )
    ap.add_argument(
        "-v", "--verbose", action="store_true", help="print pytest's output tail of every run"
    )
    args = ap.parse_args(argv)
    global _USE_SERVERS
    if args.fresh_interpreters:
        _USE_SERVERS = False
    if args.timeout is None:
        args.timeout = 120.0 if args.targeted else 900.0
    root = args.root.resolve()

    def log(*a):
        print(*a, file=sys.stderr, flush=True)

    if args.restore:
        msgs = restore_leftovers(root)
        for m in msgs:
            log(m)
        if not msgs:
            log("nothing to restore")
        return 0

    leftovers = _leftovers(root)
    if leftovers:
        log("a killed run left backups behind (the files may still hold a fault):")
        for p in leftovers:
            log(f"    {p.relative_to(root)}")
        log(f"run: {Path(sys.argv[0]).as_posix()} --restore")
        return 2

    faults = FAULTS
    if args.only:
        unknown = [n for n in args.only if n not in {f.name for f in FAULTS}]
        if unknown:
            log(
                f"unknown fault(s): {', '.join(unknown)}; known: "
                f"{', '.join(f.name for f in FAULTS)}"
            )
            return 2
        faults = [f for f in FAULTS if f.name in args.only]
    names = [f.name for f in FAULTS]
    dup = {n for n in names if names.count(n) > 1}
    if dup:
        log(f"duplicate fault names: {', '.join(sorted(dup))}")
        return 2

    problems = snippet_problems(root, faults)
    if args.list:
        bad = {p.split(":")[0].removeprefix("fault ") for p in problems}
        for f in faults:
            mark = "ROTTEN" if f.name in bad else "ok"
            print(f"{f.name:32s} {mark:6s} {f.file:40s} {f.description}")
            for c in f.catchers:
                print(f"{'':40s}caught by {c}")
        for p in problems:
            log(p)
        return 2 if problems else 0
    if problems:
        for p in problems:
            log(p)
        return 2

    for sig in _SIGNALS:
        signal.signal(sig, _on_signal)

    python = _python(root)
    if args.targeted:
        return targeted(args, root, faults, python, log)
    extra = list(args.pytest_arg) + test_args(root, args.plain_order)
    rows: list[dict] = []
    warnings: list[str] = []
    baseline = None
    try:
        if args.baseline:
            log("baseline: the unmutated suite ...")
            status, first, dt, tail = run_suite(root, args.timeout, extra, python)
            baseline = {"result": status, "first_failure": first, "seconds": round(dt, 1)}
            log(f"baseline: {status} in {dt:.0f} s {first}")
            if status != "passed":
                log(tail)
                log("the suite fails without any fault: fix the tree first")
                return 2
        for f in faults:
            log(f"{f.name}: {f.description} ...")
            mut = Mutation(root, f)
            try:
                mut.apply()
                status, first, dt, tail = run_suite(root, args.timeout, extra, python)
            finally:
                _kill_child()
                w = mut.restore()
                if w:
                    warnings.append(w)
                    log("WARNING:", w)
            result = {"failed": "caught", "passed": "SURVIVED", "timeout": "TIMEOUT"}[status]
            row = {
                "name": f.name,
                "file": f.file,
                "description": f.description,
                "result": result,
                "first_failure": first,
                "how": failure_reason(tail) if result == "caught" else "",
                "seconds": round(dt, 1),
            }
            if args.verbose:
                log(tail)
            if result == "caught" and not args.no_confirm and "::" in first:
                c_status, c_first, _, c_tail = run_suite(
                    root, args.timeout, list(args.pytest_arg) + [first], python
                )
                row["confirmed"] = c_status == "passed"
                if c_status != "passed":
                    row["result"] = "UNCONFIRMED"
                    log(f"    {first} fails without the fault too:\n{c_tail}")
            log(
                f"    {row['result']} in {dt:.0f} s {first}"
                + (f"\n      {row['how']}" if row["how"] else "")
            )
            rows.append(row)
    except Interrupted as e:
        log(f"interrupted ({e}); every file restored")
        _emit(args, rows, baseline, warnings, interrupted=True)
        return 130
    finally:
        _kill_child()
    _emit(args, rows, baseline, warnings)
    return 0 if all(r["result"] == "caught" for r in rows) else 1


#: What a private copy of the tree for ``--targeted`` leaves out (nothing a test reads).
_COPY_IGNORE = shutil.ignore_patterns(
    ".git",
    ".venv",
    "exports",
    "site",
    "node_modules",
    "__pycache__",
    "*.egg-info",
    "*" + BACKUP_SUFFIX,
    ".mutate-*",
)


def _private_copies(root: Path, n: int) -> tuple[Path, list[Path]]:
    """``n`` copies of the working tree in a temporary folder: faults are applied there, never in
    ``root``."""
    top = Path(tempfile.mkdtemp(prefix="bvsr-mutate-"))
    copies = [top / f"tree{i}" for i in range(n)]
    for c in copies:
        shutil.copytree(root, c, ignore=_COPY_IGNORE, symlinks=True)
    return top, copies


def _run_fault_in(copy: Path, f: Fault, args, python: str) -> tuple[str, str, float, str]:
    """``f`` applied to the private ``copy``, its catchers run there, the file put back for the next
    fault."""
    path = copy / f.file
    if not path.resolve().is_relative_to(
        copy.resolve()
    ):  # a link out of the copy would mutate the real tree
        raise SnippetError(f, -1)
    original = path.read_bytes()
    text = original.decode("utf-8")
    if text.count(f.old) != 1:
        raise SnippetError(f, text.count(f.old))
    path.write_bytes(text.replace(f.old, f.new, 1).encode("utf-8"))
    try:
        return run_suite(
            copy,
            args.timeout,
            list(args.pytest_arg) + list(f.catchers),
            python,
            TARGETED_ARGS,
            200_000,
        )  # every line of pytest's short summary
    finally:
        path.write_bytes(original)


def targeted(args, root: Path, faults: list[Fault], python: str, log) -> int:
    """Each fault against its own catchers: caught when every catcher fails, PARTIAL when some pass
    (they no longer catch it), SURVIVED when all pass, BROKEN when a catcher does not exist. First,
    unless ``--no-baseline``, every catcher runs on the unmutated tree and must pass, so that a
    failure under a fault is the fault's. The faults are applied in private copies of the tree
    (``--jobs`` of them, run side by side), so ``root`` is never mutated, and a killed run leaves
    nothing to restore."""
    bare = [f.name for f in faults if not f.catchers]
    if bare:
        log(f"faults without catchers (add them to FAULTS): {', '.join(bare)}")
        return 2
    every = list(dict.fromkeys(c for f in faults for c in f.catchers))
    jobs = max(1, min(args.jobs, len(faults)))
    rows: list[dict | None] = [None] * len(faults)
    baseline = None
    t_start = time.monotonic()
    top, copies = _private_copies(root, jobs)
    free: list[Path] = list(copies)
    free_lock = threading.Lock()

    def one(i: int, f: Fault) -> None:
        with free_lock:
            copy = free.pop()
        try:
            status, first, dt, tail = _run_fault_in(copy, f, args, python)
        except SnippetError as e:
            status, first, dt, tail = "failed", f"(rotten fault: {e})", 0.0, ""
        finally:
            with free_lock:
                free.append(copy)
        failed = failed_ids(tail) if status == "failed" else set()
        missed = missed_catchers(f.catchers, failed)
        if status == "timeout":
            result = "TIMEOUT"
        elif (
            first.startswith(("(pytest usage error", "(rotten fault"))
            or first == "(no tests collected)"
        ):
            result = "BROKEN"  # a catcher that does not exist: the list has rotted
        elif not missed:
            result = "caught"
        else:
            result = "SURVIVED" if len(missed) == len(f.catchers) else "PARTIAL"
        rows[i] = {
            "name": f.name,
            "file": f.file,
            "description": f.description,
            "result": result,
            "first_failure": first,
            "how": failure_reason(tail) if result == "caught" else "",
            "seconds": round(dt, 1),
            "catchers": list(f.catchers),
            "missed": missed,
        }
        if args.verbose or result != "caught":
            log(tail[-3000:])
        log(
            f"{f.name}: {result} in {dt:.0f} s"
            + (f"; not failing: {', '.join(missed)}" if missed else "")
        )

    pool = ThreadPoolExecutor(jobs)
    try:
        if not args.no_baseline:
            log(f"baseline: the {len(every)} catchers on the unmutated tree, in {jobs} parts ...")
            parts = [every[k::jobs] for k in range(jobs)]
            runs = list(
                pool.map(
                    lambda k: run_suite(
                        copies[k],
                        max(args.timeout, 600.0),
                        list(args.pytest_arg) + parts[k],
                        python,
                        TARGETED_ARGS,
                        200_000,
                    ),
                    range(jobs),
                )
            )
            status = "passed" if all(r[0] == "passed" for r in runs) else "failed"
            first = next((r[1] for r in runs if r[0] != "passed"), "")
            baseline = {
                "result": status,
                "first_failure": first,
                "seconds": round(max(r[2] for r in runs), 1),
            }
            log(f"baseline: {status} in {baseline['seconds']:.0f} s {first}")
            if status != "passed":
                for r in runs:
                    if r[0] != "passed":
                        log(r[3][-3000:])
                log(
                    "catchers fail without any fault (or do not exist): fix the tree or FAULTS "
                    "first"
                )
                _emit(args, [], baseline, [])
                return 2
        log(f"{len(faults)} faults, {jobs} at a time, each against its catchers ...")
        for future in [pool.submit(one, i, f) for i, f in enumerate(faults)]:
            future.result()
    except Interrupted as e:
        log(f"interrupted ({e}); the tree was never mutated (faults go to private copies)")
        _kill_child()
        _emit(args, [r for r in rows if r], baseline, [], interrupted=True)
        return 130
    finally:
        pool.shutdown(wait=False, cancel_futures=True)  # no fault starts after this
        _kill_child()  # the runs under way end, and with them their threads
        pool.shutdown(wait=True)
        _kill_child()
        _close_servers()
        shutil.rmtree(top, ignore_errors=True)
    done = [r for r in rows if r]
    _emit(args, done, baseline, [])
    if not args.json:
        print(
            f"targeted run: {len(done)} faults, {jobs} at a time, in "
            f"{time.monotonic() - t_start:.0f} s"
        )
    return 0 if all(r["result"] == "caught" for r in done) else 1


def _emit(args, rows, baseline, warnings, interrupted=False) -> None:
    survived = [r["name"] for r in rows if r["result"] != "caught"]
    if args.json:
        print(
            json.dumps(
                {
                    "faults": rows,
                    "baseline": baseline,
                    "survived": survived,
                    "warnings": warnings,
                    "interrupted": interrupted,
                    "all_caught": not survived and not interrupted,
                },
                indent=1,
            )
        )
        return
    print(_table(rows))
    print(
        f"\n{len(rows) - len(survived)} of {len(rows)} faults caught"
        + (f"; not caught: {', '.join(survived)}" if survived else "")
    )
    for w in warnings:
        print("WARNING:", w)


if __name__ == "__main__":
    sys.exit(main())
