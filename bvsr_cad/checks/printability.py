"""Printability of every printed part of an export (the manifest's ``print_jobs``): the mesh checks.

Per STL, in the orientation it is exported in:

* ``print_fits_volume``: the bounding box fits the job's build volume (either way round on the bed);
* ``print_flat_base``: it rests on z = 0 with a flat face of some area;
* ``print_overhang``: the overhang map. A downward face steeper than
  ``max_overhang_deg`` from vertical is an overhang; connected overhang
  regions narrower than ``max_bridge_mm`` (bridges over holes, short ledges)
  print without support, wider ones are named with their place. Powder-bed
  (MJF) parts need no support: their map is reported, not judged;
* ``print_min_wall``: the thinnest wall, from rays cast inwards from the
  surface (embree) at area-weighted sample points;
* ``print_min_hole``: the smallest hole, the hydraulic diameter 4 A / P of
  every enclosed void in sections along x, y and z (manifold3d's planar
  sections; trimesh's when the STL is not a closed manifold);
* ``slice:<job>/<part>``: the STL slices in PrusaSlicer's command line, from the
  slice cache (:mod:`bvsr_cad.checks.slicer`, which drives the slicer and owns that cache);
* ``rigid_tail_envelope``: the rigid twin, assembled, against the BVSR at
  rest: every sample of the twin's outer surface lies within
  ``envelope_tolerance_mm`` of the BVSR's surface and every sample of the
  BVSR's surface lies inside the twin or on it, except inside the pin and
  tie-rod holes the twin adds.
* ``rigid_tail_robot_loads``: MuJoCo compiles the twin's MJCF and URDF.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from typing import Any

import manifold3d
import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from shapely.geometry import MultiPoint

from .export import Export
from .memo import CheckMemo
from .queries import contains
from .result import CheckResult
from .slicer import check_slicing

BED_Z_TOL_MM = 1e-6
MIN_BASE_AREA_MM2 = 25.0
#: A tessellated circle of n sides has 4 A / P = d cos(pi / n); allow for it.
HOLE_POLYGON_FACTOR = 0.97
WALL_SAMPLES = 3000
SECTIONS_PER_AXIS = 10
#: Rays that leave the part within this distance graze an edge: not a wall.
WALL_GRAZE_MM = 0.02
#: Opposite faces within this angle of parallel make a wall.
WALL_PARALLEL_DEG = 20.0


def _fits(size: np.ndarray, volume: list[float]) -> bool:
    x, y, z = (float(v) for v in size)
    vx, vy, vz = volume
    return z <= vz and ((x <= vx and y <= vy) or (x <= vy and y <= vx))


def overhang_regions(mesh: trimesh.Trimesh, max_overhang_deg: float) -> list[dict[str, Any]]:
    """Connected regions of downward faces steeper than ``max_overhang_deg`` from vertical (bed
    excluded)."""
    n = mesh.face_normals
    zmin = mesh.bounds[0][2]
    on_bed = np.abs(mesh.triangles[:, :, 2] - zmin).max(axis=1) < 1e-4
    # Angle from vertical of a downward face = its normal's angle below the horizontal.
    steep = (n[:, 2] < -np.sin(np.radians(max_overhang_deg)) + 1e-9) & ~on_bed
    idx = np.flatnonzero(steep)
    if len(idx) == 0:
        return []
    # Connected components of the steep faces over shared edges; labels are numbered in
    # order of each region's lowest face index.
    adj = mesh.face_adjacency.reshape(-1, 2)
    adj = adj[steep[adj[:, 0]] & steep[adj[:, 1]]]
    local = np.full(len(n), -1)
    local[idx] = np.arange(len(idx))
    graph = coo_matrix(
        (np.ones(len(adj)), (local[adj[:, 0]], local[adj[:, 1]])), shape=(len(idx), len(idx))
    )
    count, labels = connected_components(graph, directed=False)
    order = np.argsort(labels, kind="stable")
    groups = np.split(idx[order], np.cumsum(np.bincount(labels, minlength=count))[:-1])
    regions = []
    for faces in groups:
        pts = mesh.triangles[faces].reshape(-1, 3)
        area = float(mesh.area_faces[faces].sum())
        hull = MultiPoint(pts[:, :2]).minimum_rotated_rectangle
        if hull.geom_type == "Polygon":
            xy = np.asarray(hull.exterior.coords)[:4]
            sides = np.linalg.norm(np.diff(np.vstack([xy, xy[:1]]), axis=0), axis=1)
            width = float(min(sides[0], sides[1]))
        else:
            width = 0.0
        c = (mesh.triangles_center[faces] * mesh.area_faces[faces, None]).sum(axis=0) / max(
            area, 1e-12
        )
        regions.append(
            {"area_mm2": area, "width_mm": width, "centre_mm": [round(float(v), 2) for v in c]}
        )
    return sorted(regions, key=lambda r: -r["area_mm2"])


def min_wall_mm(
    mesh: trimesh.Trimesh, samples: int = WALL_SAMPLES, seed: int = 0, horizontal: bool = False
) -> tuple[float, list[float]]:
    """Thinnest wall: rays from area-weighted surface samples inwards to an opposite face within
    ``WALL_PARALLEL_DEG`` of parallel."""
    rng = np.random.default_rng(seed)
    p = mesh.area_faces / mesh.area_faces.sum()
    faces = rng.choice(len(mesh.faces), size=min(samples, len(mesh.faces)), replace=False, p=p)
    # Walls (faces within 45 deg of vertical) and plates (the rest) have different limits in FDM:
    # a wall is extrusion widths, a plate is layers.
    flat = np.abs(mesh.face_normals[faces, 2]) > np.sqrt(0.5)
    faces = faces[flat] if horizontal else faces[~flat]
    if len(faces) == 0:
        return float("inf"), [0.0, 0.0, 0.0]
    origins = mesh.triangles_center[faces] - mesh.face_normals[faces] * 1e-4
    dirs = -mesh.face_normals[faces]
    locs, ray_idx, tri_idx = mesh.ray.intersects_location(origins, dirs, multiple_hits=False)
    if len(ray_idx) == 0:
        return float("inf"), [0.0, 0.0, 0.0]
    d = np.linalg.norm(locs - origins[ray_idx], axis=1)
    # A wall has an opposite face nearly parallel to the one the ray leaves; the tip of a
    # wedge (a sharp edge) is thin by nature and prints as the edge it is.
    parallel = np.einsum("ij,ij->i", mesh.face_normals[tri_idx], dirs[ray_idx]) >= np.cos(
        np.radians(WALL_PARALLEL_DEG)
    )
    ok = (d > WALL_GRAZE_MM) & parallel
    if not ok.any():
        return float("inf"), [0.0, 0.0, 0.0]
    i = int(np.argmin(np.where(ok, d, np.inf)))
    return float(d[i]), [round(float(v), 2) for v in origins[ray_idx[i]]]


def _voids(path) -> list[tuple[float, float, np.ndarray]]:
    """(area, 4 A / P, centroid) of every enclosed void of a trimesh planar section."""
    from shapely.geometry import Polygon

    out = []
    if path is None:
        return out
    for poly in path.polygons_full:
        for ring in poly.interiors:
            hole = Polygon(ring)
            if hole.length > 0:
                out.append(
                    (hole.area, 4.0 * hole.area / hole.length, np.asarray(hole.centroid.coords[0]))
                )
    return out


def _ring_voids(rings) -> list[tuple[float, float, np.ndarray]]:
    """(area, 4 A / P, centroid) of every hole of a manifold3d cross-section: its clockwise
    contours."""
    out = []
    for ring in rings:
        r = np.asarray(ring, float)
        if len(r) < 3:
            continue
        x, y = r[:, 0], r[:, 1]
        xn, yn = np.roll(x, -1), np.roll(y, -1)
        cross = x * yn - xn * y
        area = 0.5 * float(cross.sum())
        if area >= 0.0:  # an outline (counter-clockwise), not a hole
            continue
        perimeter = float(np.hypot(xn - x, yn - y).sum())
        centroid = np.array([((x + xn) * cross).sum(), ((y + yn) * cross).sum()]) / (6.0 * area)
        out.append((-area, -4.0 * area / perimeter, centroid))
    return out


#: Rigid maps that turn x (resp. y, z) into z, so that a z section of the mapped solid is an x (y,
#: z) section.
_AXIS_TO_Z = (
    np.array([[0.0, 1, 0, 0], [0, 0, 1, 0], [1, 0, 0, 0]]),
    np.array([[0.0, 0, 1, 0], [1, 0, 0, 0], [0, 1, 0, 0]]),
    np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]),
)


def _manifold(mesh: trimesh.Trimesh) -> manifold3d.Manifold | None:
    """The mesh as a manifold3d solid (double precision), or None if it is not a closed manifold."""
    solid = manifold3d.Manifold(
        manifold3d.Mesh64(
            vert_properties=np.asarray(mesh.vertices, np.float64),
            tri_verts=np.asarray(mesh.faces, np.uint32),
        )
    )
    return solid if solid.status() == manifold3d.Error.NoError and not solid.is_empty() else None


def _section_voids(
    mesh: trimesh.Trimesh, solid: manifold3d.Manifold | None, axis: int, offsets: np.ndarray
):
    """Voids of the sections normal to ``axis`` at ``bounds[0][axis] + offsets``: manifold3d's
    planar sections of ``solid``, or trimesh's sections of the mesh when it is not a closed manifold
    (None if trimesh cannot cut it)."""
    lo = mesh.bounds[0]
    if solid is not None:
        turned = solid.transform(_AXIS_TO_Z[axis])
        return [_ring_voids(turned.slice(float(lo[axis] + h)).to_polygons()) for h in offsets]
    normal = np.zeros(3)
    normal[axis] = 1.0
    try:
        paths = mesh.section_multiplane(
            plane_origin=lo.copy(), plane_normal=normal, heights=offsets
        )
    except (ValueError, IndexError):
        return None
    return [_voids(path) for path in paths]


def min_hole_mm(
    mesh: trimesh.Trimesh, sections: int = SECTIONS_PER_AXIS, step_mm: float = 0.25
) -> tuple[float, str]:
    """Smallest hole whose axis runs along x, y or z: the hydraulic diameter 4 A / P of an
    enclosed void that appears with the same size and place in two sections ``step_mm`` apart
    (a section grazing a hole across it makes a thin sliver that is not a hole). Of holes equal
    within ``1e-6`` mm the first found (x, then y, then z; from below) gives the place."""
    best, where = float("inf"), ""
    lo, hi = mesh.bounds
    solid = _manifold(mesh)
    for axis in range(3):
        span = hi[axis] - lo[axis]
        base = (
            np.linspace(lo[axis] + 0.013 * span, hi[axis] - 0.011 * span - step_mm, sections)
            - lo[axis]
        )
        heights = np.sort(np.concatenate([base, base + step_mm]))
        voids = _section_voids(mesh, solid, axis, heights)
        if voids is None:
            continue
        for i in range(0, len(heights) - 1, 2):
            a, b = voids[i], voids[i + 1]
            for area, d, c in a:
                twin = any(
                    np.linalg.norm(c - c2) < 0.2 and abs(area2 - area) <= 0.15 * area
                    for area2, _d2, c2 in b
                )
                if twin and d < best - 1e-6:
                    best, where = d, f"{'xyz'[axis]} = {lo[axis] + heights[i]:.2f} mm"
    return best, where


def _bvsr_rest_meshes(exp: Export) -> list[trimesh.Trimesh]:
    parts = {p["name"]: p for p in exp.parts}
    out = []
    for inst in exp.manifest["assembly"]["instances"]:
        p = parts[inst["part"]]
        m = exp.part_frame_mesh(p)
        m.apply_transform(np.asarray(inst["transform"], float))
        out.append(m)
    return out


def _in_features(
    points: np.ndarray, features: list[dict[str, Any]], margin_mm: float
) -> np.ndarray:
    inside = np.zeros(len(points), bool)
    for f in features:
        p0, p1 = np.asarray(f["p0_mm"]), np.asarray(f["p1_mm"])
        axis = p1 - p0
        L = np.linalg.norm(axis)
        axis /= L
        rel = points - p0
        t = rel @ axis
        radial = np.linalg.norm(rel - np.outer(t, axis), axis=1)
        inside |= (
            (t >= -margin_mm) & (t <= L + margin_mm) & (radial <= f["diameter_mm"] / 2 + margin_mm)
        )
    return inside


class _SurfaceIndex:
    """Closest points on a triangle mesh (the distances ``trimesh.proximity.closest_point`` finds,
    to rounding: the tests compare the two) from libigl's AABB tree, built once per mesh in C++,
    rather than trimesh's k-d tree bound and R-tree search in Python: the envelope check queries
    the twin's and the tail's whole meshes at rest. A point equally near two triangles (an
    edge, a corner) gets either: :meth:`signed_distance` takes the sign from a triangle's normal
    only where the point lies over that triangle, which is right for either, and from ``contains``
    elsewhere."""

    def __init__(self, mesh: trimesh.Trimesh):
        import igl

        self.mesh = mesh
        self.vertices = np.ascontiguousarray(mesh.vertices, np.float64)
        self.faces = np.ascontiguousarray(mesh.faces, np.int64)
        self.tri = self.vertices[self.faces]
        self.tree = igl.AABB()
        self.tree.init(self.vertices, self.faces)

    def closest_point(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(closest point, distance, triangle id) per point."""
        pts = np.ascontiguousarray(points, np.float64).reshape(-1, 3)
        if len(pts) == 0:
            return np.zeros((0, 3)), np.zeros(0), np.zeros(0, np.int64)
        d2, tid, close = self.tree.squared_distance(self.vertices, self.faces, pts)
        return (
            np.asarray(close, np.float64),
            np.sqrt(np.maximum(np.asarray(d2, np.float64), 0.0)),
            np.asarray(tid, np.int64).ravel(),
        )

    def signed_distance(
        self, points: np.ndarray, contains: Callable[[np.ndarray], np.ndarray] | None = None
    ) -> np.ndarray:
        """Positive inside, as ``trimesh.proximity.signed_distance``: the sign from the closest
        face's normal where the point projects into that face, else from ``contains`` (default: a
        ray test on the mesh)."""
        from trimesh.constants import tol
        from trimesh.triangles import points_to_barycentric

        pts = np.asarray(points, np.float64)
        closest, distance, tid = self.closest_point(pts)
        nonzero = np.flatnonzero(distance > tol.merge)
        if len(nonzero) == 0:
            return distance
        normals = self.mesh.face_normals[tid[nonzero]]
        p = pts[nonzero]
        projection = p - normals * np.einsum("ij,ij->i", p - closest[nonzero], normals)[:, None]
        bary = points_to_barycentric(self.tri[tid[nonzero]], projection)
        on = ~((bary < -tol.merge) | (bary > 1 + tol.merge)).any(axis=1)
        sign = np.sign(np.einsum("ij,ij->i", normals[on], p[on] - projection[on]))
        distance[nonzero[on]] *= -1.0 * sign
        inside = (contains or self.mesh.ray.contains_points)(p[~on])
        distance[nonzero[~on]] *= inside.astype(int) * 2 - 1.0
        return distance


def _inside_any(
    meshes: list[trimesh.Trimesh], points: np.ndarray, skip: np.ndarray | None = None
) -> np.ndarray:
    """Which points lie inside one of ``meshes``; ``skip[i]``: a mesh not to test point i in (its
    own piece)."""
    inside = np.zeros(len(points), bool)
    for k, m in enumerate(meshes):
        lo, hi = m.bounds
        sel = np.all((points >= lo - 1e-6) & (points <= hi + 1e-6), axis=1) & ~inside
        if skip is not None:
            sel &= skip != k
        if sel.any():
            idx = np.flatnonzero(sel)
            inside[idx[contains(m, points[idx])]] = True
    return inside


#: A sample of a twin piece's surface is on the twin's outer surface unless the point this far
#: out along its normal is inside another piece: faces where two pieces meet (the STLs leave
#: them a few nanometres apart) are not surface of the assembled twin.
OUTER_PROBE_MM = 1e-3


def envelope_reads(exp: Export) -> tuple[list[str], Any]:
    """What :func:`check_envelope` reads: the twin's pieces and the BVSR's instances (STLs,
    transforms, features) and the manifest's ``rigid_tail`` tolerance and filled features."""
    rt = exp.manifest.get("rigid_tail") or {}
    parts = {p["name"]: p for p in exp.parts}
    pieces = [p for p in exp.parts if p["kind"] == "rigid_tail"]
    instances = exp.manifest["assembly"]["instances"] if rt else []
    used = sorted({i["part"] for i in instances})
    files = [p["files"]["stl"] for p in pieces] + [parts[n]["files"]["stl"] for n in used]
    return files, {
        "rigid_tail": [rt.get("envelope_tolerance_mm"), rt.get("filled_features")],
        "pieces": [
            [
                p["files"]["stl"],
                p["print_transform"],
                p["tail_transform"],
                p["info"]["print_features"],
            ]
            for p in pieces
        ],
        "parts": [[n, parts[n]["files"]["stl"], parts[n]["print_transform"]] for n in used],
        "instances": [[i["part"], i["transform"]] for i in instances],
    }


def check_envelope(exp: Export, samples: int = 6000, seed: int = 1) -> list[CheckResult]:
    """The rigid twin's outer surface against the BVSR at rest (both ways). The twin is its pieces,
    assembled: a point is inside it when it is inside a piece, and its outer surface is the pieces'
    surface less the faces where two pieces meet."""
    rt = exp.manifest.get("rigid_tail")
    if not rt:
        return []
    tol = float(rt["envelope_tolerance_mm"])
    pieces = [p for p in exp.parts if p["kind"] == "rigid_tail"]
    features = [f for p in pieces for f in p["info"]["print_features"]] + list(
        rt.get("filled_features", [])
    )
    rigid_parts = []
    for p in pieces:
        m = exp.part_frame_mesh(p)  # a copy
        m.apply_transform(np.asarray(p["tail_transform"], float))
        rigid_parts.append(m)
    rigid = trimesh.util.concatenate(rigid_parts)
    piece_of_face = np.repeat(np.arange(len(rigid_parts)), [len(m.faces) for m in rigid_parts])
    bvsr = _bvsr_rest_meshes(exp)
    bvsr_all = trimesh.util.concatenate(bvsr)
    rng = np.random.default_rng(seed)
    margin = 0.3
    # Twin -> BVSR: every outer-surface sample of the twin is on the BVSR's surface. Twice as many
    # samples of the pieces' surfaces as wanted; the first ``samples`` on the outer surface are
    # kept.
    pts, fid = trimesh.sample.sample_surface(rigid, 2 * samples, seed=int(rng.integers(1 << 31)))
    probe = pts + OUTER_PROBE_MM * rigid.face_normals[fid]
    pts = pts[~_inside_any(rigid_parts, probe, skip=piece_of_face[fid])][:samples]
    pts = pts[~_in_features(pts, features, margin)]
    _, d_out, _ = _SurfaceIndex(bvsr_all).closest_point(pts)
    i = int(np.argmax(d_out))
    # BVSR -> twin: every BVSR surface sample is inside the twin or on its surface.
    bpts, _ = trimesh.sample.sample_surface(bvsr_all, samples, seed=int(rng.integers(1 << 31)))
    bpts = bpts[~_in_features(bpts, features, margin)]
    sd = _SurfaceIndex(rigid).signed_distance(
        bpts, lambda q: _inside_any(rigid_parts, q)
    )  # positive inside
    j = int(np.argmin(sd))
    outside = float(max(0.0, -sd[j]))
    where = "rigid_tail/* vs the BVSR at rest"
    return [
        CheckResult(
            "rigid_tail_envelope_twin_on_bvsr",
            float(d_out[i]) <= tol,
            float(d_out[i]),
            tol,
            "mm",
            where,
            f"{len(pts)} samples of the twin's surface (pin, tie-rod and nut holes and the filled "
            "pneumatic and "
            "socket features excluded); farthest from "
            f"the BVSR's surface at {np.round(pts[i], 2).tolist()}",
        ),
        CheckResult(
            "rigid_tail_envelope_bvsr_inside_twin",
            outside <= tol,
            outside,
            tol,
            "mm",
            where,
            f"{len(bpts)} samples of the BVSR's surface; farthest outside the twin at "
            f"{np.round(bpts[j], 2).tolist()}",
        ),
    ]


def check_rigid_robot(exp: Export) -> list[CheckResult]:
    rt = exp.manifest.get("rigid_tail", {}).get("robot")
    if not rt:
        return []
    import mujoco

    out = []
    for key in ("mjcf", "urdf"):
        path = exp.root / rt[key]
        try:
            model = mujoco.MjModel.from_xml_path(str(path))
            data = mujoco.MjData(model)
            mujoco.mj_step(model, data)
            mass = float(model.body_mass.sum())
            ok = abs(mass - rt["mass_kg"]) <= 1e-6 * max(1.0, rt["mass_kg"])
            note = (
                f"MuJoCo {mujoco.__version__}: {model.nbody - 1} body, {model.njnt} joints, "
                f"mass {mass:.4f} kg"
            )
        except Exception as exc:  # MuJoCo raises ValueError with its own message
            ok, note = False, f"MuJoCo failed: {exc}"
        out.append(CheckResult(f"rigid_tail_robot_loads:{key}", ok, int(ok), 1, "", rt[key], note))
    return out


def print_item_reads(
    job: dict[str, Any], it: dict[str, Any], fab: dict[str, Any]
) -> tuple[list[str], Any]:
    """What :func:`check_print_item` reads: the item's STL, its name and kind, the job's process and
    build volume, the manifest's ``fabrication`` limits."""
    return [it["stl"]], {
        "job": [job["name"], job["process"], job["build_volume_mm"]],
        "item": [it["part"], it["kind"], it["stl"]],
        "fabrication": fab,
    }


def check_print_item(
    exp: Export, job: dict[str, Any], it: dict[str, Any], fab: dict[str, Any]
) -> list[CheckResult]:
    """The printability checks of one STL of a print job."""
    fdm = job["process"] == "FDM"
    rel, name = it["stl"], f"{job['name']}/{it['part']}"
    mesh = exp.mesh(rel)
    return [
        *_bed_checks(mesh, name, rel, job["build_volume_mm"]),
        _overhang_check(mesh, name, rel, fab, fdm),
        *_thickness_checks(mesh, name, rel, fab, fdm, it["kind"]),
        _hole_check(mesh, name, rel, fab, fdm),
    ]


def _bed_checks(
    mesh: trimesh.Trimesh, name: str, rel: str, volume_mm: list[float]
) -> list[CheckResult]:
    """The item fits the printer's build volume and stands on the bed on a flat base."""
    lo, hi = mesh.bounds
    size = hi - lo
    fits = CheckResult(
        f"print_fits_volume:{name}",
        _fits(size, volume_mm),
        [round(float(v), 2) for v in size],
        volume_mm,
        "mm",
        rel,
    )
    zmin = float(lo[2])
    down = (mesh.face_normals[:, 2] < -0.9999) & (
        np.abs(mesh.triangles[:, :, 2] - zmin).max(axis=1) < 1e-6
    )
    base = float(mesh.area_faces[down].sum())
    flat = CheckResult(
        f"print_flat_base:{name}",
        abs(zmin) < BED_Z_TOL_MM and base >= MIN_BASE_AREA_MM2,
        base,
        MIN_BASE_AREA_MM2,
        "mm2",
        rel,
        f"lowest z {zmin:.6f} mm",
    )
    return [fits, flat]


def _overhang_check(
    mesh: trimesh.Trimesh, name: str, rel: str, fab: dict[str, Any], fdm: bool
) -> CheckResult:
    """No overhang wider than a bridge needs support (FDM; a powder bed supports itself, so there
    the check only reports)."""
    regions = overhang_regions(mesh, fab["max_overhang_deg"])
    down_area = float(mesh.area_faces[mesh.face_normals[:, 2] < 0].sum())
    over = sum(r["area_mm2"] for r in regions)
    support = [r for r in regions if r["width_mm"] > fab["max_bridge_mm"]]
    frac = over / down_area if down_area > 0 else 0.0
    text = (
        f"{100 * frac:.2f} % of the downward area is steeper than {fab['max_overhang_deg']:g} deg "
        "from "
        f"vertical in {len(regions)} regions; {len(regions) - len(support)} no wider than "
        f"{fab['max_bridge_mm']:g} mm (bridges, short ledges)"
    )
    if support:
        text += "; needs support at " + "; ".join(
            f"{r['centre_mm']} ({r['area_mm2']:.1f} mm2, {r['width_mm']:.1f} mm wide)"
            for r in support[:5]
        )
    elif regions:
        r = max(regions, key=lambda r: r["width_mm"])
        text += f"; widest {r['width_mm']:.2f} mm at {r['centre_mm']}"
    if not fdm:
        text = "powder bed (MJF): no support needed; " + text
    return CheckResult(
        f"print_overhang:{name}",
        (len(support) == 0) if fdm else None,
        sum(r["area_mm2"] for r in support),
        0.0,
        "mm2 needing support",
        rel,
        text,
    )


def _thickness_checks(
    mesh: trimesh.Trimesh, name: str, rel: str, fab: dict[str, Any], fdm: bool, kind: str
) -> list[CheckResult]:
    """The thinnest wall and the thinnest plate reach the process's minimum (a mold's own minimum
    for molds and mold cores)."""
    wall, at = min_wall_mm(mesh)
    plate, at_plate = min_wall_mm(mesh, horizontal=True)
    wall_min = fab["fdm_min_wall_mm"] if fdm else fab["mjf_min_wall_mm"]
    plate_min = fab["fdm_min_plate_mm"] if fdm else fab["mjf_min_wall_mm"]
    if kind in ("mold", "mold_core"):
        wall_min = plate_min = fab["mold_min_wall_mm"]
    note = "" if fdm else f"; limit {fab.get('mjf_min_wall_note', '')}"
    return [
        CheckResult(
            f"print_min_wall:{name}",
            wall >= wall_min,
            wall,
            wall_min,
            "mm",
            rel,
            f"thinnest wall (faces within 45 deg of vertical) at {at}, rays inwards to a "
            f"parallel face{note}",
        ),
        CheckResult(
            f"print_min_plate:{name}",
            plate >= plate_min,
            plate,
            plate_min,
            "mm",
            rel,
            f"thinnest plate (faces within 45 deg of horizontal) at {at_plate}{note}",
        ),
    ]


def _hole_check(
    mesh: trimesh.Trimesh, name: str, rel: str, fab: dict[str, Any], fdm: bool
) -> CheckResult:
    """The smallest enclosed void is one the process can print open (its polygonal section
    allowed for)."""
    hole, where = min_hole_mm(mesh)
    hole_min = fab["fdm_min_hole_mm"] if fdm else fab["mjf_min_hole_mm"]
    return CheckResult(
        f"print_min_hole:{name}",
        hole >= HOLE_POLYGON_FACTOR * hole_min,
        hole if np.isfinite(hole) else None,
        hole_min,
        "mm",
        rel,
        f"smallest enclosed void (4 A / P) at {where}"
        if where
        else "no enclosed void in any section",
    )


def check_printability(
    exp: Export, sliced_now: Collection[str] = (), memo: CheckMemo | None = None
) -> list[CheckResult]:
    """Every printability check on every STL the manifest's ``print_jobs`` names (slicing results
    from the cache: see :func:`check_slicing`). ``memo``: verdicts of unchanged inputs from the
    artifact cache."""
    jobs = exp.manifest.get("print_jobs")
    if not jobs:
        return []
    memo = memo or CheckMemo(exp)
    fab = exp.manifest["fabrication"]
    out: list[CheckResult] = []
    for job in jobs:
        for it in job["items"]:
            out += memo(
                "print_item",
                print_item_reads(job, it, fab),
                lambda job=job, it=it: check_print_item(exp, job, it, fab),
            )
    out += check_slicing(exp, sliced_now=sliced_now)
    out += memo("envelope", envelope_reads(exp), lambda: check_envelope(exp))
    out += check_rigid_robot(exp)
    return out
