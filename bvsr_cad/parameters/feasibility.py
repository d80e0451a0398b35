"""What a parameter file asks of its analyses, against what its layout can give, decided at load.

The joint-limit search of `bvsr build` (:mod:`bvsr_cad.analysis.limits`) starts at the straight
tail: a joint whose solids stand closer at rest than ``analysis.min_clearance_mm`` gets a limit of 0
in every bending plane, after minutes of exact distances. The solids that stand closest at rest are
placed by the layout alone (:func:`bvsr_cad.parameters.layout.panel_layout`,
:func:`~bvsr_cad.parameters.layout.soa_frame`), so their distances are known in closed form before
any solid is made:

* the flanges of neighbouring SOAs of a joint, seated side by side in a panel's pockets;
* the bellows of neighbouring SOAs, at their end folds (the side-b square, corners rounded at R);
* the SOAs stacked on either side of a panel, across its pocket floor;
* an SOA and the rod on the tail's axis;
* two neighbouring panels across their gap (less any set-screw collars standing in it).

Each :class:`RestGap` is the distance between two points that lie on the two solids as designed, so
it is never below their true distance at rest: a file refused for it is one whose tail cannot keep
the clearance even straight, where the joint-limit search starts. The plane-section map of the
analyses moves a joint's cross-section rigidly, so the SOA pairs (two points at one height, to the
SOAs' tilt in the cone) keep that distance in every pose, too: no bend can mend them. The analyses
measure meshes inscribed in the solids (chords of at most 0.02 mm), which read the same distances up
to a few hundredths of a millimetre long; a refusal is about the solids.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .layout import (
    N_SOA,
    PanelLayout,
    half_angle_rad,
    key_value,
    panel_layout,
    soa_angles_deg,
    soa_frame,
)
from .panel_rules import _WEB_KEYS, _binding_text
from .tables import AUTO, TailSpec

#: One SOA's neighbour is its copy turned by this about the tail's axis.
_TURN = np.array(
    [
        [math.cos(2 * math.pi / N_SOA), -math.sin(2 * math.pi / N_SOA), 0.0, 0.0],
        [math.sin(2 * math.pi / N_SOA), math.cos(2 * math.pi / N_SOA), 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ]
)


@dataclass(frozen=True)
class RestGap:
    """Two solids of the straight tail and an upper bound of their distance (mm): the distance
    between a point of each. ``joints``: the (1-based) joints whose bending moves them apart or
    together, whose limits need the required clearance between them; ``keys``: the parameter keys
    that set the gap."""

    solids: str
    joints: tuple[int, ...]
    gap_mm: float
    keys: tuple[str, ...]


def _at(frame: np.ndarray, xy: np.ndarray, z_mm: float) -> np.ndarray:
    """A point given in an SOA's own frame (its axis +Z, the lower flange face z = 0), in the tail
    frame."""
    return (frame @ np.array([xy[0], xy[1], z_mm, 1.0]))[:3]


def _toward(frame: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """The unit vector of an SOA's section plane (its own x, y) nearest a direction of the tail
    frame."""
    local = np.array([direction @ frame[:3, 0], direction @ frame[:3, 1]])
    return local / np.linalg.norm(local)


def _disc_gap(fa: np.ndarray, fb: np.ndarray, radius_mm: float, z_mm: float) -> float:
    """Distance between the rims of two flange discs (each SOA's section at ``z_mm``), along the
    line of their centres projected into each disc."""
    ca, cb = _at(fa, np.zeros(2), z_mm), _at(fb, np.zeros(2), z_mm)
    pa = _at(fa, radius_mm * _toward(fa, cb - ca), z_mm)
    pb = _at(fb, radius_mm * _toward(fb, ca - cb), z_mm)
    return float(np.linalg.norm(pa - pb))


def _square(side_mm: float, radius_mm: float) -> np.ndarray:
    """The corners of the square a rounded square is the Minkowski sum of with a disc of
    ``radius_mm``."""
    h = side_mm / 2.0 - radius_mm
    return np.array([[h, h], [-h, h], [-h, -h], [h, -h]])


def _segment_nearest(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    d = b - a
    t = 0.0 if not d.any() else float(np.clip((p - a) @ d / (d @ d), 0.0, 1.0))
    return a + t * d


def _polygon_witnesses(pa: np.ndarray, pb: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The nearest points of two disjoint convex polygons (corners in order): over every corner of
    one and edge of the other."""
    best = (math.inf, pa[0], pb[0])
    for first, second, flip in ((pa, pb, False), (pb, pa, True)):
        for p in first:
            for i in range(len(second)):
                q = _segment_nearest(p, second[i], second[(i + 1) % len(second)])
                d = float(np.linalg.norm(p - q))
                if d < best[0]:
                    best = (d, q, p) if flip else (d, p, q)
    return best[1], best[2]


def _bellows_gap(spec: TailSpec, fa: np.ndarray, fb: np.ndarray, z_mm: float) -> float:
    """Distance between two neighbouring bellows' side-b sections at height ``z_mm`` of their own
    frames: the nearest points of the two rounded squares, solved in the first's section plane, each
    then put on its own section."""
    side, r = spec.soa.long_side_mm, min(spec.soa.fillet_radius_mm, spec.soa.long_side_mm / 2.0)
    sq = _square(side, r)
    rel = np.linalg.inv(fa) @ fb  # the second SOA's frame in the first's
    cb, turn = rel[:2, 3], rel[:2, :2]
    a, b = _polygon_witnesses(sq, sq @ turn.T + cb)
    n = b - a
    n = n / np.linalg.norm(n) if n.any() else np.array([1.0, 0.0])
    qa, qb = a + r * n, np.linalg.solve(turn, b - r * n - cb)
    return float(np.linalg.norm(_at(fa, qa, z_mm) - _at(fb, qb, z_mm)))


def _inner_reach(spec: TailSpec, frame: np.ndarray, z_mm: float, radius_mm: float) -> float:
    """Distance from the tail's axis of the section point of an SOA nearest it, at height ``z_mm``
    of its frame: the flange disc's rim (``radius_mm``) or, ``radius_mm`` None, the bellows' side-b
    square."""
    centre = _at(frame, np.zeros(2), z_mm)
    inward = _toward(frame, -np.array([centre[0], centre[1], 0.0]))
    if radius_mm is not None:
        point = radius_mm * inward
    else:
        side, r = spec.soa.long_side_mm, min(spec.soa.fillet_radius_mm, spec.soa.long_side_mm / 2.0)
        sq = _square(side, r)
        point = sq[int(np.argmax(sq @ inward))] + r * inward
    return float(math.hypot(*_at(frame, point, z_mm)[:2]))


_FLANGE_KEYS = ("joint.pitch_diameter_mm", "joint.base_diameter_mm", "taper.half_angle_deg")
_BELLOWS_KEYS = (
    "soa.long_side_mm",
    "soa.fillet_radius_mm",
    "soa.rotation_deg",
    "joint.pitch_diameter_mm",
    "taper.half_angle_deg",
)
_FLOOR_KEYS = ("joint.joint_height_mm", "joint.gap_mm", "soa.height_mm", "soa.origami_height_mm")
_ROD_KEYS = (
    "joint.pitch_diameter_mm",
    "joint.base_diameter_mm",
    "soa.long_side_mm",
    "vertebra.diameter_mm",
)


def rest_gaps(spec: TailSpec, layouts: list[PanelLayout] | None = None) -> list[RestGap]:
    """The distances of the solids that stand closest in the straight tail (see the module), each an
    upper bound of their true distance. ``layouts``: :func:`panel_layout` of every panel, when the
    caller has them."""
    lays = layouts or [panel_layout(spec, k, half_angle_rad(spec)) for k in range(spec.panels)]
    a0 = float(soa_angles_deg()[0])
    frames = [
        soa_frame(lays[k - 1], lays[k], a0, spec.soa.rotation_deg) for k in range(1, spec.panels)
    ]
    height, flange = spec.soa.built_height_mm, spec.soa.flange_thickness_mm
    disc = spec.joint.base_diameter_mm / 2.0
    out: list[RestGap] = []
    for k, fa in enumerate(frames, start=1):
        fb = _TURN @ fa
        pair = f"j{k}_soa1 and j{k}_soa2 (and the other neighbours, turned copies)"
        for z, panel in ((0.0, k - 1), (height, k)):
            out.append(
                RestGap(
                    f"the flanges of neighbouring SOAs seated in panel{panel}, {pair}",
                    (k,),
                    _disc_gap(fa, fb, disc, z),
                    _FLANGE_KEYS,
                )
            )
        for z, end in ((flange, "lower"), (height - flange, "upper")):
            out.append(
                RestGap(
                    f"the bellows of neighbouring SOAs at their {end} fold, {pair}",
                    (k,),
                    _bellows_gap(spec, fa, fb, z),
                    _BELLOWS_KEYS,
                )
            )
        if spec.vertebra.has_rod:
            reach = min(
                _inner_reach(spec, fa, z, r)
                for z in (0.0, flange, height - flange, height)
                for r in (disc, None)
            )
            out.append(
                RestGap(
                    f"the SOAs of joint {k} and the rod on the tail's axis",
                    (k,),
                    reach - spec.vertebra.diameter_mm / 2.0,
                    _ROD_KEYS,
                )
            )
    for k in range(1, len(frames)):
        top, bottom = (
            _at(frames[k - 1], np.array([disc, 0.0]), height),
            _at(frames[k], np.array([disc, 0.0]), 0.0),
        )
        out.append(
            RestGap(
                f"the SOAs stacked across panel{k}'s pocket floor, j{k}_soa1 and j{k + 1}_soa1",
                (k, k + 1),
                float(np.linalg.norm(top - bottom)),
                _FLOOR_KEYS,
            )
        )
    out += _panel_gaps(spec, lays)
    return out


def _panel_gaps(spec: TailSpec, lays: list[PanelLayout]) -> list[RestGap]:
    """Neighbouring panels face each other across the gap, less the set-screw collars that stand in
    it (above every panel but the tip's, below the tip's)."""
    out = []
    for k in range(1, len(lays)):
        lower = max((b.z_range[1] for b in lays[k - 1].bosses), default=lays[k - 1].thickness_mm)
        upper = min((b.z_range[0] for b in lays[k].bosses), default=0.0)
        gap = (
            lays[k].z0_mm
            + min(upper, 0.0)
            - (lays[k - 1].z0_mm + max(lower, lays[k - 1].thickness_mm))
        )
        collars = (
            " (less the set-screw collars standing in it)"
            if lays[k - 1].bosses or lays[k].bosses
            else ""
        )
        keys = ("joint.gap_mm", "socket.boss_height_mm") if collars else ("joint.gap_mm",)
        out.append(
            RestGap(f"panel{k - 1} and panel{k} across joint {k}'s gap{collars}", (k,), gap, keys)
        )
    return out


def clearance_problems(spec: TailSpec, layouts: list[PanelLayout] | None = None) -> list[str]:
    """``analysis.min_clearance_mm`` against the closest solids of the straight tail: a problem when
    the requirement exceeds a :class:`RestGap` (every joint that gap feels would get a limit of
    0)."""
    need = spec.analysis.min_clearance_mm
    gaps = rest_gaps(spec, layouts)
    short = [g for g in gaps if g.gap_mm < need]
    if not short:
        return []
    worst = min(gaps, key=lambda g: g.gap_mm)
    joints = sorted({j for g in short for j in g.joints})
    set_by = ", ".join(f"{k} = {key_value(spec, k)!r}" for k in worst.keys)
    if "taper.half_angle_deg" in worst.keys and spec.taper.half_angle_deg == AUTO:
        webs = ", ".join(f"fabrication.{k} = {getattr(spec.fabrication, k)!r}" for k in _WEB_KEYS)
        set_by += (
            f"; the 'auto' cone is the widest that keeps the panel webs ({webs}), limited by: "
            f"{_binding_text(spec)}"
        )
    most = math.floor(worst.gap_mm * 1000.0) / 1000.0
    return [
        f"analysis.min_clearance_mm = {need!r}: more than the tail keeps between its solids even "
        "straight: "
        f"{worst.solids} stand {worst.gap_mm:.3f} mm apart at rest (set by {set_by}), so the "
        "joint-limit "
        f"search would find no pose of joint{'s' if len(joints) > 1 else ''} "
        f"{', '.join(str(j) for j in joints)} that keeps it (every limit 0); allowed: <= {most:g} "
        "mm with "
        "the other keys as they are"
    ]
