"""The tail at rest: unique parts, named instances and their placements (mm).

Instances are named by their place in the tail (``panel0`` .. ``panelN``,
``jk_soa1`` .. ``jk_soa5``, ``rod_s1`` ..). Parts that are geometrically
identical are built once and shared: a part is named ``soa`` for the SOAs and
after its first instance otherwise.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass, field

import build123d as bd
import numpy as np

from .. import units
from ..parameters.layout import (
    PanelLayout,
    half_angle_rad,
    panel_layout,
    rod_bore_mm,
    soa_angles_deg,
    soa_frame,
)
from ..parameters.standard_parts import metric
from ..parameters.tables import TailSpec
from ..parts.kernel import PrintPosed, location
from ..parts.panel import panel
from ..parts.soa import soa_body
from ..parts.vertebra import rod
from .inertia import SolidProperties

Progress = Callable[[str], None]


@dataclass(frozen=True)
class PartDef(PrintPosed):
    """One unique part: its solid in the part frame and in print orientation."""

    name: str
    kind: str  # panel, soa, rod
    material: str  # key into spec.materials
    process: str  # MJF, cast, cut
    solid: bd.Solid
    print_transform: tuple[tuple[float, ...], ...]  # 4x4, part frame -> print frame (mm)
    info: dict = field(default_factory=dict, hash=False, compare=False)


class _SolidOnUse(PartDef):
    """A :class:`PartDef` whose solid is made the first time it is read (:func:`build_assembly` with
    ``solids=False``): the same solid as an eager build's, by the same function, made at most
    once."""

    def __init__(self, make: Callable[[], bd.Solid], **fields):
        object.__setattr__(self, "_make", make)
        object.__setattr__(self, "_lock", threading.Lock())
        super().__init__(solid=None, **fields)

    @property
    def solid(self) -> bd.Solid:
        made = self.__dict__.get("_solid")
        if made is None:
            with self._lock:  # the analyses' threads may ask at once
                made = self.__dict__.get("_solid")
                if made is None:
                    made = self._make()
                    object.__setattr__(self, "_solid", made)
        return made

    @solid.setter
    def solid(self, value: bd.Solid | None) -> None:  # the dataclass's __init__ sets the field
        object.__setattr__(self, "_solid", value)

    @property
    def solid_made(self) -> bool:
        return self.__dict__.get("_solid") is not None


@dataclass(frozen=True)
class Instance:
    """One placed part. Its identity is in fields, never parsed from ``name``."""

    name: str
    part: str
    transform: tuple[tuple[float, ...], ...]  # 4x4, part frame -> tail frame (mm)
    role: str  # panel, soa, rod
    segment: int | None  # 1-based; None for a panel shared by two segments or the root
    segments: tuple[int, ...]  # every segment this instance belongs to (standalone builds)
    panel: int | None = None  # a panel's index k (panel0 = root)
    joint: int | None = None  # an SOA's joint k (between panel k-1 and panel k)
    soa_index: int | None = None  # an SOA's place i = 1..N_SOA around the pitch circle
    pressure_line: int | None = None  # the line i = 1..N_SOA of its segment that feeds an SOA

    @property
    def line_name(self) -> str | None:
        """``s{segment}_line{i}`` of an SOA (the name the robot descriptions give its line)."""
        return None if self.pressure_line is None else f"s{self.segment}_line{self.pressure_line}"


@dataclass
class Assembly:
    spec: TailSpec
    parts: dict[str, PartDef]
    instances: list[Instance]
    panel_layouts: list[PanelLayout]
    taper_half_angle_deg: float
    _properties: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    def part_of(self, inst: Instance) -> PartDef:
        return self.parts[inst.part]

    def instances_of(self, part: str) -> list[Instance]:
        return [i for i in self.instances if i.part == part]

    def instance(self, name: str) -> Instance:
        for i in self.instances:
            if i.name == name:
                return i
        raise KeyError(f"no instance {name!r} in {self.spec.name}")

    def panel(self, k: int) -> Instance:
        return next(i for i in self.instances if i.role == "panel" and i.panel == k)

    def soas_of_joint(self, k: int) -> list[Instance]:
        """The SOAs of joint k in pentagon order (soa_index 1..N_SOA)."""
        return sorted(
            (i for i in self.instances if i.role == "soa" and i.joint == k),
            key=lambda i: i.soa_index,
        )

    def solid_properties(self, part: str) -> SolidProperties:
        """The part's volume, centre of mass and inertia (unit density), integrated once per
        part."""
        if part not in self._properties:
            self._properties[part] = SolidProperties.of(self.parts[part].solid)
        return self._properties[part]

    def remember_properties(self, properties: dict[str, SolidProperties]) -> None:
        """Take parts' mass properties computed from the same solids elsewhere (a build's cache):
        the parts' solids are then not integrated again, nor made (``build_assembly(...,
        solids=False)``)."""
        for part, props in properties.items():
            if part in self.parts:
                self._properties.setdefault(part, props)

    def volume_mm3(self, part: str) -> float:
        return self.solid_properties(part).volume_mm3

    def mass_g(self, part: str) -> float:
        p = self.parts[part]
        return units.mass_g(self.volume_mm3(part), self.spec.material(p.material).density_g_cm3)


def _as_tuple(m: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in m)


def translation(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = (x, y, z)
    return m


def _panel_key(lay: PanelLayout) -> tuple:
    def r(v: float) -> float:
        return round(v, 6)

    def cyl(c) -> tuple:
        return (c.role, tuple(map(r, c.p0)), tuple(map(r, c.p1)), r(c.diameter_mm))

    return (
        lay.kind,
        r(lay.rim_radius_lower_mm),
        r(lay.rim_radius_upper_mm),
        tuple(map(cyl, lay.cuts)),
        tuple(map(cyl, lay.bosses)),
        tuple(map(cyl, lay.passages)),
    )


def rod_span_mm(spec: TailSpec, s: int) -> tuple[float, float]:
    """z range of segment s's rod: through the root panel, to the tip face, and
    to the mid-plane of a boundary panel shared with the next segment."""
    j = spec.joint
    t = j.panel_thickness_mm
    p0, p1 = spec.joints_per_segment * (s - 1), spec.joints_per_segment * s
    z_start = 0.0 if p0 == 0 else p0 * j.joint_height_mm + t / 2
    z_end = p1 * j.joint_height_mm + (t if p1 == spec.panels - 1 else t / 2)
    return z_start, z_end


def _print_transform_panel(lay: PanelLayout) -> np.ndarray:
    """Lower face on the bed, unless a collar hangs below it (then flipped)."""
    below = [b for b in lay.bosses if b.z_range[0] < 0]
    if not below:
        return np.eye(4)
    flip = np.diag([1.0, -1.0, -1.0, 1.0])
    return translation(z=lay.thickness_mm) @ flip


def build_assembly(
    spec: TailSpec,
    progress: Progress | None = None,
    solids: bool = True,
) -> Assembly:
    """Make every unique part and place every instance of the tail at rest.

    Args:
        spec: a validated tail spec.
        progress: called with a short message before each slow step.
        solids: False makes each part's solid when it is first read, not now (the analyses' process
            of a build whose geometry analyses, posed tail and parts' mass properties come from the
            cache reads none: an edit that moves no solid makes none there).
    """
    say = (progress or (lambda _msg: None)) if solids else (lambda _msg: None)

    def part(*, solid: Callable[[], bd.Solid], **fields) -> PartDef:
        return PartDef(solid=solid(), **fields) if solids else _SolidOnUse(solid, **fields)

    beta = half_angle_rad(spec)
    layouts = [panel_layout(spec, k, beta) for k in range(spec.panels)]
    parts: dict[str, PartDef] = {}
    instances: list[Instance] = []
    _add_panels(spec, layouts, part, say, parts, instances)
    _add_soas(spec, layouts, part, say, parts, instances)
    _add_rods(spec, part, parts, instances)
    asm = Assembly(
        spec=spec,
        parts=parts,
        instances=instances,
        panel_layouts=layouts,
        taper_half_angle_deg=math.degrees(beta),
    )
    return asm


def _add_panels(
    spec: TailSpec,
    layouts: list[PanelLayout],
    part: Callable[..., PartDef],
    say: Progress,
    parts: dict[str, PartDef],
    instances: list[Instance],
) -> None:
    """One part per distinct panel (panels alike share it) and every panel's instance."""
    J = spec.joints_per_segment

    def segments_of_panel(k: int) -> tuple[int, ...]:
        segs = {s for s in range(1, spec.segments + 1) if J * (s - 1) <= k <= J * s}
        return tuple(sorted(segs))

    by_key: dict[tuple, str] = {}
    for lay in layouts:
        key = _panel_key(lay)
        if key not in by_key:
            say(f"panel {lay.name} ({lay.kind})")
            by_key[key] = lay.name
            parts[lay.name] = part(
                name=lay.name,
                kind="panel",
                material=spec.use.panel,
                process="MJF",
                solid=lambda lay=lay: panel(lay),
                print_transform=_as_tuple(_print_transform_panel(lay)),
                info={
                    "panel_kind": lay.kind,
                    "thickness_mm": lay.thickness_mm,
                    "pocket_depth_mm": lay.pocket_depth_mm,
                    "pocket_faces": [
                        f
                        for f, on in (("lower", lay.lower_pockets), ("upper", lay.upper_pockets))
                        if on
                    ],
                    "pitch_radius_lower_mm": lay.pitch_radius_lower_mm,
                    "pitch_radius_upper_mm": lay.pitch_radius_upper_mm,
                    "pocket_diameter_mm": lay.cuts[0].diameter_mm,
                    "rod_socket": spec.vertebra.socket,
                    "rod_bore_mm": rod_bore_mm(spec),
                    "rod_thread": (
                        f"M{spec.vertebra.diameter_mm:g}"
                        f"x{metric(spec.vertebra.diameter_mm).pitch_mm:g}, "
                        "tap after printing"
                        if spec.vertebra.socket == "threaded"
                        else None
                    ),
                },
            )
        segs = segments_of_panel(lay.index)
        instances.append(
            Instance(
                lay.name,
                by_key[key],
                _as_tuple(translation(z=lay.z0_mm)),
                "panel",
                segs[0] if len(segs) == 1 else None,
                segs,
                panel=lay.index,
            )
        )


def _add_soas(
    spec: TailSpec,
    layouts: list[PanelLayout],
    part: Callable[..., PartDef],
    say: Progress,
    parts: dict[str, PartDef],
    instances: list[Instance],
) -> None:
    """The one SOA part and its five instances in every joint, seated between the joint's panels."""
    say("SOA body")
    parts["soa"] = part(
        name="soa",
        kind="soa",
        material=spec.use.soa,
        process="cast",
        solid=lambda: soa_body(spec.soa, spec.joint.base_diameter_mm),
        print_transform=_as_tuple(np.eye(4)),
        info={
            "height_mm": spec.soa.built_height_mm,
            "fold_residual_mm": spec.soa.built_origami_height_mm - spec.soa.origami_height_mm,
        },
    )
    rot = spec.soa.rotation_deg
    for k in range(1, spec.panels):
        lo, hi = layouts[k - 1], layouts[k]
        s = (k - 1) // spec.joints_per_segment + 1
        for i, a in enumerate(soa_angles_deg(), start=1):
            instances.append(
                Instance(
                    f"j{k}_soa{i}",
                    "soa",
                    _as_tuple(soa_frame(lo, hi, a, rot)),
                    "soa",
                    s,
                    (s,),
                    joint=k,
                    soa_index=i,
                    pressure_line=i,
                )
            )


def _add_rods(
    spec: TailSpec,
    part: Callable[..., PartDef],
    parts: dict[str, PartDef],
    instances: list[Instance],
) -> None:
    """One rod part per distinct cut length and each segment's rod (none where the vertebra has no
    rod)."""
    rods: dict[float, str] = {}
    for s in range(1, spec.segments + 1 if spec.vertebra.has_rod else 1):  # "none": sockets, no rod
        z0, z1 = rod_span_mm(spec, s)
        length = round(z1 - z0, 6)
        if length not in rods:
            name = f"rod_s{s}"
            rods[length] = name
            parts[name] = part(
                name=name,
                kind="rod",
                material=spec.vertebra.material,
                process="cut",
                solid=lambda length=length: rod(spec.vertebra.diameter_mm, length),
                print_transform=_as_tuple(np.eye(4)),
                info={"cut_length_mm": length, "diameter_mm": spec.vertebra.diameter_mm},
            )
        instances.append(
            Instance(f"rod_s{s}", rods[length], _as_tuple(translation(z=z0)), "rod", s, (s,))
        )


def instance_solid(asm: Assembly, inst: Instance) -> bd.Solid:
    """The instance's solid in the tail frame."""
    return asm.part_of(inst).solid.moved(location(inst.transform))


def segment_masses_g(asm: Assembly) -> tuple[list[float], list[float]]:
    """(in-tail masses, standalone masses) per segment.

    In the tail a panel shared by two segments counts half to each and the
    root mount to segment 1, so the in-tail masses add up to the tail; a
    standalone segment has all four of its panels, its SOAs and its rod.
    """
    n = asm.spec.segments
    in_tail = [0.0] * n
    standalone = [0.0] * n
    for inst in asm.instances:
        m = asm.mass_g(inst.part)
        for s in inst.segments:
            standalone[s - 1] += m
            in_tail[s - 1] += m / len(inst.segments)
    return in_tail, standalone
