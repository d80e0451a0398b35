"""The panel layout's rules: whether a placement (:mod:`bvsr_cad.parameters.layout`) leaves every
web, wall and passage the fabrication needs, the largest taper that does, and the explanations a
refused file gets (the keys that set each broken rule and the values that would mend it).

Both the parameter validation (:func:`validate_layout`, at load) and the manifest
(:func:`binding_constraint`) read these rules; the placement reads :func:`max_feasible_taper_deg`
for a taper of ``auto``.
"""

from __future__ import annotations

import dataclasses
import math
import re
from functools import lru_cache
from typing import NamedTuple

import numpy as np

from .layout import (
    Cyl,
    PanelLayout,
    feature_keys,
    half_angle_rad,
    key_value,
    panel_layout,
    pocket_depth_mm,
    soa_neighbour_gap_mm,
    soa_radial_extent_mm,
    with_key,
)
from .tables import AUTO, TailSpec, feasible_interval, rule_bounds


class LayoutProblem(NamedTuple):
    """A panel rule broken: what, the web it leaves and the one it needs (mm), the features
    (:class:`Cyl` names, ``rim``, ``bellows``, ``pocket_depth``) whose keys set it, and the panel's
    index (None: a rule of the whole tail)."""

    desc: str
    measured_mm: float
    need_mm: float
    features: tuple[str, ...]
    panel: int | None = None


def _circle_gap(a: Cyl, b: Cyl) -> tuple[float, bool]:
    (xa, ya), (xb, yb) = a.xy, b.xy
    dist = math.hypot(xa - xb, ya - yb)
    ra, rb = a.diameter_mm / 2, b.diameter_mm / 2
    nested = dist + min(ra, rb) <= max(ra, rb) + 1e-6
    return dist - ra - rb, nested


def _near_pairs(cuts: list[Cyl], need_mm: float) -> list[list[int]]:
    """For each cut i, the cuts j > i (in order) whose circles may come within ``need_mm`` of it:
    every pair but those whose plan-view gap (numpy's, within 1e-12 mm of :func:`_circle_gap`'s)
    exceeds it by 1e-6 mm, which no rule of :func:`panel_problems` on webs between cuts can flag.
    The pairs a panel has are a few hundred; testing each in Python was most of
    :func:`max_feasible_taper_deg`'s bisection."""
    if len(cuts) < 2:
        return [[] for _ in cuts]
    xy = np.array([c.xy for c in cuts], float)
    r = np.array([c.diameter_mm / 2 for c in cuts], float)
    gap = (
        np.hypot(xy[:, None, 0] - xy[None, :, 0], xy[:, None, 1] - xy[None, :, 1])
        - r[:, None]
        - r[None, :]
    )
    ii, jj = np.nonzero(np.triu(gap < need_mm + 1e-6, 1))
    out: list[list[int]] = [[] for _ in cuts]
    for i, j in zip(ii.tolist(), jj.tolist()):
        out[i].append(j)
    return out


def _z_overlap(a: Cyl, b: Cyl) -> bool:
    (a0, a1), (b0, b1) = a.z_range, b.z_range
    return min(a1, b1) - max(a0, b0) > 1e-6


def _segment_point_distance(p0, p1, q) -> float:
    p0, p1, q = (np.asarray(v[:2], float) for v in (p0, p1, q))
    d = p1 - p0
    t = float(np.clip(np.dot(q - p0, d) / max(np.dot(d, d), 1e-12), 0.0, 1.0))
    return float(np.linalg.norm(p0 + t * d - q))


def panel_problems(spec: TailSpec, lay: PanelLayout) -> list[LayoutProblem]:
    """Every violated rule of one panel."""
    out = (
        _pocket_depth_problems(spec, lay)
        + _cut_problems(spec, lay)
        + _collar_problems(spec, lay)
        + _passage_problems(spec, lay)
    )
    return [found._replace(panel=lay.index) for found in out]


def _pocket_depth_problems(spec: TailSpec, lay: PanelLayout) -> list[LayoutProblem]:
    """The flange pockets from both faces plus a floor must fit in the panel, and the SOA must
    reach across the gap (a pocket of positive depth)."""
    fab = spec.fabrication
    out: list[LayoutProblem] = []
    t = lay.thickness_mm
    depth_total = lay.pocket_depth_mm * (int(lay.lower_pockets) + int(lay.upper_pockets))
    if depth_total + fab.socket_floor_mm > t + 1e-9:
        out.append(
            LayoutProblem(
                f"{lay.name}: flange pockets ({lay.pocket_depth_mm:.3f} mm per face) deeper than "
                f"the panel allows (thickness {t:.2f} mm, floor {fab.socket_floor_mm} mm)",
                t - depth_total,
                fab.socket_floor_mm,
                ("pocket_depth",),
            )
        )
    if lay.pocket_depth_mm < 0:
        out.append(
            LayoutProblem(
                f"{lay.name}: the SOA ({spec.soa.built_height_mm:.2f} mm) is shorter than the gap "
                f"H_a ({spec.joint.gap_mm} mm)",
                lay.pocket_depth_mm,
                0.0,
                ("pocket_depth",),
            )
        )
    return out


def _cut_problems(spec: TailSpec, lay: PanelLayout) -> list[LayoutProblem]:
    """Each cut's lip to the panel's rim, and the web between it and every cut near it at the same
    height (set screws aside, nested cuts aside)."""
    fab = spec.fabrication
    out: list[LayoutProblem] = []
    t = lay.thickness_mm
    cuts = list(lay.cuts)
    near = _near_pairs(cuts, max(fab.min_pocket_gap_mm, fab.min_wall_mm))
    for i, a in enumerate(cuts):
        ra = a.diameter_mm / 2
        rho = math.hypot(*a.xy)
        # The rim shrinks upwards: the narrowest rim a feature meets is at its top.
        z_top = min(max(a.z_range[1], 0.0), t) / t
        rim = lay.rim_radius_lower_mm + (lay.rim_radius_upper_mm - lay.rim_radius_lower_mm) * z_top
        lip = rim - rho - ra
        need = fab.min_rim_lip_mm if a.role == "pocket" else fab.min_wall_mm
        if a.role not in ("setscrew",) and lip < need - 1e-9:
            out.append(
                LayoutProblem(
                    f"{lay.name}: {a.name} is {lip:.2f} mm from the rim", lip, need, (a.name, "rim")
                )
            )
        for j in near[i]:
            b = cuts[j]
            if not _z_overlap(a, b) or "setscrew" in (a.role, b.role):
                continue
            gap, nested = _circle_gap(a, b)
            if nested:
                continue
            need = fab.min_pocket_gap_mm if a.role == b.role == "pocket" else fab.min_wall_mm
            if gap < need - 1e-9:
                out.append(
                    LayoutProblem(
                        f"{lay.name}: {a.name} and {b.name} leave a {gap:.2f} mm web",
                        gap,
                        need,
                        (a.name, b.name),
                    )
                )
    return out


def _collar_problems(spec: TailSpec, lay: PanelLayout) -> list[LayoutProblem]:
    """The wall between each set-screw collar and the cuts at its height (the rod's and the set
    screw's own aside)."""
    fab = spec.fabrication
    out: list[LayoutProblem] = []
    cuts = list(lay.cuts)
    for boss in lay.bosses:
        for b in cuts:
            if b.role in ("rod", "setscrew"):
                continue
            if not _z_overlap(boss, b):
                continue  # e.g. blind inserts on the face away from the collar
            gap, nested = _circle_gap(boss, b)
            if not nested and gap < fab.min_wall_mm - 1e-9:
                out.append(
                    LayoutProblem(
                        f"{lay.name}: set-screw collar and {b.name} leave {gap:.2f} mm",
                        gap,
                        fab.min_wall_mm,
                        (boss.name, b.name),
                    )
                )
    return out


def _passage_problems(spec: TailSpec, lay: PanelLayout) -> list[LayoutProblem]:
    """The wall between each pneumatic passage and the cuts at its height (its own line's port
    and feed, and the shallow pockets, aside)."""
    fab = spec.fabrication
    out: list[LayoutProblem] = []
    cuts = list(lay.cuts)
    for p in lay.passages:
        line = p.name.split("_", 1)[1]
        for b in cuts:
            if b.name.endswith(line) and b.role in ("tube_port", "feed"):
                continue
            if b.role == "pocket":
                continue  # pockets are shallow; _pocket_depth_problems' floor keeps them apart
            lo, hi = b.z_range
            if hi < p.p0[2] - p.diameter_mm / 2 or lo > p.p0[2] + p.diameter_mm / 2:
                continue
            web = _segment_point_distance(p.p0, p.p1, b.xy) - b.diameter_mm / 2 - p.diameter_mm / 2
            if web < fab.min_wall_mm - 1e-9:
                out.append(
                    LayoutProblem(
                        f"{lay.name}: {p.name} passes {web:.2f} mm from {b.name}",
                        web,
                        fab.min_wall_mm,
                        (p.name, b.name),
                    )
                )
    return out


def _problems_at(spec: TailSpec, beta: float) -> list[LayoutProblem]:
    out = []
    for k in range(spec.panels):
        out.extend(panel_problems(spec, panel_layout(spec, k, beta)))
    return out + _problems_at_tip(spec, beta)


def _problems_at_tip(spec: TailSpec, beta: float) -> list[LayoutProblem]:
    """Bellows of neighbouring SOAs at the smallest pitch radius (the tip's)."""
    out: list[LayoutProblem] = []
    r_min = spec.joint.pitch_diameter_mm / 2 - (
        spec.panels - 1
    ) * spec.joint.joint_height_mm * math.tan(beta)
    gap = soa_neighbour_gap_mm(spec, r_min)
    if gap < spec.fabrication.min_pocket_gap_mm - 1e-9:
        out.append(
            LayoutProblem(
                f"SOA bellows of neighbouring actuators leave {gap:.2f} mm at the tip",
                gap,
                spec.fabrication.min_pocket_gap_mm,
                ("bellows",),
            )
        )
    return out


def _any_problem(spec: TailSpec, beta: float, first: tuple[int, ...] = ()) -> bool:
    """Some rule of :func:`_problems_at` is broken (it stops at the first rule broken, trying the
    panels ``first``, then the bellows at the tip, then the other panels)."""
    hot = [k for k in first if k < spec.panels]
    others = [k for k in range(spec.panels) if k not in first]
    return (
        any(panel_problems(spec, panel_layout(spec, k, beta)) for k in hot)
        or bool(_problems_at_tip(spec, beta))
        or any(panel_problems(spec, panel_layout(spec, k, beta)) for k in others)
    )


# A memo of one process, not a stage cache: the validation and the layout ask it of each spec again
# (docs/architecture.md, The cache).
@lru_cache(maxsize=64)
def max_feasible_taper_deg(spec: TailSpec) -> float:
    """Largest cone half-angle for which every panel keeps its webs (found by bisection over the
    same rules the validation applies; a cone that breaks one is left at the first it breaks: the
    bisection needs only whether some rule breaks, not which)."""
    if _problems_at(spec, 0.0):
        return 0.0
    lo, hi = 0.0, math.radians(10.0)
    for _ in range(40):
        mid = (lo + hi) / 2
        if _any_problem(spec, mid):
            hi = mid
        else:
            lo = mid
    return math.degrees(lo)


def _binding_problem(spec: TailSpec) -> LayoutProblem | None:
    """The first rule broken just past the feasible cone, or None."""
    probs = _problems_at(spec, math.radians(max_feasible_taper_deg(spec) + 0.01))
    return probs[0] if probs else None


def binding_constraint(spec: TailSpec) -> str:
    """What stops a larger taper: the first rule broken just past the feasible cone."""
    found = _binding_problem(spec)
    return found.desc if found else "none"


def _keys_of(problems: list[LayoutProblem]) -> list[str]:
    """The parameter keys that set the features of ``problems``, each once, in order."""
    return list(dict.fromkeys(k for p in problems for f in p.features for k in feature_keys(f)))


def _set_by(spec: TailSpec, problems: list[LayoutProblem]) -> str:
    """``; set by key = value, ...`` for the keys of ``problems`` (empty without any)."""
    keys = _keys_of(problems)
    return "; set by " + ", ".join(f"{k} = {key_value(spec, k)!r}" for k in keys) if keys else ""


def _binding_text(spec: TailSpec) -> str:
    """:func:`binding_constraint` with the keys (and their values) that set the features it
    names."""
    found = _binding_problem(spec)
    return found.desc + _set_by(spec, [found]) if found else "none"


def soa_is_sound(spec: TailSpec) -> bool:
    """The SOA's own rules hold (:func:`validate_layout` names any that does not), so the dimensions
    derived from Table II (fold levels, wall offset, interior) mean something."""
    s = spec.soa
    return (
        s.long_side_mm > s.short_side_mm
        and s.origami_height_mm < s.height_mm
        and s.short_side_mm - 2 * s.wall_offset_mm > 0.5
        and 2 * s.fillet_radius_mm < s.short_side_mm
    )


#: Smallest cone the panels can be built with (other than none): below it the oblique air channels'
#: end faces nearly coincide with the pocket floors and OCC's boolean cut returns the pockets as
#: loose solids (found by the property tests: 1e-5 to 0.01 deg fail, 0.02 deg builds, for channels
#: of 2 to 16 mm).
MIN_BUILDABLE_TAPER_DEG = 0.05
#: The longest chain whose exported MJCF passes its MuJoCo checks (couplings held within 0.01 rad,
#: settled within 1 s): 6 (1 x 6, 2 x 3), 8 (2 x 4) and 9 (3 x 3) joints pass; 10 (2 x 5) and 12 (2
#: x 6, 3 x 4) fail.
MAX_JOINTS = 9
#: The [fabrication] minimums a panel rule can require (the message names the one that binds).
_WEB_KEYS = ("min_pocket_gap_mm", "min_wall_mm", "min_rim_lip_mm", "socket_floor_mm")


def validate_layout(spec: TailSpec) -> list[str]:
    """Every geometric impossibility, as messages that name the parameter to change."""
    problems = _axial_problems(spec)
    if problems:
        return problems
    problems = _rim_problems(spec)
    taper = _taper_problems(spec)
    if taper:
        return problems + taper
    return problems + panel_rule_messages(spec, half_angle_rad(spec)) + mjf_problems(spec)


def _axial_problems(spec: TailSpec) -> list[str]:
    """What cannot stack along the axis: the gap in the joint, the SOA's shape and interior, its
    flanges' pockets in the panels, the number of joints and segments, the tube ports' depth. Each
    of the first rules stops the others (their numbers are meaningless past it)."""
    blocker = _shape_blocker(spec)
    if blocker:
        return [blocker]
    problems = _soa_interior_problems(spec)
    blocker = _pocket_blocker(spec)
    if blocker:
        return problems + [blocker]
    return problems + _chain_length_problems(spec) + _tube_port_problems(spec)


def _shape_blocker(spec: TailSpec) -> str | None:
    """The first broken rule among those every other axial number rests on: the gap within the
    joint's height, the SOA's long side over its short side, its origami within its height."""
    j = spec.joint
    if j.gap_mm >= j.joint_height_mm:
        return (
            f"joint.gap_mm = {j.gap_mm}: must be below joint.joint_height_mm = {j.joint_height_mm} "
            "(the difference is the panel thickness)"
        )
    if spec.soa.long_side_mm <= spec.soa.short_side_mm:
        return (
            f"soa.long_side_mm = {spec.soa.long_side_mm}: must exceed soa.short_side_mm = "
            f"{spec.soa.short_side_mm}"
        )
    if spec.soa.origami_height_mm >= spec.soa.height_mm:
        return (
            f"soa.origami_height_mm = {spec.soa.origami_height_mm}: must be below soa.height_mm "
            f"= {spec.soa.height_mm} (the rest is the two flanges)"
        )
    return None


def _soa_interior_problems(spec: TailSpec) -> list[str]:
    """The SOA's interior at the valleys (what the wall's offset leaves of the short side) and its
    fillets within the short side."""
    problems: list[str] = []
    inner = spec.soa.short_side_mm - 2 * spec.soa.wall_offset_mm
    if inner <= 0.5:
        soa = spec.soa
        problems.append(
            f"soa.facet_thickness_mm = {soa.facet_thickness_mm}: leaves {inner:.2f} mm of interior "
            "at the "
            f"valleys (soa.short_side_mm = {soa.short_side_mm} less twice the wall's "
            f"{soa.wall_offset_mm:.2f} mm offset, which the fold's slope sets: soa.long_side_mm = "
            f"{soa.long_side_mm}, soa.origami_height_mm = {soa.origami_height_mm}, soa.pleats = "
            f"{soa.pleats}); allowed: > 0.5 mm"
        )
    if 2 * spec.soa.fillet_radius_mm >= spec.soa.short_side_mm:
        problems.append(
            f"soa.fillet_radius_mm = {spec.soa.fillet_radius_mm}: must be below half of "
            f"soa.short_side_mm = {spec.soa.short_side_mm}"
        )
    return problems


def _pocket_blocker(spec: TailSpec) -> str | None:
    """The SOA's flanges in the panels' pockets: the SOA as built reaches across the gap, and two
    pockets plus a floor fit in a panel (either broken stops the later rules)."""
    j = spec.joint
    depth = pocket_depth_mm(spec)
    floor = spec.fabrication.socket_floor_mm
    if depth < 0:
        return (
            f"soa.height_mm = {spec.soa.height_mm}: the SOA as built "
            f"({spec.soa.built_height_mm:.3f} mm, "
            f"soa.fold_height_from = {spec.soa.fold_height_from!r}) is {-2 * depth:.3f} mm shorter "
            "than the gap "
            f"joint.gap_mm = {j.gap_mm}, so its flanges cannot sit in the panels' pockets; "
            "allowed: an SOA at "
            "least as long as the gap (change soa.height_mm, soa.origami_height_mm or joint.gap_mm)"
        )
    if 2 * depth + floor > j.panel_thickness_mm + 1e-9:
        return (
            f"joint.joint_height_mm = {j.joint_height_mm}: flange pockets deeper than the panel: "
            "two pockets of "
            f"(H - H_a) / 2 = {depth:.3f} mm plus a {floor} mm floor need {2 * depth + floor:.3f} "
            "mm, the panel "
            f"is H_j - H_a = {j.panel_thickness_mm:.3f} mm (change joint.joint_height_mm, "
            "joint.gap_mm, "
            "soa.height_mm or fabrication.socket_floor_mm)"
        )
    return None


def _chain_length_problems(spec: TailSpec) -> list[str]:
    """The number of segments the tube rings serve and the number of joints the exported MJCF
    holds together."""
    problems: list[str] = []
    if spec.segments > 3:
        problems.append(
            f"segments = {spec.segments}: tube rings exist for the distal tubes of at most 3 "
            "segments; allowed: 1 to 3"
        )
    elif spec.joints > MAX_JOINTS:
        problems.append(
            f"joints_per_segment = {spec.joints_per_segment} with segments = {spec.segments}: "
            f"{spec.joints} joints; "
            f"allowed: at most {MAX_JOINTS} joints (joints_per_segment <= "
            f"{MAX_JOINTS // spec.segments} here): the "
            "exported MJCF's longer chains fail its checks (measured: 10 joints held the couplings "
            "to 0.011 rad, "
            "limit 0.01, and still moved 0.22 rad/s 1 s after release, limit 0.1; 12 joints worse)"
        )
    return problems


def _tube_port_problems(spec: TailSpec) -> list[str]:
    """The tube ports reach the panel's mid-plane passage and keep a floor under them."""
    j = spec.joint
    problems: list[str] = []
    if (
        spec.tubes.port_depth_mm < j.panel_thickness_mm / 2
        or spec.tubes.port_depth_mm > j.panel_thickness_mm - spec.fabrication.socket_floor_mm
    ):
        problems.append(
            f"tubes.port_depth_mm = {spec.tubes.port_depth_mm}: must reach the mid-plane passage "
            "and "
            f"keep a floor (fabrication.socket_floor_mm = {spec.fabrication.socket_floor_mm!r}) in "
            "the "
            f"{j.panel_thickness_mm:.2f} mm panels (joint.joint_height_mm = {j.joint_height_mm!r} "
            "minus "
            f"joint.gap_mm = {j.gap_mm!r}): allowed {j.panel_thickness_mm / 2:.2f} to "
            f"{j.panel_thickness_mm - spec.fabrication.socket_floor_mm:.2f} mm"
        )
    return problems


def _rim_problems(spec: TailSpec) -> list[str]:
    """The panels' rim against the SOAs' reach."""
    j = spec.joint
    problems: list[str] = []
    radial_out, _ = soa_radial_extent_mm(spec)
    if j.pitch_diameter_mm / 2 + radial_out > j.panel_diameter_mm / 2 + 1e-9:
        soa = spec.soa
        reach = j.pitch_diameter_mm / 2 + radial_out
        problems.append(
            f"joint.panel_diameter_mm = {j.panel_diameter_mm}: the rim lies inside the SOA "
            "envelope: "
            f"joint.pitch_diameter_mm / 2 = {j.pitch_diameter_mm / 2:.2f} mm plus the bellows' "
            f"{radial_out:.2f} mm "
            f"(soa.long_side_mm = {soa.long_side_mm!r}, soa.fillet_radius_mm = "
            f"{soa.fillet_radius_mm!r}, "
            f"soa.rotation_deg = {soa.rotation_deg!r}) reach {reach:.2f} mm, beyond the rim's "
            f"{j.panel_diameter_mm / 2:.2f} mm; allowed: >= {math.ceil(200 * reach) / 100:g} mm, "
            "or a smaller "
            "joint.pitch_diameter_mm or soa.long_side_mm"
        )
    return problems


def _taper_problems(spec: TailSpec) -> list[str]:
    """A cone beyond the feasible one, or too slight to cut; either stops the panel rules."""
    if spec.taper.half_angle_deg != AUTO:
        beta_max = max_feasible_taper_deg(spec)
        # Rules broken without any cone are the other keys' doing: reported below, not as the
        # taper's.
        if float(spec.taper.half_angle_deg) > beta_max + 1e-9 and not _problems_at(spec, 0.0):
            return [
                f"taper.half_angle_deg = {spec.taper.half_angle_deg}: beyond the feasible cone; "
                "allowed: 0 to "
                f"{beta_max:.4f} deg ('auto' picks it); limited by: {_binding_text(spec)}"
            ]
    beta_deg = math.degrees(half_angle_rad(spec))
    if 0.0 < beta_deg < MIN_BUILDABLE_TAPER_DEG and spec.joints_per_segment > 1:
        why = (
            f"a cone below {MIN_BUILDABLE_TAPER_DEG:g} deg tilts the intermediate panels' air "
            "channels so "
            "little that their end faces lie within micrometres of the flange pockets' floors, "
            "which the CAD "
            "kernel cannot cut (the panel falls apart)"
        )
        beta_max = max_feasible_taper_deg(spec)
        if spec.taper.half_angle_deg == AUTO:
            return [
                f"taper.half_angle_deg = 'auto': the largest feasible cone is {beta_deg:.4f} deg "
                f"(limited by: {_binding_text(spec)}); {why}; allowed: 0 (no taper)"
            ]
        wider = (
            f", or {MIN_BUILDABLE_TAPER_DEG:g} to {beta_max:.4f} deg"
            if beta_max >= MIN_BUILDABLE_TAPER_DEG
            else ""
        )
        return [f"taper.half_angle_deg = {spec.taper.half_angle_deg}: {why}; allowed: 0{wider}"]
    return []


def mjf_problems(spec: TailSpec) -> list[str]:
    """The panels (printed flat in MJF, either way round on the bed, as the print job lays them out)
    must fit the MJF build volume: the widest (the root's rim) and the tallest (a set-screw collar
    adds to it)."""
    fp = spec.fabrication_package
    beta = half_angle_rad(spec)
    layouts = [panel_layout(spec, k, beta) for k in range(spec.panels)]
    wide = max(layouts, key=lambda lay: lay.rim_radius_lower_mm)
    width = 2.0 * wide.rim_radius_lower_mm

    def height(lay: PanelLayout) -> float:
        zs = [0.0, lay.thickness_mm] + [z for b in lay.bosses for z in b.z_range]
        return max(zs) - min(zs)

    tall = max(layouts, key=height)
    out = []
    lo_key = "mjf_x_mm" if fp.mjf_x_mm <= fp.mjf_y_mm else "mjf_y_mm"
    if width > min(fp.mjf_x_mm, fp.mjf_y_mm) + 1e-9:
        out.append(
            f"fabrication_package.{lo_key} = {getattr(fp, lo_key)!r}: {wide.name} prints "
            f"{width:.2f} mm across "
            f"(joint.panel_diameter_mm), wider than the {fp.mjf_x_mm:g} x {fp.mjf_y_mm:g} mm MJF "
            "bed; allowed: "
            f"fabrication_package.mjf_x_mm and mjf_y_mm >= {math.ceil(width * 100) / 100:g} mm"
        )
    if height(tall) > fp.mjf_z_mm + 1e-9:
        out.append(
            f"fabrication_package.mjf_z_mm = {fp.mjf_z_mm!r}: {tall.name} prints "
            f"{height(tall):.2f} mm tall "
            f"(the panel and its set-screw collar), more than the MJF build volume; allowed: >= "
            f"{math.ceil(height(tall) * 100) / 100:g} mm"
        )
    return out


def _allowed_values(spec: TailSpec, key: str, holds) -> str | None:
    """What ``key`` may be for ``holds(spec with that value)``, the other keys as they are (None:
    nothing)."""
    *tables, name = key.split(".")
    section = key_value(spec, ".".join(tables)) if tables else spec
    meta = {f.name: f.metadata for f in dataclasses.fields(section)}[name]
    value = getattr(section, name)
    if meta.get("choices"):
        ok = [c for c in meta["choices"] if holds(with_key(spec, key, c))]
        return "one of " + ", ".join(repr(c) for c in ok) if ok else None
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    if isinstance(value, int):
        lo = meta["ge"] if meta.get("ge") is not None else meta["gt"] + 1
        hi = meta["le"] if meta.get("le") is not None else meta["lt"] - 1
        ok = [n for n in range(int(lo), int(hi) + 1) if holds(with_key(spec, key, n))]
        return ", ".join(str(n) for n in ok) if ok else None
    span = feasible_interval(meta, lambda x: holds(with_key(spec, key, x)), float(value))
    if span is None:
        return None
    lo, hi = rule_bounds(meta)
    first, last = math.ceil(span[0] * 100) / 100, math.floor(span[1] * 100) / 100
    if span[0] == span[1]:
        return f"{span[0]:g}"
    low, high = span[0] - lo > 5e-3, hi - span[1] > 5e-3  # ends short of the rule's bounds
    if low and high:
        return f"{first:g} to {last:g}"
    return f">= {first:g}" if low else f"<= {last:g}"


def _panels_text(indices: list[int]) -> str:
    runs: list[list[int]] = []
    for k in sorted(set(indices)):
        if runs and k == runs[-1][-1] + 1:
            runs[-1].append(k)
        else:
            runs.append([k])
    return ", ".join(f"{r[0]}-{r[-1]}" if len(r) > 1 else f"{r[0]}" for r in runs)


#: Candidate tails :func:`panel_rule_messages` judges, at most, before it stops looking for the next
#: key's allowed values: a file whose rim cuts through every feature names many keys, none of which
#: alone can mend it, and without a bound its refusal waits for every key's whole search, past the
#: 10 s a load may take (tests/test_feasibility.py).
ALLOWED_SEARCH_BUDGET = 1200
#: Candidates judged for one key before its first feasible value, at most: the search's values
#: nearest the file's (1.6 % steps) from 0.27 to 3.7 times it, a new user's edit either way (a key
#: that cannot mend the panels alone otherwise tries 322).
ALLOWED_TRIES_PER_KEY = 160


class _SearchSpent(Exception):
    """A key's search for an allowed value judged :data:`ALLOWED_TRIES_PER_KEY` candidates, none
    feasible."""


def panel_rule_messages(spec: TailSpec, beta: float) -> list[str]:
    """The panel rules broken at cone ``beta`` (rad), as messages that name the keys the user
    writes.

    First each key that sets a broken feature and could, alone, make every rule hold, with its value
    and what it may be (searched key by key until :data:`ALLOWED_SEARCH_BUDGET` candidates were
    judged); then each rule once (the same rule on other panels and feature pairs counted), its
    worst case, the web it needs and the keys that set its features."""
    found = _problems_at(spec, beta)
    if not found:
        return []
    at = (
        0.0 if spec.taper.half_angle_deg == AUTO else beta
    )  # 'auto' finds a cone when the rules hold without one
    keys = _keys_of(found)
    hot = tuple(dict.fromkeys(p.panel for p in found if p.panel is not None))
    out = []
    judged = 0
    for key in keys:
        if judged >= ALLOWED_SEARCH_BUDGET:
            break  # the other keys are still named below, with the rules their features break
        tries, feasible = 0, False

        def holds(candidate: TailSpec) -> bool:
            nonlocal judged, tries, feasible
            judged, tries = judged + 1, tries + 1
            if tries > ALLOWED_TRIES_PER_KEY and not feasible:
                raise _SearchSpent
            feasible |= (ok := not _any_problem(candidate, at, hot))
            return ok

        try:
            allowed = _allowed_values(spec, key, holds)
        except _SearchSpent:
            allowed = None
        if allowed is not None:
            unit = " mm" if key.endswith("_mm") and allowed[0] in "<>0123456789" else ""
            unit = " deg" if key.endswith("_deg") else unit
            out.append(
                f"{key} = {key_value(spec, key)!r}: allowed: {allowed}{unit} for the panel rules "
                "below to "
                "hold, with the other keys as they are"
            )
    groups: dict[str, list[LayoutProblem]] = {}
    for p in found:
        groups.setdefault(re.sub(r"\d+(\.\d+)?", "#", p.desc), []).append(
            p
        )  # same rule, any panel or size
    for same in groups.values():
        worst = min(same, key=lambda p: p.measured_mm - p.need_mm)
        need = worst.need_mm
        web = (
            " or ".join(
                f"fabrication.{k} = {getattr(spec.fabrication, k)!r}"
                for k in _WEB_KEYS
                if getattr(spec.fabrication, k) == need
            )
            or f"{need:g} mm"
        )
        line = f"{worst.desc}, {need - worst.measured_mm:.2f} mm short (allowed: >= {web})"
        panels = [p.panel for p in same if p.panel is not None]
        if len(same) > 1:
            line += f"; {len(same) - 1} more like it" + (
                f" (panels {_panels_text(panels)})" if panels else ""
            )
        out.append(line + _set_by(spec, same))
    return out
