"""Collision-free bending limit theta_max(phi) of every joint (the others straight).

For each joint and bending-plane angle, bisection on theta in [0, theta_hi]
for the largest pose at which every pair that feels the joint keeps the
required clearance (the others do not move relative to each other). A pose
is tested in the stages of :mod:`bvsr_cad.analysis.clearance`: the stage-1a
bound clears most pairs, the stage-1b bound (z-scaled rest distances) most
of the rest, and exact mesh distances of the posed meshes decide what is left.

The SOAs bound the bend too: a bellows cannot fold shorter than its stack of
walls. In the plane-section model the pleated section at a point shortens by
lambda = 1 - kappa h, so the joint's SOAs reach their stack at
    theta_stack(phi) = (1 - lambda_solid) L / h_soa(phi),
lambda_solid = facet rows x wall thickness / H_o and h_soa the SOAs' reach
towards the bending direction (their bellows, flanges excluded). The search
for the clearance limit stops there.

Two limits come out per plane: ``theta_bound_rad`` from the bounds alone
(conservative: every bend up to it is certainly free, the bounds only fall
as theta grows) and ``theta_max_rad``, searched above it with exact
distances at EXACT_SAMPLES bends up to the top of the search and bisection
below the first that fails. Clearance is not monotone in theory (a pair
could touch and part again between samples), so above the bound the search
assumes, as every sampled limit does, that the free set is an interval.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..parameters.load import ParamError
from ..parameters.tables import TailSpec
from .clearance import SUPPORT_BINS, PosedTail


class UselessResultError(ParamError):
    """An analysis of the build stopped as soon as its result was known to be useless (every problem
    names the key that asked for it, its value and what the tail allows)."""

    what = "the analyses"


def rest_problems(pt: PosedTail, need_mm: float) -> list[str]:
    """The joints whose limits are 0 before any search: a pair that feels the joint stands closer
    than ``need_mm`` in the straight tail, where every search starts (``analysis.min_clearance_mm``
    the file asks for: :mod:`bvsr_cad.parameters.feasibility` refuses it at load where the layout
    decides)."""
    low = np.flatnonzero(pt.rest_mm < need_mm)
    if len(low) == 0:
        return []
    worst = int(low[np.argmin(pt.rest_mm[low])])
    joints = sorted({int(k) + 1 for p in low for k in np.flatnonzero(pt.span[p])})
    a, b = pt.pairs[worst]
    most = np.floor(float(pt.rest_mm.min()) * 1000.0) / 1000.0
    return [
        f"analysis.min_clearance_mm = {need_mm!r}: {pt.names[a]} and {pt.names[b]} stand "
        f"{pt.rest_mm[worst]:.3f} mm apart in the straight tail ({len(low)} pair(s) closer than "
        "required), "
        f"so joint(s) {', '.join(str(j) for j in joints)} would get a limit of 0 in every bending "
        "plane; "
        f"allowed: <= {most:g} mm with the other keys as they are"
    ]


def _check_rest(pt: PosedTail, spec: TailSpec) -> None:
    problems = rest_problems(pt, spec.analysis.min_clearance_mm)
    if problems:
        raise UselessResultError(f"tail {spec.name!r}", problems)


def fold_stack(spec: TailSpec) -> tuple[float, float]:
    """(lambda_solid, flange thickness mm): a bellows folds no shorter than its facet rows x wall
    thickness."""
    soa = spec.soa
    return soa.facet_rows * soa.facet_thickness_mm / soa.origami_height_mm, soa.flange_thickness_mm


@dataclass(frozen=True)
class JointLimits:
    joint: str
    phi_rad: list[float]
    theta_max_rad: list[float]  # exact (or the bound where exact=False)
    theta_bound_rad: list[float]  # from the bounds alone: never above theta_max_rad
    limiting_pair: list[
        list[str]
    ]  # the pair that would come closer than required just beyond the limit
    clearance_at_limit_mm: list[float | None]  # its exact clearance there (None: not evaluated)
    limited_by: list[str]  # "clearance", "fold stack" (the SOAs fully folded) or "search range"


#: Exact checks between the bounds' limit and the top of the search (the fold stack or theta_hi).
EXACT_SAMPLES = 4


def _pose(pt: PosedTail, joint: int, theta: float, phi: float) -> np.ndarray:
    w = np.zeros((pt.kin.n_joints, 2))
    w[joint] = (theta * np.cos(phi), theta * np.sin(phi))
    return w


class _Tester:
    """Whether joint k bent to (theta, phi) keeps ``need_mm`` between every pair that feels it."""

    def __init__(self, pt: PosedTail, joint: int, need_mm: float):
        self.pt, self.k, self.need = pt, joint, need_mm
        self.ids = np.flatnonzero(pt.span[:, joint])
        self._support = pt.support_mm[self.ids]
        self.exact_calls = 0
        self._exact: dict[
            tuple[float, float], tuple[bool, int, float]
        ] = {}  # the search asks twice at its end

    def _stretch(self, w: np.ndarray) -> np.ndarray:
        """:meth:`PosedTail.stretch` of the pairs that feel joint k, at a pose bending joint k
        alone: in every other joint theta = 0 leaves lambda at 1, so the one term left is computed,
        with the same operations on the same values (the same numbers to the last bit:
        ``tests/test_workspace_clearance.py``)."""
        pt, k = self.pt, self.k
        theta = np.hypot(w[None, :, 0], w[None, :, 1])
        kappa = theta / pt.kin.length_mm
        bins = (
            np.floor(
                (np.arctan2(w[None, :, 1], w[None, :, 0]) + np.pi) / (2 * np.pi) * SUPPORT_BINS
            ).astype(int)
            % SUPPORT_BINS
        )
        bulge = pt.kin.length_mm * theta[0, k] / 8.0
        lam = np.minimum(1.0, 1.0 - kappa[0, k] * (self._support[:, bins[0, k]] + bulge))
        return np.clip(lam, 0.0, 1.0)

    def _screen(self, theta: float, phi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The pose, and the pairs whose stage-1a bound is below the need with their stage-1b
        bounds."""
        w = _pose(self.pt, self.k, theta, phi)
        lam = self._stretch(w)
        low = lam * self.pt.rest_mm[self.ids] < self.need
        return w, self.ids[low], self.pt.refine(lam[low], self.ids[low])

    def bound_ok(self, theta: float, phi: float) -> tuple[bool, int]:
        """(the bounds guarantee the need, the pair with the lowest bound or -1)."""
        _w, cand, rb = self._screen(theta, phi)
        if len(cand) == 0:
            return True, -1
        return bool((rb >= self.need).all()), int(cand[np.argmin(rb)])

    def exact_ok(self, theta: float, phi: float) -> tuple[bool, int, float]:
        """(the need is kept, the closest pair or -1, its exact clearance): exact distances for the
        pairs the bounds do not clear."""
        if (theta, phi) not in self._exact:
            w, cand, rb = self._screen(theta, phi)
            cand = cand[rb < self.need]
            if len(cand) == 0:
                self._exact[theta, phi] = (True, -1, float("inf"))
            else:
                d = self.pt.exact(w, cand)
                self.exact_calls += len(cand)
                i = int(np.argmin(d))
                self._exact[theta, phi] = (bool(d[i] >= self.need), int(cand[i]), float(d[i]))
        return self._exact[theta, phi]


def _bisect(ok: Callable[[float], bool], lo: float, hi: float, tol: float) -> tuple[float, float]:
    """Largest free theta: ``ok(lo)`` holds, ``ok(hi)`` does not; returns the final (lo, hi)."""
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if ok(mid):
            lo = mid
        else:
            hi = mid
    return lo, hi


def stack_limit_rad(
    pt: PosedTail, joint: int, phis: np.ndarray, lambda_solid: float, flange_mm: float
) -> np.ndarray:
    """theta_stack(phi) of joint ``joint`` (0-based): where its most compressed SOA is fully
    folded."""
    reach = np.full(len(phis), -np.inf)
    dirs = np.c_[np.cos(phis), np.sin(phis)]
    for inst, m in zip(pt.instances, pt.coarse):
        if inst.role == "soa" and inst.joint == joint + 1:
            z = m.vertices[:, 2]
            bellows = m.vertices[(z > z.min() + flange_mm) & (z < z.max() - flange_mm), :2]
            reach = np.maximum(reach, (bellows @ dirs.T).max(axis=0))
    with np.errstate(divide="ignore"):
        return np.where(reach > 0, (1.0 - lambda_solid) * pt.kin.length_mm / reach, np.inf)


@dataclass(frozen=True)
class _Plane:
    """One bending plane's search: the exact and the bounds' limit, the pair beyond it and why it
    stops."""

    theta_max_rad: float
    theta_bound_rad: float
    pair: int  # -1: none
    clearance_mm: float | None
    limited_by: str


def _plane(
    test: _Tester, phi: float, t_stack: float, theta_hi_rad: float, tol_rad: float, exact: bool
) -> _Plane:
    """theta_max of one bending plane (see :func:`joint_limits`)."""
    top = float(min(theta_hi_rad, t_stack))
    reached = "fold stack" if t_stack <= theta_hi_rad else "search range"
    if test.bound_ok(top, phi)[0]:
        return _Plane(top, top, -1, None, reached)
    lo, hi = _bisect(lambda t: test.bound_ok(t, phi)[0], 0.0, top, tol_rad)
    th_b = lo
    if exact:
        # Free up to the bound's limit for certain; above it, exact distances at EXACT_SAMPLES
        # evenly spaced bends up to the top, and bisection below the first that fails.
        for t in np.linspace(lo, top, EXACT_SAMPLES + 1)[1:]:
            if not test.exact_ok(float(t), phi)[0]:
                hi = float(t)
                break
            lo = float(t)
        else:
            hi = lo
        if hi > lo:
            lo, hi = _bisect(lambda t: test.exact_ok(t, phi)[0], lo, hi, tol_rad)
    if hi <= lo:
        return _Plane(lo, th_b, -1, None, reached)
    d, p = None, -1
    if exact:
        _ok, p, dist = test.exact_ok(hi, phi)
        d = dist if np.isfinite(dist) else None
    if p < 0:
        p = test.bound_ok(hi, phi)[1]
    return _Plane(lo, th_b, p, d, "clearance")


def _joints(pt: PosedTail, need_mm: float, phis: np.ndarray, stack: tuple[float, float] | None):
    """Per joint of a search: (its 0-based index, its tester, the fold stack's limit per plane,
    start time)."""
    for k in range(pt.kin.n_joints):
        t0 = time.perf_counter()
        yield (
            k,
            _Tester(pt, k, need_mm),
            stack_limit_rad(pt, k, phis, *stack) if stack else np.full(len(phis), np.inf),
            t0,
        )


def joint_limits(
    pt: PosedTail,
    need_mm: float,
    n_phi: int = 36,
    theta_hi_rad: float = 1.0,
    tol_rad: float = 1e-3,
    exact: bool = True,
    stack: tuple[float, float] | None = None,
    progress: Callable[[str], None] | None = None,
) -> list[JointLimits]:
    """theta_max(phi) of every joint at ``n_phi`` bending planes, to ``tol_rad``.

    Args:
        stack: (lambda_solid, flange thickness mm) to stop at the SOAs' fold stack; None: no stack
            limit.
        exact: False stops at the bounds' limit (conservative; theta_max_rad = theta_bound_rad).
    """
    say = progress or (lambda _m: None)
    phis = np.linspace(-np.pi, np.pi, n_phi, endpoint=False)
    out = []
    for k, test, th_stack, t0 in _joints(pt, need_mm, phis, stack):
        planes = [
            _plane(test, phi, t_stack, theta_hi_rad, tol_rad, exact)
            for phi, t_stack in zip(phis, th_stack)
        ]
        th_x = [pl.theta_max_rad for pl in planes]
        why = [pl.limited_by for pl in planes]
        say(
            f"limits j{k + 1}: theta_max {min(th_x):.3f}..{max(th_x):.3f} rad "
            f"({'exact' if exact else 'bounds'}; {why.count('clearance')} of {n_phi} planes "
            "limited by clearance, "
            f"{why.count('fold stack')} by the fold stack), {test.exact_calls} exact distances, "
            f"{time.perf_counter() - t0:.1f} s"
        )
        out.append(
            JointLimits(
                f"j{k + 1}",
                [float(v) for v in phis],
                [float(v) for v in th_x],
                [float(pl.theta_bound_rad) for pl in planes],
                [
                    [pt.names[pt.pairs[pl.pair][0]], pt.names[pt.pairs[pl.pair][1]]]
                    if pl.pair >= 0
                    else []
                    for pl in planes
                ],
                [pl.clearance_mm for pl in planes],
                why,
            )
        )
    return out


def lowest_limits_rad(
    pt: PosedTail,
    need_mm: float,
    n_phi: int = 36,
    theta_hi_rad: float = 1.0,
    tol_rad: float = 1e-3,
    stack: tuple[float, float] | None = None,
    progress: Callable[[str], None] | None = None,
) -> list[float]:
    """Each joint's lowest theta_max over the planes: ``per_joint_rad(joint_limits(...))`` (exact),
    with the planes that cannot lower it skipped.

    A plane's search ends within ``tol_rad`` below the top T of its free interval [0, T] (the
    assumption every sampled limit makes). Once a plane gave ``best``, a plane free at ``best + 2
    tol_rad`` has T >= best + 2 tol_rad, so its search would end above ``best``: one exact test
    instead of its search. The planes are searched tightest first (their stage-1a bound at half the
    search range), so ``best`` is low early. The planes searched are searched as
    :func:`joint_limits` searches them: the result is the same number to the last bit
    (``tests/test_workspace_clearance.py``)."""
    say = progress or (lambda _m: None)
    phis = np.linspace(-np.pi, np.pi, n_phi, endpoint=False)
    out = []
    for k, test, th_stack, t0 in _joints(pt, need_mm, phis, stack):
        rest = pt.rest_mm[test.ids]
        tight = [
            float(
                np.min(test._stretch(_pose(pt, k, 0.5 * theta_hi_rad, phi)) * rest, initial=np.inf)
            )
            for phi in phis
        ]
        best, searched = np.inf, 0
        for i in sorted(range(n_phi), key=lambda i: (min(theta_hi_rad, th_stack[i]), tight[i], i)):
            probe = best + 2.0 * tol_rad
            if probe < min(theta_hi_rad, th_stack[i]) and test.exact_ok(probe, float(phis[i]))[0]:
                continue
            best = min(
                best,
                _plane(
                    test, float(phis[i]), th_stack[i], theta_hi_rad, tol_rad, True
                ).theta_max_rad,
            )
            searched += 1
        say(
            f"limits j{k + 1}: lowest theta_max {best:.3f} rad ({searched} of {n_phi} planes "
            "searched, "
            f"{time.perf_counter() - t0:.1f} s)"
        )
        out.append(float(best))
    return out


#: Limits in the build: 36 bending planes, 1 mrad steps, searched up to 1 rad.
BUILD_LIMIT_PHIS = 36
THETA_SEARCH_MAX_RAD = 1.0
LIMIT_RESOLUTION_RAD = 1e-3


def build_joint_limits(
    pt: PosedTail, spec: TailSpec, progress: Callable[[str], None] | None = None
) -> list[JointLimits]:
    """The build's exact joint limits of a posed tail: :func:`joint_limits` with the build's planes,
    search range and resolution, the spec's required clearance and fold stack.

    Raises:
        UselessResultError: the straight tail already breaks the required clearance
            (:func:`rest_problems`), before any search."""
    _check_rest(pt, spec)
    return joint_limits(
        pt,
        spec.analysis.min_clearance_mm,
        BUILD_LIMIT_PHIS,
        THETA_SEARCH_MAX_RAD,
        LIMIT_RESOLUTION_RAD,
        exact=True,
        stack=fold_stack(spec),
        progress=progress,
    )


def per_joint_rad(limits: list[JointLimits]) -> list[float]:
    """Each joint's limit as one number: the minimum of theta_max over its bending planes (what the
    robot files are built with)."""
    return [float(np.min(j.theta_max_rad)) for j in limits]


def theta_max_per_joint_rad(asm, progress: Callable[[str], None] | None = None) -> list[float]:
    """:func:`per_joint_rad` of :func:`build_joint_limits` of ``asm``, found by
    :func:`lowest_limits_rad` (the same numbers, a fraction of the search)."""
    from .clearance import posed_tail

    spec = asm.spec
    pt = posed_tail(asm, progress)
    _check_rest(pt, spec)
    return lowest_limits_rad(
        pt,
        spec.analysis.min_clearance_mm,
        BUILD_LIMIT_PHIS,
        THETA_SEARCH_MAX_RAD,
        LIMIT_RESOLUTION_RAD,
        fold_stack(spec),
        progress,
    )
