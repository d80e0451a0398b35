"""Checks on the SOA mold set saved in an export: is the set castable?

Everything here works on meshes (the files the export names, or meshes a
test builds in memory), never on CAD geometry:

* cavity: the closed mold's void (bounding box minus the union of every mold
  part, manifold3d booleans) minus the gate and vent channels equals the cast
  part within 0.5 % in volume; no mold part intrudes into the cast and no two
  mold parts overlap; every bit of the cast surface is formed by a part or
  opens into a channel;
* demoldability: each rigid part withdrawn along its pull direction: the
  draft of every cast facet the part forms (from the facet normals) and the
  fraction of that surface whose ray along the pull hits the cast (blocked);
* printability: every mold part watertight, one body, on the bed in its print
  orientation, walls at least ``min_print_wall_mm`` thick;
* channels: the gate and every vent open onto the cavity, reach the outside of
  the closed mold and hold no mold material;
* PU volume and mass per casting (informational, for the BOM).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import manifold3d
import numpy as np
import trimesh

from .export import Export
from .queries import contains
from .result import CheckResult as _CheckResult

CAVITY_VOLUME_TOLERANCE = 0.005  # 0.5 % of the cast volume
#: Tessellation leaves slivers where two meshes of one surface meet; real
#: intrusions or overlaps are orders of magnitude larger than this.
INTRUSION_TOLERANCE = 0.0005  # 0.05 % of the cast volume
#: Cast facets are resampled to this edge length so that draft, blocked area
#: and ownership are measured on small pieces, not on whole tessellation facets.
SAMPLE_EDGE_MM = 1.0
#: Sample points sit this far off the cast surface, in the mold, for ownership and rays.
SURFACE_OFFSET_MM = 0.02
#: A tessellated fillet or cylinder can show a slightly negative draft where the
#: true surface has none; anything steeper is an undercut.
DRAFT_TOLERANCE_DEG = -0.5
BLOCKED_LIMIT = 0.001  # 0.1 % of the surface a part forms
#: Two faces are opposite walls of one web when their normals are within this of anti-parallel.
WALL_OPPOSITION_DEG = 45.0
WALL_SAMPLE_EDGE_MM = 1.0
CHANNEL_OPENING_MIN = 0.5  # of the nominal cross-section


def _plain(v: Any) -> Any:
    """numpy scalars as Python ones, so every result serialises to JSON."""
    return v.item() if isinstance(v, np.generic) else v


def CheckResult(
    name: str,
    passed: Any,
    value: Any,
    limit: Any,
    unit: str,
    where: str,  # noqa: N802
    note: str = "",
) -> _CheckResult:
    """A :class:`~bvsr_cad.checks.result.CheckResult` with plain Python values."""
    return _CheckResult(
        name,
        None if passed is None else bool(passed),
        _plain(value),
        _plain(limit),
        unit,
        where,
        note,
    )


@dataclass(frozen=True)
class MoldMesh:
    """One mold part as the checks see it."""

    name: str
    assembled: trimesh.Trimesh  # cast frame
    pull_direction: np.ndarray | None  # None: sacrificial
    parting_planes: tuple[tuple[np.ndarray, np.ndarray], ...] = ()
    printed: trimesh.Trimesh | None = None  # print orientation
    where: str = ""


@dataclass(frozen=True)
class CastSamples:
    """The cast surface cut into small pieces, each with the part that forms it."""

    centres: np.ndarray  # (n, 3)
    normals: np.ndarray  # (n, 3) outward from the cast
    areas: np.ndarray  # (n,)
    owner: np.ndarray  # (n,) index into the part list, -1 none, -2 several


def to_manifold(mesh: trimesh.Trimesh) -> manifold3d.Manifold:
    """A watertight trimesh as a manifold3d solid (raises on a broken mesh)."""
    m = manifold3d.Manifold(
        manifold3d.Mesh64(
            vert_properties=np.asarray(mesh.vertices, np.float64),
            tri_verts=np.asarray(mesh.faces, np.uint32),
        )
    )
    if m.status() != manifold3d.Error.NoError:
        raise ValueError(f"not a closed manifold mesh ({m.status()})")
    return m


def _union(meshes: list[manifold3d.Manifold]) -> manifold3d.Manifold:
    return manifold3d.Manifold.batch_boolean(meshes, manifold3d.OpType.Add)


def subdivided_triangles(mesh: trimesh.Trimesh, max_edge: float, max_iter: int = 10) -> np.ndarray:
    """The triangles of ``trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, max_edge)``,
    as (n, 3, 3) corners (in another order), computed face by face: a face's pieces depend only on
    its own edges, so the shared-vertex bookkeeping (the slow part of trimesh's version) is not
    needed for centres, normals and areas."""
    tri = np.asarray(mesh.triangles, np.float64)
    done = []
    for i in range(max_iter + 1):
        ends = np.roll(tri, -1, axis=1)  # edge k runs from corner k to corner k + 1
        long_edge = np.sqrt(((tri - ends) ** 2).sum(axis=2)) > max_edge
        count = long_edge.sum(axis=1)
        done.append(tri[count == 0])
        if not count.any():
            break
        if i >= max_iter:
            raise ValueError("max_iter exceeded!")
        mid = (tri + ends) / 2.0
        pieces = []
        # One long edge (a, b): the midpoint p fans to the opposite corner c.
        sel = count == 1
        if sel.any():
            j = np.argmax(long_edge[sel], axis=1)
            r = np.arange(len(j))
            t, m = tri[sel], mid[sel]
            a, b, c, p = t[r, j], t[r, (j + 1) % 3], t[r, (j + 2) % 3], m[r, j]
            pieces += [np.stack([a, p, c], axis=1), np.stack([p, b, c], axis=1)]
        # Two long edges (a, b) and (b, c): the corner (p, b, q) and the quad (a, p, q, c) cut along
        # its shorter diagonal.
        sel = count == 2
        if sel.any():
            j = (np.argmin(long_edge[sel], axis=1) + 1) % 3
            r = np.arange(len(j))
            t, m = tri[sel], mid[sel]
            a, b, c = t[r, j], t[r, (j + 1) % 3], t[r, (j + 2) % 3]
            p, q = m[r, j], m[r, (j + 1) % 3]
            use_aq = (((a - q) ** 2).sum(axis=1) <= ((p - c) ** 2).sum(axis=1))[:, None]
            pieces += [
                np.stack([p, b, q], axis=1),
                np.where(use_aq[:, None], np.stack([a, p, q], axis=1), np.stack([a, p, c], axis=1)),
                np.where(use_aq[:, None], np.stack([a, q, c], axis=1), np.stack([p, q, c], axis=1)),
            ]
        # Three: the regular 1 -> 4 split.
        sel = count == 3
        if sel.any():
            t, m = tri[sel], mid[sel]
            v0, v1, v2 = t[:, 0], t[:, 1], t[:, 2]
            m0, m1, m2 = m[:, 0], m[:, 1], m[:, 2]
            pieces += [
                np.stack(x, axis=1)
                for x in ((v0, m0, m2), (m0, v1, m1), (m2, m1, v2), (m0, m1, m2))
            ]
        tri = np.concatenate(pieces)
    return np.concatenate(done)


def _centres_normals_areas(tri: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centres, unit normals (zero for a degenerate triangle, as trimesh) and areas of (n, 3, 3)
    triangles."""
    cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    norm = np.linalg.norm(cross, axis=1)
    normals = np.zeros_like(cross)
    ok = norm > 0
    normals[ok] = cross[ok] / norm[ok, None]
    return tri.mean(axis=1), normals, norm / 2.0


def cast_samples(
    cast: trimesh.Trimesh, parts: list[MoldMesh], channels: list[trimesh.Trimesh]
) -> CastSamples:
    """Resample the cast surface and find, for each piece, the part it touches.

    A piece belongs to the part that contains a point just outside the cast
    there; a piece outside every part must open into a channel.
    """
    centres, normals, areas = _centres_normals_areas(subdivided_triangles(cast, SAMPLE_EDGE_MM))
    probe = centres + SURFACE_OFFSET_MM * normals
    hits = np.zeros((len(parts), len(probe)), bool)
    for i, part in enumerate(parts):
        lo, hi = part.assembled.bounds
        near = np.all((probe >= lo - 1e-6) & (probe <= hi + 1e-6), axis=1)
        if near.any():
            hits[i, near] = contains(part.assembled, probe[near])
    count = hits.sum(axis=0)
    owner = np.where(count == 1, hits.argmax(axis=0), np.where(count == 0, -1, -2))
    return CastSamples(centres, normals, areas, owner)


def _boxes_apart(a: manifold3d.Manifold, b: manifold3d.Manifold) -> bool:
    """The bounding boxes do not overlap: the solids share no volume."""
    ba, bb = np.asarray(a.bounding_box()), np.asarray(b.bounding_box())
    return bool(np.any(ba[3:] <= bb[:3]) or np.any(bb[3:] <= ba[:3]))


def _shared_volume(a: manifold3d.Manifold, b: manifold3d.Manifold) -> float:
    return 0.0 if _boxes_apart(a, b) else (a ^ b).volume()


def check_cavity(
    cast: trimesh.Trimesh,
    parts: list[MoldMesh],
    channels: list[trimesh.Trimesh],
    samples: CastSamples,
    where: str = "molds",
    *,
    part_solids: list[manifold3d.Manifold] | None = None,
    closed: manifold3d.Manifold | None = None,
) -> list[CheckResult]:
    """The closed mold's void, minus the channels, is the cast part. ``part_solids`` and ``closed``
    (the parts as solids and their union) save converting them again."""
    cast_m = to_manifold(cast)
    part_m = part_solids if part_solids is not None else [to_manifold(p.assembled) for p in parts]
    closed = closed if closed is not None else _union(part_m)
    limit = INTRUSION_TOLERANCE * cast_m.volume()
    return [
        _cavity_volume_result(cast_m, closed, channels, where),
        _intrusion_result(cast_m, parts, part_m, limit, where),
        _overlap_result(parts, part_m, limit, where),
        _surface_formed_result(samples, channels, where),
    ]


def _cavity_volume_result(
    cast_m: manifold3d.Manifold,
    closed: manifold3d.Manifold,
    channels: list[trimesh.Trimesh],
    where: str,
) -> CheckResult:
    """The void of the ``closed`` mold that meets the cast, minus the channels, has the cast's
    volume."""
    cast_v = cast_m.volume()
    lo, hi = closed.bounding_box()[:3], closed.bounding_box()[3:]
    box = manifold3d.Manifold.cube(tuple(float(b - a) for a, b in zip(lo, hi))).translate(
        tuple(map(float, lo))
    )
    # The void also holds bolt holes and pin clearances; the cavity is the
    # part of it that meets the cast (the cast with its gate and vents).
    # A region smaller than half the cast cannot hold half of it: no need to intersect.
    regions = (box - closed).decompose()
    touching = [
        r for r in regions if r.volume() > 0.5 * cast_v and (r ^ cast_m).volume() > 0.5 * cast_v
    ]
    others = [r for r in regions if not any(r is t for t in touching)]
    void = _union(touching) if touching else manifold3d.Manifold()
    cavity = void - _union([to_manifold(c) for c in channels]) if channels else void
    cavity_v = cavity.volume()
    rel = (cavity_v - cast_v) / cast_v
    return CheckResult(
        "mold_cavity_volume",
        abs(rel) <= CAVITY_VOLUME_TOLERANCE,
        100.0 * rel,
        100.0 * CAVITY_VOLUME_TOLERANCE,
        "% of cast volume",
        where,
        f"void minus channels {cavity_v:.1f} mm3 against the cast {cast_v:.1f} mm3; "
        f"{len(touching)} cavity region(s); {len(others)} other void(s) (around the rotated "
        "block, bolt holes, pin clearances) "
        f"of {sum(r.volume() for r in others):.1f} mm3 do not reach the cast",
    )


def _intrusion_result(
    cast_m: manifold3d.Manifold,
    parts: list[MoldMesh],
    part_m: list[manifold3d.Manifold],
    limit: float,
    where: str,
) -> CheckResult:
    """No mold part reaches into the cast by more than ``limit`` mm3."""
    intrusions = {p.name: _shared_volume(m, cast_m) for p, m in zip(parts, part_m)}
    worst = max(intrusions, key=intrusions.get)
    return CheckResult(
        "mold_intrusion",
        intrusions[worst] <= limit,
        intrusions[worst],
        limit,
        "mm3",
        f"{where}:{worst}",
        "largest volume of mold material inside the cast: "
        + ", ".join(f"{k} {v:.3f}" for k, v in intrusions.items()),
    )


def _overlap_result(
    parts: list[MoldMesh], part_m: list[manifold3d.Manifold], limit: float, where: str
) -> CheckResult:
    """No two parts of the closed mold share more than ``limit`` mm3."""
    overlap, pair = 0.0, "-"
    for i in range(len(parts)):
        for j in range(i + 1, len(parts)):
            vol = _shared_volume(part_m[i], part_m[j])
            if vol > overlap:
                overlap, pair = vol, f"{parts[i].name}/{parts[j].name}"
    return CheckResult(
        "mold_parts_overlap",
        overlap <= limit,
        overlap,
        limit,
        "mm3",
        f"{where}:{pair}",
        "largest volume shared by two mold parts of the closed mold",
    )


def _surface_formed_result(
    samples: CastSamples, channels: list[trimesh.Trimesh], where: str
) -> CheckResult:
    """Every piece of the cast surface is formed by exactly one mold part or opens into a
    channel."""
    total = float(samples.areas.sum())
    several = float(samples.areas[samples.owner == -2].sum())
    free = samples.owner == -1
    if channels and free.any():
        probe = samples.centres[free] + SURFACE_OFFSET_MM * samples.normals[free]
        in_channel = np.zeros(len(probe), bool)
        for ch in channels:
            in_channel |= contains(ch, probe)
        uncovered = float(samples.areas[free][~in_channel].sum())
    else:
        uncovered = float(samples.areas[free].sum())
    bad = (uncovered + several) / total
    return CheckResult(
        "mold_cast_surface_formed",
        bad <= BLOCKED_LIMIT,
        100.0 * bad,
        100.0 * BLOCKED_LIMIT,
        "% of cast surface",
        where,
        f"{uncovered:.3f} mm2 touch no part and no channel, {several:.3f} mm2 touch two parts",
    )


def draft_and_blocking(
    cast: trimesh.Trimesh,
    part: MoldMesh,
    index: int,
    samples: CastSamples,
    parting_margin_mm: float,
) -> dict[str, float]:
    """Draft and ray-cast blocking of the cast surface one part forms.

    Returns:
        ``area_mm2`` formed by the part, ``min_draft_deg`` over the pieces
        farther than ``parting_margin_mm`` from the part's parting planes,
        ``min_draft_all_deg`` over every piece, ``blocked_fraction`` of the
        area whose ray along the pull hits the cast.
    """
    mine = samples.owner == index
    pull = np.asarray(part.pull_direction, float)
    pull = pull / np.linalg.norm(pull)
    centres, normals, areas = samples.centres[mine], samples.normals[mine], samples.areas[mine]
    if not mine.any():
        return {
            "area_mm2": 0.0,
            "min_draft_deg": math.nan,
            "min_draft_all_deg": math.nan,
            "blocked_fraction": 0.0,
        }
    draft = np.degrees(np.arcsin(np.clip(normals @ pull, -1.0, 1.0)))
    away = np.ones(len(centres), bool)
    for point, normal in part.parting_planes:
        n = normal / np.linalg.norm(normal)
        away &= np.abs((centres - point) @ n) > parting_margin_mm
    origins = centres + SURFACE_OFFSET_MM * normals
    blocked = cast.ray.intersects_any(origins, np.repeat(pull[None, :], len(origins), axis=0))
    return {
        "area_mm2": float(areas.sum()),
        "min_draft_deg": float(draft[away].min()) if away.any() else math.nan,
        "min_draft_all_deg": float(draft.min()),
        "blocked_fraction": float(areas[blocked].sum() / areas.sum()),
    }


def check_demolding(
    cast: trimesh.Trimesh, parts: list[MoldMesh], samples: CastSamples, parting_margin_mm: float
) -> list[CheckResult]:
    """Every rigid part comes off along its pull direction (the diagonal split: about 34 deg)."""
    out = []
    for i, part in enumerate(parts):
        if part.pull_direction is None:
            out.append(
                CheckResult(
                    f"mold_demold:{part.name}",
                    None,
                    "sacrificial",
                    "-",
                    "",
                    part.where,
                    "dissolved or melted out: no pull direction",
                )
            )
            continue
        r = draft_and_blocking(cast, part, i, samples, parting_margin_mm)
        ok = (
            r["blocked_fraction"] <= BLOCKED_LIMIT and r["min_draft_all_deg"] >= DRAFT_TOLERANCE_DEG
        )
        pull = ", ".join(f"{v:.4f}" for v in part.pull_direction)
        out.append(
            CheckResult(
                f"mold_demold:{part.name}",
                ok,
                100.0 * r["blocked_fraction"],
                100.0 * BLOCKED_LIMIT,
                "% of formed surface blocked",
                part.where,
                f"pulled along ({pull}): {'demoldable' if ok else 'NOT demoldable'}; forms "
                f"{r['area_mm2']:.1f} mm2, "
                f"draft >= {r['min_draft_all_deg']:.2f} deg everywhere (limit "
                f"{DRAFT_TOLERANCE_DEG:g})",
            )
        )
        out.append(
            CheckResult(
                f"mold_draft:{part.name}",
                None,
                r["min_draft_deg"],
                0.0,
                "deg",
                part.where,
                f"minimum draft over the surface it forms farther than {parting_margin_mm:.2f} mm "
                "from its parting planes",
            )
        )
    return out


def min_wall_mm(mesh: trimesh.Trimesh) -> tuple[float, np.ndarray]:
    """Thinnest web of a solid: from each (resampled) face into the material
    to the opposite face, counting only faces within WALL_OPPOSITION_DEG of
    anti-parallel (the ridge of a V-groove is not a thin wall).

    Returns:
        (thickness, location of the thinnest point).
    """
    centres, normals, _ = _centres_normals_areas(subdivided_triangles(mesh, WALL_SAMPLE_EDGE_MM))
    origins = centres - 1e-4 * normals
    locs, ray_idx, tri_idx = mesh.ray.intersects_location(origins, -normals, multiple_hits=False)
    if len(ray_idx) == 0:
        return math.inf, np.zeros(3)
    dist = np.linalg.norm(locs - origins[ray_idx], axis=1)
    opposite = (mesh.face_normals[tri_idx] * normals[ray_idx]).sum(axis=1) <= -math.cos(
        math.radians(WALL_OPPOSITION_DEG)
    )
    if not opposite.any():
        return math.inf, np.zeros(3)
    k = int(np.argmin(np.where(opposite, dist, np.inf)))
    return float(dist[k]), origins[ray_idx[k]]


def min_section_width_mm(mesh: trimesh.Trimesh, step_mm: float = 0.05) -> tuple[float, float]:
    """Narrowest cross-section of a bar-like part along its print Z: the short
    side of the smallest rectangle around each slice. The face-to-face rays of
    :func:`min_wall_mm` cannot see a neck between two V-shaped faces (a core's
    valley), which is where a sacrificial core breaks.

    Returns:
        (width, height of that slice).
    """
    from shapely.geometry import Polygon

    solid = to_manifold(mesh)
    lo, hi = mesh.bounds[0][2], mesh.bounds[1][2]
    best, at = math.inf, lo
    for z in np.arange(lo + step_mm / 2.0, hi, step_mm):
        for ring in solid.slice(float(z)).to_polygons():
            if len(ring) < 3:
                continue
            rect = np.asarray(Polygon(ring).minimum_rotated_rectangle.exterior.coords)
            sides = np.linalg.norm(np.diff(rect[:3], axis=0), axis=1)
            if sides.min() < best:
                best, at = float(sides.min()), float(z)
    return best, at


def check_printable(part: MoldMesh, min_wall_limit_mm: float) -> list[CheckResult]:
    mesh = part.printed if part.printed is not None else part.assembled
    where = part.where
    out = [
        CheckResult(
            f"mold_watertight:{part.name}",
            bool(mesh.is_watertight and mesh.is_winding_consistent),
            int(mesh.is_watertight and mesh.is_winding_consistent),
            1,
            "",
            where,
        )
    ]
    bodies = int(mesh.body_count)
    out.append(CheckResult(f"mold_one_body:{part.name}", bodies == 1, bodies, 1, "bodies", where))
    zmin = float(mesh.bounds[0][2])
    down = (mesh.face_normals[:, 2] < -0.9999) & (
        np.abs(mesh.triangles[:, :, 2] - zmin).max(axis=1) < 1e-6
    )
    bed = float(mesh.area_faces[down].sum())
    out.append(
        CheckResult(
            f"mold_on_bed:{part.name}",
            abs(zmin) < 1e-6 and bed > 0,
            bed,
            "> 0 at z = 0",
            "mm2",
            where,
            f"lowest z {zmin:.6f} mm",
        )
    )
    wall, at = min_wall_mm(mesh)
    note = "thinnest web at (" + ", ".join(f"{c:.2f}" for c in at) + ") in print frame"
    if part.pull_direction is None:
        neck, z = min_section_width_mm(mesh)
        note += f"; narrowest cross-section {neck:.3f} mm at print z {z:.2f} mm"
        wall = min(wall, neck)
    out.append(
        CheckResult(
            f"mold_min_wall:{part.name}",
            wall >= min_wall_limit_mm,
            wall,
            min_wall_limit_mm,
            "mm",
            where,
            note,
        )
    )
    return out


def check_channels(
    channels: list[tuple[str, float, trimesh.Trimesh]],
    parts: list[MoldMesh],
    samples: CastSamples,
    where: str = "molds",
    *,
    closed: manifold3d.Manifold | None = None,
) -> list[CheckResult]:
    """Each gate and vent opens onto the cavity, is empty and reaches the outside. ``closed``: the
    union of the parts, if already made."""
    closed = closed if closed is not None else _union([to_manifold(p.assembled) for p in parts])
    bb = np.asarray(closed.bounding_box())
    lo, hi = bb[:3], bb[3:]
    free = samples.owner == -1
    probe = samples.centres[free] + SURFACE_OFFSET_MM * samples.normals[free]
    out = []
    for name, diameter_mm, mesh in channels:
        opening = float(samples.areas[free][contains(mesh, probe)].sum()) if free.any() else 0.0
        nominal = math.pi * diameter_mm**2 / 4.0
        blocked = _shared_volume(to_manifold(mesh), closed)
        outside = bool(
            np.any(np.abs(mesh.bounds - lo).min(axis=0) < 1e-3)
            or np.any(np.abs(mesh.bounds - hi).min(axis=0) < 1e-3)
        )
        ok = opening >= CHANNEL_OPENING_MIN * nominal and outside and blocked <= 1e-3 * mesh.volume
        out.append(
            CheckResult(
                f"mold_channel:{name}",
                ok,
                opening,
                CHANNEL_OPENING_MIN * nominal,
                "mm2",
                where,
                f"opening onto the cavity (nominal {nominal:.2f} mm2); reaches the outside: "
                f"{outside}; mold material inside it {blocked:.4f} mm3",
            )
        )
    return out


def check_pu(
    cast: trimesh.Trimesh,
    channels: list[trimesh.Trimesh],
    density_g_cm3: float,
    soa_volume_mm3: float | None,
    where: str = "molds",
) -> list[CheckResult]:
    """PU per casting (for the BOM): the part, and the part with its gate and vents full."""
    part_v = float(cast.volume)
    shot_v = part_v + float(sum(c.volume for c in channels))
    out = [
        CheckResult(
            "mold_pu_part",
            None,
            part_v,
            "-",
            "mm3",
            where,
            f"{part_v / 1000.0 * density_g_cm3:.3f} g of PU in the part at {density_g_cm3} g/cm3",
        ),
        CheckResult(
            "mold_pu_shot",
            None,
            shot_v,
            "-",
            "mm3",
            where,
            f"{shot_v / 1000.0 * density_g_cm3:.3f} g per casting with gate and vents full",
        ),
    ]
    if soa_volume_mm3:
        out.append(
            CheckResult(
                "mold_cavity_vs_soa",
                None,
                100.0 * (part_v / soa_volume_mm3 - 1.0),
                "-",
                "% of SOA volume",
                where,
                f"cast part {part_v:.1f} mm3 (shrinkage allowance) against the SOA "
                f"{soa_volume_mm3:.1f} mm3",
            )
        )
    return out


def check_mold_set(
    cast: trimesh.Trimesh,
    parts: list[MoldMesh],
    channels: list[tuple[str, float, trimesh.Trimesh]],
    *,
    parting_margin_mm: float,
    min_wall_limit_mm: float,
    density_g_cm3: float,
    soa_volume_mm3: float | None = None,
    where: str = "molds",
) -> list[CheckResult]:
    """Every mold check on meshes (the entry point tests use with their own meshes)."""
    channel_meshes = [m for _, _, m in channels]
    samples = cast_samples(cast, parts, channel_meshes)
    part_solids = [to_manifold(p.assembled) for p in parts]
    closed = _union(part_solids)
    out = check_cavity(
        cast, parts, channel_meshes, samples, where, part_solids=part_solids, closed=closed
    )
    out += check_demolding(cast, parts, samples, parting_margin_mm)
    for part in parts:
        out += check_printable(part, min_wall_limit_mm)
    out += check_channels(channels, parts, samples, where, closed=closed)
    out += check_pu(cast, channel_meshes, density_g_cm3, soa_volume_mm3, where)
    return out


def mold_meshes(
    exp: Export,
) -> tuple[trimesh.Trimesh, list[MoldMesh], list[tuple[str, float, trimesh.Trimesh]]]:
    """The cast, the mold parts and the channels an export's manifest names."""
    molds = exp.manifest["molds"]
    parts = []
    for p in molds["parts"]:
        pull = p.get("pull_direction")
        planes = tuple(
            (np.asarray(pl["point"], float), np.asarray(pl["normal"], float))
            for pl in p.get("parting_planes", [])
        )
        parts.append(
            MoldMesh(
                p["name"],
                exp.mesh(p["files"]["assembled_stl"]),
                None if pull is None else np.asarray(pull, float),
                planes,
                exp.mesh(p["files"]["stl"]),
                p["files"]["stl"],
            )
        )
    channels = [
        (c["name"], float(c["diameter_mm"]), exp.mesh(c["files"]["stl"]))
        for c in molds.get("channels", [])
    ]
    return exp.mesh(molds["cast_part"]), parts, channels


def molds_reads(exp: Export) -> tuple[list[str], Any]:
    """What :func:`check_molds` reads: the manifest's ``molds`` section and the meshes it names."""
    molds = exp.manifest.get("molds") or {}
    files = [molds["cast_part"]] if molds else []
    for p in molds.get("parts", []):
        files += [p["files"]["assembled_stl"], p["files"]["stl"]]
    files += [c["files"]["stl"] for c in molds.get("channels", [])]
    return files, molds


def check_molds(exp: Export) -> list[CheckResult]:
    """Every mold check on an export (none when the export has no mold set)."""
    molds: dict[str, Any] | None = exp.manifest.get("molds")
    if not molds:
        return []
    cast, parts, channels = mold_meshes(exp)
    return check_mold_set(
        cast,
        parts,
        channels,
        parting_margin_mm=float(molds["parting_margin_mm"]),
        min_wall_limit_mm=float(molds["min_print_wall_mm"]),
        density_g_cm3=float(molds["density_g_cm3"]),
        soa_volume_mm3=molds.get("soa_volume_mm3"),
        where=molds["cast_part"],
    )
