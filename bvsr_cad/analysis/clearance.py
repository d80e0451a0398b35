"""Clearance between the posed solids of the tail over its workspace.

Deformation model: plane sections. A point of the tail at rest with height z
in the gap of joint k (arc parameter s = (z - z_start) / L) goes to
Base_k T_s(s w_k) (x, y, 0): every cross-section stays plane and normal to the
rod's arc, so the SOAs and the rod bend with their joint and stretch or shorten
with their distance from the bending axis; points inside a panel's thickness
(panels, the SOA flanges seated in the pockets, the rod in its bore) move
rigidly with that panel.

Stage 1 (every pose, vectorised): in a joint gap the map's metric is
diag(1, 1, lambda^2) with lambda = 1 - rho theta / L (rho: a point's distance
from the rod towards the bending plane), identity in the panels. A straight
segment between two posed points pulls back to a rest curve at most
1 / min(1, lambda_min) times longer, so for every pair
    clearance >= min(1, lambda_min) x rest clearance,
lambda_min over the joints the pair spans and rho up to the pair's radial
extent (valid for theta < L / rho, about 1 rad, far beyond the workspace).
Exact rest clearances come from the meshes once. Stage 2: exact mesh distances
(python-fcl) of the posed meshes for the lowest bounds confirm the minimum.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import fcl
import numpy as np
import trimesh

from ..assembly.build import Assembly
from ..models.kinematics import TailKinematics, joint_transform_uv, theta_phi_from_uv

Progress = Callable[[str], None]
#: Longest mesh edge on bending parts, so that deformed triangles follow the arc (chord error < 0.01 mm).
BENDING_EDGE_MM = 2.0


@dataclass
class PosedTail:
    """Rest meshes of every instance (tail frame) and the pairs that must not touch."""

    kin: TailKinematics
    names: list[str]
    meshes: list[trimesh.Trimesh]
    joint_height_mm: float
    pairs: np.ndarray  # (n_pairs, 2) instance indices
    rest_mm: np.ndarray  # (n_pairs,) exact rest clearance
    rho_mm: np.ndarray  # (n_pairs,) radial extent of the pair
    span: np.ndarray  # (n_pairs, n_joints) bool: joints whose bending the pair feels
    _fcl_rest: list = field(default_factory=list, repr=False)

    def deform_points(self, pts: np.ndarray, w: np.ndarray) -> np.ndarray:
        """Plane-section map of rest points (m, 3) for one pose w (n_joints, 2)."""
        base, panel = self.kin.frames(w)
        hj, t = self.joint_height_mm, self.kin.panel_thickness_mm
        z = pts[:, 2]
        k = np.clip(np.floor(z / hj).astype(int), 0, self.kin.n_joints)  # panel below (or containing)
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

    def lower_bounds(self, w: np.ndarray) -> np.ndarray:
        """Stage 1: conservative clearance of every pair at every pose, (n_poses, n_pairs)."""
        theta = np.hypot(w[..., 0], w[..., 1])  # (n, J)
        on = self.span[None, :, :]
        kmax = np.max(np.where(on, theta[:, None, :], 0.0), axis=-1) / self.kin.length_mm  # (n, pairs)
        # A straight segment between two posed points bulges outwards from the
        # arcs by at most its sagitta, (L / theta)(1 - cos(span / 2)) <= L span / 8,
        # so its preimage reaches rho + L span / 8.
        bulge = self.kin.length_mm * np.sum(np.where(on, theta[:, None, :], 0.0), axis=-1) / 8.0
        lam = np.clip(1.0 - (self.rho_mm[None, :] + bulge) * kmax, 0.0, 1.0)
        return lam * self.rest_mm[None, :]

    def exact(self, w: np.ndarray, pair_ids: np.ndarray) -> np.ndarray:
        """Stage 2: exact clearance of some pairs at one pose (negative: penetration depth unknown, -0)."""
        posed: dict[int, fcl.CollisionObject] = {}

        def obj(i: int) -> fcl.CollisionObject:
            if i not in posed:
                m = self.meshes[i]
                posed[i] = _fcl_object(trimesh.Trimesh(self.deform_points(m.vertices, w), m.faces, process=False))
            return posed[i]

        out = np.empty(len(pair_ids))
        for n, p in enumerate(pair_ids):
            a, b = self.pairs[p]
            req = fcl.DistanceRequest()
            res = fcl.DistanceResult()
            out[n] = fcl.distance(obj(int(a)), obj(int(b)), req, res)
        return out


def _mesh(solid, bending: bool) -> trimesh.Trimesh:
    verts, tris = solid.tessellate(0.02, 0.3)
    m = trimesh.Trimesh(np.array([[v.X, v.Y, v.Z] for v in verts]), np.array(tris), process=True)
    if bending:
        v, f = trimesh.remesh.subdivide_to_size(m.vertices, m.faces, BENDING_EDGE_MM)
        m = trimesh.Trimesh(v, f, process=False)
    return m


def _rod_mesh(diameter_mm: float, length_mm: float, sections: int = 32) -> trimesh.Trimesh:
    """The rod as rings every BENDING_EDGE_MM (a plain cylinder: the vertices must follow the bend).
    Its 32-gon is inscribed in the circle: distances read up to r (1 - cos(pi/32)) = 0.014 mm long."""
    n_ring = max(2, int(np.ceil(length_mm / BENDING_EDGE_MM)) + 1)
    a = np.linspace(0, 2 * np.pi, sections, endpoint=False)
    z = np.linspace(0, length_mm, n_ring)
    r = diameter_mm / 2
    ring = np.stack([r * np.cos(a), r * np.sin(a)], -1)
    verts = np.concatenate([np.c_[np.tile(ring, (n_ring, 1)), np.repeat(z, sections)], [[0, 0, 0], [0, 0, length_mm]]])
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
    bvh = fcl.BVHModel()
    bvh.beginModel(len(m.vertices), len(m.faces))
    bvh.addSubModel(m.vertices, m.faces)
    bvh.endModel()
    return fcl.CollisionObject(bvh, fcl.Transform())


def _fcl_distance(a: trimesh.Trimesh | fcl.CollisionObject, b: trimesh.Trimesh | fcl.CollisionObject) -> float:
    objs = [m if isinstance(m, fcl.CollisionObject) else _fcl_object(m) for m in (a, b)]
    return fcl.distance(objs[0], objs[1], fcl.DistanceRequest(), fcl.DistanceResult())


def must_not_touch(asm: Assembly) -> list[tuple[str, str]]:
    """Every pair of instances except those joined by design: an SOA and its two
    panels (bonded flanges), a rod and the panels it is screwed through, two
    rods meeting in a segment-boundary panel."""
    spec = asm.spec
    J = spec.joints_per_segment
    names = [i.name for i in asm.instances]
    joined: set[frozenset[str]] = set()
    for k in range(1, spec.panels):
        for i in range(1, 6):
            joined |= {frozenset((f"j{k}_soa{i}", f"panel{k - 1}")), frozenset((f"j{k}_soa{i}", f"panel{k}"))}
    for s in range(1, spec.segments + 1):
        for k in range(J * (s - 1), J * s + 1):
            joined.add(frozenset((f"rod_s{s}", f"panel{k}")))
        if s > 1:
            joined.add(frozenset((f"rod_s{s - 1}", f"rod_s{s}")))
    return [(a, b) for a, b in itertools.combinations(names, 2) if frozenset((a, b)) not in joined]


def posed_tail(asm: Assembly, progress: Progress | None = None, cutoff_mm: float | None = None) -> PosedTail:
    """Meshes, pairs and their exact rest clearances. Pairs farther apart at rest
    than one joint pitch (and never spanning a common joint) are dropped: the
    bound above keeps them apart by at least min(1, lambda) x that distance."""
    from ..assembly.build import instance_solid

    say = progress or (lambda _m: None)
    spec = asm.spec
    kin = TailKinematics.from_spec(spec)
    cutoff = spec.joint.joint_height_mm if cutoff_mm is None else cutoff_mm
    say("clearance: meshing the instances")
    part_mesh: dict[str, trimesh.Trimesh] = {}
    names, meshes = [], []
    for inst in asm.instances:
        part = asm.part_of(inst)
        if part.name not in part_mesh:
            if part.kind == "rod":
                part_mesh[part.name] = _rod_mesh(part.info["diameter_mm"], part.info["cut_length_mm"])
            else:
                part_mesh[part.name] = _mesh(part.solid, bending=part.kind == "soa")
        m = part_mesh[part.name].copy()
        m.apply_transform(np.asarray(inst.transform, float))
        names.append(inst.name)
        meshes.append(m)
    index = {n: i for i, n in enumerate(names)}
    hj, t = spec.joint.joint_height_mm, spec.joint.panel_thickness_mm
    gaps = np.array([[k * hj + t, (k + 1) * hj] for k in range(spec.joints)])
    pairs, rest, rho, span = [], [], [], []
    rest_obj: dict[int, fcl.CollisionObject] = {}
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
        for i in (index[a], index[b]):
            if i not in rest_obj:
                rest_obj[i] = _fcl_object(meshes[i])
        rest.append(_fcl_distance(rest_obj[index[a]], rest_obj[index[b]]))
        rho.append(max(np.max(np.hypot(m.vertices[:, 0], m.vertices[:, 1])) for m in (ma, mb)))
        span.append((gaps[:, 1] > zlo) & (gaps[:, 0] < zhi))
    return PosedTail(kin, names, meshes, hj, np.array(pairs), np.array(rest), np.array(rho), np.array(span))


@dataclass(frozen=True)
class ClearanceResult:
    poses: int
    min_clearance_mm: float
    pair: tuple[str, str]
    theta_rad: list[float]
    phi_rad: list[float]
    lower_bound_mm: float  # stage 1 over every pose and pair
    confirmed: int  # exact evaluations
    certified: bool  # no unconfirmed (pose, pair) has a bound below the reported minimum
    seconds: float
    rest_pairs: dict[str, float]

    @property
    def poses_per_s(self) -> float:
        return self.poses / self.seconds if self.seconds > 0 else float("inf")

    def to_json(self) -> dict:
        return {"poses": int(self.poses), "min_clearance_mm": float(self.min_clearance_mm), "pair": list(self.pair),
                "pose": {"theta_rad": self.theta_rad, "phi_rad": self.phi_rad},
                "lower_bound_mm": float(self.lower_bound_mm), "exact_evaluations": int(self.confirmed),
                "certified": bool(self.certified), "seconds": self.seconds, "poses_per_s": self.poses_per_s}


def clearance_over(pt: PosedTail, w: np.ndarray, max_exact: int = 4) -> ClearanceResult:
    """Two-stage minimum clearance over poses w (n, n_joints, 2).

    Candidates are confirmed in increasing order of their bound until the next
    bound is not below the best exact value (then the minimum is certified) or
    ``max_exact`` evaluations were spent.
    """
    t0 = time.perf_counter()
    lb = pt.lower_bounds(w)
    flat = lb.ravel()
    order = np.argpartition(flat, min(len(flat) - 1, 4 * max_exact))[: 4 * max_exact + 1]
    order = order[np.argsort(flat[order])]
    best, best_at = np.inf, None
    done = 0
    certified = False
    for idx in order:
        if flat[idx] >= best:
            certified = True
            break
        if done >= max_exact:
            break
        pose, pair = divmod(int(idx), lb.shape[1])
        d = float(pt.exact(w[pose], np.array([pair]))[0])
        done += 1
        if d < best:
            best, best_at = d, (pose, pair)
    pose, pair = best_at
    theta, phi = theta_phi_from_uv(w[pose])
    a, b = pt.pairs[pair]
    seconds = time.perf_counter() - t0
    rest = {f"{pt.names[i]}|{pt.names[j]}": float(r) for (i, j), r in zip(pt.pairs, pt.rest_mm)}
    return ClearanceResult(len(w), best, (pt.names[a], pt.names[b]), [float(v) for v in theta],
                           [float(v) for v in phi], float(flat.min()), done, certified, seconds, rest)


def brute_force(pt: PosedTail, w: np.ndarray) -> np.ndarray:
    """Exact clearance of every pair at every pose: (n_poses,) minimum (the reference of the benchmark)."""
    all_pairs = np.arange(len(pt.pairs))
    return np.array([np.min(pt.exact(wp, all_pairs)) for wp in w])


def clearance_map(pt: PosedTail, joint: int, theta_max_rad: float, n_theta: int = 60, n_phi: int = 72
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stage-1 bound of the minimum clearance when only ``joint`` (0-based) bends: (theta, phi, bound)."""
    th = np.linspace(0, theta_max_rad, n_theta)
    ph = np.linspace(-np.pi, np.pi, n_phi)
    tt, pp = np.meshgrid(th, ph, indexing="ij")
    w = np.zeros((tt.size, pt.kin.n_joints, 2))
    w[:, joint, 0] = (tt * np.cos(pp)).ravel()
    w[:, joint, 1] = (tt * np.sin(pp)).ravel()
    return th, ph, pt.lower_bounds(w).min(-1).reshape(tt.shape)


def plot_clearance_map(th: np.ndarray, ph: np.ndarray, bound: np.ndarray, path, title: str,
                       workspace_theta_rad: float, min_clearance_mm: float) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.6))
    cs = ax.pcolormesh(np.degrees(ph), np.degrees(th), bound, shading="auto", cmap="viridis")
    fig.colorbar(cs, label="clearance lower bound (mm)")
    ax.contour(np.degrees(ph), np.degrees(th), bound, levels=[min_clearance_mm], colors="r")
    ax.axhline(np.degrees(workspace_theta_rad), color="w", ls="--", lw=1, label="largest theta in the workspace")
    ax.set_xlabel("phi (deg)")
    ax.set_ylabel("theta (deg)")
    ax.set_title(title)
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
