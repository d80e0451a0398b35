"""`bvsr build`: parameters -> assembly -> files -> checks, published atomically.

Everything is written into a temporary folder beside the output and moved
into place only when every file was written (:mod:`bvsr_cad.publish`); a
failure (bad parameters, a kernel error, a full disk, Ctrl-C) leaves any
earlier export untouched and no partial one.
"""

from __future__ import annotations

import pickle
import shutil
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import trimesh

from .analysis.poses import mold_scene, twin_scene, viewer_scenes
from .analysis.limits import per_joint_rad
from .analysis.run import BESIDE_BUILD_THREADS, BESIDE_IDLE_BUILD_THREADS, run_analyses
from .analyses_process import (SHARED_SOLIDS_FOLDER, SharedSolids, drop_geometry_ahead, keep_rest,
                               take_geometry_ahead)
from .assembly.build import Assembly, build_assembly
from .assembly.inertia import SolidProperties
from .assembly.products import build_mold_set, build_rigid_twin, mold_set_inputs, rigid_robot_model
from .assembly.collision import part_fits, remember_fits
from .assembly.robot import RobotModel, collision_shapes, robot_model
from .cache import OWNER_FILE, copy_tree, object_stage, spec_without, stage_key
from .checks.run import Checks
from .exporters.analysis_files import write_analyses
from .exporters.cad import write_assembly_step, write_part_step, write_part_stl
from .exporters.drawings import stamp_drawings, write_drawing_sheets
from .exporters.manifest import manifest_dict
from .exporters.manifest_file import write_manifest
from .exporters.mold_files import molds_manifest, write_mold_files
from .exporters.fabrication_files import write_fabrication, write_rigid_files
from .exporters.render import render_previews
from .exporters.report import report_pictures, write_report
from .exporters.reproducible import make_reproducible
from .exporters.robot_files import write_robot
from .exporters.robot_meshes import write_robot_meshes
from .exporters.viewer import write_viewer
from .exporters.gltf import scene_glb, write_scenes
from .parameters.load import params_sha256
from .parts._kernel import kernel_threads
from .publish import BuildResult, OpenedBuild, open_build, publish, reuse_whole, temporary_folder, volatile
from .sim import protocol_radius_mm
from . import units
from .worker import SecondProcess, result_or

Progress = Callable[[str], None]
#: In the geometry analyses' cache entry: :class:`bvsr_cad.analysis.run.GeometryAnalyses`, pickled.
GEOMETRY_FILE = "geometry.pkl"


#: What each cached stage does not read (``table`` or ``table.key``); everything else of the
#: parameters is part of its key. The part files are geometry (the assembly STEP is named after the
#: tail): no material property, no physics.
PART_FILES_IGNORE = ("materials", "use", "vertebra.material", "actuation", "analysis", "robot", "casting",
                     "fabrication_package", "pneumatics", "cart", "calibration")
#: The analyses read the whole tail but for the robot description, the molds and the fabrication
#: package (of which only the tube lengths, for the supply model); the name decides whether the
#: calibration's measurements are this tail's.
ANALYSES_IGNORE = ("robot", "casting", "fabrication_package")
#: The geometry analyses (joint limits, the tip's clearance map: :func:`bvsr_cad.analysis.run.geometry_analyses`)
#: read the tail's solids and placements (the part files' inputs, not the tail's name), the SOAs' fold stack
#: (``soa``, in them) and the required clearance (``analysis.min_clearance_mm``, in the key beside them).
ANALYSIS_GEOMETRY_IGNORE = PART_FILES_IGNORE + ("name",)
#: The drawings' views and hole tables are the panels' and the mold set's geometry: the part files'
#: inputs and the molds' (``casting``); the title block (tail name, materials, processes, the params
#: SHA-256) is stamped at every build, outside the cache.
DRAWINGS_IGNORE = tuple(k for k in PART_FILES_IGNORE if k != "casting") + ("name",)
#: The rigid twin's pieces and files are the part files' geometry and the printer volume it is split
#: for (``fabrication_package``); its pieces are named by joint, not after the tail. (The mold set's
#: key is its arguments, :func:`bvsr_cad.assembly.products.mold_set_inputs`.)
TWIN_IGNORE = tuple(k for k in PART_FILES_IGNORE if k != "fabrication_package") + ("name",)
#: The robot's meshes and its collision shapes' fits are the tail's solids and placements (named by part
#: and joint, not after the tail) and which collision shapes ``robot.collision_geometry`` asks for
#: (:func:`robot_geometry_key`); no mass, limit or actuator of the robot table.
ROBOT_GEOMETRY_IGNORE = PART_FILES_IGNORE + ("name",)


def robot_geometry_key(spec) -> str:
    """The cache key of the robot's meshes and collision fits (:data:`ROBOT_GEOMETRY_IGNORE`)."""
    return stage_key("robot_geometry", spec=spec_without(spec, *ROBOT_GEOMETRY_IGNORE), rod=spec.vertebra.has_rod,
                     collision_geometry=spec.robot.collision_geometry)


def build_export(params: str | Path, out_dir: str | Path | None = None,
                 progress: Progress | None = None, use_cache: bool = True,
                 standby: SecondProcess | None = None,
                 on_assembly: Callable[[Assembly], None] | None = None) -> BuildResult:
    """Build every part of the tail described by ``params`` into ``out_dir``.

    With ``use_cache`` the stages whose inputs are unchanged are taken from the artifact cache
    (:mod:`bvsr_cad.cache`): the whole export, the analyses, the parts' files and previews.
    ``standby``: the analyses' second process started ahead (``SecondProcess.standby("bvsr_cad.analyses_process")``,
    as the command line does before it imports this module, so that the two import side by side), given
    its work here if the analyses are to be run, else stopped. ``on_assembly``: called with the tail's
    assembly as soon as it is built, before the rest of the export (``bvsr watch --show``); an export the
    cache holds whole is published first, then its assembly built for it.

    Args:
        params: the parameter file.
        out_dir: the export folder (None: ``exports/<name>``), replaced only when the build succeeds.
        progress: called with one progress line at a time (None: silent).
        use_cache: take unchanged stages from the artifact cache (False: build everything).
        standby: the analyses' second process started ahead, or None.

    Returns:
        The published export: its folder, the checks' results and the stages' timings.

    Raises:
        ParamError: the parameter file is unreadable or describes an impossible tail.
        OutputError: ``out_dir`` cannot be replaced.
        GeometryError: the CAD kernel failed.
    """
    try:
        opened = open_build(params, out_dir, progress or (lambda _m: None), use_cache)
        whole = reuse_whole(opened)
        if whole is not None and on_assembly is not None:
            on_assembly(build_assembly(opened.spec))
        return whole or build_opened(opened, standby, on_assembly)
    finally:
        if standby is not None:
            standby.close()  # a no-op once it gave its result; stops one given no work


def build_opened(opened: OpenedBuild, standby: SecondProcess | None = None,
                 on_assembly: Callable[[Assembly], None] | None = None) -> BuildResult:
    """Build, stage by stage, the export that :func:`bvsr_cad.publish.open_build` prepared and the cache
    does not hold whole (:func:`bvsr_cad.publish.reuse_whole`). ``standby``, ``on_assembly``: as in
    :func:`build_export`; the caller closes ``standby``.

    Raises:
        GeometryError: the CAD kernel failed.
    """
    params, spec, out, cache, data, log = opened.params, opened.spec, opened.out, opened.cache, opened.data, opened.log
    say = log.say
    tmp = temporary_folder(out)
    analyses = None
    checks: Checks | None = None
    kernel_before = None
    try:
        say(f"building {spec.name}: {spec.segments} segments, {spec.joints} joints, {spec.panels} panels")
        analyses_key = stage_key("analyses", spec=spec_without(spec, *ANALYSES_IGNORE), data=data,
                                 tubes=(spec.fabrication_package.tube_lead_mm,
                                        spec.fabrication_package.tube_bend_allowance))
        cached_analyses = cache.get(analyses_key) if cache else None
        if cached_analyses is not None and standby is not None:
            # Nothing for it to do: stopped now, not at the end, so that its imports and its head start
            # (the tail's assembly) do not take a core from this build's stages.
            standby.close()
        geometry_key = stage_key("analysis_geometry", spec=spec_without(spec, *ANALYSIS_GEOMETRY_IGNORE),
                                 rod=spec.vertebra.has_rod, min_clearance_mm=spec.analysis.min_clearance_mm)
        geometry_hit = cache.get(geometry_key) if cache and cached_analyses is None else None
        geometry = None
        if geometry_hit is not None:
            t = time.perf_counter()
            geometry = pickle.loads((geometry_hit / GEOMETRY_FILE).read_bytes())
            log.record("analysis geometry (joint limits, clearance map)", True, time.perf_counter() - t)
        if cached_analyses is None:
            # The analyses (workspace, clearance, limits) need only the parameters: a second process
            # runs them from the file while this one builds, exports and fabricates.
            # With its geometry analyses cached the tail's solids are unchanged: the CAD stages come from
            # the cache, and the analyses take both cores while this process waits for them.
            work = [str(params.resolve()), params_sha256(params),
                    str(geometry_hit / GEOMETRY_FILE) if geometry_hit is not None else "",
                    str(BESIDE_BUILD_THREADS if geometry_hit is None else BESIDE_IDLE_BUILD_THREADS),
                    str(tmp.resolve()), spec.name]  # absolute: the process works in another folder
            analyses = (standby if standby is not None and standby.begin(work, tmp)
                        else SecondProcess.start("bvsr_cad.analyses_process", work, tmp, say))
            if analyses is not None:
                say("analyses: started in a second process")
                # Both cores are busy from here to the end: OCCT's own threads would only contend.
                kernel_before = kernel_threads(1)
        t = time.perf_counter()
        # Both processes need every solid where the geometry analyses are not cached: made once, shared.
        asm = build_assembly(spec, say, shared=SharedSolids(tmp / SHARED_SOLIDS_FOLDER)
                             if analyses is not None and geometry_hit is None else None)
        log.record("assembly", False, time.perf_counter() - t)
        if on_assembly is not None:
            on_assembly(asm)
        t = time.perf_counter()
        files: dict[str, dict[str, str]] = {name: {"step": f"step/{name}.step", "stl": f"stl/{name}.stl"}
                                             for name in asm.parts}
        # A rod material of "none" removes the rod part: the one material fact the part files read.
        part_inputs = {"spec": spec_without(spec, *PART_FILES_IGNORE), "rod": spec.vertebra.has_rod}
        part_key = stage_key("part_files", **part_inputs)
        part_hit = cache.get(part_key) if cache else None

        def write_parts(folder: Path) -> None:
            """The parts' STEP and STL and the assembly STEP."""
            (folder / "step").mkdir()
            (folder / "stl").mkdir()
            for name, part in asm.parts.items():
                say(f"export {name} (STEP, STL)")
                write_part_step(part, folder / files[name]["step"])
                write_part_stl(part, folder / files[name]["stl"])
            say("export assembly STEP")
            write_assembly_step(asm, folder / "step" / "assembly.step")

        if cache is None:
            write_parts(tmp)
        else:
            copy_tree(part_hit if part_hit is not None else cache.put(part_key, write_parts), tmp)
        log.record("part files", part_hit is not None, time.perf_counter() - t)
        # The robot's collision fits mesh the panels and the SOA at the print STLs' tolerances: made now,
        # with the STLs' triangulation on the solids, they take it as it is (0.5 CPU s instead of 2; the
        # robot's meshes later take it too: bounding boxes here keep it, parts._kernel.bounds). Not when
        # the cache holds them (nor the STLs).
        t = time.perf_counter()
        robot_key = robot_geometry_key(spec)
        robot_cached = cache is not None and cache.get(robot_key) is not None
        if part_hit is None and not robot_cached:
            collision_shapes(asm)
        fits_s = time.perf_counter() - t
        shutil.copyfile(params, tmp / "params.toml")
        manifest = manifest_dict(asm, params_sha256(params), files, "step/assembly.step")
        manifest["previews"] = {}  # rendered once the checks of the print files have started (below)
        t = time.perf_counter()
        say("SOA mold set")

        def make_molds(folder: Path) -> tuple:
            made = build_mold_set(asm)
            entries = write_mold_files(made, folder, say)
            # Its viewer scene now: the mold STLs' triangulation is what the scene shows (OCCT keeps the finest).
            return made, entries, mold_scene(made)

        (mold_set, mold_entries, mold_view), reused = object_stage(
            cache, stage_key("molds", inputs=mold_set_inputs(spec)), make_molds, tmp)
        molds = molds_manifest(spec, mold_set, *mold_entries)
        log.record("molds", reused, time.perf_counter() - t)
        t = time.perf_counter()
        say("rigid comparison tail")

        def make_twin(folder: Path) -> tuple:
            made = build_rigid_twin(asm)
            visual = write_rigid_files(made, folder)
            arrays = [(m.vertices.view(np.ndarray), m.faces.view(np.ndarray)) for m in visual]
            # The 3D view shows the twin's visual meshes (metres, tail frame) rather than meshing it again.
            # Measured on the solids made here: OCCT's integrals of a B-rep read back differ in the last bit.
            return (made, arrays, twin_scene(made, [(units.m_to_mm(v), f) for v, f in arrays]),
                    [SolidProperties.of(p.solid) for p in made])

        (pieces, visual, twin_view, twin_props), reused = object_stage(
            cache, stage_key("rigid_twin", spec=spec_without(spec, *TWIN_IGNORE)), make_twin, tmp)
        log.record("rigid twin", reused, time.perf_counter() - t)
        t = time.perf_counter()
        mold_files = {e["name"]: e["files"] for e in molds["molds"]["parts"]}
        fabrication = write_fabrication(asm, pieces, rigid_robot_model(asm, pieces, twin_props),
                                        [trimesh.Trimesh(v, f, process=False) for v, f in visual], mold_set, files,
                                        mold_files, tmp, say, cache)
        manifest["parts"] += fabrication.pop("rigid_parts")
        manifest.update(molds)
        manifest.update(fabrication)
        log.record("print jobs, BOM", False, time.perf_counter() - t)
        # The robot's files as soon as the joint limits exist, from the cache (an edit that moves no solid)
        # or left in this folder by the analyses' process (it has them long before its other analyses):
        # they need nothing else of the analyses, and their checks then go to the checks' second process
        # with those of the CAD files. They are entered in the manifest after the analyses' files, as in
        # every build; the early checks read them from a manifest written for them.
        # The robot's meshes and its collision shapes' fits read the geometry alone (and which shapes:
        # robot.collision_geometry): one cached stage, so that an edit that moves no solid (a material,
        # the robot's limits) neither meshes a part nor fits one. Both mesh the panels and the SOA at the
        # print STLs' tolerances with an absolute deflection: the same triangulation whichever stages
        # ran before (tests/test_robot.py).
        t = time.perf_counter()

        def robot_files(theta_max_rad: list[float]) -> dict:
            t0 = time.perf_counter()
            made: dict[str, RobotModel] = {}

            def make(folder: Path) -> tuple:
                say("robot meshes and collision fits")
                made["robot"] = robot_model(asm, theta_max_rad, shapes=collision_shapes(asm))
                return part_fits(asm), write_robot_meshes(made["robot"], folder / "robot" / "meshes")

            (fits, mesh_files), reused = object_stage(cache, robot_key, make, tmp)
            if reused:
                remember_fits(asm, fits)
            log.record("robot meshes, collision fits", reused, fits_s + time.perf_counter() - t0)
            say("robot model (B-rep inertials)")
            robot = made["robot"] if "robot" in made else robot_model(asm, theta_max_rad,
                                                                      shapes=collision_shapes(asm))
            return write_robot(robot, tmp, say, spec.cart, mesh_files)

        def limits_ahead() -> list[float] | None:
            """The joint limits, if the cache or the analyses' process has given them by now."""
            if cached_analyses is not None:
                return None  # the robot's files after the analyses' pickle is read (no process to wait for)
            ahead = geometry if geometry is not None or analyses is None else take_geometry_ahead(tmp)
            return per_joint_rad(ahead.limits) if ahead is not None else None

        early_limits = limits_ahead()
        robot_entries = robot_files(early_limits) if early_limits is not None else None
        robot_s = time.perf_counter() - t
        # What reads only the CAD files (and the robot's) goes on while the analyses finish: the checks of
        # the meshes, the molds and the print files (and the robot's files), the drawings, the 3D view and
        # the report's pictures.
        t = time.perf_counter()
        write_manifest(tmp, {**manifest, **(robot_entries or {})})
        fixed: set[Path] = set()
        make_reproducible(tmp, fixed)  # the files the early checks hash are the published ones
        say("checks of the CAD files")
        checks = Checks.start(tmp, say, cache=cache, meshes_beside=True, robot_beside=robot_entries is not None)
        checks_s = time.perf_counter() - t
        # The drawings after the checks' start: the printability and mold checks, the longest chain of
        # the build's end, read none of them (the checks of the drawings run at the finish).
        t = time.perf_counter()
        say("drawings (SVG sheets)")
        drawings_key = stage_key("drawings", spec=spec_without(spec, *DRAWINGS_IGNORE))
        drawings_hit = cache.get(drawings_key) if cache else None
        draw = lambda folder: write_drawing_sheets(asm, mold_set, folder)  # noqa: E731
        if cache is None:
            draw(tmp)
        else:
            copy_tree(drawings_hit if drawings_hit is not None else cache.put(drawings_key, draw), tmp)
        manifest.update(stamp_drawings(tmp, asm, mold_set, params_sha256(params)))
        log.record("drawings", drawings_hit is not None, time.perf_counter() - t)
        t = time.perf_counter()
        say("interactive 3D view")
        scenes = viewer_scenes(asm, mold_view, twin_view, progress=say)
        glb = {s.name: scene_glb(s) for s in scenes}
        manifest.update(write_scenes(tmp, scenes, glb))
        manifest.update(write_viewer(tmp, manifest["scenes"]["files"], glb))
        log.record("interactive 3D view", False, time.perf_counter() - t)
        t = time.perf_counter()
        say("previews (off-screen renders)")
        # The parts' geometry and the tail's name (the part files' inputs); after the printability
        # checks' start, which wait for the print files and nothing drawn here.
        manifest["previews"], reused = object_stage(
            cache, stage_key("previews", **part_inputs), lambda folder: render_previews(asm, folder), tmp)
        log.record("previews", reused, time.perf_counter() - t)
        t = time.perf_counter()
        say("report pictures")
        pictures = report_pictures(tmp, manifest, cache)
        pictures_s = time.perf_counter() - t
        # The joint limits were not in when the checks started: the robot's files now if they are, before
        # the wait for the analyses; else its collision fits now (what needs no limits) and the files after it.
        t = time.perf_counter()
        late_limits = limits_ahead() if robot_entries is None else None
        if late_limits is not None:
            robot_entries = robot_files(late_limits)
        elif robot_entries is None and not robot_cached:
            collision_shapes(asm)
        robot_s += time.perf_counter() - t
        if robot_entries is not None:
            t = time.perf_counter()
            if late_limits is not None:
                write_manifest(tmp, {**manifest, **robot_entries})  # written again, in its order, below
            # Their checks here, before the wait, unless the checks' process (given them at its start) has
            # begun them: whichever is free first.
            checks.robot_ahead()
            checks_s += time.perf_counter() - t
        t = time.perf_counter()
        if cached_analyses is not None:
            with (cached_analyses / "analyses.pkl").open("rb") as fh:
                results, drawn = pickle.load(fh), False
            log.record("analyses", True, time.perf_counter() - t)
        else:
            # With their pictures, drawn in the second process (not when it was lost: then run here).
            results, drawn = result_or(analyses, lambda: (run_analyses(asm, say, str(params), protocol_radius_mm,
                                                                       geometry), False), say, "analyses")
            if geometry is None:
                log.record("analysis geometry (joint limits, clearance map)", False, results.geometry_seconds)
                if cache is not None:
                    def keep_geometry(folder: Path) -> None:
                        (folder / GEOMETRY_FILE).write_bytes(pickle.dumps(results.geometry))
                        keep_rest(tmp, folder)  # the analyses' process made it: for the next edit

                    cache.put(geometry_key, keep_geometry)
            if cache is not None:
                cache.put(analyses_key, lambda folder: (folder / "analyses.pkl").write_bytes(pickle.dumps(results)))
            # Their own time (in the second process, beside the stages above); the wait was shorter.
            log.record("analyses", False, results.seconds)
            log.process("analyses", analyses.cpu_s if analyses is not None else None)
        drop_geometry_ahead(tmp)  # not taken above (made after the robot's stage, or by a process since lost)
        t = time.perf_counter()
        manifest.update(write_analyses(results, tmp, spec.name, pictures=not drawn))
        manifest.update(robot_entries if robot_entries is not None else robot_files(results.theta_max_per_joint()))
        write_manifest(tmp, manifest)
        # STEP and 3MF time stamps (the build time is in the manifest's volatile section), of the files
        # written since the first go.
        make_reproducible(tmp, fixed)
        log.record("analysis files and robot descriptions", False, robot_s + time.perf_counter() - t)
        t = time.perf_counter()
        say("checks")
        results = checks.finish()
        log.process("checks", checks.cpu_s)
        manifest["checks"] = [r.to_json() for r in results]
        log.record("checks", False, checks_s + time.perf_counter() - t)
        t = time.perf_counter()
        say("report")
        manifest.update(write_report(tmp, manifest, cache, pictures))
        log.record("report", False, pictures_s + time.perf_counter() - t)
        manifest["volatile"] = volatile(opened.t0, log)
        write_manifest(tmp, manifest)
        if cache is not None:
            cache.put(opened.export_key, lambda folder: copy_tree(tmp, folder, skip=(OWNER_FILE,)))
        publish(tmp, out)
    except BaseException:
        if analyses is not None:
            analyses.close()
        if checks is not None:
            checks.close()
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    finally:
        if kernel_before is not None:
            kernel_threads(kernel_before)
    return BuildResult(out, results, time.perf_counter() - opened.t0, log.stages, manifest["volatile"]["cpu_seconds"])
