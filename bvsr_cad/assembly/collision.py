"""Collision geometry of the robot's links, fitted to the B-rep (mm in, SI out).

Every collision shape is carried by a panel link, whose frame is rigid at rest
and in motion, so the shapes are exact at rest whatever chain the exporters
build between two panels:

- ``panel{k}``: one cylinder around the panel (its rim, pockets and the rod
  inside it), coaxial with the tail;
- each SOA of a joint as two cylinders along its own axis, the half next to
  panel ``k-1`` carried by it and the half next to panel ``k`` by that panel,
  meeting at the middle of the gap (a soft column bends; two rigid halves
  follow both of its ends);
- the rod piece in each gap likewise as two coaxial cylinders.

Each cylinder contains its B-rep piece: its radius is the piece's largest
distance from the axis, its ends the piece's extremes along it (tessellation
vertices, which lie on the exact surfaces, plus :data:`FIT_TOLERANCE_MM`).
The SOA parts inside the panels' pockets are covered by the panel cylinders,
so the halves start at the panel faces. Cylinders, not capsules: the SOA's
12 mm caps would stand out 6 mm beyond the 6 mm tip and root panels, a box's
corners past the panel rim; URDF has no capsule, and one shape kind keeps the
MJX collision functions of a scene few.

``robot.collision_geometry = "convex"`` gives each of the same pieces as a
mesh (the exporters write its convex hull) instead of its cylinder.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import build123d as bd
import numpy as np
from scipy.spatial import ConvexHull

from .. import units
from ..parts.kernel import bounds, location, mesh_arrays
from ..parts.vertebra import rod
from .assemble import Assembly

#: Allowed values of ``robot.collision_geometry``.
COLLISION_GEOMETRIES = ("primitives", "convex")
#: Tessellation deflection of the fit; added to every fitted extent so the shape holds the B-rep.
FIT_TOLERANCE_MM = 0.01
_ANGULAR_TOLERANCE = 0.1


@dataclass(frozen=True, eq=False)
class Collision:
    """One collision shape in its link's frame.

    ``cylinder``: radius and length (m), axis along the geom frame's z, centred on its origin.
    ``mesh``: the convex hull of ``solid`` (link frame, mm), written by the exporters.
    """

    name: str
    kind: str  # cylinder, mesh
    covers: str  # panel, soa, rod
    radius_m: float
    length_m: float
    T_link_geom: tuple[tuple[float, ...], ...]  # metres
    solid: bd.Shape | None = None
    radial_margin_mm: float = 0.0  # radius minus the piece's largest distance from the axis
    volume_ratio: float = 1.0  # shape volume / the B-rep's convex hull volume (see margins())


@dataclass(frozen=True)
class CylinderFit:
    radius_mm: float
    z0_mm: float
    z1_mm: float
    T_mm: np.ndarray  # the axis frame (z along the axis) in the piece's frame
    max_radius_mm: float  # the B-rep's largest distance from the axis (vertices)
    hull_volume_mm3: float  # the B-rep's convex hull (its outline: an SOA is hollow)

    @property
    def length_mm(self) -> float:
        return self.z1_mm - self.z0_mm

    def volume_mm3(self) -> float:
        return float(np.pi * self.radius_mm**2 * self.length_mm)


def fit_cylinder(piece: bd.Shape, T_axis_mm: np.ndarray) -> CylinderFit:
    """The smallest cylinder about the axis frame ``T_axis_mm`` (its z) holding ``piece`` (mm)."""
    T = np.asarray(T_axis_mm, float)
    # An absolute deflection: the part's print STL triangulation (the same tolerances), whichever
    # stages ran before (build123d's bounding_box clears a triangulation; OCCT makes the same one
    # again).
    p, _ = mesh_arrays(piece, FIT_TOLERANCE_MM, _ANGULAR_TOLERANCE, relative=False)
    local = (p - T[:3, 3]) @ T[:3, :3]
    r = float(np.max(np.hypot(local[:, 0], local[:, 1])))
    return CylinderFit(
        r + FIT_TOLERANCE_MM,
        float(local[:, 2].min()) - FIT_TOLERANCE_MM,
        float(local[:, 2].max()) + FIT_TOLERANCE_MM,
        T,
        r,
        float(ConvexHull(p).volume),
    )


def cylinder_solid(c: Collision) -> bd.Shape:
    """A cylinder collision as a B-rep in its link's frame, mm (for checks)."""
    length = units.m_to_mm(c.length_m)
    T = np.array(c.T_link_geom, float)
    T[:3, 3] = units.m_to_mm(T[:3, 3])
    return bd.Solid.make_cylinder(units.m_to_mm(c.radius_m), length).moved(
        location(T @ _translation_mm(-length / 2))
    )


def slab(solid: bd.Shape, z0_mm: float, z1_mm: float) -> bd.Shape:
    """The part of ``solid`` between two planes z = z0 and z = z1 of its frame (exact boolean)."""
    bb = bounds(solid)
    w = 2.0 * max(abs(bb.min.X), abs(bb.max.X), abs(bb.min.Y), abs(bb.max.Y)) + 2.0
    box = bd.Solid.make_box(w, w, z1_mm - z0_mm).moved(bd.Location((-w / 2, -w / 2, z0_mm)))
    parts = solid.intersect(box)
    parts = list(parts) if isinstance(parts, (list, tuple)) else [parts]
    return parts[0] if len(parts) == 1 else bd.Compound(parts)


def _translation_mm(z: float) -> np.ndarray:
    T = np.eye(4)
    T[2, 3] = z
    return T


def _cylinder(
    name: str, covers: str, fit: CylinderFit, T_link_axis_mm: np.ndarray, z0_mm: float, z1_mm: float
) -> Collision:
    """The cylinder of ``fit``'s radius between z0 and z1 along an axis placed in the link frame."""
    return Collision(
        name,
        "cylinder",
        covers,
        units.mm_to_m(fit.radius_mm),
        units.mm_to_m(z1_mm - z0_mm),
        _si(T_link_axis_mm @ _translation_mm((z0_mm + z1_mm) / 2)),
        None,
        fit.radius_mm - fit.max_radius_mm,
        fit.volume_mm3() / fit.hull_volume_mm3,
    )


def _mesh(name: str, covers: str, solid: bd.Shape) -> Collision:
    return Collision(name, "mesh", covers, 0.0, 0.0, _si(np.eye(4)), solid)


def panel_collisions(
    asm: Assembly,
    rod_in_gap: dict[int, list[tuple[float, float]]],
    geometry: str = "primitives",
    fits: dict[str, CylinderFit] | None = None,
) -> dict[int, list[Collision]]:
    """Per panel index, its link's collision shapes (see the module docstring); ``rod_in_gap``:
    the tail-frame z ranges of rod in each gap; ``fits``: the panels' and the SOA's fits about their
    own axes by part name, those missing made here and added (a build keeps them in its cache)."""
    fits = {} if fits is None else fits

    def fit_of(part) -> CylinderFit:
        if part.name not in fits:
            fits[part.name] = fit_cylinder(part.solid, np.eye(4))
        return fits[part.name]

    if geometry not in COLLISION_GEOMETRIES:
        raise ValueError(
            f"robot.collision_geometry = {geometry!r}: allowed {', '.join(COLLISION_GEOMETRIES)}"
        )
    convex = geometry == "convex"
    spec = asm.spec
    t = spec.joint.panel_thickness_mm
    out: dict[int, list[Collision]] = {}
    for lay in asm.panel_layouts:
        panel = asm.part_of(asm.panel(lay.index))
        out[lay.index] = [_panel_shape(f"panel{lay.index}", panel.solid, fit_of(panel), convex)]
    r_rod_mm = spec.vertebra.diameter_mm / 2
    for k in range(1, spec.panels):
        lo, hi = asm.panel_layouts[k - 1], asm.panel_layouts[k]
        g0, g1 = lo.z0_mm + t, hi.z0_mm
        mid = (g0 + g1) / 2
        halves = ((k - 1, lo.z0_mm, g0, mid, "lower"), (k, hi.z0_mm, mid, g1, "upper"))
        for inst in asm.soas_of_joint(k):
            part = asm.part_of(inst)
            for panel, shape in _soa_halves(inst, part.solid, fit_of(part), halves, convex):
                out[panel].append(shape)
        for panel, shape in _rod_halves(k, rod_in_gap.get(k, []), r_rod_mm, halves, convex):
            out[panel].append(shape)
    return out


#: A joint's gap split at its middle, per half: (panel index, the panel's z0, the half's tail-frame
#: z range, "lower" or "upper"), mm.
_Halves = tuple[tuple[int, float, float, float, str], ...]


def _panel_shape(name: str, solid: bd.Shape, fit: CylinderFit, convex: bool) -> Collision:
    """A panel's own shape: its solid (convex) or the cylinder of its fit."""
    if convex:
        return _mesh(name, "panel", solid)
    return _cylinder(name, "panel", fit, np.eye(4), fit.z0_mm, fit.z1_mm)


def _soa_halves(
    inst, solid: bd.Shape, fit: CylinderFit, halves: _Halves, convex: bool
) -> Iterator[tuple[int, Collision]]:
    """An SOA's column in each half of its joint's gap, on the panel that half belongs to: the
    slab of its solid (convex), or its fit's cylinder cut where the half's planes cross the axis."""
    T_tail = np.asarray(inst.transform)
    d = T_tail[:3, 2]
    # Along the SOA's axis, a plane z = c of the tail cuts the column within +-r tan(tilt) of the
    # axis.
    overhang = fit.radius_mm * float(np.hypot(d[0], d[1]) / d[2])
    for panel, z_panel, a, b, which in halves:
        name = f"{inst.name}_{which}"
        if convex:
            cut = slab(solid.moved(location(T_tail)), a, b)
            yield panel, _mesh(name, "soa", cut.moved(bd.Location((0, 0, -z_panel))))
            continue
        s0, s1 = ((c - T_tail[2, 3]) / d[2] for c in (a, b))
        z0, z1 = max(fit.z0_mm, s0 - overhang), min(fit.z1_mm, s1 + overhang)
        yield panel, _cylinder(name, "soa", fit, _translation_mm(-z_panel) @ T_tail, z0, z1)


def _rod_halves(
    k: int, rod_ranges_mm: list[tuple[float, float]], r_rod_mm: float, halves: _Halves, convex: bool
) -> Iterator[tuple[int, Collision]]:
    """Joint k's rod pieces (tail-frame z ranges) in each half of the gap they reach into: a rod
    solid (convex) or a cylinder of the rod's radius."""
    rod_fit = CylinderFit(r_rod_mm, 0.0, 1.0, np.eye(4), r_rod_mm, np.pi * r_rod_mm**2)
    for n, (z0, z1) in enumerate(rod_ranges_mm):
        for panel, z_panel, a, b, which in halves:
            lo_z, hi_z = max(z0, a), min(z1, b)
            if hi_z - lo_z <= 1e-9:
                continue
            name = f"j{k}_rod{n}_{which}"
            if convex:
                piece = rod(2 * r_rod_mm, hi_z - lo_z).moved(bd.Location((0, 0, lo_z - z_panel)))
                yield panel, _mesh(name, "rod", piece)
            else:
                yield (
                    panel,
                    _cylinder(name, "rod", rod_fit, np.eye(4), lo_z - z_panel, hi_z - z_panel),
                )


def _si(T_mm: np.ndarray) -> tuple[tuple[float, ...], ...]:
    T = np.array(T_mm, float)
    T[:3, 3] = T[:3, 3] / units.MM_PER_M
    return tuple(tuple(float(v) for v in row) for row in T)


def margins(collisions: dict[int, list[Collision]]) -> dict[str, dict[str, float]]:
    """Per kind of piece covered: count, largest radial margin (mm) and the range of the shapes'
    volume over their B-rep's convex hull (an SOA's: the whole part's), for the manifest."""
    out: dict[str, dict[str, float]] = {}
    for c in (c for cs in collisions.values() for c in cs):
        row = out.setdefault(
            c.covers,
            {
                "count": 0,
                "radial_margin_mm_max": 0.0,
                "volume_ratio_min": np.inf,
                "volume_ratio_max": 0.0,
            },
        )
        row["count"] += 1
        row["radial_margin_mm_max"] = max(row["radial_margin_mm_max"], c.radial_margin_mm)
        row["volume_ratio_min"] = float(min(row["volume_ratio_min"], c.volume_ratio))
        row["volume_ratio_max"] = float(max(row["volume_ratio_max"], c.volume_ratio))
    return out
