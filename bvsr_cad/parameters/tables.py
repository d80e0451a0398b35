"""Frozen dataclasses for the tail's parameters (the paper's Tables I and II,
materials, the vertebra choice, the taper and fabrication allowances).

The classes declare each field's name and type; the rules (a documentation
line, bounds or choices, a default) live in one data file,
``parameters/data/schema.toml``, and :func:`table` attaches them to the fields'
``metadata``. The loader in :mod:`bvsr_cad.parameters.load` validates every file
from that metadata, so every error names the key, the value and what is allowed.
"""

from __future__ import annotations

import dataclasses
import math
import sys
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from importlib import resources
from typing import Any

AUTO = "auto"

_RULE_KEYS = ("gt", "ge", "lt", "le")
_SCHEMA: dict[str, dict[str, dict[str, Any]]] = tomllib.loads(
    resources.files(__package__).joinpath("data/schema.toml").read_text(encoding="utf-8")
)
#: What `bvsr calibrate` may fit, by name: {doc, gt/ge/lt/le} (schema.toml [calibratable]).
CALIBRATABLE: dict[str, dict[str, Any]] = _SCHEMA["calibratable"]


def table(cls: type) -> Any:
    """Make ``cls`` a frozen dataclass whose fields carry their rules from schema.toml.

    Each field gets ``metadata`` {doc, gt, ge, lt, le, choices, keys, depends_on} and, where the
    schema gives one, its default (``"table"``: the default instance of the
    field's own table). A field without a rule, or a rule without a field, is a
    programming error caught at import.
    """
    rules = _SCHEMA.get(cls.__name__, {})
    declared = list(cls.__dict__.get("__annotations__", {}))
    if declared != list(rules):
        raise RuntimeError(
            f"schema.toml [{cls.__name__}] lists {list(rules)}; {cls.__name__} declares {declared}"
        )
    module = vars(sys.modules[cls.__module__])
    for name in declared:
        rule = dict(rules[name])
        meta = {
            "doc": rule.pop("doc"),
            **{k: rule.pop(k, None) for k in _RULE_KEYS},
            "keys": rule.pop("keys", None),
            "depends_on": tuple(rule.pop("depends_on", ())),
        }
        choices = rule.pop("choices", None)
        meta["choices"] = tuple(choices) if choices is not None else None
        default = rule.pop("default", dataclasses.MISSING)
        if rule:
            raise RuntimeError(
                f"schema.toml [{cls.__name__}].{name}: unknown rule keys {sorted(rule)}"
            )
        if default == "table":
            default = module[cls.__annotations__[name]]()
        if default == "empty":
            setattr(cls, name, field(default_factory=dict, metadata=meta, hash=False))
            continue
        unhashable = str(cls.__annotations__[name]).startswith(("dict", "Mapping"))
        setattr(cls, name, field(default=default, metadata=meta, hash=not unhashable))
    return dataclass(frozen=True)(cls)


def rule_bounds(meta: Any) -> tuple[float, float]:
    """(lowest, highest) of a field's rule range (``meta``: its metadata); a strict end is the bound
    itself."""
    lo = meta["ge"] if meta.get("ge") is not None else meta["gt"]
    hi = meta["le"] if meta.get("le") is not None else meta["lt"]
    return lo, hi


def _inside(meta: Any, x: float) -> bool:
    lo, hi = rule_bounds(meta)
    return (
        lo <= x <= hi
        and (meta.get("gt") is None or x > meta["gt"])
        and (meta.get("lt") is None or x < meta["lt"])
    )


def feasible_span(
    meta: Any, ok: Callable[[float], bool], samples: int
) -> tuple[float, float] | None:
    """The feasible part of a field's rule range: (first, last) of ``samples`` + 1 evenly spaced
    values within its bounds (``meta``: a field's metadata; a strict bound is left out) for which
    ``ok`` holds, or None."""
    lo, hi = rule_bounds(meta)
    good = [
        x
        for x in (lo + (hi - lo) * i / samples for i in range(samples + 1))
        if _inside(meta, x) and ok(x)
    ]
    return (good[0], good[-1]) if good else None


def feasible_interval(
    meta: Any, ok: Callable[[float], bool], value: float, steps: int = 14
) -> tuple[float, float] | None:
    """The interval of a field's rule range around ``value`` (which need not hold) where ``ok``
    holds, assuming there is one: the value nearest ``value`` that holds, searched in steps of 1.6 %
    from an eighth to eight times it and then over the whole range in 64 even steps, then each end
    found by ``steps`` bisections towards the range's bound (None: nothing holds). Cheap when ``ok``
    fails fast."""
    lo, hi = rule_bounds(meta)
    near = (
        [value * 8.0 ** (i / 128) for k in range(129) for i in ((k, -k) if k else (0,))]
        if value > 0
        else []
    )
    found = next(
        (
            x
            for x in [*near, *(lo + (hi - lo) * i / 64 for i in range(65))]
            if _inside(meta, x) and ok(x)
        ),
        None,
    )
    if found is None:
        return None

    def edge(bound: float) -> float:
        if _inside(meta, bound) and ok(bound):
            return bound
        bad, good = bound, found
        for _ in range(steps):
            mid = (bad + good) / 2
            bad, good = (bad, mid) if ok(mid) else (mid, good)
        return good

    return edge(lo), edge(hi)


@table
class JointTable:
    """Table I of the paper: one joint (one layer of five SOAs between two panels)."""

    joint_height_mm: float
    gap_mm: float
    pitch_diameter_mm: float
    panel_diameter_mm: float
    base_diameter_mm: float
    channel_diameter_mm: float
    actuator_spacing_deg: float
    segment_tilt_deg: float

    @property
    def panel_thickness_mm(self) -> float:
        return self.joint_height_mm - self.gap_mm


@table
class SoaTable:
    """Table II of the paper: the soft origami actuator (a square bellows)."""

    height_mm: float
    origami_height_mm: float
    facet_thickness_mm: float
    dihedral_deg: float
    fillet_radius_mm: float
    circumcircle_mm: float
    short_side_mm: float
    long_side_mm: float
    pleats: int
    fold_height_from: str
    rotation_deg: float

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


@table
class Material:
    name: str
    density_g_cm3: float
    youngs_modulus_mpa: float
    source: str


@table
class MaterialUse:
    panel: str
    soa: str


#: ``vertebra.material`` of an invertebrate tail: no rod (the paper's "no vertebra" segment). The
#: panels keep their sockets (sized by ``vertebra.diameter_mm``); the rod, its mass and its
#: stiffness go.
NO_ROD = "none"


@table
class Vertebra:
    material: str
    diameter_mm: float
    socket: str

    @property
    def has_rod(self) -> bool:
        return self.material != NO_ROD


@table
class Taper:
    half_angle_deg: Any


@table
class Fabrication:
    pocket_clearance_mm: float
    hole_compensation_mm: float
    min_pocket_gap_mm: float
    min_wall_mm: float
    min_rim_lip_mm: float
    socket_floor_mm: float


@table
class Tubes:
    outer_diameter_mm: float
    clearance_mm: float
    port_depth_mm: float
    passage_diameter_mm: float
    inner_radius_mm: float
    second_radius_mm: float
    inner_diameter_mm: float


@table
class Socket:
    set_screw_tap_drill_mm: float
    boss_height_mm: float
    boss_wall_mm: float
    rod_clearance_mm: float


@table
class Mount:
    bolt_circle_diameter_mm: float
    insert_diameter_mm: float
    insert_depth_mm: float
    fitting_tap_drill_mm: float


@table
class Payload:
    insert_circle_diameter_mm: float
    insert_count: int
    insert_diameter_mm: float
    insert_depth_mm: float


@table
class Lightening:
    hole_diameter_mm: float


@table
class Casting:
    """Allowances of the SOA casting mold set (PU rubber cast in printed molds)."""

    cavity_wall_mm: float
    core_print_mm: float
    pin_diameter_mm: float
    pin_length_mm: float
    pin_clearance_mm: float
    bolt_hole_diameter_mm: float
    gate_diameter_mm: float
    vent_diameter_mm: float
    shrinkage_percent: float
    min_print_wall_mm: float


@table
class Actuation:
    """The SOA force model of Eq 3-4 and the pressures it is driven with.

    Eq 4's fit k = 9.4 P + 2918 is read with P as gauge pressure in kPa and k in
    N/m: an SOA of about 1.4 cm^2 then pushes 14 N at 100 kPa and loses 2.9 N
    per mm of stretch, the magnitudes of the paper's blocked forces; P in Pa or
    k in N/mm would make the SOA 1000 times stiffer or softer than its force.
    """

    effective_area_mm2: float
    stiffness_slope_n_per_m_per_kpa: float
    stiffness_offset_n_per_m: float
    damping_n_s_per_m: float
    pressure_max_kpa: float
    pressure_min_kpa: float
    atmospheric_kpa: float
    workspace_pressurised_max_kpa_abs: float
    workspace_depressurised_min_kpa_abs: float
    workspace_cycle_s: float


@table
class Analysis:
    """How the kinematic analyses of `bvsr build` are run and judged."""

    min_clearance_mm: float
    build_workspace_samples: int
    build_clearance_poses: int
    seed: int
    workspace_protocol_cycles: int


@table
class RobotDescription:
    """Settings of the URDF/MJCF robot descriptions."""

    segment_velocity_deg_s: float
    velocity_margin: float
    pulse_pressure_max_kpa: float
    timestep_s: float
    collision_geometry: str
    quadruped_experiments: str


@table
class FabricationPackage:
    """The fabrication package: printer, FDM limits, the rigid comparison tail, BOM items.

    Every field has a default so older parameter files still load; the
    parameter files spell them out with comments.
    """

    printer_x_mm: float
    printer_y_mm: float
    printer_z_mm: float
    mjf_x_mm: float
    mjf_y_mm: float
    mjf_z_mm: float
    max_overhang_deg: float
    max_bridge_mm: float
    fdm_min_wall_mm: float
    fdm_min_plate_mm: float
    fdm_min_hole_mm: float
    mjf_min_hole_mm: float
    envelope_tolerance_mm: float
    pin_diameter_mm: float
    pin_length_mm: float
    pin_hole_clearance_mm: float
    tie_rod_thread: float
    tie_rod_clearance_mm: float
    core_material: str
    mold_material: str
    mold_sets: int
    tube_lead_mm: float
    tube_bend_allowance: float
    valves_per_line: int
    slicer_timeout_s: float


@table
class Pneumatics:
    """The pneumatic supply of a pulse: the paper's Eq 13 ramp, or valve, tube and chambers (ISO
    6358)."""

    model: str
    ramp_time_s: float
    valve_sonic_conductance_l_s_bar: float
    valve_critical_pressure_ratio: float
    polytropic_index: float
    air_temperature_k: float


@table
class CartPlatform:
    """The hinged cart of the paper's platform experiment (Eq 20-22)."""

    mass_kg: float
    length_m: float
    width_m: float
    tail_mount_behind_hinge_m: float


@table
class Calibration:
    """What `bvsr calibrate` fitted, and to which data (empty: the tables' values hold)."""

    data_file: str
    measured_tail: str
    data_sha256: str
    rms_rel_fit: float
    rms_rel_holdout: float
    rms_rel_holdout_uncalibrated: float
    fitted: Mapping[str, float]
    rod_material: str
    rod_diameter_mm: float


@table
class TailSpec:
    """The whole tail: what a parameter file describes."""

    name: str
    segments: int
    joints_per_segment: int
    joint: JointTable
    soa: SoaTable
    materials: dict[str, Material]
    use: MaterialUse
    vertebra: Vertebra
    taper: Taper
    fabrication: Fabrication
    tubes: Tubes
    socket: Socket
    mount: Mount
    payload: Payload
    lightening: Lightening
    actuation: Actuation
    analysis: Analysis
    casting: Casting
    robot: RobotDescription
    fabrication_package: FabricationPackage
    pneumatics: Pneumatics
    cart: CartPlatform
    calibration: Calibration

    def fitted(self, name: str, table_value: float) -> float:
        """A calibratable quantity's value: fitted by `bvsr calibrate` if the file says so, else the
        table's."""
        return float(self.calibration.fitted.get(name, table_value))

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
