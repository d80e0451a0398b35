"""Scenes for the report's interactive 3D view, computed in memory.

Six scenes, each a list of coloured triangle meshes in millimetres placed by a
4 x 4 transform: the assembly at rest; the tail posed in extension, flexion
and waggle at the pressure limits; the SOA mold set exploded along its pull
directions; the rigid twin. The exporter
(:func:`bvsr_cad.exporters.viewer.write_viewer`) only serialises them.

Poses: every segment's five lines get the pattern of
:func:`bvsr_cad.models.statics.pressure_pattern_kpa` at the lines' pressure
limits (the bending side evacuated to the minimum, the opposite side at the
maximum, as the paper's Table III protocol), the forward statics of the
assembled tail (:func:`bvsr_cad.analysis.workspace.tail_statics`, gravity
along -Y) give every joint's bending vector, and the plane-section map of
:class:`bvsr_cad.analysis.clearance.PosedTail` moves the rest meshes (the
same map the clearance analysis certifies).

Meshes are coarse on purpose (the viewer's data stays a few MB): OCCT's
tessellation at :data:`TOLERANCE_MM` / :data:`ANGULAR_TOLERANCE_RAD`; the
parts that bend (SOAs and rods) are cut by planes every
:data:`BENDING_SLICE_MM` along their axis (the rods are meshed as rings, as the
clearance analysis meshes them) so that posed triangles follow the arcs.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import build123d as bd
import numpy as np
import trimesh

from ..assembly.assemble import Assembly
from ..assembly.products import piece_transform_mm
from ..colors import rgb, rgba
from ..models.kinematics import TailKinematics
from ..models.statics import MOTION_PHI_RAD, pressure_pattern_kpa, segment_bend_angle_rad
from ..parameters.tables import TailSpec
from ..parts.kernel import fresh_copy, mesh_arrays
from ..parts.mold import MoldSet
from ..parts.rigid_tail import RigidPiece
from .clearance import PosedTail, _cut_at_z, _rod_mesh, plane_sections
from .workspace import tail_statics

Progress = Callable[[str], None]

#: OCCT tessellation of the viewer's meshes (chord tolerance, mm; angular tolerance, rad).
TOLERANCE_MM = 0.2
ANGULAR_TOLERANCE_RAD = 0.6
#: Spacing of the cuts along a bending part's axis: its posed triangles are chords of at most this.
BENDING_SLICE_MM = 3.0
#: Polygon of the rod's cross-section.
ROD_SECTIONS = 16
#: The mold set explodes each part along its pull direction by this fraction of the set's extent
#: there.
EXPLODE_FRACTION = 0.6
#: Opacity of the cast SOA in the mold scene (the core inside it shows through).
CAST_ALPHA = 0.45
#: Up axis of the tail scenes: the tail is mounted horizontally with gravity along -Y (dorsal +Y
#: up).
TAIL_UP = (0.0, 1.0, 0.0)
#: Scene names in the order the report offers them.
SCENES = ("rest", "extension", "flexion", "waggle", "molds", "rigid_twin")


@dataclass(frozen=True)
class ViewObject:
    """One coloured mesh of a scene.

    ``vertices_mm`` (n, 3) float32 and ``triangles`` (m, 3) uint32 are in the
    object's frame; ``transform`` (4 x 4) takes them to the scene frame (mm).
    """

    label: str
    kind: str  # colour key of bvsr_cad.colors
    vertices_mm: np.ndarray
    triangles: np.ndarray
    rgb: tuple[float, float, float]
    transform: np.ndarray = field(default_factory=lambda: np.eye(4))
    alpha: float = 1.0


@dataclass(frozen=True)
class ViewScene:
    """A named scene: its objects, the up axis and the direction the camera looks from."""

    name: str
    title: str
    note: str
    objects: tuple[ViewObject, ...]
    up: tuple[float, float, float] = TAIL_UP
    eye_direction: tuple[float, float, float] = (1.0, 0.5, -0.6)

    @property
    def triangle_count(self) -> int:
        return sum(len(o.triangles) for o in self.objects)


@dataclass(frozen=True)
class TailPose:
    """The tail at equilibrium for one motion's line pressures at the limits."""

    motion: str
    phi_rad: float  # bending direction from +X towards +Y (tail frame)
    line_kpa: np.ndarray  # (n_segments, 5) gauge
    w: np.ndarray  # (n_joints, 2) bending vectors
    tip_mm: np.ndarray  # (3,) centre of the tip panel's distal face
    rest_tip_mm: np.ndarray  # (3,)
    segment_bend_deg: (
        np.ndarray
    )  # (n_segments,) angle between each segment's first and last panel axes


def limit_poses(asm: Assembly, spec: TailSpec | None = None) -> dict[str, TailPose]:
    """Extension, flexion and waggle of the whole tail at the lines' pressure limits (with gravity).

    Args:
        asm: the assembled tail (its masses load the statics).
        spec: the statics' parameters (default the assembly's; may carry fitted values).

    Returns:
        motion -> pose, in the order of :data:`bvsr_cad.models.statics.MOTION_PHI_RAD`.
    """
    st = tail_statics(asm, spec=spec)
    kin = st.kin
    j = kin.joints_per_segment
    poses = {}
    for motion, phi in MOTION_PHI_RAD.items():
        pattern = pressure_pattern_kpa(phi, st.act.pressure_min_kpa, st.act.pressure_max_kpa)
        line = np.tile(pattern, (kin.n_segments, 1))
        w = st.forward(line)
        bends = [
            float(
                np.degrees(
                    segment_bend_angle_rad(
                        TailKinematics(kin.joints[s * j : (s + 1) * j], kin.panel_thickness_mm, j),
                        w[s * j : (s + 1) * j],
                    )
                )
            )
            for s in range(kin.n_segments)
        ]
        poses[motion] = TailPose(
            motion, phi, line, w, kin.tip_point_mm(w), kin.rest_tip_mm(), np.array(bends)
        )
    return poses


def _mesh(solid: bd.Shape) -> trimesh.Trimesh:
    return trimesh.Trimesh(*mesh_arrays(solid, TOLERANCE_MM, ANGULAR_TOLERANCE_RAD), process=True)


def _fresh_mesh(solid: bd.Shape) -> trimesh.Trimesh:
    """:func:`_mesh` of a copy without the triangulation earlier stages left on ``solid`` (OCCT
    keeps a finer one): the scene is the same whichever stages a build took from its cache."""
    return _mesh(fresh_copy(solid))


def _sliced(m: trimesh.Trimesh) -> trimesh.Trimesh:
    """``m`` with every triangle split at planes z = const every BENDING_SLICE_MM or less (part
    frame)."""
    lo, hi = m.bounds[:, 2]
    n = max(1, math.ceil((hi - lo) / BENDING_SLICE_MM))
    out = _cut_at_z(m, np.linspace(lo, hi, n + 1))
    out.merge_vertices()
    return out


def _obj(
    label: str,
    kind: str,
    m: trimesh.Trimesh,
    transform: np.ndarray | None = None,
    colour: tuple[float, float, float] | None = None,
    alpha: float | None = None,
) -> ViewObject:
    r, g, b, a = rgba(kind)
    return ViewObject(
        label,
        kind,
        np.asarray(m.vertices, np.float32),
        np.asarray(m.faces, np.uint32),
        colour or (r, g, b),
        np.eye(4) if transform is None else np.asarray(transform, float),
        a if alpha is None else alpha,
    )


def _tail_meshes(asm: Assembly) -> dict[str, trimesh.Trimesh]:
    """Every unique part's viewer mesh in its part frame (bending parts sliced along their axis)."""
    out = {}
    for name, part in asm.parts.items():
        if part.kind == "rod":  # rings along the axis, as the clearance analysis meshes it
            out[name] = _rod_mesh(
                part.info["diameter_mm"], part.info["cut_length_mm"], ROD_SECTIONS
            )
        elif part.kind == "soa":
            out[name] = _sliced(_fresh_mesh(part.solid))
        else:
            out[name] = _fresh_mesh(part.solid)
    return out


def rest_scene(asm: Assembly, meshes: dict[str, trimesh.Trimesh]) -> ViewScene:
    objs = tuple(
        _obj(i.name, asm.part_of(i).kind, meshes[i.part], np.asarray(i.transform, float))
        for i in asm.instances
    )
    spec = asm.spec
    return ViewScene(
        "rest",
        "Assembly at rest",
        f"{spec.segments} segments, {spec.joints} joints, {spec.panels} panels, "
        f"{sum(1 for i in asm.instances if i.role == 'soa')} SOAs (translucent) around the rod; "
        "tail frame: +Z along the tail, +Y dorsal, gravity along -Y",
        objs,
    )


def posed_scene(
    asm: Assembly, meshes: dict[str, trimesh.Trimesh], pose: TailPose, deformer: PosedTail
) -> ViewScene:
    """The assembly's meshes moved by the plane-section map of ``pose`` (vertices in the tail
    frame)."""
    objs = []
    for inst in asm.instances:
        m = meshes[inst.part]
        t = np.asarray(inst.transform, float)
        rest = np.asarray(m.vertices, float) @ t[:3, :3].T + t[:3, 3]
        posed = deformer.deform_points(rest, pose.w)
        objs.append(
            _obj(inst.name, asm.part_of(inst).kind, trimesh.Trimesh(posed, m.faces, process=False))
        )
    p_hi, p_lo = float(np.nanmax(pose.line_kpa)), float(np.nanmin(pose.line_kpa))
    moved = pose.tip_mm - pose.rest_tip_mm
    note = (
        f"every segment's lines at the limits ({p_lo:+.0f} kPa on the bending side, {p_hi:+.0f} "
        "kPa opposite, "
        f"gauge), forward statics with gravity along -Y; segment bends "
        + ", ".join(f"{b:.1f}" for b in pose.segment_bend_deg)
        + f" deg; tip moved by ({moved[0]:+.1f}, {moved[1]:+.1f}, {moved[2]:+.1f}) mm"
    )
    # Look across the bending plane (from its positive side) so the bend shows in profile.
    bend = np.array([math.cos(pose.phi_rad), math.sin(pose.phi_rad), 0.0])
    across = np.array([-bend[1], bend[0], 0.0])
    across *= np.sign(across[np.argmax(np.abs(across))])
    eye = across + 0.35 * np.abs(bend) - 0.3 * np.array([0.0, 0.0, 1.0])
    return ViewScene(
        pose.motion,
        f"{pose.motion.capitalize()} at the pressure limits",
        note,
        tuple(objs),
        TAIL_UP,
        tuple(float(v) for v in eye),
    )


def mold_scene(mold_set: MoldSet) -> ViewScene:
    """Every rigid mold part moved out along its pull direction; the core, the cast and the channels
    in place."""
    parts = {name: _mesh(p.solid) for name, p in mold_set.parts.items()}
    every = np.vstack([m.vertices for m in parts.values()])
    objs = []
    for name, part in mold_set.parts.items():
        offset = np.zeros(3)
        if not part.sacrificial:
            d = np.asarray(part.pull_direction, float)
            proj = every @ d
            offset = d * EXPLODE_FRACTION * float(proj.max() - proj.min())
        t = np.eye(4)
        t[:3, 3] = offset
        objs.append(
            _obj(name + (" (sacrificial)" if part.sacrificial else ""), part.role, parts[name], t)
        )
    objs.append(_obj("cast SOA", "cast", _mesh(mold_set.cast), alpha=CAST_ALPHA))
    objs += [_obj(f"{ch.kind} {ch.name}", "channel", _mesh(ch.solid)) for ch in mold_set.channels]
    d = (
        np.asarray(mold_set.parts["half_a"].pull_direction, float)
        if "half_a" in mold_set.parts
        else np.array([1.0, 0.0, 0.0])
    )
    eye = (
        np.cross([0.0, 0.0, 1.0], d) + 0.35 * np.array([0.0, 0.0, 1.0]) + 0.25 * d
    )  # along the parting plane
    return ViewScene(
        "molds",
        "SOA mold set, exploded",
        f"cast x{mold_set.scale:.4f} (shrinkage) in place with its sacrificial core; rigid parts "
        "moved "
        f"out along their pull directions by {EXPLODE_FRACTION:g} x the set's extent there; "
        "gate and vents in red",
        tuple(objs),
        (0.0, 0.0, 1.0),
        tuple(float(v) for v in eye),
    )


def twin_scene(
    pieces: list[RigidPiece], meshes_mm: list[tuple[np.ndarray, np.ndarray]] | None = None
) -> ViewScene:
    """The rigid twin assembled in the tail frame, alternate pieces shaded apart.

    ``meshes_mm``: each piece's mesh in the tail frame (vertices mm, triangles) where the caller has
    one (the build: the rigid robot's visual meshes, so the viewer shows the twin as a simulator
    does); otherwise each piece is meshed here at the viewer's tolerance from a copy (by then the
    build has meshed the pieces for print, 0.01 mm, and OCCT would hand that mesh back, far finer
    than a view needs)."""
    base = np.array(rgb("rigid_tail"))
    if meshes_mm is None:
        placed = [(_fresh_mesh(p.solid), piece_transform_mm(p)) for p in pieces]
    else:
        placed = [
            (trimesh.Trimesh(np.asarray(v, float), np.asarray(f), process=True), np.eye(4))
            for v, f in meshes_mm
        ]
    objs = tuple(
        _obj(
            p.name,
            "rigid_tail",
            m,
            t,
            tuple(float(c) for c in base * (1.0 if i % 2 == 0 else 0.88)),
        )
        for i, (p, (m, t)) in enumerate(zip(pieces, placed))
    )
    return ViewScene(
        "rigid_twin",
        "Rigid PLA twin",
        f"{len(pieces)} printed pieces stacked in the tail frame (alternate pieces shaded darker)",
        objs,
    )


def viewer_scenes(
    asm: Assembly,
    mold_set: MoldSet | ViewScene,
    pieces: list[RigidPiece] | ViewScene,
    spec: TailSpec | None = None,
    progress: Progress | None = None,
) -> list[ViewScene]:
    """Every scene of :data:`SCENES`, in that order.

    Args:
        asm: the assembled tail.
        mold_set: its SOA mold set (:func:`bvsr_cad.assembly.products.build_mold_set`), or its scene
            already made (:func:`mold_scene`: the build caches it with the mold set's files).
        pieces: the rigid twin's pieces (:func:`bvsr_cad.assembly.products.build_rigid_twin`), or
            their scene already made (:func:`twin_scene`).
        spec: the statics' parameters for the poses (default the assembly's).
        progress: called with a short message before each slow step.
    """
    say = progress or (lambda _m: None)
    say("viewer: meshing the parts")
    meshes = _tail_meshes(asm)
    say("viewer: poses at the pressure limits")
    poses = limit_poses(asm, spec)
    deformer = plane_sections(asm)
    scenes = [rest_scene(asm, meshes)]
    scenes += [posed_scene(asm, meshes, pose, deformer) for pose in poses.values()]
    say("viewer: mold set and rigid twin")
    scenes += [
        mold_set if isinstance(mold_set, ViewScene) else mold_scene(mold_set),
        pieces if isinstance(pieces, ViewScene) else twin_scene(pieces),
    ]
    return scenes
