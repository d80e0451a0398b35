"""Tests that catch a wrong answer: every expected value here comes from a
source independent of the code under test.

Sources, named at each test: the raw parameter file read with ``tomllib``
(never through the loader's derived properties), closed forms written here
(pi d^4 / 64, a cylinder's inertia, the pentagon 90 + 72 (i - 1) deg, the
linearised equilibrium of Eq 3-5 and Eq 10), published tables (ISO 2306 tap
drills, ISO 2338 dowels), and second methods (MuJoCo compiling the MJCF and
URDF the exporters produce in memory, trimesh's mesh inertia against the
B-rep one, probing the B-rep solid at chosen points). Unit factors are
written out by hand (1 g/cm^3 = 1e-3 g/mm^3 = 1e-6 kg/mm^3), never taken from
:mod:`bvsr_cad.units`.

All fast: in-memory objects only (one assembly, one robot model, one MJCF
compiled without its meshes). ``tools/mutate.py`` relies on these tests.
"""

from __future__ import annotations

import dataclasses
import math
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest

from bvsr_cad.assembly.assemble import build_assembly
from bvsr_cad.parameters import layout

from .test_parts import _bellows_volume_closed_form

THETA_MAX = 0.5  # a fixed joint limit: these tests do not depend on the clearance analysis
N_SOA = 5  # the paper: five SOAs per joint on a regular pentagon (alpha_1 = 72 deg)
KG_PER_G_CM3_MM3 = 1e-6  # 1 g/cm^3 = 1e-3 g/mm^3 = 1e-6 kg/mm^3
#: ISO 2306 / ISO 261 tap drill for the coarse metric threads of the threaded vertebra socket.
ISO_TAP_DRILL = {4.0: 3.3, 5.0: 4.2, 6.0: 5.0}
#: The MJCF mounts the tail frame in MuJoCo's world: tail Z -> world +X, tail Y -> world +Z,
#: tail X -> world +Y (written here from the README, not read from the exporter).
R_WORLD_TAIL = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


# -- the raw parameter file: the inputs, read without the loader ---------------------------------
@pytest.fixture(scope="module")
def bvsr_spec(bvsr_spec):
    """The shipped file with its tables' values: this module checks that every table's number
    reaches its consumers exactly. The shipped ``[calibration]`` replaces some of them in their one
    home; that path is checked against the file's fitted numbers in ``test_calibration``."""
    from bvsr_cad.analysis.calibrate import uncalibrated

    return uncalibrated(bvsr_spec)


@pytest.fixture(scope="module")
def raw(bvsr_data):
    """Plain numbers of params/bvsr.toml (tomllib), named as the paper does."""
    d = bvsr_data
    j, soa = d["joint"], d["soa"]
    rod_mat = d["materials"][d["vertebra"]["material"]]
    return dict(
        H_j=j["joint_height_mm"],
        H_a=j["gap_mm"],
        D_a=j["pitch_diameter_mm"],
        D_p=j["panel_diameter_mm"],
        D_b=j["base_diameter_mm"],
        H=soa["height_mm"],
        H_o=soa["origami_height_mm"],
        d_rod=d["vertebra"]["diameter_mm"],
        E_rod_mpa=rod_mat["youngs_modulus_mpa"],
        rho_rod=rod_mat["density_g_cm3"],
        rho_panel=d["materials"][d["use"]["panel"]]["density_g_cm3"],
        rho_soa=d["materials"][d["use"]["soa"]]["density_g_cm3"],
        segments=d["segments"],
        joints_per_segment=d["joints_per_segment"],
        A_mm2=d["actuation"]["effective_area_mm2"],
        m_a_per_kpa=d["actuation"]["stiffness_slope_n_per_m_per_kpa"],
        n_a=d["actuation"]["stiffness_offset_n_per_m"],
        c=d["actuation"]["damping_n_s_per_m"],
        hole_comp=d["fabrication"]["hole_compensation_mm"],
        rod_clearance=d["socket"]["rod_clearance_mm"],
    )


@pytest.fixture(scope="module")
def asm(bvsr_spec):
    return build_assembly(bvsr_spec)


@pytest.fixture(scope="module")
def robot(asm):
    """Without its collision shapes: mass-less, checked elsewhere (tests/test_robot.py), and their
    fits are most of the model's making (seconds each time ``tools/mutate.py --targeted`` runs a
    catcher here)."""
    from bvsr_cad.assembly.robot import robot_model

    return robot_model(asm, [THETA_MAX] * asm.spec.joints, collisions=False)


def _without_meshes(root: ET.Element) -> str:
    """The XML with its mesh assets and mesh geoms removed (visual geoms carry no mass: density
    0)."""
    for parent in list(root.iter()):
        for child in list(parent):
            if child.tag == "mesh" or (
                child.tag in ("geom", "visual")
                and (child.get("mesh") is not None or child.find(".//mesh") is not None)
            ):
                parent.remove(child)
    return ET.tostring(root, encoding="unicode")


def _mesh_files(robot) -> dict[str, str]:
    return {v.name: f"{v.name}.stl" for link in robot.links.values() for v in link.visuals}


@pytest.fixture(scope="module")
def mjcf(robot):
    """MuJoCo's compiled model of the per-joint MJCF with the URDF's exact chain
    (robot/bvsr_exact.xml), made in memory: the hand calculations below follow its theta_a, chord,
    theta_b and phi joints."""
    from bvsr_cad.exporters.mjcf import mjcf_tree

    tree, _ = mjcf_tree(robot, _mesh_files(robot), False, chain="exact")
    return mujoco.MjModel.from_xml_string(_without_meshes(tree.getroot()))


@pytest.fixture(scope="module")
def urdf_root(robot) -> ET.Element:
    from bvsr_cad.exporters.urdf import urdf_tree

    return urdf_tree(robot, _mesh_files(robot)).getroot()


def _n_joints(raw) -> int:
    return raw["segments"] * raw["joints_per_segment"]


def _tail_length_mm(raw) -> float:
    """n joints of H_a and n + 1 panels of H_j - H_a."""
    n = _n_joints(raw)
    return n * raw["H_a"] + (n + 1) * (raw["H_j"] - raw["H_a"])


def _ei_nmm2(raw) -> float:
    """E I of a solid round rod, I = pi d^4 / 64 (N mm^2)."""
    return raw["E_rod_mpa"] * math.pi * raw["d_rod"] ** 4 / 64.0


def _beta(asm) -> float:
    return math.radians(asm.taper_half_angle_deg)


# -- units: hand-written factors ------------------------------------------------------------------
def test_unit_conversions_by_hand():
    from bvsr_cad import units

    assert units.mass_g(1000.0, 1.0) == pytest.approx(1.0)  # 1 cm^3 of water weighs 1 g
    assert units.mass_g(1.0, 7.85) == pytest.approx(7.85e-3)
    assert units.g_cm3_to_kg_m3(1.0) == pytest.approx(1000.0)
    assert units.g_to_kg(1000.0) == pytest.approx(1.0)
    assert units.g_mm2_to_kg_m2(1.0) == pytest.approx(1e-9)  # 1e-3 kg * 1e-6 m^2
    assert units.mm_to_m(1000.0) == pytest.approx(1.0)
    assert units.nmm_to_nm(1000.0) == pytest.approx(1.0)
    assert units.kpa_to_pa(1.0) == pytest.approx(1000.0)
    assert units.mm2_to_m2(1e6) == pytest.approx(1.0)


# -- the rod: closed forms with the table's E and density ----------------------------------------
def test_rod_section_is_the_closed_form_with_the_tables_material(bvsr_spec, raw):
    from bvsr_cad.models.rod import rod_section

    rod = rod_section(bvsr_spec)
    d = raw["d_rod"]
    assert rod.diameter_mm == d
    assert rod.area_mm2 == pytest.approx(math.pi * d * d / 4, rel=1e-12)
    assert rod.second_moment_mm4 == pytest.approx(math.pi * d**4 / 64, rel=1e-12)
    assert rod.second_moment_mm4 == pytest.approx(63.617, abs=1e-3)  # pi 6^4 / 64 by hand
    assert rod.flexural_rigidity_n_mm2 == pytest.approx(_ei_nmm2(raw), rel=1e-12)
    assert rod.flexural_rigidity_n_mm2 == pytest.approx(
        178128.3, abs=0.1
    )  # nylon 2800 MPa x 63.617 mm^4
    assert rod.bending_stiffness_nmm_per_rad(raw["H_a"]) == pytest.approx(
        _ei_nmm2(raw) / raw["H_a"], rel=1e-12
    )
    assert rod.bending_stiffness_nm_per_rad(raw["H_a"]) == pytest.approx(4.8789, abs=1e-4)
    # Mass per length: area (mm^2) x density (g/cm^3 = 1e-3 g/mm^3).
    assert rod.mass_per_length_g_mm == pytest.approx(
        math.pi * d * d / 4 * raw["rho_rod"] * 1e-3, rel=1e-12
    )
    assert rod.mass_per_length_g_mm == pytest.approx(0.032233, abs=1e-6)


@pytest.mark.parametrize("material", ["nylon", "PVC", "TPU", "rubber"])
def test_rod_section_follows_the_vertebra_material(bvsr_spec, bvsr_data, material):
    from bvsr_cad.models.rod import rod_section

    spec = dataclasses.replace(
        bvsr_spec, vertebra=dataclasses.replace(bvsr_spec.vertebra, material=material)
    )
    table = bvsr_data["materials"][material]
    rod = rod_section(spec)
    d = spec.vertebra.diameter_mm
    assert rod.flexural_rigidity_n_mm2 == pytest.approx(
        table["youngs_modulus_mpa"] * math.pi * d**4 / 64
    )
    assert rod.mass_per_length_g_mm == pytest.approx(
        table["density_g_cm3"] * 1e-3 * math.pi * d * d / 4
    )


def test_statics_rod_stiffness_is_ei_over_l(bvsr_spec, raw):
    from bvsr_cad.models.statics import TailStatics

    st = TailStatics.from_spec(bvsr_spec)
    assert st.rod_nmm_per_rad == pytest.approx(_ei_nmm2(raw) / raw["H_a"], rel=1e-12)


# -- the SOA force law: Eq 3-4 with the damper, by hand ------------------------------------------
def test_soa_force_law_by_hand(bvsr_spec, raw):
    from bvsr_cad.models.actuator import soa_force_law

    law = soa_force_law(bvsr_spec)
    p_pa, dl_m, rate = 1e5, 1e-3, 0.01
    # F = P A - (m_a P + n_a) dl - c dl/dt with m_a given per kPa (Eq 4 read with P in kPa, k in
    # N/m).
    k = raw["m_a_per_kpa"] * p_pa / 1000.0 + raw["n_a"]
    expected = p_pa * raw["A_mm2"] * 1e-6 - k * dl_m - raw["c"] * rate
    assert float(law.force_n(p_pa, dl_m, rate)) == pytest.approx(expected, rel=1e-12)
    assert float(law.force_n(p_pa, dl_m, rate)) == pytest.approx(
        9.442, abs=1e-9
    )  # 13.82 - 3.858 - 0.52 N
    # Stretched with no pressure the SOA pulls back; compressed it pushes.
    assert float(law.force_n(0.0, 1e-3)) == pytest.approx(-raw["n_a"] * 1e-3)
    assert float(law.force_n(0.0, -1e-3)) == pytest.approx(raw["n_a"] * 1e-3)


def test_statics_actuator_in_n_mm_kpa_by_hand(bvsr_spec, raw):
    from bvsr_cad.models.statics import Actuator

    act = Actuator.from_spec(bvsr_spec)
    # 100 kPa on 138.2 mm^2 = 0.1 N/mm^2 x 138.2 mm^2; k = 9.4 x 100 + 2918 N/m = 3.858 N/mm.
    assert float(act.force_n(100.0, 0.0)) == pytest.approx(0.1 * raw["A_mm2"], rel=1e-12)
    assert float(act.force_n(100.0, 1.0)) == pytest.approx(0.1 * raw["A_mm2"] - 3.858, rel=1e-12)


def test_linearised_equilibrium_of_one_pressurised_soa(bvsr_spec, raw):
    """Eq 3-5 and Eq 10 by hand, small pressure, no gravity, no taper.

    A joint bent by w = theta (cos phi, sin phi) shortens the SOA at angle a on
    the pitch radius r by r theta cos(a - phi), so dl = J w with J = -r (cos a, sin a).
    Equilibrium (K_rod I + sum k_i J_i J_i^T) w = A sum P_i J_i. With SOA 1
    (a = 90 deg) at P and the others at 0: u = 0 and
    v = -A P r / (E I / L + r^2 (5/2 n_a + m_a P)), using sum sin^2 = 5/2 over a pentagon.
    """
    from bvsr_cad.models.statics import TailStatics

    spec = layout.replace_taper(bvsr_spec, 0.0)
    st = TailStatics.from_spec(spec)
    p_kpa = 1.0
    lines = np.zeros((1, raw["segments"], N_SOA))
    lines[0, 0, 0] = p_kpa
    w = st.forward(lines)[0]
    r = raw["D_a"] / 2
    k_rod = _ei_nmm2(raw) / raw["H_a"]  # N mm / rad
    n_a, m_a = raw["n_a"] * 1e-3, raw["m_a_per_kpa"] * 1e-3  # N/mm, N/mm per kPa
    force = p_kpa * 1e-3 * raw["A_mm2"]  # N
    v = -force * r / (k_rod + r * r * (2.5 * n_a + m_a * p_kpa))
    seg1 = slice(0, raw["joints_per_segment"])
    np.testing.assert_allclose(w[seg1, 1], v, rtol=2e-3)
    np.testing.assert_allclose(w[seg1, 0], 0.0, atol=1e-9)
    np.testing.assert_allclose(
        w[raw["joints_per_segment"] :], 0.0, atol=1e-12
    )  # segment 2 unpressurised


def test_workspace_lumped_masses_by_hand(asm, raw):
    from bvsr_cad.analysis.workspace import lumped_masses

    m = lumped_masses(asm)
    t = raw["H_j"] - raw["H_a"]
    rod_area = math.pi * raw["d_rod"] ** 2 / 4
    v_soa = _bellows_volume_closed_form(asm.spec.soa, raw["D_b"])
    for k in range(asm.spec.panels):
        v_panel = asm.parts[asm.panel(k).part].solid.volume
        expected = (v_panel * raw["rho_panel"] + rod_area * t * raw["rho_rod"]) * KG_PER_G_CM3_MM3
        assert m.panel_kg[k] == pytest.approx(expected, rel=1e-9), k
    joint = (
        N_SOA * v_soa * raw["rho_soa"] + rod_area * raw["H_a"] * raw["rho_rod"]
    ) * KG_PER_G_CM3_MM3
    np.testing.assert_allclose(m.joint_kg, joint, rtol=1e-6)


# -- the chord -------------------------------------------------------------------------------------
def test_chord_is_two_l_sin_half_theta_over_theta():
    from bvsr_cad.assembly.robot import chord_m
    from bvsr_cad.models.kinematics import chord_length_mm

    L = 36.51
    th = np.array([1e-9, 1e-3, 0.05, 0.3, 0.8, 1.5, -0.4])
    expected = 2 * L * np.sin(th / 2) / th
    np.testing.assert_allclose(chord_length_mm(th, L), expected, rtol=1e-12)
    np.testing.assert_allclose(chord_m(th, L / 1000), expected / 1000, rtol=1e-12)
    assert float(chord_length_mm(0.0, L)) == pytest.approx(L, rel=1e-15)
    # A quarter circle: chord = r sqrt(2) with r = L / theta.
    assert float(chord_length_mm(math.pi / 2, L)) == pytest.approx(
        L / (math.pi / 2) * math.sqrt(2), rel=1e-12
    )


# -- panel geometry: thickness, taper, bore, pentagon --------------------------------------------
def test_panels_sit_every_h_j_and_are_h_j_minus_h_a_thick(asm, raw):
    t = raw["H_j"] - raw["H_a"]
    assert t == pytest.approx(6.00, abs=1e-9)  # Table I: 42.51 - 36.51
    for k in range(asm.spec.panels):
        inst = asm.panel(k)
        assert np.asarray(inst.transform)[:3, 3] == pytest.approx(
            [0.0, 0.0, k * raw["H_j"]], abs=1e-9
        )
        lay = asm.panel_layouts[k]
        assert lay.thickness_mm == pytest.approx(t, abs=1e-12)
    # The root panel has no collar (threaded socket): its B-rep is exactly t tall.
    box = asm.parts[asm.panel(0).part].solid.bounding_box()
    assert box.max.Z - box.min.Z == pytest.approx(t, abs=1e-4)
    assert asm.spec.length_mm == pytest.approx(_tail_length_mm(raw), abs=1e-9)
    assert _tail_length_mm(raw) == pytest.approx(261.06, abs=1e-9)


def test_rims_and_pitch_circles_follow_one_cone(asm, raw):
    tan_b = math.tan(_beta(asm))
    t = raw["H_j"] - raw["H_a"]
    for lay in asm.panel_layouts:
        z0 = lay.index * raw["H_j"]
        assert lay.rim_radius_lower_mm == pytest.approx(raw["D_p"] / 2 - z0 * tan_b, abs=1e-9)
        assert lay.rim_radius_upper_mm == pytest.approx(raw["D_p"] / 2 - (z0 + t) * tan_b, abs=1e-9)
        assert lay.pitch_radius_lower_mm == pytest.approx(raw["D_a"] / 2 - z0 * tan_b, abs=1e-9)
        assert lay.pitch_radius_upper_mm == pytest.approx(
            raw["D_a"] / 2 - (z0 + t) * tan_b, abs=1e-9
        )
    # The B-rep's rim: a point just inside the cone at each face is material, just outside is not
    # (probed at 0 deg, where no feature reaches the rim).
    import build123d as bd

    for k in (0, asm.spec.panels - 1):
        solid = asm.parts[asm.panel(k).part].solid
        z0 = k * raw["H_j"]
        for z in (0.02, t - 0.02):
            r = raw["D_p"] / 2 - (z0 + z) * tan_b
            assert solid.is_inside(bd.Vector(r - 0.005, 0, z)), (k, z)
            assert not solid.is_inside(bd.Vector(r + 0.005, 0, z)), (k, z)


def test_panels_narrow_from_root_to_tip_on_the_b_rep(asm, raw):
    """The paper (Sec. II-E): "the diameter of the rigid panels decreasing from the root to the
    tip". Measured on each panel's B-rep (its bounding box across X, where the rim is widest: the
    lower face): strictly decreasing, the root panel at D_p (the cone starts at the root face) and
    every step the same (one cone). The angle is not read back from the assembly, so a cone turned
    the wrong way cannot pass. Tolerance 1e-3 mm: the B-rep's bounding box of a circle (exact up to
    the kernel's 1e-7 mm)."""
    widths = []
    for k in range(asm.spec.panels):
        box = asm.parts[asm.panel(k).part].solid.bounding_box()
        widths.append(box.max.X - box.min.X)
    steps = -np.diff(widths)
    assert (steps > 0.1).all(), (
        widths
    )  # strictly narrower, each by tenths of a mm (2 H_j tan(beta))
    assert widths[0] == pytest.approx(raw["D_p"], abs=1e-3)
    np.testing.assert_allclose(steps, steps.mean(), atol=1e-3)


@pytest.mark.parametrize("socket", ["threaded", "set_screw"])
@pytest.mark.parametrize("diameter", [4.0, 5.0, 6.0])
def test_rod_bore_is_the_iso_tap_drill_or_the_rod_with_clearance(bvsr_spec, raw, diameter, socket):
    """ISO 2306 tap drills (M4 3.3, M5 4.2, M6 5.0) or d + clearance, plus the printed-hole
    compensation."""
    spec = dataclasses.replace(
        bvsr_spec,
        vertebra=dataclasses.replace(bvsr_spec.vertebra, diameter_mm=diameter, socket=socket),
    )
    nominal = ISO_TAP_DRILL[diameter] if socket == "threaded" else diameter + raw["rod_clearance"]
    expected = nominal + raw["hole_comp"]
    for k in range(spec.panels):
        bores = [c for c in layout.panel_layout(spec, k).cuts if c.role == "rod"]
        assert bores and all(c.diameter_mm == pytest.approx(expected, abs=1e-12) for c in bores), k
    # A threaded bore leaves thread to cut (smaller than the rod), a set-screw bore lets the rod
    # through.
    assert (expected < diameter) == (socket == "threaded")


def test_rod_bore_in_the_panel_solids(asm, raw):
    """Probe each unique panel's B-rep: inside the M6 tap drill is empty, just outside is
    material."""
    import build123d as bd

    bore_r = (ISO_TAP_DRILL[raw["d_rod"]] + raw["hole_comp"]) / 2  # 2.55 mm
    t = raw["H_j"] - raw["H_a"]
    seen = set()
    for inst in (i for i in asm.instances if i.role == "panel"):
        if inst.part in seen:
            continue
        seen.add(inst.part)
        solid = asm.parts[inst.part].solid
        for ang in (0.0, 100.0, 200.0):
            c, s = math.cos(math.radians(ang)), math.sin(math.radians(ang))
            for z in (t * 0.25, t * 0.5, t * 0.75):
                assert not solid.is_inside(
                    bd.Vector((bore_r - 0.03) * c, (bore_r - 0.03) * s, z)
                ), inst.part
                assert solid.is_inside(bd.Vector((bore_r + 0.03) * c, (bore_r + 0.03) * s, z)), (
                    inst.part
                )
    assert len(seen) >= 3


def test_soas_sit_on_the_pentagon(asm, raw):
    """SOA i of every joint at 90 + 72 (i - 1) deg from +X towards +Y, on the pitch cone, numbered
    by line."""
    tan_b = math.tan(_beta(asm))
    t = raw["H_j"] - raw["H_a"]
    depth = (raw["H"] - raw["H_a"]) / 2  # each flange sits (H - H_a) / 2 deep: 0.545 mm
    n = _n_joints(raw)
    soas = [i for i in asm.instances if i.role == "soa"]
    assert len(soas) == N_SOA * n == 30
    assert len(asm.instances_of("soa")) == N_SOA * n
    for k in range(1, n + 1):
        mine = sorted((i for i in soas if i.joint == k), key=lambda i: i.soa_index)
        assert [i.soa_index for i in mine] == [1, 2, 3, 4, 5]
        for i, inst in enumerate(mine, start=1):
            a = math.radians(90.0 + 72.0 * (i - 1))
            z = (k - 1) * raw["H_j"] + t - depth  # the pocket floor of panel k - 1's upper face
            r = raw["D_a"] / 2 - ((k - 1) * raw["H_j"] + t) * tan_b
            origin = np.asarray(inst.transform)[:3, 3]
            assert origin == pytest.approx([r * math.cos(a), r * math.sin(a), z], abs=1e-9), (
                inst.name
            )
            assert inst.name == f"j{k}_soa{i}" and inst.pressure_line == i
            assert inst.segment == (k - 1) // raw["joints_per_segment"] + 1
    # soa1 dorsal (+Y), soa2 at 162 deg (-X side), soa3/soa4 ventral.
    j1 = {i.soa_index: np.asarray(i.transform)[:3, 3] for i in soas if i.joint == 1}
    assert (
        abs(j1[1][0]) < 1e-9 and j1[1][1] > 20 and j1[2][0] < -20 and j1[3][1] < 0 and j1[4][1] < 0
    )


def test_pockets_are_cut_on_the_pentagon_in_the_solid(asm, raw):
    """Probe the root panel's B-rep: a void at each SOA pocket, material half-way between
    pockets."""
    import build123d as bd

    tan_b = math.tan(_beta(asm))
    t = raw["H_j"] - raw["H_a"]
    depth = (raw["H"] - raw["H_a"]) / 2
    r = raw["D_a"] / 2 - t * tan_b
    solid = asm.parts[asm.panel(0).part].solid
    z = t - depth / 2
    for i in range(1, N_SOA + 1):
        a = math.radians(90.0 + 72.0 * (i - 1))
        assert not solid.is_inside(bd.Vector(r * math.cos(a), r * math.sin(a), z)), i
        b = a + math.radians(36.0)
        assert solid.is_inside(bd.Vector(r * math.cos(b), r * math.sin(b), z)), i


def test_features_between_the_pockets_sit_on_the_mid_angles(asm, raw):
    """Lightening holes, segment-2 tubes and mount inserts half-way between SOAs: 126 + 72 (i - 1)
    deg."""
    import build123d as bd

    checked = 0
    for lay in asm.panel_layouts:
        for c in lay.cuts:
            if (
                c.role in ("lightening", "tube", "insert")
                and c.name.rsplit("_", 1)[-1].isdigit()
                and not c.name.startswith(("payload", "tube_s3"))
            ):
                i = int(c.name.rsplit("_", 1)[-1])
                a = math.radians(126.0 + 72.0 * (i - 1))
                x, y = c.xy
                rho = math.hypot(x, y)
                assert (x, y) == pytest.approx((rho * math.cos(a), rho * math.sin(a)), abs=1e-9), (
                    lay.name,
                    c.name,
                )
                checked += 1
    assert checked >= 3 * N_SOA
    # In the solid: panel 1's lightening holes are voids.
    lay = asm.panel_layouts[1]
    solid = asm.parts[asm.panel(1).part].solid
    holes = [c for c in lay.cuts if c.role == "lightening"]
    assert len(holes) == N_SOA
    for c in holes:
        i = int(c.name.rsplit("_", 1)[-1])
        a = math.radians(126.0 + 72.0 * (i - 1))
        rho = math.hypot(*c.xy)
        assert not solid.is_inside(
            bd.Vector(rho * math.cos(a), rho * math.sin(a), lay.thickness_mm / 2)
        ), c.name


def test_flange_pockets_are_d_b_plus_clearance(asm, raw, bvsr_data):
    """A pocket takes the D_b = 24.32 mm flange with the 0.10 mm bonding clearance: probed in the
    solid."""
    import build123d as bd

    d_pocket = raw["D_b"] + bvsr_data["fabrication"]["pocket_clearance_mm"]
    assert d_pocket == pytest.approx(24.42)
    for lay in asm.panel_layouts:
        pockets = [c for c in lay.cuts if c.role == "pocket"]
        assert len(pockets) == N_SOA * (int(lay.lower_pockets) + int(lay.upper_pockets))
        assert all(c.diameter_mm == pytest.approx(d_pocket, abs=1e-12) for c in pockets), lay.name
    lay = asm.panel_layouts[1]
    solid = asm.parts[asm.panel(1).part].solid
    depth = (raw["H"] - raw["H_a"]) / 2
    for c in (c for c in lay.cuts if c.name.startswith("pocket_upper_")):
        x, y = c.xy
        rho = math.hypot(x, y)
        ux, uy = -x / rho, -y / rho  # towards the tail axis: solid web beyond the pocket wall
        z = lay.thickness_mm - depth / 2
        r_in, r_out = d_pocket / 2 - 0.03, d_pocket / 2 + 0.03
        assert not solid.is_inside(bd.Vector(x + r_in * ux, y + r_in * uy, z)), c.name
        assert solid.is_inside(bd.Vector(x + r_out * ux, y + r_out * uy, z)), c.name


def test_soa_body_height_and_pocket_depth(asm, raw):
    """The SOA is H tall (flanges (H - H_o) / 2 each) and its flanges sit (H - H_a) / 2 deep."""
    box = asm.parts["soa"].solid.bounding_box()
    assert box.max.Z - box.min.Z == pytest.approx(
        raw["H"], abs=1e-4
    )  # fold_height_from = origami_height
    for lay in asm.panel_layouts:
        assert lay.pocket_depth_mm == pytest.approx((raw["H"] - raw["H_a"]) / 2, abs=1e-12)
        assert lay.pocket_depth_mm == pytest.approx(0.545, abs=1e-12)
    assert asm.spec.soa.flange_thickness_mm == pytest.approx((raw["H"] - raw["H_o"]) / 2)
    assert asm.spec.soa.flange_thickness_mm == pytest.approx(1.30, abs=1e-12)
    assert asm.parts["soa"].solid.volume == pytest.approx(
        _bellows_volume_closed_form(asm.spec.soa, raw["D_b"]), rel=1e-6
    )


# -- materials and masses --------------------------------------------------------------------------
def _hand_tail_mass_kg(asm, raw) -> float:
    """B-rep volumes (panels), the SOA closed form and the rod cylinder, times the table's
    densities."""
    n = _n_joints(raw)
    panels = sum(asm.parts[asm.panel(k).part].solid.volume for k in range(n + 1)) * raw["rho_panel"]
    soas = N_SOA * n * _bellows_volume_closed_form(asm.spec.soa, raw["D_b"]) * raw["rho_soa"]
    rods = (
        math.pi * raw["d_rod"] ** 2 / 4 * _tail_length_mm(raw) * raw["rho_rod"]
    )  # the rods span the tail
    return (panels + soas + rods) * KG_PER_G_CM3_MM3


#: Densities (g/cm^3) of the shipped tail's materials as their datasheets give them (the ranges the
#: parameter file's sources quote; a single figure as +-0.005, its last digit): an outside truth for
#: the masses.
DATASHEET_DENSITY_G_CM3 = {
    "PA12_MJF": (1.005, 1.015),
    "PU75A": (1.04, 1.06),
    "nylon": (1.135, 1.145),
}


def test_soa_and_tail_masses_within_the_datasheets_densities(asm, raw, bvsr_data):
    """The SOA's mass and the whole tail's against hand sums of their volumes (the bellows' closed
    form, the panels' B-rep volumes, the rod cylinders) times the datasheets' densities, bounds from
    each range's ends: a density that left its datasheet (a 10 % heavier SOA) fails, whatever the
    parameter file says."""
    use = bvsr_data["use"]
    assert (use["panel"], use["soa"], bvsr_data["vertebra"]["material"]) == (
        "PA12_MJF",
        "PU75A",
        "nylon",
    )
    lo, hi = (np.array([r[i] for r in DATASHEET_DENSITY_G_CM3.values()]) for i in (0, 1))
    g_per_mm3 = 1e-3  # per g/cm^3
    v_soa = _bellows_volume_closed_form(asm.spec.soa, raw["D_b"])
    assert lo[1] * v_soa * g_per_mm3 <= asm.mass_g("soa") <= hi[1] * v_soa * g_per_mm3
    n = _n_joints(raw)
    volumes = np.array(
        [
            sum(asm.parts[asm.panel(k).part].solid.volume for k in range(n + 1)),
            N_SOA * n * v_soa,
            math.pi * raw["d_rod"] ** 2 / 4 * _tail_length_mm(raw),
        ]
    )
    total_g = sum(asm.mass_g(i.part) for i in asm.instances)
    assert volumes @ lo * g_per_mm3 <= total_g <= volumes @ hi * g_per_mm3


def test_parts_are_made_of_their_tables_material(asm, bvsr_data):
    use = bvsr_data["use"]
    for part in asm.parts.values():
        expected = {
            "panel": use["panel"],
            "soa": use["soa"],
            "rod": bvsr_data["vertebra"]["material"],
        }[part.kind]
        assert part.material == expected, part.name


def test_assembly_mass_by_hand(asm, raw):
    total_g = sum(asm.mass_g(i.part) for i in asm.instances)
    assert total_g / 1000 == pytest.approx(_hand_tail_mass_kg(asm, raw), rel=1e-6)


def test_robot_mass_by_hand(robot, asm, raw):
    virtual = 2 * _n_joints(raw) * 1e-7  # two 0.1 mg frames per joint (after phi, after theta_b)
    assert robot.mass_kg == pytest.approx(_hand_tail_mass_kg(asm, raw) + virtual, rel=1e-6)


# -- the robot model and its MJCF and URDF, read back by MuJoCo ------------------------------------
def test_robot_rod_stiffness_is_ei_over_l_in_si(robot, raw):
    E_pa, d_m, L_m = raw["E_rod_mpa"] * 1e6, raw["d_rod"] / 1000, raw["H_a"] / 1000
    assert robot.actuation.rod_bending_stiffness_nm_rad == pytest.approx(
        E_pa * math.pi * d_m**4 / 64 / L_m, rel=1e-12
    )
    assert robot.actuation.rod_axial_stiffness_n_m == pytest.approx(
        E_pa * math.pi * d_m**2 / 4 / L_m, rel=1e-12
    )


def test_mujoco_joint_stiffness_is_the_rods(mjcf, raw):
    """Two half-angle hinges in series each 2 E I / L; the chord slide E A / L; phi free."""
    E_pa, d_m, L_m = raw["E_rod_mpa"] * 1e6, raw["d_rod"] / 1000, raw["H_a"] / 1000
    ei_l = E_pa * math.pi * d_m**4 / 64 / L_m  # 4.879 N m / rad
    for k in range(1, _n_joints(raw) + 1):
        for half in ("theta_a", "theta_b"):
            assert mjcf.jnt_stiffness[mjcf.joint(f"j{k}_{half}").id] == pytest.approx(
                2 * ei_l, rel=1e-9
            )
        assert mjcf.jnt_stiffness[mjcf.joint(f"j{k}_chord").id] == pytest.approx(
            E_pa * math.pi * d_m**2 / 4 / L_m, rel=1e-9
        )
        assert mjcf.jnt_stiffness[mjcf.joint(f"j{k}_phi").id] == 0.0


def _body_mass(m, name: str) -> float:
    return float(m.body_mass[m.body(name).id])


def test_mujoco_body_masses_by_hand(mjcf, asm, raw):
    n = _n_joints(raw)
    t = raw["H_j"] - raw["H_a"]
    rod_area = math.pi * raw["d_rod"] ** 2 / 4
    for k in range(n + 1):
        v_panel = asm.parts[asm.panel(k).part].solid.volume
        expected = (v_panel * raw["rho_panel"] + rod_area * t * raw["rho_rod"]) * KG_PER_G_CM3_MM3
        assert _body_mass(mjcf, f"panel{k}") == pytest.approx(expected, rel=1e-6), k
    soft = (
        N_SOA * _bellows_volume_closed_form(asm.spec.soa, raw["D_b"]) * raw["rho_soa"]
        + rod_area * raw["H_a"] * raw["rho_rod"]
    ) * KG_PER_G_CM3_MM3
    for k in range(1, n + 1):
        pair = _body_mass(mjcf, f"j{k}_after_theta_a") + _body_mass(mjcf, f"j{k}_after_chord")
        assert pair == pytest.approx(soft, rel=1e-6), k
    virtual = 2 * n * 1e-7
    assert float(mjcf.body_mass.sum()) == pytest.approx(
        _hand_tail_mass_kg(asm, raw) + virtual, rel=1e-6
    )


def _rest_data(m):
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    return d


def _tail_frame(m, d, world: np.ndarray) -> np.ndarray:
    """World point -> tail frame (m), about the mount."""
    return R_WORLD_TAIL.T @ (np.asarray(world) - d.body("bvsr_mount").xpos)


def test_mujoco_rest_pose_is_the_straight_tail(mjcf, raw):
    d = _rest_data(mjcf)
    for k in range(_n_joints(raw) + 1):
        p = _tail_frame(mjcf, d, d.body(f"panel{k}").xpos)
        assert p == pytest.approx([0.0, 0.0, k * raw["H_j"] / 1000], abs=1e-9), k
        # Every panel keeps the tail's orientation at rest.
        R = d.body(f"panel{k}").xmat.reshape(3, 3)
        np.testing.assert_allclose(
            R_WORLD_TAIL.T @ R, R_WORLD_TAIL.T @ d.body("bvsr_mount").xmat.reshape(3, 3), atol=1e-9
        )


def test_mujoco_sockets_on_the_pentagon(mjcf, asm, raw):
    d = _rest_data(mjcf)
    tan_b = math.tan(_beta(asm))
    t = raw["H_j"] - raw["H_a"]
    depth = (raw["H"] - raw["H_a"]) / 2
    for k in range(1, _n_joints(raw) + 1):
        for i in range(1, N_SOA + 1):
            a = math.radians(90.0 + 72.0 * (i - 1))
            z_b = (k - 1) * raw["H_j"] + t  # panel k - 1's upper face
            z_t = k * raw["H_j"]  # panel k's lower face
            for site, z_face, z in (
                (f"j{k}_soa{i}_bottom", z_b, z_b - depth),
                (f"j{k}_soa{i}_top", z_t, z_t + depth),
            ):
                r = raw["D_a"] / 2 - z_face * tan_b
                p = _tail_frame(mjcf, d, d.site(site).xpos) * 1000
                assert p == pytest.approx([r * math.cos(a), r * math.sin(a), z], abs=1e-6), site


def test_mujoco_bent_joint_is_eq2_by_hand(mjcf, raw):
    """Eq 2 in the sagittal plane (phi = 90 deg, the MJCF's rest phi): bent by theta, panel 1's
    lower face centre sits at (0, L (1 - cos theta) / theta, t + L sin theta / theta) and its axis
    at (0, sin, cos)."""
    d = mujoco.MjData(mjcf)
    L, t = raw["H_a"] / 1000, (raw["H_j"] - raw["H_a"]) / 1000
    for theta in (0.2, -0.35):
        d.qpos[:] = mjcf.qpos0
        assert d.qpos[mjcf.joint("j1_phi").qposadr[0]] == pytest.approx(math.pi / 2)
        for half in ("theta_a", "theta_b"):
            d.qpos[mjcf.joint(f"j1_{half}").qposadr[0]] = theta / 2
        d.qpos[mjcf.joint("j1_chord").qposadr[0]] = 2 * L * math.sin(theta / 2) / theta - L
        mujoco.mj_kinematics(mjcf, d)
        p = _tail_frame(mjcf, d, d.body("panel1").xpos)
        assert p == pytest.approx(
            [0.0, L * (1 - math.cos(theta)) / theta, t + L * math.sin(theta) / theta], abs=1e-12
        )
        z_axis = R_WORLD_TAIL.T @ d.body("panel1").xmat.reshape(3, 3)[:, 2]
        assert z_axis == pytest.approx([0.0, math.sin(theta), math.cos(theta)], abs=1e-12)


def test_robot_limits_by_hand(urdf_root, raw, bvsr_data):
    """Velocity: the segment's peak 678.6 deg/s shared by its three joints, x 1.5, half per
    half-angle joint. Effort: five SOAs at the 6 bar pulse pressure on A, on the pitch radius
    (torque) or the chord (force)."""
    rb = bvsr_data["robot"]
    joint_rate = (
        math.radians(rb["segment_velocity_deg_s"])
        / raw["joints_per_segment"]
        * rb["velocity_margin"]
    )
    push = N_SOA * rb["pulse_pressure_max_kpa"] * 1000 * raw["A_mm2"] * 1e-6  # 414.6 N
    assert push == pytest.approx(414.6)
    torque = push * raw["D_a"] / 2 / 1000  # 9.509 N m
    limits = {j.get("name"): j.find("limit") for j in urdf_root.iter("joint")}
    for k in range(1, _n_joints(raw) + 1):
        for half in ("theta_a", "theta_b"):
            lim = limits[f"j{k}_{half}"]
            assert float(lim.get("velocity")) == pytest.approx(joint_rate / 2, rel=1e-9)
            assert float(lim.get("effort")) == pytest.approx(torque, rel=1e-9)
            assert float(lim.get("upper")) == pytest.approx(THETA_MAX / 2, rel=1e-9)
        assert float(limits[f"j{k}_chord"].get("effort")) == pytest.approx(push, rel=1e-9)


def test_mujoco_soa_actuator_is_eq3_by_hand(mjcf, raw):
    """At rest the SOA pushes P A; bent, P A - (m_a P + n_a)(l - l0) with l from MuJoCo's tendon. P
    is the chamber pressure: the actuator's activation (the commanded pressure reaches it through
    the supply lag), set here directly."""
    d = mujoco.MjData(mjcf)
    p = 1e5
    a_m2 = raw["A_mm2"] * 1e-6
    for name in ("j1_soa1", "j2_soa3"):
        d.qpos[:] = mjcf.qpos0
        d.ctrl[:] = 0.0
        d.act[:] = 0.0
        act = mjcf.actuator(name)
        assert act.dyntype[0] == mujoco.mjtDyn.mjDYN_FILTEREXACT
        d.ctrl[act.id] = p
        d.act[mjcf.actuator_actadr[act.id]] = p
        mujoco.mj_forward(mjcf, d)
        l0 = float(d.ten_length[mjcf.tendon(f"{name}_tendon").id])
        assert float(d.actuator_force[mjcf.actuator(name).id]) == pytest.approx(
            p * a_m2, abs=1e-6
        )  # l0 written to 10 digits
        joint = name.split("_")[0]
        for half in ("theta_a", "theta_b"):
            d.qpos[mjcf.joint(f"{joint}_{half}").qposadr[0]] = 0.1
        mujoco.mj_forward(mjcf, d)
        dl = float(d.ten_length[mjcf.tendon(f"{name}_tendon").id]) - l0
        assert abs(dl) > 1e-4  # the bend stretched or shortened it
        k = raw["m_a_per_kpa"] * p / 1000 + raw["n_a"]
        assert float(d.actuator_force[mjcf.actuator(name).id]) == pytest.approx(
            p * a_m2 - k * dl, abs=1e-6
        )


def test_mujoco_panel_inertia_against_trimesh(mjcf, asm, raw):
    """Second method: the panel's tessellated mesh (trimesh) plus the rod piece (closed-form
    cylinder), composed by hand, against MuJoCo's compiled inertia of the panel body."""
    import trimesh

    k = 1
    part = asm.parts[asm.panel(k).part]
    verts, faces = part.solid.tessellate(0.005, 0.1)
    mesh = trimesh.Trimesh(np.array([tuple(v) for v in verts]) / 1000.0, np.array(faces))
    assert mesh.is_volume
    mesh.density = raw["rho_panel"] * 1000.0  # kg/m^3
    t = (raw["H_j"] - raw["H_a"]) / 1000
    r = raw["d_rod"] / 2000
    m_rod = math.pi * r * r * t * raw["rho_rod"] * 1000.0
    c_rod = np.array([0.0, 0.0, t / 2])
    I_rod = np.diag([m_rod * (3 * r * r + t * t) / 12] * 2 + [m_rod * r * r / 2])
    m = mesh.mass + m_rod
    com = (mesh.mass * mesh.center_mass + m_rod * c_rod) / m

    def shifted(I, mass, c):
        dv = c - com
        return I + mass * (dv @ dv * np.eye(3) - np.outer(dv, dv))

    I_hand = shifted(mesh.moment_inertia, mesh.mass, mesh.center_mass) + shifted(
        I_rod, m_rod, c_rod
    )
    b = mjcf.body(f"panel{k}")
    assert float(b.mass[0]) == pytest.approx(m, rel=2e-3)
    assert b.ipos == pytest.approx(com, abs=2e-6)
    q = b.iquat
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, q)
    R = R.reshape(3, 3)
    I_mj = R @ np.diag(b.inertia) @ R.T
    np.testing.assert_allclose(I_mj, I_hand, rtol=0, atol=5e-3 * np.abs(I_hand).max())


def test_urdf_masses_and_joint_origins_by_hand(urdf_root, asm, raw):
    masses = {
        link.get("name"): float(link.find("inertial/mass").get("value"))
        for link in urdf_root.iter("link")
    }
    virtual = 2 * _n_joints(raw) * 1e-7
    assert sum(masses.values()) == pytest.approx(_hand_tail_mass_kg(asm, raw) + virtual, rel=1e-6)
    joints = {j.get("name"): j for j in urdf_root.iter("joint")}
    t_m, L_m = (raw["H_j"] - raw["H_a"]) / 1000, raw["H_a"] / 1000
    for k in range(1, _n_joints(raw) + 1):
        xyz = [float(v) for v in joints[f"j{k}_phi"].find("origin").get("xyz").split()]
        assert xyz == pytest.approx([0.0, 0.0, t_m], abs=1e-12)
        xyz = [float(v) for v in joints[f"j{k}_chord"].find("origin").get("xyz").split()]
        assert xyz == pytest.approx([0.0, 0.0, L_m], abs=1e-12)
        assert joints[f"j{k}_theta_a"].find("axis").get("xyz").split() == ["0", "1", "0"]


def test_urdf_compiles_in_mujoco_with_the_hand_masses(urdf_root, asm, raw):
    """Second reader: MuJoCo's URDF parser on the same XML (meshes removed; they carry no mass)."""
    root = ET.fromstring(ET.tostring(urdf_root))
    m = mujoco.MjModel.from_xml_string(_without_meshes(root))
    virtual = 2 * _n_joints(raw) * 1e-7
    assert float(m.body_mass.sum()) == pytest.approx(
        _hand_tail_mass_kg(asm, raw) + virtual, rel=1e-6
    )


# -- fabrication products: published sizes ---------------------------------------------------------
@pytest.fixture(scope="module")
def twin(asm):
    from bvsr_cad.assembly.products import build_rigid_twin

    return build_rigid_twin(asm)


def _radial_probe(solid, x, y, z, r, directions=12):
    """Whether points at distance r around (x, y) at height z are inside the solid, one per
    direction."""
    import build123d as bd

    return [
        solid.is_inside(bd.Vector(x + r * math.cos(a), y + r * math.sin(a), z))
        for a in np.linspace(0, 2 * math.pi, directions, endpoint=False)
    ]


def test_rigid_twin_dowel_holes(twin, bvsr_data):
    """ISO 2338 dowel 3 m6 in a hole of d + clearance (3.2 mm), probed in every piece's solid."""
    fp = bvsr_data["fabrication_package"]
    hole = fp["pin_diameter_mm"] + fp["pin_hole_clearance_mm"]
    assert hole == pytest.approx(3.2)
    assert len(twin) == _n_joints_from(bvsr_data) + 1
    for piece in twin:
        pins = [f for f in piece.features if f.kind == "pin_hole"]
        # A column's top under the next panel, and (except at the ends) the panel's own from below.
        assert len(pins) == (N_SOA if piece is twin[0] or piece is twin[-1] else 2 * N_SOA), (
            piece.name
        )
        assert all(f.diameter_mm == pytest.approx(hole, abs=1e-12) for f in pins), piece.name
    piece = twin[0]
    for f in (f for f in piece.features if f.kind == "pin_hole"):
        lo, hi = sorted((f.p0[2], f.p1[2]))
        z = (lo + hi) / 2 - piece.z0_mm
        assert not any(_radial_probe(piece.solid, f.p0[0], f.p0[1], z, hole / 2 - 0.05, 8)), f.name
        assert all(_radial_probe(piece.solid, f.p0[0], f.p0[1], z, hole / 2 + 0.05, 8)), f.name


def test_rigid_twin_tie_rod_and_nut_pocket(twin, bvsr_data):
    """M3 tie rod (DIN 976-1) in a 3 + 0.4 mm hole; its ISO 4032 nut (5.5 mm across flats, 2.4 mm
    tall) in a hexagonal pocket 0.3 mm wider and 0.5 mm deeper, in the root face."""
    fp = bvsr_data["fabrication_package"]
    assert fp["tie_rod_thread"] == 3.0
    root = twin[0]
    tie = next(f for f in root.features if f.kind == "tie_rod_hole")
    assert tie.diameter_mm == pytest.approx(3.0 + fp["tie_rod_clearance_mm"])
    af, m = 5.5 + 0.3, 2.4 + 0.5  # pocket across flats and depth
    inscribed, circumscribed = af / 2, af / math.sqrt(3)
    assert not any(
        _radial_probe(root.solid, 0, 0, 1.0, inscribed - 0.05)
    )  # the nut fits every way round
    assert all(
        _radial_probe(root.solid, 0, 0, 1.0, circumscribed + 0.05)
    )  # and no wider than its corners
    assert not any(_radial_probe(root.solid, 0, 0, m - 0.1, 2.0))  # as deep as the nut plus 0.5 mm
    assert all(_radial_probe(root.solid, 0, 0, m + 0.1, 2.0))  # then the tie-rod hole only (1.7 mm)


def _n_joints_from(data) -> int:
    return data["segments"] * data["joints_per_segment"]


def test_mold_cast_is_the_soa_grown_by_the_shrinkage(asm, bvsr_data):
    """The cavity is the SOA scaled by 1 + 0.3 %: 37.60 mm x 1.003 tall."""
    from bvsr_cad.assembly.products import build_mold_set

    molds = build_mold_set(asm)
    k = 1 + bvsr_data["casting"]["shrinkage_percent"] / 100
    assert k == pytest.approx(1.003)
    box = molds.cast.bounding_box()
    assert box.max.Z - box.min.Z == pytest.approx(bvsr_data["soa"]["height_mm"] * k, abs=1e-4)


def test_composed_inertia_by_hand():
    """Two small bodies composed about their common centre of mass (the parallel-axis theorem),
    worked by hand: 0.2 kg at (0.1, 0, 0) m and 0.3 kg at (0, 0.2, 0) m, each with 1e-6 kg m^2 of
    its own about every axis. The CoM is (0.04, 0.12, 0); the offsets (0.06, -0.12, 0) and (-0.04,
    0.08, 0) give Ixx = 0.2 x 0.0144 + 0.3 x 0.0064 = 0.0048, Iyy = 0.2 x 0.0036 + 0.3 x 0.0016 =
    0.0012, Izz = Ixx + Iyy, Ixy = -(0.2 x 0.06 x -0.12 + 0.3 x -0.04 x 0.08) = 0.0024 (plus 2e-6 on
    the diagonal)."""
    from bvsr_cad.assembly.inertia import Inertial, compose

    own = np.eye(3) * 1e-6
    both = compose(
        [Inertial.make(0.2, (0.1, 0.0, 0.0), own), Inertial.make(0.3, (0.0, 0.2, 0.0), own)]
    )
    assert both.mass_kg == pytest.approx(0.5, rel=1e-15)
    assert np.allclose(both.com, (0.04, 0.12, 0.0), rtol=0, atol=1e-15)
    expected = np.array([[0.0048, 0.0024, 0.0], [0.0024, 0.0012, 0.0], [0.0, 0.0, 0.006]]) + 2 * own
    assert np.allclose(both.inertia, expected, rtol=1e-12, atol=1e-15)
