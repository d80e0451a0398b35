"""Clearance between the posed solids of the tail over its workspace.

Deformation model: plane sections. A point of the tail at rest with height z
in the gap of joint k (arc parameter s = (z - z_start) / L) goes to
Base_k T_s(s w_k) (x, y, 0): every cross-section stays plane and normal to the
rod's arc, so the SOAs and the rod bend with their joint and stretch or shorten
with their distance from the bending axis; points inside a panel's thickness
(panels, the SOA flanges seated in the pockets, the rod in its bore) move
rigidly with that panel.

Stage 1 (every pose, vectorised). In a joint gap the map's metric is
diag(1, 1, lambda^2) in the rest coordinates, with lambda = 1 - kappa h,
kappa = theta / L and h = x cos(phi) + y sin(phi) a point's distance from the
rod towards the bending direction (identity in the panels). A straight
segment between two posed points pulls back to a rest curve that reaches at
most h_pair(phi) + L sum(theta) / 8 towards the bending direction (h_pair:
the pair's support function; the second term the segment's sagitta), so on
it the metric is at least diag(1, 1, lambda_min^2) with
    lambda_min = min over the joints the pair spans of 1 - kappa (h_pair(phi) + bulge).
Hence (valid for theta < L / h, about 1 rad, far beyond the workspace)
    clearance >= d_lambda(rest) >= min(1, lambda_min) x rest clearance,
where d_lambda is the rest distance after the joint gaps the pair spans are shortened by lambda_min
along z and the panels are not (the metric is identity in a panel: two SOAs stacked on either side
of a panel stay at least its thickness apart). Stage 1a evaluates the right-hand bound for every
pose and pair at once; stage 1b tightens the candidates below the running minimum with d_lambda,
taken from a per-pair table on a lambda grid (rest meshes cut at the gap faces and shortened,
python-fcl, computed on first use: d_lambda grows with lambda, so the grid value below is a bound).
It is what keeps, for instance, the flanges of two SOAs seated side by side in a panel at their rest
clearance: their gap is horizontal. Stage 2: exact mesh distances (python-fcl) of the posed meshes
for the lowest bounds confirm the minimum; it is certified when no unconfirmed (pose, pair) has a
bound below it.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import fcl
import numpy as np
import trimesh

from ..assembly.assemble import Assembly, build_assembly
from ..models.kinematics import TailKinematics, joint_transform_uv, theta_phi_from_uv
from ..parameters.tables import TailSpec
from ..parts.kernel import fresh_copy, mesh_arrays

Progress = Callable[[str], None]
#: Longest mesh edge on bending parts, so that deformed triangles follow the arc (chord error < 0.01
#: mm).
BENDING_EDGE_MM = 2.0
#: Bending-direction bins of the pairs' support functions.
SUPPORT_BINS = 72
#: z-scales of the stage-1b table (ascending; 0 and 1 included).
LAMBDA_GRID = np.array(
    [
        0.0,
        0.1,
        0.2,
        0.3,
        0.4,
        0.5,
        0.55,
        0.6,
        0.65,
        0.7,
        0.75,
        0.8,
        0.84,
        0.88,
        0.9,
        0.92,
        0.94,
        0.95,
        0.96,
        0.97,
        0.98,
        0.99,
        0.995,
        1.0,
    ]
)
#: Bounds and exact values closer than this are equal: the posed meshes follow the arcs by chords
#: of at most BENDING_EDGE_MM, so their "exact" distances are good to about 0.01 mm.
TIE_MM = 0.01


@dataclass
class PosedTail:
    """Rest meshes of every instance (tail frame) and the pairs that must not touch."""

    kin: TailKinematics
    names: list[str]
    meshes: list[
        trimesh.Trimesh
    ]  # bending parts subdivided so that the posed triangles follow the arcs
    joint_height_mm: float
    pairs: np.ndarray  # (n_pairs, 2) instance indices
    rest_mm: np.ndarray  # (n_pairs,) exact rest clearance
    span: np.ndarray  # (n_pairs, n_joints) bool: joints whose bending the pair feels (contiguous)
    support_mm: np.ndarray  # (n_pairs, SUPPORT_BINS) h_pair over each bin of bending directions
    coarse: list[trimesh.Trimesh]  # the same surfaces, not subdivided (rest distances)
    cut: list[
        trimesh.Trimesh
    ]  # the coarse surfaces cut at every gap face (piecewise-affine maps in z)
    _aniso: dict = field(default_factory=dict, repr=False)  # (pair, grid index) -> d_lambda
    _scaled: dict = field(
        default_factory=dict, repr=False
    )  # (instance, grid index, span) -> shortened mesh
    _scaled_fcl: dict = field(
        default_factory=dict, repr=False
    )  # the same key -> its BVH, when FCL needs it
    rest_bvh: dict = field(
        default_factory=dict, repr=False
    )  # instance -> BVH of its coarse rest mesh
    instances: list = field(
        default_factory=list, repr=False
    )  # the assembly's Instance of each mesh

    def __getstate__(self) -> dict:
        """Pickled without what it keeps as it goes (FCL's objects do not pickle; the caches
        refill): the build keeps a geometry's posed tail in its cache, so that an edit that moves no
        solid skips its meshing and its exact rest distances."""
        state = dict(self.__dict__)
        state.update(_aniso={}, _scaled={}, _scaled_fcl={}, rest_bvh={})
        return state

    def __post_init__(self) -> None:
        # Pairs grouped by the (contiguous) run of joints they span.
        groups: dict[tuple[int, int], list[int]] = {}
        for p, row in enumerate(self.span):
            on = np.flatnonzero(row)
            if len(on):
                groups.setdefault((int(on[0]), int(on[-1])), []).append(p)
        self._groups = [(lo, hi, np.array(ids)) for (lo, hi), ids in sorted(groups.items())]
        # Each joint's gap starts at its lower panel's upper face and ends at the next panel's lower
        # face.
        self._gap_lo_mm = (
            np.arange(self.kin.n_joints) * self.joint_height_mm + self.kin.panel_thickness_mm
        )
        # Per cut mesh, the gaps that start below its top: shortening any other moves none of its
        # vertices.
        self._gaps_under = [self._gap_lo_mm < m.vertices[:, 2].max() for m in self.cut]
        # Stage 1b's shortened meshes: an instance that is a turned copy of an earlier one about the
        # tail's axis (the SOAs of a joint) shortens to the earlier one's turned (shortening acts
        # along z, which the turn keeps), and pairs that are turned copies of an earlier pair share
        # its d_lambda.
        n = len(self.cut)
        self._turn = (
            _axis_turns(self.instances)
            if len(self.instances) == n
            else [(i, None) for i in range(n)]
        )
        first: dict[tuple, int] = {}
        self._orbit = [first.setdefault(self._orbit_key(p), p) for p in range(len(self.pairs))]
        # Instances that lie inside one panel's thickness move with that panel as a rigid body:
        # their posed mesh is the rest BVH under a transform (no rebuild).
        hj, t = self.joint_height_mm, self.kin.panel_thickness_mm
        self._rigid_in: list[int] = []
        for m in self.meshes:
            zlo, zhi = m.bounds[:, 2]
            k = int(np.floor(zlo / hj + 1e-9))
            self._rigid_in.append(k if zhi <= k * hj + t + 1e-9 and k <= self.kin.n_joints else -1)

    def deform_points(self, pts: np.ndarray, w: np.ndarray) -> np.ndarray:
        """Plane-section map of rest points (m, 3) for one pose w (n_joints, 2)."""
        base, panel = self.kin.frames(w)
        hj, t = self.joint_height_mm, self.kin.panel_thickness_mm
        z = pts[:, 2]
        k = np.clip(
            np.floor(z / hj).astype(int), 0, self.kin.n_joints
        )  # panel below (or containing)
        zr = z - k * hj
        out = np.empty_like(pts)
        in_panel = (zr <= t) | (k == self.kin.n_joints)
        loc = np.c_[pts[:, :2], zr, np.ones(len(pts))]
        out[in_panel] = np.einsum("nij,nj->ni", panel[k[in_panel]], loc[in_panel])[:, :3]
        gap = ~in_panel
        if np.any(gap):
            kg = k[gap]  # joint kg + 1 (0-based kg) spans panel kg's upper face to panel kg+1
            s = (zr[gap] - t) / self.kin.length_mm
            # The partial arc up to s has bending vector s w and length s L.
            ts = joint_transform_uv(s * w[kg, 0], s * w[kg, 1], 1.0)
            ts[:, :3, 3] *= (s * self.kin.length_mm)[:, None]
            q = np.c_[pts[gap, :2], np.zeros(gap.sum()), np.ones(gap.sum())]
            out[gap] = np.einsum("nij,nj->ni", base[kg] @ ts, q)[:, :3]
        return out

    def stretch(self, w: np.ndarray) -> np.ndarray:
        """lambda_min of every pair at every pose, (n_poses, n_pairs), in [0, 1]."""
        w = np.asarray(w, float)
        theta = np.hypot(w[..., 0], w[..., 1])  # (n, J)
        kappa = theta / self.kin.length_mm
        bins = (
            np.floor(
                (np.arctan2(w[..., 1], w[..., 0]) + np.pi) / (2 * np.pi) * SUPPORT_BINS
            ).astype(int)
            % SUPPORT_BINS
        )
        lam = np.ones((len(w), len(self.pairs)))
        for lo, hi, ids in self._groups:
            bulge = self.kin.length_mm * theta[:, lo : hi + 1].sum(axis=1) / 8.0  # (n,)
            h = self.support_mm[ids]  # (g, bins)
            worst = np.ones((len(w), len(ids)))
            for j in range(lo, hi + 1):
                reach = np.take(h, bins[:, j], axis=1).T + bulge[:, None]  # (n, g)
                np.minimum(worst, 1.0 - kappa[:, j, None] * reach, out=worst)
            lam[:, ids] = worst
        return np.clip(lam, 0.0, 1.0)

    def lower_bounds(self, w: np.ndarray) -> np.ndarray:
        """Stage 1a: min(1, lambda_min) x rest clearance of every pair at every pose, (n_poses,
        n_pairs)."""
        return self.stretch(w) * self.rest_mm[None, :]

    def shorten_z(self, z: np.ndarray, lam: float, joints: np.ndarray) -> np.ndarray:
        """z after the gaps of ``joints`` (bool, n_joints) are shortened by ``lam`` (panels
        unchanged)."""
        hj = self.joint_height_mm
        out = np.array(z, float)
        for j in np.flatnonzero(joints):
            lo, hi = self._gap_lo_mm[j], (j + 1) * hj
            out -= (1.0 - lam) * np.clip(z - lo, 0.0, hi - lo)
        return out

    def _orbit_key(self, pair: int) -> tuple:
        """What makes two pairs turned copies of each other (their d_lambda equal): the instances
        they are turned copies of, the turn between their two instances (degrees, to 1e-6), the
        joints they span and the gaps under each mesh; a pair with an instance of no known turn is
        its own."""
        a, b = (int(i) for i in self.pairs[pair])
        if self._turn[a][1] is None or self._turn[b][1] is None:
            return ("pair", pair)
        return (
            _turned_pair(
                self._turn, a, b, self._gaps_under[a].tobytes(), self._gaps_under[b].tobytes()
            ),
            self.span[pair].tobytes(),
        )

    def _shortened(self, i: int, k: int, span: np.ndarray) -> tuple[tuple, np.ndarray | None]:
        """The key of the shortened mesh that instance ``i``'s is a turned copy of, and the turn
        (None: none); the mesh is made on first use (its BVH when FCL first needs it)."""
        ref, rot = self._turn[i]
        ck = (ref, k, span.tobytes())
        if ck not in self._scaled:
            m = self.cut[ref]
            v = m.vertices.copy()
            v[:, 2] = self.shorten_z(v[:, 2], float(LAMBDA_GRID[k]), span)
            self._scaled[ck] = trimesh.Trimesh(v, m.faces, process=False)
        return ck, None if ref == i else rot

    def aniso_rest(self, pair: int, k: int) -> float:
        """d_lambda of ``pair`` at LAMBDA_GRID[k] (cached; a pair that is a turned copy of an
        earlier one takes that one's)."""
        key = (pair, k)
        if key not in self._aniso:
            if LAMBDA_GRID[k] == 1.0 or not self.span[pair].any():
                self._aniso[key] = float(self.rest_mm[pair])
            elif self._orbit[pair] != pair:
                self._aniso[key] = self.aniso_rest(self._orbit[pair], k)
            else:
                # A gap that starts above the mesh moves none of its vertices (z - 0.0, the same
                # bits): left out of the key, meshes shortened by different spans share one BVH.
                made = [
                    self._shortened(int(i), k, self.span[pair] & self._gaps_under[int(i)])
                    for i in self.pairs[pair]
                ]
                gap = attained_gap_mm(
                    *(
                        self._scaled[ck]
                        if rot is None
                        else trimesh.Trimesh(
                            self._scaled[ck].vertices @ rot.T, self._scaled[ck].faces, process=False
                        )
                        for ck, rot in made
                    )
                )
                if gap is None:
                    objs = []
                    for ck, rot in made:
                        if ck not in self._scaled_fcl:
                            self._scaled_fcl[ck] = _bvh(self._scaled[ck])
                        objs.append(
                            fcl.CollisionObject(
                                self._scaled_fcl[ck],
                                fcl.Transform() if rot is None else fcl.Transform(rot, np.zeros(3)),
                            )
                        )
                    gap = _fcl_distance(*objs)
                self._aniso[key] = gap
        return self._aniso[key]

    def refine(self, lam: np.ndarray, pair_ids: np.ndarray) -> np.ndarray:
        """Stage 1b: max(lambda x rest, d_lambda at the grid value below lambda) for matching
        arrays."""
        lam = np.asarray(lam, float)
        k = np.clip(np.searchsorted(LAMBDA_GRID, lam, side="right") - 1, 0, len(LAMBDA_GRID) - 1)
        if len(k) == 0:
            return np.zeros(0)
        uniq, inv = np.unique(np.c_[pair_ids, k], axis=0, return_inverse=True)
        table = np.array([self.aniso_rest(int(p), int(kk)) for p, kk in uniq])[inv.ravel()]
        return np.maximum(lam * self.rest_mm[pair_ids], table)

    def exact(self, w: np.ndarray, pair_ids: np.ndarray) -> np.ndarray:
        """Stage 2: exact clearance of some pairs at one pose (negative: penetration depth unknown,
        -0)."""
        posed: dict[int, fcl.CollisionObject] = {}
        panel_frames = None

        def obj(i: int) -> fcl.CollisionObject:
            nonlocal panel_frames
            if i not in posed:
                k = self._rigid_in[i]
                if k >= 0:  # the same map as deform_points, applied as one rigid transform
                    if panel_frames is None:
                        panel_frames = self.kin.frames(w)[1]
                    if (
                        i not in self.rest_bvh
                    ):  # a rigid instance is not subdivided: coarse is its mesh
                        self.rest_bvh[i] = _bvh(self.coarse[i])
                    tf = panel_frames[k].copy()
                    tf[:3, 3] -= tf[:3, 2] * (k * self.joint_height_mm)
                    posed[i] = fcl.CollisionObject(
                        self.rest_bvh[i], fcl.Transform(tf[:3, :3], tf[:3, 3])
                    )
                else:
                    m = self.meshes[i]
                    posed[i] = _fcl_object(
                        trimesh.Trimesh(self.deform_points(m.vertices, w), m.faces, process=False)
                    )
            return posed[i]

        out = np.empty(len(pair_ids))
        for n, p in enumerate(pair_ids):
            a, b = self.pairs[p]
            req = fcl.DistanceRequest()
            res = fcl.DistanceResult()
            out[n] = fcl.distance(obj(int(a)), obj(int(b)), req, res)
        return out


def _mesh(solid) -> trimesh.Trimesh:
    """A copy of ``solid`` meshed (OCCT keeps a finer triangulation than asked: an earlier stage's
    on ``solid`` itself would change the clearances)."""
    return trimesh.Trimesh(*mesh_arrays(fresh_copy(solid), 0.02, 0.3), process=True)


def _cut_at_z(m: trimesh.Trimesh, levels: np.ndarray) -> trimesh.Trimesh:
    """The same surface with every triangle that crosses a plane z = level split along it."""
    lo, hi = m.bounds[:, 2]
    v, f = np.asarray(m.vertices, float), np.asarray(m.faces)
    for z in levels[(levels > lo + 1e-9) & (levels < hi - 1e-9)]:
        o = np.array([0.0, 0.0, z])
        va, fa = trimesh.intersections.slice_faces_plane(v, f, np.array([0.0, 0.0, 1.0]), o)[:2]
        vb, fb = trimesh.intersections.slice_faces_plane(v, f, np.array([0.0, 0.0, -1.0]), o)[:2]
        v, f = np.vstack([va, vb]), np.vstack([fa, fb + len(va)])
    return trimesh.Trimesh(v, f, process=False)


def _subdivided(m: trimesh.Trimesh) -> trimesh.Trimesh:
    v, f = trimesh.remesh.subdivide_to_size(m.vertices, m.faces, BENDING_EDGE_MM)
    return trimesh.Trimesh(v, f, process=False)


def _rod_mesh(diameter_mm: float, length_mm: float, sections: int = 32) -> trimesh.Trimesh:
    """The rod as rings every BENDING_EDGE_MM (a plain cylinder: the vertices must follow the bend).
    Its 32-gon is inscribed in the circle: distances read up to r (1 - cos(pi/32)) = 0.014 mm
    long."""
    n_ring = max(2, int(np.ceil(length_mm / BENDING_EDGE_MM)) + 1)
    a = np.linspace(0, 2 * np.pi, sections, endpoint=False)
    z = np.linspace(0, length_mm, n_ring)
    r = diameter_mm / 2
    ring = np.stack([r * np.cos(a), r * np.sin(a)], -1)
    verts = np.concatenate(
        [np.c_[np.tile(ring, (n_ring, 1)), np.repeat(z, sections)], [[0, 0, 0], [0, 0, length_mm]]]
    )
    faces = []
    for i in range(n_ring - 1):
        for j in range(sections):
            a0, a1 = i * sections + j, i * sections + (j + 1) % sections
            faces += [[a0, a1, a1 + sections], [a0, a1 + sections, a0 + sections]]
    c0, c1 = len(verts) - 2, len(verts) - 1
    top = (n_ring - 1) * sections
    for j in range(sections):
        faces += [[c0, (j + 1) % sections, j], [c1, top + j, top + (j + 1) % sections]]
    return trimesh.Trimesh(verts, np.array(faces), process=False)


def _fcl_object(m: trimesh.Trimesh) -> fcl.CollisionObject:
    return fcl.CollisionObject(_bvh(m), fcl.Transform())


def _bvh(m: trimesh.Trimesh) -> fcl.BVHModel:
    bvh = fcl.BVHModel()
    bvh.beginModel(len(m.vertices), len(m.faces))
    # Plain arrays: python-fcl reads them row by row, and each row of trimesh's tracked arrays is a
    # Python-level view.
    bvh.addSubModel(np.array(m.vertices, dtype=np.float64), np.array(m.faces, dtype=np.int32))
    bvh.endModel()
    return bvh


def _fcl_distance(
    a: trimesh.Trimesh | fcl.CollisionObject, b: trimesh.Trimesh | fcl.CollisionObject
) -> float:
    objs = [m if isinstance(m, fcl.CollisionObject) else _fcl_object(m) for m in (a, b)]
    return fcl.distance(objs[0], objs[1], fcl.DistanceRequest(), fcl.DistanceResult())


#: Two instances of one part whose placements differ by a turn about the tail's axis within this
#: (mm, and the rotation's entries) are turned copies of each other for stage 1b (the SOAs of a
#: joint: 4e-15).
TURN_TOLERANCE = 1e-9


def _axis_turns(instances: list) -> list[tuple[int, np.ndarray]]:
    """For each instance, ``(r, R)``: the first instance ``r`` of the same part whose placement,
    turned by ``R`` (3 x 3) about the tail's axis, is this one's within :data:`TURN_TOLERANCE`;
    itself and the identity where there is none."""
    out: list[tuple[int, np.ndarray]] = []
    firsts: dict[str, list[int]] = {}
    for i, inst in enumerate(instances):
        t = np.asarray(inst.transform, float)
        found = (i, np.eye(3))
        for r in firsts.get(inst.part, []):
            m = t @ np.linalg.inv(np.asarray(instances[r].transform, float))
            c, s = math.cos(a := math.atan2(m[1, 0], m[0, 0])), math.sin(a)
            turn = np.array(
                [[c, -s, 0.0, 0.0], [s, c, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]
            )
            if np.abs(m - turn).max() <= TURN_TOLERANCE:
                found = (r, turn[:3, :3])
                break
        else:
            firsts.setdefault(inst.part, []).append(i)
        out.append(found)
    return out


def _turned_pair(
    turns: list[tuple[int, np.ndarray]], a: int, b: int, tag_a: object = None, tag_b: object = None
) -> tuple:
    """What two pairs that are turned copies of each other share (see :func:`_axis_turns`): the
    instances their two are turned copies of, each with its ``tag``, and the turn between them
    (degrees, to 1e-6), the same whichever instance comes first."""
    (ra, rot_a), (rb, rot_b) = turns[a], turns[b]
    rel = rot_a.T @ rot_b
    turn = round(math.degrees(math.atan2(rel[1, 0], rel[0, 0])) % 360.0, 6) % 360.0
    ends = ((ra, tag_a), (rb, tag_b))
    return min((ends, turn), (ends[::-1], round(-turn % 360.0, 6) % 360.0))


#: Candidate points :func:`attained_gap_mm` tries (per side, in batches) before it leaves a pair to
#: FCL.
GAP_WITNESSES = 256


def attained_gap_mm(a: trimesh.Trimesh, b: trimesh.Trimesh) -> float | None:
    """The distance between two meshes whose bounding boxes are apart along one axis only, when that
    gap is attained: a point of one mesh on its face of the gap lies over (or under) a triangle of
    the other that lies in its own face of the gap. Then no two points are closer (the boxes' gap is
    a lower bound) and the distance is the gap itself, ``upper.min - lower.max`` on that axis,
    exactly (one rounding). Otherwise None (the boxes overlap, are apart along two axes, or no
    witness is found among :data:`GAP_WITNESSES` candidates per side).

    Two panels face each other across a joint's gap with parallel faces: every triangle pair of the
    two faces is at the same distance, and FCL's traversal, which prunes a bounding-volume pair only
    when its bound is not below the distance found, visits them all: a tail at rest has many such
    pairs, and they take most of its rest distances' time."""
    va, vb = np.asarray(a.vertices, float), np.asarray(b.vertices, float)
    lo_a, hi_a, lo_b, hi_b = va.min(0), va.max(0), vb.min(0), vb.max(0)
    apart = np.maximum(lo_b - hi_a, lo_a - hi_b)
    axes = np.flatnonzero(apart > 0)
    if len(axes) != 1:
        return None
    k = int(axes[0])
    (low, v_low, hi), (up, v_up, lo) = (
        ((a, va, hi_a[k]), (b, vb, lo_b[k]))
        if lo_b[k] > hi_a[k]
        else ((b, vb, hi_b[k]), (a, va, lo_a[k]))
    )
    plane = [i for i in range(3) if i != k]
    for points, mesh, verts, level in (
        (v_up[v_up[:, k] == lo], low, v_low, hi),
        (v_low[v_low[:, k] == hi], up, v_up, lo),
    ):
        faces = np.asarray(mesh.faces)
        flat = faces[np.all(verts[faces][:, :, k] == level, axis=1)]
        if not len(flat) or not len(points):
            continue
        tri = verts[flat][:, :, plane]  # (n, 3, 2): the triangles lying in the gap's face
        pts = points[:GAP_WITNESSES, plane]
        for chunk in range(0, len(pts), 32):
            if _any_in_triangles(pts[chunk : chunk + 32], tri):
                return float(lo - hi)
    return None


def _any_in_triangles(points: np.ndarray, tri: np.ndarray) -> bool:
    """Whether any of ``points`` (m, 2) lies in any of the closed triangles ``tri`` (n, 3, 2)."""
    p = points[:, None, :]
    a, b, c = tri[None, :, 0], tri[None, :, 1], tri[None, :, 2]

    def side(u, v):  # the sign of the cross product (v - u) x (p - u)
        return (v[..., 0] - u[..., 0]) * (p[..., 1] - u[..., 1]) - (v[..., 1] - u[..., 1]) * (
            p[..., 0] - u[..., 0]
        )

    s1, s2, s3 = side(a, b), side(b, c), side(c, a)
    inside = ((s1 >= 0) & (s2 >= 0) & (s3 >= 0)) | ((s1 <= 0) & (s2 <= 0) & (s3 <= 0))
    return bool(inside.any())


def must_not_touch(asm: Assembly) -> list[tuple[str, str]]:
    """Every pair of instances except those joined by design: an SOA and its two
    panels (bonded flanges), a rod and the panels it is screwed through, two
    rods meeting in a segment-boundary panel."""
    J = asm.spec.joints_per_segment

    def joined(a, b) -> bool:
        roles = {a.role: a, b.role: b}
        if set(roles) == {"soa", "panel"}:
            return roles["panel"].panel in (roles["soa"].joint - 1, roles["soa"].joint)
        if set(roles) == {"rod", "panel"}:
            s = roles["rod"].segment
            return J * (s - 1) <= roles["panel"].panel <= J * s
        if a.role == b.role == "rod":
            return abs(a.segment - b.segment) == 1
        return False

    return [
        (a.name, b.name) for a, b in itertools.combinations(asm.instances, 2) if not joined(a, b)
    ]


def plane_sections(asm: Assembly) -> PosedTail:
    """The tail's plane-section map alone (:meth:`PosedTail.deform_points`, which reads only the
    joints' kinematics): no meshes, no pairs. The 3D view and :class:`bvsr_cad.api.Tail` pose with
    it; :func:`posed_tail` with no pairs gives the same map after meshing every instance for
    nothing."""
    spec = asm.spec
    return PosedTail(
        TailKinematics.from_spec(spec),
        [],
        [],
        spec.joint.joint_height_mm,
        np.zeros((0, 2), int),
        np.zeros(0),
        np.zeros((0, spec.joints), bool),
        np.zeros((0, SUPPORT_BINS)),
        [],
        [],
        instances=list(asm.instances),
    )


def posed_tail(
    asm: Assembly, progress: Progress | None = None, cutoff_mm: float | None = None
) -> PosedTail:
    """Meshes, pairs and their exact rest clearances. Pairs farther apart at rest
    than one joint pitch (and never spanning a common joint) are dropped: the
    bound above keeps them apart by at least min(1, lambda) x that distance."""
    say = progress or (lambda _m: None)
    spec = asm.spec
    kin = TailKinematics.from_spec(spec)
    cutoff = spec.joint.joint_height_mm if cutoff_mm is None else cutoff_mm
    say("clearance: meshing the instances")
    names, coarse, meshes = _instance_meshes(asm)
    index = {n: i for i, n in enumerate(names)}
    hj, t = spec.joint.joint_height_mm, spec.joint.panel_thickness_mm
    gaps = np.array([[k * hj + t, (k + 1) * hj] for k in range(spec.joints)])
    pairs, rest, span, support = [], [], [], []
    h_edge = _edge_supports(meshes)
    rest_gap = _RestGaps(coarse, _axis_turns(list(asm.instances)))
    say("clearance: exact rest distances of the candidate pairs")
    for a, b in must_not_touch(asm):
        ma, mb = meshes[index[a]], meshes[index[b]]
        lo = np.maximum(ma.bounds[0], mb.bounds[0])
        hi = np.minimum(ma.bounds[1], mb.bounds[1])
        if np.linalg.norm(np.maximum(lo - hi, 0.0)) > cutoff:
            continue
        zlo = min(ma.bounds[0, 2], mb.bounds[0, 2])
        zhi = max(ma.bounds[1, 2], mb.bounds[1, 2])
        pairs.append((index[a], index[b]))
        rest.append(rest_gap(index[a], index[b]))
        span.append((gaps[:, 1] > zlo) & (gaps[:, 0] < zhi))
        h = np.maximum(h_edge[index[a]], h_edge[index[b]])
        hb = np.maximum(h[:-1], h[1:])
        support.append(np.where(hb > 0, hb / np.cos(np.pi / SUPPORT_BINS), hb))
    levels = np.sort(gaps.ravel())
    return PosedTail(
        kin,
        names,
        meshes,
        hj,
        np.array(pairs),
        np.array(rest),
        np.array(span),
        np.array(support),
        coarse,
        [_cut_at_z(m, levels) for m in coarse],
        rest_bvh=rest_gap.rest_bvh,
        instances=list(asm.instances),
    )


def _instance_meshes(
    asm: Assembly,
) -> tuple[list[str], list[trimesh.Trimesh], list[trimesh.Trimesh]]:
    """Each instance's name and its two meshes in the tail frame, each part meshed once: the
    coarse one (the part's tessellation, for rest distances and sections) and the one to pose (an
    SOA's subdivided so that it bends smoothly)."""
    part_mesh: dict[str, tuple[trimesh.Trimesh, trimesh.Trimesh]] = {}
    coarse = []
    names, meshes = [], []
    for inst in asm.instances:
        part = asm.part_of(inst)
        if part.name not in part_mesh:
            if part.kind == "rod":
                rod = _rod_mesh(part.info["diameter_mm"], part.info["cut_length_mm"])
                part_mesh[part.name] = (rod, rod)
            else:
                m = _mesh(part.solid)
                part_mesh[part.name] = (m, _subdivided(m) if part.kind == "soa" else m)
        c = part_mesh[part.name][0].copy()
        c.apply_transform(np.asarray(inst.transform, float))
        coarse.append(c)
        m = part_mesh[part.name][1].copy()
        m.apply_transform(np.asarray(inst.transform, float))
        names.append(inst.name)
        meshes.append(m)
    return names, coarse, meshes


def _edge_supports(meshes: list[trimesh.Trimesh]) -> dict[int, np.ndarray]:
    """Each mesh's support function in the XY plane at the SUPPORT_BINS + 1 bin edges. Over a bin
    of width d a support function is at most max(edges) / cos(d / 2) (sublinearity), or
    max(edges) where that is negative."""
    edges = np.linspace(-np.pi, np.pi, SUPPORT_BINS + 1)
    dirs = np.c_[np.cos(edges), np.sin(edges)]
    return {i: (m.vertices[:, :2] @ dirs.T).max(axis=0) for i, m in enumerate(meshes)}


class _RestGaps:
    """The exact rest distance of a pair of instances (by index): the distance the coarse meshes
    attain, else FCL's between rest BVHs. An SOA is a turned copy of its joint's first (see
    _axis_turns): its rest BVH is that one's under the turn, and a pair that is a turned copy of
    an earlier pair is at that one's distance."""

    def __init__(self, coarse: list[trimesh.Trimesh], turns: list[tuple[int, np.ndarray]]):
        self.coarse, self.turns = coarse, turns
        self.rest_bvh: dict[int, fcl.BVHModel] = {}
        self.turned_rest: dict[tuple, float] = {}

    def __call__(self, ia: int, ib: int) -> float:
        gap = attained_gap_mm(self.coarse[ia], self.coarse[ib])
        if gap is not None:
            return gap
        key = _turned_pair(self.turns, ia, ib)
        if key not in self.turned_rest:
            objs = []
            for i in (ia, ib):
                ref, rot = self.turns[i]
                if ref not in self.rest_bvh:
                    self.rest_bvh[ref] = _bvh(self.coarse[ref])
                objs.append(
                    fcl.CollisionObject(
                        self.rest_bvh[ref],
                        fcl.Transform() if ref == i else fcl.Transform(rot, np.zeros(3)),
                    )
                )
            self.turned_rest[key] = _fcl_distance(*objs)
        return self.turned_rest[key]


@dataclass(frozen=True)
class ClearanceResult:
    poses: int
    min_clearance_mm: float
    pair: tuple[str, str]
    theta_rad: list[float]
    phi_rad: list[float]
    lower_bound_mm: float  # the true minimum over the poses is not below this
    stage1_min_mm: float  # stage 1a bound, minimum over every pose and pair
    refined: int  # (pose, pair) candidates tightened by stage 1b
    confirmed: int  # exact evaluations
    certified: bool  # no unconfirmed (pose, pair) has a bound below the reported minimum
    seconds: float
    rest_pairs: dict[str, float]

    @property
    def poses_per_s(self) -> float:
        return self.poses / self.seconds if self.seconds > 0 else float("inf")

    def to_json(self) -> dict:
        return {
            "poses": int(self.poses),
            "min_clearance_mm": float(self.min_clearance_mm),
            "pair": list(self.pair),
            "pose": {"theta_rad": self.theta_rad, "phi_rad": self.phi_rad},
            "lower_bound_mm": float(self.lower_bound_mm),
            "stage1_min_mm": float(self.stage1_min_mm),
            "refined_candidates": int(self.refined),
            "exact_evaluations": int(self.confirmed),
            "certified": bool(self.certified),
        }


def clearance_over(
    pt: PosedTail, w: np.ndarray, max_exact: int = 8, seed_candidates: int = 64
) -> ClearanceResult:
    """Two-stage minimum clearance over poses w (n, n_joints, 2).

    The smallest stage-1 bounds are refined (stage 1b) and the lowest is
    evaluated exactly; then every (pose, pair) whose bound is below that value
    is refined, and the survivors are confirmed exactly in increasing order of
    their bound until the next bound is not below the best exact value (the
    minimum is then certified) or ``max_exact`` evaluations were spent.
    """
    t0 = time.perf_counter()
    n_pairs = len(pt.pairs)
    lam = pt.stretch(w).ravel()
    lb = lam * np.tile(pt.rest_mm, len(w))
    m = min(len(lb), seed_candidates)
    seed = np.argpartition(lb, m - 1)[:m]
    rb_seed = pt.refine(lam[seed], seed % n_pairs)
    first = int(seed[np.argmin(rb_seed)])

    def exact(idx: int) -> float:
        pose, pair = divmod(idx, n_pairs)
        return float(pt.exact(w[pose], np.array([pair]))[0])

    best, best_at, done = exact(first), first, 1
    cand = np.flatnonzero(lb < best - TIE_MM)
    cand = cand[cand != first]
    rb = pt.refine(lam[cand], cand % n_pairs)
    n_refined = len(cand) + m
    keep = rb < best - TIE_MM
    cand, rb = cand[keep], rb[keep]
    order = np.argsort(rb, kind="stable")
    cand, rb = cand[order], rb[order]
    certified, lower = True, best
    for idx, bound in zip(cand, rb):  # rb ascending: the first bound not below the best ends it
        if bound >= best - TIE_MM:
            break
        if done >= max_exact:
            certified, lower = False, float(min(best, bound))
            break
        d = exact(int(idx))
        done += 1
        if d < best:
            best, best_at = d, int(idx)
    if certified:
        lower = best
    pose, pair = divmod(best_at, n_pairs)
    theta, phi = theta_phi_from_uv(w[pose])
    a, b = pt.pairs[pair]
    seconds = time.perf_counter() - t0
    rest = {f"{pt.names[i]}|{pt.names[j]}": float(r) for (i, j), r in zip(pt.pairs, pt.rest_mm)}
    return ClearanceResult(
        len(w),
        best,
        (pt.names[a], pt.names[b]),
        [float(v) for v in theta],
        [float(v) for v in phi],
        lower,
        float(lb.min()),
        n_refined,
        done,
        certified,
        seconds,
        rest,
    )


def brute_force(pt: PosedTail, w: np.ndarray) -> np.ndarray:
    """Exact clearance of every pair at every pose: (n_poses,) minimum (the reference of the
    benchmark)."""
    all_pairs = np.arange(len(pt.pairs))
    return np.array([np.min(pt.exact(wp, all_pairs)) for wp in w])


def clearance_map(
    pt: PosedTail, joint: int, theta_max_rad: float, n_theta: int = 60, n_phi: int = 72
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stage-1 bound (1a, tightened by 1b) of the minimum clearance over the pairs that feel
    ``joint`` (0-based) when only it bends: (theta, phi, bound). The others keep their rest
    clearance."""
    th = np.linspace(0, theta_max_rad, n_theta)
    ph = np.linspace(-np.pi, np.pi, n_phi)
    tt, pp = np.meshgrid(th, ph, indexing="ij")
    w = np.zeros((tt.size, pt.kin.n_joints, 2))
    w[:, joint, 0] = (tt * np.cos(pp)).ravel()
    w[:, joint, 1] = (tt * np.sin(pp)).ravel()
    ids = np.flatnonzero(pt.span[:, joint])
    lam = pt.stretch(w)[:, ids]
    lb = lam * pt.rest_mm[ids]
    # Stage 1b only where it can lower the minimum: entries whose 1a bound is below the smallest
    # rest clearance of the joint's pairs (a refined bound never exceeds the rest clearance).
    cap = pt.rest_mm[ids].min()
    refined = np.where(lb >= cap, lb, np.inf)
    pose, pair = np.nonzero(lb < cap)
    if len(pose):
        refined[pose, pair] = pt.refine(lam[pose, pair], ids[pair])
    out = refined.min(axis=1)
    return th, ph, out.reshape(tt.shape)


def workspace_clearance(
    spec: TailSpec, poses: int, progress: Callable[[str], None] | None = None
) -> tuple[ClearanceResult, dict]:
    """The closest approach of the tail's solids over ``poses`` poses of its workspace (the
    paper's random chamber-state protocol, seeded by ``analysis.seed``), against
    ``analysis.min_clearance_mm``.

    Args:
        spec: the tail.
        poses: how many workspace poses the solids are checked at.
        progress: called with a line per stage.

    Returns:
        (the result; its JSON with ``required_mm``, ``seconds``, ``poses_per_s`` and ``passed``).
    """
    from .workspace import run_workspace

    say = progress or (lambda _m: None)
    asm = build_assembly(spec, say)
    ws = run_workspace(asm, poses, spec.analysis.seed, say)
    pt = posed_tail(asm, say)
    say(f"clearance over {poses} workspace poses")
    res = clearance_over(pt, ws.w)
    required = spec.analysis.min_clearance_mm
    return res, res.to_json() | {
        "required_mm": required,
        "seconds": res.seconds,
        "poses_per_s": res.poses_per_s,
        "passed": res.min_clearance_mm >= required,
    }
