"""The analyses' second process of `bvsr build` (``python -m bvsr_cad.pipeline.processes.worker
bvsr_cad.pipeline.processes.analyses_process``).

Its own module, beside :mod:`bvsr_cad.pipeline.stages` rather than in it, so that the process
imports what the analyses read (the CAD kernel, the models, the simulator) and not the exporters the
build's own process writes with (matplotlib, pyvista, the drawings' SVG): less import time
(measured with ``python -X importtime``: benchmarks/RESULTS.md). Here, not in the analysis layer,
because a measured workspace is predicted in the simulator.
"""

from __future__ import annotations

import os
import pickle
import sys
from pathlib import Path

from ...analysis.run import BESIDE_BUILD_THREADS, GeometryAnalyses, RestGeometry
from ...parameters.load import load_spec, params_sha256
from ...process import kernel_threads
from ...simulation.sim import protocol_radius_mm

#: In the build's temporary folder: the geometry analyses, pickled by the analyses' second process
#: as soon as it has them (:func:`write_geometry_ahead`), so that the build writes and checks the
#: robot files (which need the joint limits alone) while the other analyses go on; the build removes
#: it before it publishes.
GEOMETRY_AHEAD_FILE = ".analysis-geometry.pkl"


def _write_whole(path: Path, value) -> None:
    """``value`` pickled into ``path``, whole or not at all: written beside, then renamed."""
    part = path.with_name(path.name + ".part")
    part.write_bytes(pickle.dumps(value, protocol=pickle.HIGHEST_PROTOCOL))
    os.replace(part, path)


def write_geometry_ahead(folder: Path, geo: GeometryAnalyses) -> None:
    """``geo`` into ``folder``'s :data:`GEOMETRY_AHEAD_FILE`, whole or not at all."""
    _write_whole(folder / GEOMETRY_AHEAD_FILE, geo)


#: In the build's temporary folder: the rest geometry (:class:`bvsr_cad.analysis.run.RestGeometry`:
#: the posed tail and the parts' mass properties) the analyses' process made, pickled
#: (:func:`write_rest_ahead`); the build moves it into its cache entry of the geometry analyses as
#: :data:`REST_FILE` (:func:`keep_rest`), beside their pickle, and the next build of the same
#: geometry hands it back: an edit that moves no solid then makes no solid in this process, meshes
#: none and measures no rest distance (its assembly ahead and the posed tail are seconds of this
#: process's work, most of it before its analyses could start; figures: benchmarks/RESULTS.md).
REST_AHEAD_FILE = ".analysis-rest.pkl"
#: The rest geometry's name in the cache entry of the geometry analyses.
REST_FILE = "rest_geometry.pkl"


def write_rest_ahead(folder: Path, rest: RestGeometry) -> None:
    """``rest`` into ``folder``'s :data:`REST_AHEAD_FILE`, whole or not at all."""
    _write_whole(folder / REST_AHEAD_FILE, rest)


def keep_rest(folder: Path, entry: Path) -> None:
    """Move the rest geometry the analyses' process left in ``folder`` (if any) into the cache
    ``entry`` being filled with the geometry analyses."""
    try:
        os.replace(folder / REST_AHEAD_FILE, entry / REST_FILE)
    except FileNotFoundError:
        pass


def read_rest(geometry: str) -> RestGeometry | None:
    """The rest geometry kept beside the cached geometry analyses at ``geometry`` (their pickle's
    path), or None (an entry without one, or evicted since the build looked)."""
    try:
        return pickle.loads((Path(geometry).parent / REST_FILE).read_bytes())
    except OSError:
        return None


def take_geometry_ahead(folder: Path) -> GeometryAnalyses | None:
    """The geometry analyses :func:`write_geometry_ahead` left in ``folder`` (then removed), or None
    when there are none (yet)."""
    path = folder / GEOMETRY_AHEAD_FILE
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return None
    path.unlink()
    return pickle.loads(data)


def drop_geometry_ahead(folder: Path) -> None:
    """Remove what :func:`write_geometry_ahead` and :func:`write_rest_ahead` may have left in
    ``folder`` (a file or its half-written part; the rest geometry once the build has moved it into
    its cache, or where it has none)."""
    for name in (
        GEOMETRY_AHEAD_FILE,
        GEOMETRY_AHEAD_FILE + ".part",
        REST_AHEAD_FILE,
        REST_AHEAD_FILE + ".part",
    ):
        (folder / name).unlink(missing_ok=True)


#: The standby analyses process's head start (:func:`_prepare_analyses`): (params path, SHA-256) ->
#: assembly.
_PREPARED: dict[tuple[str, str], object] = {}


def _prepare_analyses(params: str) -> None:
    """A standby analyses process's head start (``python -m bvsr_cad.pipeline.processes.worker
    bvsr_cad.pipeline.processes.analyses_process --standby PARAMS``): the tail's assembly from the
    file, its solids made one by one while the build imports and reads its cache, until the work
    comes (a build whose geometry is cached hands over the rest geometry: it needs none of them; a
    solid not made by then is made when first read). Used only if the work names the same file with
    the same SHA-256 (the bytes the assembly was built from)."""
    kernel_threads(1)  # beside the build, which keeps the other core busy
    read = _assembly_read(params)
    if read is None:
        return
    asm, sha256 = read
    _PREPARED[str(Path(params).resolve()), sha256] = asm
    for part in asm.parts.values():
        if _work_waiting():
            return
        part.solid  # noqa: B018 - made now, a head start


def _assembly_read(params: str, sha256: str | None = None):
    """``(assembly, SHA-256)``: the tail's assembly from the file (its solids made when first read)
    and the SHA-256 of the bytes it was built from; None where the file changed while it was read,
    or its bytes are not ``sha256``."""
    from ...assembly.assemble import build_assembly

    before = params_sha256(params)
    if sha256 is not None and before != sha256:
        return None
    asm = build_assembly(load_spec(params), solids=False)
    return (asm, before) if params_sha256(params) == before else None


def _work_waiting() -> bool:
    """The build has written this standby process's work (or closed its input) on stdin."""
    import select

    try:
        return bool(select.select([sys.stdin], [], [], 0)[0])
    except (OSError, ValueError):  # no pollable stdin (another platform): go on making them
        return False


def _analyses_process(
    params: str,
    sha256: str,
    geometry: str = "",
    threads: str = "",
    folder: str = "",
    name: str = "",
):
    """The analyses' second process (``python -m bvsr_cad.pipeline.processes.worker
    bvsr_cad.pipeline.processes.analyses_process - PARAMS SHA256 [GEOMETRY [THREADS [FOLDER
    NAME]]]``): ``(results, drawn)``. ``GEOMETRY``: the cached geometry analyses' pickle (computed
    here when it is gone); ``THREADS``: those that predict the measured rows (default
    :data:`bvsr_cad.analysis.run.BESIDE_BUILD_THREADS`); ``FOLDER``: the build's temporary folder.
    Into it go the geometry analyses as soon as they are computed here
    (:func:`write_geometry_ahead`: the build writes and checks the robot files, which need the joint
    limits alone, while the other analyses go on; they took the build's last seconds, on one core,
    when they waited for the whole result), and once the analyses are done their pictures of the
    tail ``NAME`` (:func:`bvsr_cad.exporters.analysis_files.write_analysis_pictures`; ``drawn`` says
    so): drawn in the build's process, they were part of its last stages too
    (benchmarks/RESULTS.md)."""
    from ...analysis.run import from_params

    kernel_threads(1)  # beside the build, which keeps the other core busy
    try:
        given = pickle.loads(Path(geometry).read_bytes()) if geometry else None
    except OSError:  # evicted since the build looked: computed here
        given = None
    asm = _PREPARED.pop((str(Path(params).resolve()), sha256), None)
    if asm is None and folder and given is None:
        read = _assembly_read(
            params, sha256
        )  # None: changed since the build read it (from_params says so)
        asm = read[0] if read is not None else None
    results = from_params(
        params,
        sha256,
        protocol_radius_mm,
        given,
        asm,
        int(threads) if threads else BESIDE_BUILD_THREADS,
        (lambda geo: write_geometry_ahead(Path(folder), geo)) if folder else None,
        read_rest(geometry) if given is not None else None,
        (lambda rest: write_rest_ahead(Path(folder), rest)) if folder and given is None else None,
    )
    if not folder:
        return results, False
    from ...exporters.analysis_files import (
        write_analysis_pictures,
    )  # matplotlib: after the analyses

    write_analysis_pictures(results, Path(folder), name)
    return results, True


#: What the analyses' second process serves (:func:`bvsr_cad.pipeline.processes.worker.child_main`):
#: its work and its head start.
SECOND_PROCESS = (_analyses_process, _prepare_analyses)
