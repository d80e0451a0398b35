"""Frozen dataclasses for the tail's parameters (the paper's Tables I and II,
materials, the vertebra choice, the taper and fabrication allowances).

Each field carries its validation rule in ``metadata`` (see :func:`rule`), so
the loader in :mod:`bvsr_cad.parameters.load` validates every file the same way and
every error names the key, the value and what is allowed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

AUTO = "auto"


def rule(
    doc: str,
    *,
    gt: float | None = None,
    ge: float | None = None,
    le: float | None = None,
    lt: float | None = None,
    choices: tuple[Any, ...] | None = None,
    default: Any = dataclass,  # sentinel: no default
    hash: bool = True,
) -> Any:
    """A dataclass field with a documented validation rule."""
    meta = {"doc": doc, "gt": gt, "ge": ge, "le": le, "lt": lt, "choices": choices}
    if default is dataclass:
        return field(metadata=meta, hash=hash)
    return field(default=default, metadata=meta, hash=hash)


@dataclass(frozen=True)
class JointTable:
    """Table I of the paper: one joint (one layer of five SOAs between two panels)."""

    joint_height_mm: float = rule("H_j, joint pitch along the tail (panel + gap)", gt=0, le=200)
    gap_mm: float = rule("H_a, initial gap between two panels = arc length L", gt=0, le=200)
    pitch_diameter_mm: float = rule("D_a, diameter of the SOA pitch circle at the root", gt=0, le=500)
    panel_diameter_mm: float = rule("D_p, panel diameter at the root", gt=0, le=500)
    base_diameter_mm: float = rule("D_b, diameter of the SOA flange (actuator base)", gt=0, le=200)
    channel_diameter_mm: float = rule("D_c, air channel through intermediate panels", gt=0, le=100)
    actuator_spacing_deg: float = rule(
        "alpha_1, angular spacing of the five SOAs (a regular pentagon)", choices=(72.0,)
    )
    segment_tilt_deg: float = rule(
        "alpha_2, 'tilt angle of segment 1' (informational, see [taper])", gt=90, lt=135
    )

    @property
    def panel_thickness_mm(self) -> float:
        return self.joint_height_mm - self.gap_mm


@dataclass(frozen=True)
class SoaTable:
    """Table II of the paper: the soft origami actuator (a square bellows)."""

    height_mm: float = rule("H, overall SOA height", gt=0, le=200)
    origami_height_mm: float = rule("H_o, height of the pleated (origami) section", gt=0, le=200)
    facet_thickness_mm: float = rule("t, wall thickness of the facets", gt=0.2, le=5)
    dihedral_deg: float = rule("alpha, V-angle at a fold between two facet rows", gt=10, lt=170)
    fillet_radius_mm: float = rule("R, fillet radius of the vertical corners", ge=0, le=20)
    circumcircle_mm: float = rule("D, circumcircle (checked against b and R, not used)", gt=0, le=200)
    short_side_mm: float = rule("a, square side at the inner (valley) folds", gt=0, le=100)
    long_side_mm: float = rule("b, square side at the outer (mountain) folds", gt=0, le=100)
    pleats: int = rule("number of pleats (each pleat = two facet rows)", ge=1, le=10)
    fold_height_from: str = rule(
        "which table value sets the rise of a facet row", choices=("origami_height", "dihedral")
    )
    rotation_deg: float = rule(
        "rotation of the square in its pocket: 0 = a side faces the tail axis, 45 = a corner does",
        ge=0,
        le=90,
    )

    @property
    def flange_thickness_mm(self) -> float:
        """Each open end carries a flange; the two share H - H_o."""
        return (self.height_mm - self.origami_height_mm) / 2.0

    @property
    def facet_rows(self) -> int:
        return 2 * self.pleats

    @property
    def pleat_depth_mm(self) -> float:
        return (self.long_side_mm - self.short_side_mm) / 2.0

    @property
    def row_rise_from_dihedral_mm(self) -> float:
        return self.pleat_depth_mm / math.tan(math.radians(self.dihedral_deg) / 2.0)

    @property
    def row_rise_mm(self) -> float:
        """Rise of one facet row as built, per ``fold_height_from``."""
        if self.fold_height_from == "dihedral":
            return self.row_rise_from_dihedral_mm
        return self.origami_height_mm / self.facet_rows

    @property
    def built_origami_height_mm(self) -> float:
        return self.row_rise_mm * self.facet_rows

    @property
    def built_height_mm(self) -> float:
        return self.built_origami_height_mm + 2.0 * self.flange_thickness_mm

    @property
    def computed_circumcircle_mm(self) -> float:
        """Diagonal extent of a square of side b with corners rounded at R."""
        half = self.long_side_mm / 2.0 - self.fillet_radius_mm
        return 2.0 * (half * math.sqrt(2.0) + self.fillet_radius_mm)

    @property
    def implied_dihedral_deg(self) -> float:
        """The dihedral that would make the facet rows fill H_o exactly."""
        rise = self.origami_height_mm / self.facet_rows
        return math.degrees(2.0 * math.atan(self.pleat_depth_mm / rise))

    @property
    def wall_offset_mm(self) -> float:
        """Horizontal offset between outer and inner facet planes for a normal thickness t."""
        return self.facet_thickness_mm / math.cos(math.atan(self.pleat_depth_mm / self.row_rise_mm))


@dataclass(frozen=True)
class Material:
    name: str = rule("display name")
    density_g_cm3: float = rule("density", gt=0.1, le=25)
    youngs_modulus_mpa: float = rule("Young's modulus", gt=0, le=500_000)
    source: str = rule("where density and modulus come from")


@dataclass(frozen=True)
class MaterialUse:
    panel: str = rule("material key of the printed panels")
    soa: str = rule("material key of the cast SOAs")


@dataclass(frozen=True)
class Vertebra:
    material: str = rule("material key of the elastic rod")
    diameter_mm: float = rule("D_e, rod diameter", choices=(4.0, 5.0, 6.0))
    socket: str = rule("how the rod is held in each panel", choices=("threaded", "set_screw"))


@dataclass(frozen=True)
class Taper:
    half_angle_deg: Any = rule(
        "half-angle of the cone followed by the panel rims and pitch circle; 'auto' = largest feasible",
        ge=0,
        le=10,
    )


@dataclass(frozen=True)
class Fabrication:
    pocket_clearance_mm: float = rule("diametral clearance of a flange pocket for the bonding layer", ge=0, le=2)
    hole_compensation_mm: float = rule("added to the diameter of every printed hole (MJF shrink)", ge=0, le=1)
    min_pocket_gap_mm: float = rule("smallest web allowed between neighbouring flange pockets", gt=0, le=20)
    min_wall_mm: float = rule("smallest web allowed between any two other panel features", gt=0, le=20)
    min_rim_lip_mm: float = rule("smallest lip allowed between a flange pocket and the panel rim", ge=0, le=20)
    socket_floor_mm: float = rule("material kept under a pocket or channel end inside a panel", gt=0, le=5)


@dataclass(frozen=True)
class Tubes:
    outer_diameter_mm: float = rule("pneumatic tube outer diameter", gt=1, le=12)
    clearance_mm: float = rule("diametral clearance of a tube pass-through hole", ge=0, le=2)
    port_depth_mm: float = rule("depth of the bonded tube port in a segment-boundary panel", gt=0.5, le=6)
    passage_diameter_mm: float = rule("internal feed passage in a segment-boundary panel", gt=0.5, le=5)
    inner_radius_mm: float = rule("radius of the tube holes between pockets (first distal segment)", gt=0, le=100)
    second_radius_mm: float = rule("radius of the tube holes on the pocket axes (second distal segment)", gt=0, le=100)


@dataclass(frozen=True)
class Socket:
    set_screw_tap_drill_mm: float = rule("tap drill of the radial set screw (M3: 2.5)", gt=0.5, le=6)
    boss_height_mm: float = rule("height of the set-screw collar above the panel face", gt=1, le=20)
    boss_wall_mm: float = rule("radial wall of the set-screw collar", gt=0.5, le=10)
    rod_clearance_mm: float = rule("diametral clearance of the rod in a set-screw bore", ge=0, le=1)


@dataclass(frozen=True)
class Mount:
    bolt_circle_diameter_mm: float = rule("robot bolt circle (five bolts between the pockets)", gt=0, le=500)
    insert_diameter_mm: float = rule("bore of an M3 heat-set insert", gt=1, le=10)
    insert_depth_mm: float = rule("depth of an insert bore from the robot face", gt=0.5, le=20)
    fitting_tap_drill_mm: float = rule("tap drill of a push-in fitting port (M5: 4.2)", gt=1, le=10)


@dataclass(frozen=True)
class Payload:
    insert_circle_diameter_mm: float = rule("circle of the tip payload inserts", gt=0, le=500)
    insert_count: int = rule("number of payload inserts", ge=2, le=12)
    insert_diameter_mm: float = rule("bore of a payload heat-set insert", gt=1, le=10)
    insert_depth_mm: float = rule("depth of a payload insert bore", gt=0.5, le=20)


@dataclass(frozen=True)
class Lightening:
    hole_diameter_mm: float = rule(
        "through holes between the pockets near the rim; 0 = none", ge=0, le=50
    )


@dataclass(frozen=True)
class Casting:
    """Allowances of the SOA casting mold set (PU rubber cast in printed molds)."""

    cavity_wall_mm: float = rule("mold material around the cavity, sideways and beyond both flanges", ge=3, le=30)
    core_print_mm: float = rule("length of the core's end prints in their sockets in bottom plate and lid",
                                gt=0.5, le=20)
    pin_diameter_mm: float = rule("registration pin diameter", ge=1, le=10)
    pin_length_mm: float = rule("registration pin length out of its face", ge=1, le=20)
    pin_clearance_mm: float = rule("diametral clearance of a pin in its socket", ge=0, le=1)
    bolt_hole_diameter_mm: float = rule("clamping bolt through-hole diameter (M3: 3.4)", ge=1, le=10)
    gate_diameter_mm: float = rule("gate (fill channel) diameter", ge=0.5, le=10)
    vent_diameter_mm: float = rule("vent channel diameter", ge=0.3, le=5)
    shrinkage_percent: float = rule("linear shrinkage of the cured PU; the cavity is the SOA scaled by 1 + this",
                                    ge=0, le=5)
    min_print_wall_mm: float = rule("smallest wall a printed mold part may have", gt=0.2, le=5)


@dataclass(frozen=True)
class Actuation:
    """The SOA force model of Eq 3-4 and the pressures it is driven with.

    Eq 4's fit k = 9.4 P + 2918 is read with P as gauge pressure in kPa and k in
    N/m: an SOA of about 1.4 cm^2 then pushes 14 N at 100 kPa and loses 2.9 N
    per mm of stretch, the magnitudes of the paper's blocked forces; P in Pa or
    k in N/mm would make the SOA 1000 times stiffer or softer than its force.
    """

    effective_area_mm2: float = rule(
        "A of Eq 3; no table gives it: default ((a + b) / 2)^2, the bellows' mean square", gt=0, le=2000
    )
    stiffness_slope_n_per_m_per_kpa: float = rule("m_a of Eq 4 (paper 9.4)", ge=0, le=1000)
    stiffness_offset_n_per_m: float = rule("n_a of Eq 4 (paper 2918)", gt=0, le=1e6)
    damping_n_s_per_m: float = rule("c of Eq 11, per SOA (paper 52)", ge=0, le=1e4)
    pressure_max_kpa: float = rule("highest sustained gauge pressure of a line", gt=0, le=600)
    pressure_min_kpa: float = rule("lowest gauge pressure of a line (vacuum)", ge=-101.325, lt=0)
    atmospheric_kpa: float = rule("absolute pressure of an inactive line (workspace protocol)", gt=50, le=120)
    workspace_pressurised_max_kpa_abs: float = rule(
        "workspace protocol: a pressurised line draws uniformly from atmospheric to this", gt=50, le=800)
    workspace_depressurised_min_kpa_abs: float = rule(
        "workspace protocol: a depressurised line draws uniformly from this to atmospheric", ge=0, le=120)


@dataclass(frozen=True)
class Analysis:
    """How the kinematic analyses of `bvsr build` are run and judged."""

    min_clearance_mm: float = rule("smallest clearance allowed between solids that must not touch", ge=0, le=10)
    build_workspace_samples: int = rule("workspace samples drawn during `bvsr build`", ge=100, le=1_000_000)
    build_clearance_poses: int = rule("clearance poses screened during `bvsr build`", ge=100, le=1_000_000)
    seed: int = rule("random seed of the workspace and clearance samples", ge=0, le=2**31 - 1)


@dataclass(frozen=True)
class RobotDescription:
    """Settings of the URDF/MJCF robot descriptions."""

    segment_velocity_deg_s: float = rule(
        "peak bending rate of a segment the velocity limits are built from (paper: 678.6 measured at 6 bar)",
        gt=0, le=10_000)
    velocity_margin: float = rule("factor on that rate for the joint velocity limits", ge=1, le=10)
    pulse_pressure_max_kpa: float = rule("highest gauge pressure of a pulse (actuator control range)",
                                         gt=0, le=1000)
    timestep_s: float = rule("MJCF integration step", gt=1e-6, le=0.01)


@dataclass(frozen=True)
class FabricationPackage:
    """The fabrication package: printer, FDM limits, the rigid comparison tail, BOM items.

    Every field has a default so older parameter files still load; the
    parameter files spell them out with comments.
    """

    printer_x_mm: float = rule("FDM printer build volume, X", gt=20, le=2000, default=250.0)
    printer_y_mm: float = rule("FDM printer build volume, Y", gt=20, le=2000, default=210.0)
    printer_z_mm: float = rule("FDM printer build volume, Z (height)", gt=20, le=2000, default=210.0)
    mjf_x_mm: float = rule("MJF build volume, X (HP 5200: 380)", gt=20, le=2000, default=380.0)
    mjf_y_mm: float = rule("MJF build volume, Y (HP 5200: 284)", gt=20, le=2000, default=284.0)
    mjf_z_mm: float = rule("MJF build volume, Z (HP 5200: 380)", gt=20, le=2000, default=380.0)
    max_overhang_deg: float = rule("steepest overhang printed without support, from vertical", gt=0, lt=90,
                                   default=45.0)
    max_bridge_mm: float = rule("widest flat downward region (bridge or short ledge) printed without support",
                                ge=0, le=50, default=10.0)
    fdm_min_wall_mm: float = rule("thinnest wall an FDM part may have (two 0.4 mm perimeters)", gt=0.2, le=10,
                                  default=0.8)
    fdm_min_plate_mm: float = rule("thinnest horizontal plate an FDM part may have (three 0.2 mm layers)",
                                   gt=0.1, le=10, default=0.6)
    fdm_min_hole_mm: float = rule("smallest hole an FDM part may have", gt=0.2, le=10, default=1.5)
    mjf_min_hole_mm: float = rule("smallest hole an MJF part may have (powder removal)", gt=0.2, le=10,
                                  default=1.5)
    envelope_tolerance_mm: float = rule("rigid tail vs the BVSR at rest: largest allowed surface deviation",
                                        gt=0, le=2, default=0.1)
    pin_diameter_mm: float = rule("rigid tail: dowel pin diameter (ISO 2338, one per SOA column end)",
                                  ge=1.5, le=6, default=3.0)
    pin_length_mm: float = rule("rigid tail: dowel pin length", ge=4, le=30, default=10.0)
    pin_hole_clearance_mm: float = rule("rigid tail: diametral clearance of a pin hole (FDM holes print small)",
                                        ge=0, le=1, default=0.2)
    tie_rod_thread: float = rule("rigid tail: metric size of the central threaded tie rod (DIN 976-1 M3)",
                                 choices=(2.0, 2.5, 3.0), default=3.0)
    tie_rod_clearance_mm: float = rule("rigid tail: diametral clearance of the tie-rod hole", ge=0, le=1,
                                       default=0.4)
    core_material: str = rule("material key of the sacrificial mold cores (printed soluble)", default="PVA")
    mold_material: str = rule("material key of the rigid mold parts", default="PLA")
    mold_sets: int = rule("rigid mold sets printed (casts run in parallel; one core per cast)", ge=1, le=30,
                          default=2)
    tube_lead_mm: float = rule("tube length per line from the root mount to its valve pair", ge=0, le=5000,
                               default=500.0)
    tube_bend_allowance: float = rule("extra tube per line inside the tail for bending (fraction of its length)",
                                      ge=0, le=1, default=0.1)
    valves_per_line: int = rule("solenoid valves per pressure line (paper: pressure + vacuum = 2)", ge=1, le=4,
                                default=2)
    slicer_timeout_s: float = rule("time allowed to slice one STL in the printability check", gt=1, le=600,
                                   default=60.0)


@dataclass(frozen=True)
class TailSpec:
    """The whole tail: what a parameter file describes."""

    name: str = rule("export name (letters, digits, _ and -)")
    segments: int = rule("number of segments", ge=1, le=6)
    joints_per_segment: int = rule("joints per segment (three joints share five lines)", ge=1, le=6)
    joint: JointTable = rule("Table I")
    soa: SoaTable = rule("Table II")
    materials: dict[str, Material] = rule("material table", hash=False)
    use: MaterialUse = rule("which material each part family is made of")
    vertebra: Vertebra = rule("the elastic rod")
    taper: Taper = rule("taper interpretation")
    fabrication: Fabrication = rule("fabrication allowances")
    tubes: Tubes = rule("pneumatic tubes")
    socket: Socket = rule("vertebra socket details")
    mount: Mount = rule("root mount")
    payload: Payload = rule("tip payload mount")
    lightening: Lightening = rule("panel lightening")
    actuation: Actuation = rule("SOA force model and pressures (Eq 3-5, workspace protocol)")
    analysis: Analysis = rule("workspace, clearance and joint-limit analyses")
    casting: Casting = rule("SOA casting mold allowances")
    robot: RobotDescription = rule("URDF/MJCF settings")
    fabrication_package: FabricationPackage = rule(
        "printer, FDM limits, rigid comparison tail, BOM items", default=FabricationPackage())

    @property
    def joints(self) -> int:
        return self.segments * self.joints_per_segment

    @property
    def panels(self) -> int:
        return self.joints + 1

    @property
    def length_mm(self) -> float:
        return self.joints * self.joint.gap_mm + self.panels * self.joint.panel_thickness_mm

    def material(self, key: str) -> Material:
        return self.materials[key]
