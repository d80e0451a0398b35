"""Every analysis of `bvsr build` as one result object, handed on in memory.

:func:`run_analyses` computes the workspace, the quasi-static table, the
certified clearance, the exact joint limits and the tip joint's clearance map;
:mod:`bvsr_cad.exporters.analysis_files` serialises the result and the robot
model takes its joint limits from it (nothing reads a file the build wrote).

:func:`from_params` is the build's second process (:mod:`bvsr_cad.pipeline.processes.worker`,
started as ``python -m bvsr_cad.pipeline.processes.worker
bvsr_cad.pipeline.processes.analyses_process``, which gives it the simulator): the same analyses
from the parameter file, the result pickled back to the build.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..assembly.assemble import Assembly
from ..assembly.inertia import SolidProperties
from .calibrate import COMPARE_THREADS
from .clearance import ClearanceResult, PosedTail, clearance_map, clearance_over, posed_tail
from .limits import (
    THETA_SEARCH_MAX_RAD,
    JointLimits,
    UselessResultError,
    build_joint_limits,
    fold_stack,
    per_joint_rad,
    stack_limit_rad,
)
from .measured import MeasuredComparison, compare_measurements
from .predict import WorkspaceSim
from .workspace import Workspace, empty_problems, quasi_static_table, run_workspace


@dataclass(frozen=True)
class ClearanceMap:
    """Stage-1 bound of the tip joint bending alone, with the saved limit and the fold stack."""

    joint: int  # 1-based
    theta_rad: np.ndarray
    phi_rad: np.ndarray
    bound_mm: np.ndarray  # (theta, phi)
    limit_phi_rad: np.ndarray
    limit_theta_rad: np.ndarray
    stack_theta_rad: np.ndarray


@dataclass(frozen=True)
class GeometryAnalyses:
    """The analyses that read the tail's geometry alone (its solids and placements, the SOAs' fold
    stack, the required clearance), not its materials, actuation or fitted values: the exact joint
    limits and the tip joint's clearance map. The build caches them on their own, so an edit of a
    material reuses them."""

    limits: list[JointLimits]
    fold_stack_lambda: float
    clearance_map: ClearanceMap
    seconds: float  # what computing them took (reused: when they were computed)


@dataclass(frozen=True)
class RestGeometry:
    """What the analyses read of the tail's solids: the posed tail (every instance's mesh, the pairs
    that must not touch, their exact rest distances) and each part's mass properties. Geometry
    alone: the build keeps it beside the cached geometry analyses and hands it back to an edit that
    moves no solid, whose analyses then make no solid, mesh none and measure no rest distance."""

    posed: PosedTail
    properties: dict[str, SolidProperties]

    @classmethod
    def of(cls, asm: Assembly, posed: PosedTail) -> RestGeometry:
        return cls(posed, {name: asm.solid_properties(name) for name in asm.parts})


@dataclass(frozen=True)
class AnalysisResults:
    workspace: Workspace
    quasi_static: list[dict]
    clearance: ClearanceResult
    clearance_poses_note: str
    required_clearance_mm: float
    limits: list[JointLimits]
    fold_stack_lambda: float
    clearance_map: ClearanceMap
    measured: MeasuredComparison | None
    seconds: float
    geometry_seconds: float = 0.0  # of seconds: the geometry analyses (0 when they were given)

    @property
    def geometry(self) -> GeometryAnalyses:
        return GeometryAnalyses(
            self.limits, self.fold_stack_lambda, self.clearance_map, self.geometry_seconds
        )

    def theta_max_per_joint(self) -> list[float]:
        """Each joint's limit as one number (:func:`~bvsr_cad.analysis.limits.per_joint_rad`)."""
        return per_joint_rad(self.limits)


def geometry_analyses(
    asm: Assembly, pt: PosedTail, progress: Callable[[str], None] | None = None
) -> GeometryAnalyses:
    """The exact joint limits and the tip joint's clearance map of ``asm``.

    Args:
        asm: the tail's assembly.
        pt: its plane-section deformation (:func:`bvsr_cad.analysis.clearance.plane_sections`).
        progress: called with one line per step (None: silent).

    Returns:
        The joint limits of every joint, the fold-stack limit and the tip joint's clearance map.
    """
    say = progress or (lambda _m: None)
    t0 = time.perf_counter()
    spec = asm.spec
    say("analysis: joint limits")
    stack = fold_stack(spec)
    lims = build_joint_limits(pt, spec, say)
    tip = spec.joints - 1
    th, ph, bound = clearance_map(pt, tip, THETA_SEARCH_MAX_RAD)
    phis = np.asarray(lims[tip].phi_rad)
    cmap = ClearanceMap(
        tip + 1,
        th,
        ph,
        bound,
        phis,
        np.asarray(lims[tip].theta_max_rad),
        stack_limit_rad(pt, tip, phis, *stack),
    )
    return GeometryAnalyses(lims, stack[0], cmap, time.perf_counter() - t0)


def run_analyses(
    asm: Assembly,
    progress: Callable[[str], None] | None = None,
    params_path: str | None = None,
    workspace_sim: WorkspaceSim | None = None,
    geometry: GeometryAnalyses | None = None,
    threads: int = COMPARE_THREADS,
    on_geometry: Callable[[GeometryAnalyses], None] | None = None,
    rest: RestGeometry | None = None,
    on_rest: Callable[[RestGeometry], None] | None = None,
) -> AnalysisResults:
    """Every analysis of the tail: workspace, clearance, joint limits, the model against
    measurements.

    Args:
        asm: the tail's assembly.
        progress: called with one line per step (None: silent).
        params_path: the parameter file ``asm`` was built from (its calibration's data file is
            resolved relative to it).
        workspace_sim: what predicts a measured tip workspace (see
            :func:`bvsr_cad.analysis.measured.compare_measurements`).
        geometry: :func:`geometry_analyses` of this geometry when the caller has them (from the
            build's cache), else they are computed.
        threads: the most threads that predict the measured rows (see
            :func:`bvsr_cad.analysis.calibrate.compare_rows`).
        on_geometry: called with the geometry analyses once they are computed here (not when
            given), before the other analyses go on.
        rest: the :class:`RestGeometry` of this geometry when the caller has it (from the build's
            cache), else it is made here.
        on_rest: called with the rest geometry made here.

    Returns:
        The analyses' results, handed to the exporters and the robot model.
    """
    say = progress or (lambda _m: None)
    cfg = asm.spec.analysis
    t0 = time.perf_counter()
    if rest is not None:
        asm.remember_properties(rest.properties)  # before anything integrates (or makes) a solid
    # The measurements go on in a thread beside the other analyses (the workspace protocol steps in
    # MuJoCo without Python's lock); only a workspace row of this geometry waits for its joints'
    # limits.
    limits: Future = Future()
    with ThreadPoolExecutor(1) as pool:
        measuring = pool.submit(
            compare_measurements, asm, params_path, say, workspace_sim, limits.result, threads
        )
        pt, geo = _rest_and_geometry(asm, say, geometry, on_geometry, rest, on_rest, limits)
        ws, quasi, clearance = _workspace_and_clearance(asm, pt, say)
        measured = measuring.result()
    seconds = time.perf_counter() - t0
    say(f"analysis: {seconds:.1f} s")
    return AnalysisResults(
        ws,
        quasi,
        clearance,
        "poses resampled from the build's workspace samples",
        cfg.min_clearance_mm,
        geo.limits,
        geo.fold_stack_lambda,
        geo.clearance_map,
        measured,
        seconds,
        0.0 if geometry is not None else geo.seconds,
    )


def _rest_and_geometry(
    asm: Assembly,
    say: Callable[[str], None],
    geometry: GeometryAnalyses | None,
    on_geometry: Callable[[GeometryAnalyses], None] | None,
    rest: RestGeometry | None,
    on_rest: Callable[[RestGeometry], None] | None,
    limits: Future,
) -> tuple[PosedTail, GeometryAnalyses]:
    """The posed tail and the geometry analyses, each the one given or made here and handed to
    ``on_rest`` / ``on_geometry``. The joints' limits are set on ``limits`` as soon as they are
    known, before ``on_geometry``; a failure is set there instead, for the measurements that wait
    on them."""
    try:
        say("analysis: clearance")
        pt = rest.posed if rest is not None else posed_tail(asm, say)
        if rest is None and on_rest is not None:
            on_rest(RestGeometry.of(asm, pt))
        geo = geometry if geometry is not None else geometry_analyses(asm, pt, say)
        limits.set_result(per_joint_rad(geo.limits))
        if geometry is None and on_geometry is not None:
            on_geometry(geo)
    except BaseException as exc:
        limits.set_exception(exc)
        raise
    return pt, geo


def _workspace_and_clearance(
    asm: Assembly, pt: PosedTail, say: Callable[[str], None]
) -> tuple[Workspace, list[dict], ClearanceResult]:
    """The sampled workspace (UselessResultError when it is empty), the quasi-static table and the
    certified clearance over poses resampled from the workspace's samples."""
    spec = asm.spec
    cfg = spec.analysis
    say("analysis: workspace")
    ws = run_workspace(asm, cfg.build_workspace_samples, cfg.seed, say)
    if empty := empty_problems(ws, spec):
        raise UselessResultError(f"tail {spec.name!r}", empty)
    quasi = quasi_static_table(asm, (1.0, 2.0))
    rng = np.random.default_rng(cfg.seed)
    idx = rng.integers(0, ws.samples, cfg.build_clearance_poses)
    return ws, quasi, clearance_over(pt, ws.w[idx])


#: Threads predicting the measured rows in the build's second process: the workspace protocol's
#: simulations one after the other, beside one thread for the other rows. The build's own stages
#: keep the other core busy, and the kernel shares the cores by thread: with a thread per simulation
#: (3 threads and this one against the build's one) this process ends its work before the build has
#: written the print files whose checks come next, and a core stands idle between; with 2 threads
#: both cores work until the checks' end.
BESIDE_BUILD_THREADS = 2
#: The same where the build's own stages are few (its geometry unchanged: the part files, previews
#: and drawings come from the cache): the protocol's two simulations side by side, beside one thread
#: for the other rows, so that both cores work while the build waits for them.
BESIDE_IDLE_BUILD_THREADS = 3


def from_params(
    params: str,
    sha256: str,
    workspace_sim: WorkspaceSim | None = None,
    geometry: GeometryAnalyses | None = None,
    asm: Assembly | None = None,
    threads: int = BESIDE_BUILD_THREADS,
    on_geometry: Callable[[GeometryAnalyses], None] | None = None,
    rest: RestGeometry | None = None,
    on_rest: Callable[[RestGeometry], None] | None = None,
) -> AnalysisResults:
    """The second process's work: the analyses of the parameter file the build read (``sha256``),
    progress on stderr (the parent relays it). Its entry point is
    :mod:`bvsr_cad.pipeline.processes.analyses_process`'s (which gives ``workspace_sim``, from the
    build's cache ``geometry``, ``asm`` when it built the assembly of this very file ahead,
    ``threads``: :data:`BESIDE_BUILD_THREADS` or :data:`BESIDE_IDLE_BUILD_THREADS`, ``on_geometry``,
    ``rest`` and ``on_rest``: see :func:`run_analyses`; without ``asm`` the assembly's solids are
    made when first read: none, where ``rest`` and ``geometry`` are given and no measured row needs
    a robot model)."""
    import sys

    from ..assembly.assemble import build_assembly
    from ..parameters.load import ParamError, load_spec, params_sha256

    if params_sha256(params) != sha256:
        raise ParamError(params, ["the file changed while the build was running; build again"])

    def say(msg: str) -> None:
        print(f"(second process) {msg}", file=sys.stderr, flush=True)

    if asm is None:
        asm = build_assembly(load_spec(params), solids=False)
    return run_analyses(
        asm, say, params, workspace_sim, geometry, threads, on_geometry, rest, on_rest
    )
