"""`bvsr build`: parameters -> assembly -> files -> checks, published atomically.

Everything is written into a temporary folder beside the output and moved
into place only when every file was written (:mod:`bvsr_cad.pipeline.publish`); a
failure (bad parameters, a kernel error, a full disk, Ctrl-C) leaves any
earlier export untouched and no partial one.
"""

from __future__ import annotations

import shutil
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import trimesh

from .. import units
from ..analysis.poses import mold_scene, twin_scene, viewer_scenes
from ..analysis.run import run_analyses
from ..assembly.assemble import Assembly, build_assembly
from ..assembly.collision import CylinderFit
from ..assembly.inertia import SolidProperties
from ..assembly.products import build_mold_set, build_rigid_twin, mold_set_inputs, rigid_robot_model
from ..assembly.robot import collision_shapes, robot_model
from ..checks.run import Checks
from ..exporters.analysis_files import write_analyses
from ..exporters.cad import write_assembly_step, write_part_step, write_part_stl
from ..exporters.drawings import stamp_drawings, write_drawing_sheets
from ..exporters.fabrication_files import write_fabrication, write_rigid_files
from ..exporters.gltf import scene_glb, write_scenes
from ..exporters.manifest import manifest_dict
from ..exporters.manifest_file import as_written, write_manifest
from ..exporters.mold_files import molds_manifest, write_mold_files
from ..exporters.render import render_previews
from ..exporters.report import report_pictures, write_report
from ..exporters.reproducible import make_reproducible
from ..exporters.robot_files import write_robot
from ..exporters.robot_meshes import write_robot_meshes
from ..exporters.viewer import write_viewer
from ..parameters.load import params_sha256
from ..simulation.sim import protocol_radius_mm
from .analyses import Analyses
from .cache import OWNER_FILE, copy_tree
from .processes.checks_process import finish_checks, start_checks
from .processes.worker import SecondProcess
from .publish import (
    BuildResult,
    OpenedBuild,
    open_build,
    publish,
    reuse_whole,
    temporary_folder,
    volatile,
)
from .quadruped import quadruped_section
from .runner import Runner, Stage

Progress = Callable[[str], None]


#: What each cached stage does not read (``table`` or ``table.key``); everything else of the
#: parameters is part of its key. The part files are geometry (the assembly STEP is named after the
#: tail): no material property, no physics.
PART_FILES_IGNORE = (
    "materials",
    "use",
    "vertebra.material",
    "actuation",
    "analysis",
    "robot",
    "casting",
    "fabrication_package",
    "pneumatics",
    "cart",
    "calibration",
)
#: The analyses read the whole tail but for the robot description, the molds and the fabrication
#: package (of which only the tube lengths, for the supply model); the name decides whether the
#: calibration's measurements are this tail's.
ANALYSES_IGNORE = ("robot", "casting", "fabrication_package")
#: The geometry analyses (joint limits, the tip's clearance map:
#: :func:`bvsr_cad.analysis.run.geometry_analyses`) read the tail's solids and placements (the part
#: files' inputs, not the tail's name), the SOAs' fold stack (``soa``, in them) and the required
#: clearance (``analysis.min_clearance_mm``, in the key beside them).
ANALYSIS_GEOMETRY_IGNORE = PART_FILES_IGNORE + ("name",)
#: The drawings' views and hole tables are the panels' and the mold set's geometry: the part files'
#: inputs and the molds' (``casting``); the title block (tail name, materials, processes, the params
#: SHA-256) is stamped at every build, outside the cache.
DRAWINGS_IGNORE = tuple(k for k in PART_FILES_IGNORE if k != "casting") + ("name",)
#: The rigid twin's pieces and files are the part files' geometry and the printer volume it is split
#: for (``fabrication_package``); its pieces are named by joint, not after the tail. (The mold set's
#: key is its arguments, :func:`bvsr_cad.assembly.products.mold_set_inputs`.)
TWIN_IGNORE = tuple(k for k in PART_FILES_IGNORE if k != "fabrication_package") + ("name",)
#: The robot's meshes and its collision shapes' fits are the tail's solids and placements (named by
#: part and joint, not after the tail) and which collision shapes ``robot.collision_geometry`` asks
#: for (:func:`robot_geometry_key`); no mass, limit or actuator of the robot table.
ROBOT_GEOMETRY_IGNORE = PART_FILES_IGNORE + ("name",)


def _rod(spec) -> dict:
    """A rod material of "none" removes the rod part: the one material fact the geometry reads."""
    return {"rod": spec.vertebra.has_rod}


# The stages, in the order of the build: each names what it reads, and its cache key is made of that
# (bvsr_cad.pipeline.runner). Stages without a key run at every build.
GEOMETRY_ANALYSES = Stage(
    "analysis geometry (joint limits, clearance map)",
    "analysis_geometry",
    ANALYSIS_GEOMETRY_IGNORE,
    lambda spec: {**_rod(spec), "min_clearance_mm": spec.analysis.min_clearance_mm},
)
ANALYSES = Stage(
    "analyses",
    "analyses",
    ANALYSES_IGNORE,
    data=True,
    derived=lambda spec: {
        "tubes": (
            spec.fabrication_package.tube_lead_mm,
            spec.fabrication_package.tube_bend_allowance,
        )
    },
)
ASSEMBLY = Stage("assembly")
PART_FILES = Stage("part files", "part_files", PART_FILES_IGNORE, _rod)
MOLDS = Stage(
    "molds", "molds", derived=lambda spec: {"inputs": mold_set_inputs(spec)}, say="SOA mold set"
)
RIGID_TWIN = Stage("rigid twin", "rigid_twin", TWIN_IGNORE, say="rigid comparison tail")
FABRICATION = Stage("print jobs, BOM")
ROBOT_GEOMETRY = Stage(
    "robot meshes, collision fits",
    "robot_geometry",
    ROBOT_GEOMETRY_IGNORE,
    lambda spec: {**_rod(spec), "collision_geometry": spec.robot.collision_geometry},
)
DRAWINGS = Stage("drawings", "drawings", DRAWINGS_IGNORE, say="drawings (SVG sheets)")
VIEW = Stage("interactive 3D view", say="interactive 3D view")
PREVIEWS = Stage(
    "previews", "previews", PART_FILES_IGNORE, _rod, say="previews (off-screen renders)"
)
ROBOT_FILES = Stage("analysis files and robot descriptions")
QUADRUPED = Stage("quadruped scene and experiments", say="quadruped scene")
CHECKS = Stage("checks", say="checks")
REPORT = Stage("report", say="report")


def robot_geometry_key(spec) -> str:
    """The cache key of the robot's meshes and collision fits (:data:`ROBOT_GEOMETRY_IGNORE`)."""
    return ROBOT_GEOMETRY.key_for(spec)


def build_export(
    params: str | Path,
    out_dir: str | Path | None = None,
    progress: Progress | None = None,
    use_cache: bool = True,
    standby: SecondProcess | None = None,
    on_assembly: Callable[[Assembly], None] | None = None,
) -> BuildResult:
    """Build every part of the tail described by ``params`` into ``out_dir``.

    With ``use_cache`` the stages whose inputs are unchanged are taken from the artifact cache
    (:mod:`bvsr_cad.pipeline.cache`): the whole export, the analyses, the parts' files and previews.
    ``standby``: the analyses' second process started ahead
    (``SecondProcess.standby("bvsr_cad.pipeline.processes.analyses_process")``, as the command line
    does before it imports this module, so that the two import side by side), given its work here if
    the analyses are to be run, else stopped. ``on_assembly``: called with the tail's assembly as
    soon as it is built, before the rest of the export (``bvsr watch --show``); an export the cache
    holds whole is published first, then its assembly built for it.

    Args:
        params: the parameter file.
        out_dir: the export folder (None: ``exports/<name>``), replaced only when the build
            succeeds.
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


def build_opened(
    opened: OpenedBuild,
    standby: SecondProcess | None = None,
    on_assembly: Callable[[Assembly], None] | None = None,
) -> BuildResult:
    """Build, stage by stage, the export that :func:`bvsr_cad.pipeline.publish.open_build` prepared
    and the cache does not hold whole (:func:`bvsr_cad.pipeline.publish.reuse_whole`). ``standby``,
    ``on_assembly``: as in :func:`build_export`; the caller closes ``standby``. The analyses run
    beside the CAD stages in a second process; what reads only the CAD files (the checks of the
    meshes, the molds and the print files, the robot's files once the joint limits exist) starts
    before they are in.

    Raises:
        GeometryError: the CAD kernel failed.
    """
    run = Runner(opened.spec, opened.data, opened.cache, temporary_folder(opened.out), opened.log)
    build = _Build(opened, run)
    try:
        build.cad_files(standby, on_assembly)
        build.start_checks()
        pictures = build.views()
        verdicts = build.finish(pictures)
        _publish(opened, run, build.manifest)
    except BaseException:
        for running in (build.analyses, build.checks):
            if running is not None:
                running.close()
        shutil.rmtree(run.folder, ignore_errors=True)
        raise
    finally:
        if build.analyses is not None:
            build.analyses.restore()
    return BuildResult(
        opened.out,
        verdicts,
        time.perf_counter() - opened.t0,
        run.log.stages,
        build.manifest["volatile"]["cpu_seconds"],
    )


class _Build:
    """One build's phases in their order, and what they hand on: the CAD files (the analyses
    started beside them), the checks of those files started, the drawings and views, then the
    analyses' results, the robot's and analyses' files, the checks' verdicts and the report. The
    analyses and the checks are attributes from their start, so that a failure closes them."""

    def __init__(self, opened: OpenedBuild, run: Runner):
        self.opened, self.run = opened, run
        self.spec, self.params = opened.spec, opened.params
        self.analyses: Analyses | None = None
        self.checks: Checks | None = None
        self.fits: dict[str, CylinderFit] = {}  # the collision shapes' fits: robot geometry's
        self.robot: dict | None = None  # the robot files' manifest entries, once written
        self.fixed: set[Path] = set()  # the files whose time stamps are fixed

    def cad_files(
        self, standby: SecondProcess | None, on_assembly: Callable[[Assembly], None] | None
    ) -> None:
        """The analyses started, the assembly, its parts' files and collision fits, the manifest
        so far, the molds, the rigid twin and the print jobs with the BOM."""
        spec, run = self.spec, self.run
        run.say(
            f"building {spec.name}: {spec.segments} segments, {spec.joints} joints, {spec.panels} "
            "panels"
        )
        self.analyses = Analyses.begin(run, ANALYSES, GEOMETRY_ANALYSES, self.params, standby)
        asm = self.asm = run.run(ASSEMBLY, lambda _f: build_assembly(spec, run.say))
        if on_assembly is not None:
            on_assembly(asm)
        files = {
            name: {"step": f"step/{name}.step", "stl": f"stl/{name}.stl"} for name in asm.parts
        }
        geometry_cached = run.hit(PART_FILES) is not None or run.hit(ROBOT_GEOMETRY) is not None
        run.run(PART_FILES, lambda folder: _part_files(asm, files, folder, run.say))
        with run.timed(ROBOT_GEOMETRY):
            if not geometry_cached:  # on the print STLs' triangulation, while the solids hold it
                collision_shapes(asm, self.fits)
        shutil.copyfile(self.params, run.folder / "params.toml")
        manifest = self.manifest = manifest_dict(
            asm, params_sha256(self.params), files, "step/assembly.step"
        )
        manifest["previews"] = {}  # rendered once the checks of the print files have started
        self.mold_set, mold_entries, self.mold_view = run.run(
            MOLDS, lambda folder: _molds(asm, folder, run.say)
        )
        pieces, visual, self.twin_view, twin_props = run.run(
            RIGID_TWIN, lambda folder: _rigid_twin(asm, folder)
        )
        manifest.update(
            run.run(
                FABRICATION,
                lambda folder: _fabrication(
                    asm,
                    files,
                    molds_manifest(spec, self.mold_set, *mold_entries),
                    pieces,
                    visual,
                    twin_props,
                    manifest,
                    self.mold_set,
                    folder,
                    run,
                ),
            )
        )

    def start_checks(self) -> None:
        """The robot's files if the joint limits are in already, then the checks of the files so
        far, as published (fixed time stamps), started beside the rest of the build."""
        run = self.run
        limits = self.analyses.limits_ahead()
        with run.timed(ROBOT_FILES):
            if limits is not None:
                self.robot = _robot_files(run, self.asm, limits, self.fits)
        with run.timed(CHECKS):
            make_reproducible(run.folder, self.fixed)
            run.say("checks of the CAD files")
            self.checks = start_checks(
                run.folder,
                run.say,
                cache=self.opened.cache,
                meshes_beside=True,
                robot_beside=self.robot is not None,
                manifest=as_written({**self.manifest, **(self.robot or {})}),
            )

    def views(self) -> dict:
        """The drawings (stamped with this build), the interactive 3D view, the previews and the
        report's pictures, which it returns."""
        run, asm, manifest = self.run, self.asm, self.manifest
        run.run(DRAWINGS, lambda folder: _drawings(asm, self.mold_set, folder))
        manifest.update(stamp_drawings(run.folder, asm, self.mold_set, params_sha256(self.params)))
        manifest.update(
            run.run(
                VIEW, lambda folder: _view(asm, self.mold_view, self.twin_view, folder, run.say)
            )
        )
        manifest["previews"] = run.run(PREVIEWS, lambda folder: render_previews(asm, folder))
        with run.timed(REPORT):
            run.say("report pictures")
            return report_pictures(run.folder, manifest, run.memo)

    def finish(self, pictures: dict) -> list:
        """The analyses' results, their files and the robot's, the checks' verdicts and the report;
        returns the verdicts."""
        run, asm, manifest = self.run, self.asm, self.manifest
        self.robot = _robot_before_wait(
            run, asm, self.analyses, self.checks, manifest, self.robot, self.fits
        )
        results, drawn = self.analyses.results(
            lambda geometry: run_analyses(
                asm, run.say, str(self.params), protocol_radius_mm, geometry
            )
        )
        robot = self.robot
        manifest.update(
            run.run(
                ROBOT_FILES,
                lambda folder: {
                    **write_analyses(results, folder, self.spec.name, pictures=not drawn),
                    **(
                        robot
                        if robot is not None
                        else _robot_files(run, asm, results.theta_max_per_joint(), self.fits)
                    ),
                },
            )
        )
        manifest.update(
            run.run(
                QUADRUPED,
                lambda folder: quadruped_section(
                    folder, folder / manifest["robot"]["mjcf_mount_model"], self.spec, run.say
                ),
            )
        )
        # STEP and 3MF time stamps of the files written since the checks started
        make_reproducible(run.folder, self.fixed)
        verdicts = run.run(
            CHECKS,
            lambda _f: finish_checks(self.checks, self.opened.cache, as_written(manifest)),
        )
        run.log.process("checks", self.checks.cpu_s)
        manifest["checks"] = [r.to_json() for r in verdicts]
        manifest.update(
            run.run(REPORT, lambda folder: write_report(folder, manifest, run.memo, pictures))
        )
        return verdicts


def _publish(opened: OpenedBuild, run: Runner, manifest: dict) -> None:
    """The manifest with this build's volatile section, the whole export into the cache (for a
    rebuild of the same file) and the export moved into place."""
    manifest["volatile"] = volatile(opened.t0, run.log)
    write_manifest(run.folder, manifest)
    if opened.cache is not None:
        opened.cache.put(
            opened.export_key, lambda folder: copy_tree(run.folder, folder, skip=(OWNER_FILE,))
        )
    publish(run.folder, opened.out)


def _part_files(
    asm: Assembly, files: dict[str, dict[str, str]], folder: Path, say: Progress
) -> None:
    """The parts' STEP and STL and the assembly STEP."""
    (folder / "step").mkdir()
    (folder / "stl").mkdir()
    for name, part in asm.parts.items():
        say(f"export {name} (STEP, STL)")
        write_part_step(part, folder / files[name]["step"])
        write_part_stl(part, folder / files[name]["stl"])
    say("export assembly STEP")
    write_assembly_step(asm, folder / "step" / "assembly.step")


def _molds(asm: Assembly, folder: Path, say: Progress) -> tuple:
    """The SOA's mold set, its files' entries and its viewer scene."""
    made = build_mold_set(asm)
    entries = write_mold_files(made, folder, say)
    # Its viewer scene now: the mold STLs' triangulation is what the scene shows (OCCT keeps the
    # finest).
    return made, entries, mold_scene(made)


def _rigid_twin(asm: Assembly, folder: Path) -> tuple:
    """The rigid twin's pieces, their visual meshes (metres, tail frame), its viewer scene and the
    pieces' mass properties."""
    made = build_rigid_twin(asm)
    visual = write_rigid_files(made, folder)
    arrays = [(m.vertices.view(np.ndarray), m.faces.view(np.ndarray)) for m in visual]
    # The 3D view shows the twin's visual meshes rather than meshing it again. Measured on the
    # solids made here: OCCT's integrals of a B-rep read back differ in the last bit.
    return (
        made,
        arrays,
        twin_scene(made, [(units.m_to_mm(v), f) for v, f in arrays]),
        [SolidProperties.of(p.solid) for p in made],
    )


def _fabrication(
    asm: Assembly,
    files: dict,
    molds: dict,
    pieces: list,
    visual: list,
    twin_props: list,
    manifest: dict,
    mold_set,
    folder: Path,
    run: Runner,
) -> dict:
    """The rigid twin's robot description, the print jobs and the BOM; the manifest's mold and
    fabrication sections (the twin's parts join the manifest's ``parts``)."""
    mold_files = {e["name"]: e["files"] for e in molds["molds"]["parts"]}
    fabrication = write_fabrication(
        asm,
        pieces,
        rigid_robot_model(asm, pieces, twin_props),
        [trimesh.Trimesh(v, f, process=False) for v, f in visual],
        mold_set,
        files,
        mold_files,
        folder,
        run.say,
        run.memo,
    )
    manifest["parts"] += fabrication.pop("rigid_parts")
    return {**molds, **fabrication}


def _robot_files(
    run: Runner, asm: Assembly, theta_max_rad: list[float], fits: dict[str, CylinderFit]
) -> dict:
    """The robot descriptions for these joint limits. Their meshes and collision fits read the
    geometry alone (and which shapes: ``robot.collision_geometry``): one cached stage, so that an
    edit that moves no solid (a material, the robot's limits) neither meshes a part nor fits one.
    Both mesh the panels and the SOA at the print STLs' tolerances with an absolute deflection: the
    same triangulation whichever stages ran before (tests/test_robot.py)."""
    made = {}

    def make(folder: Path) -> tuple:
        run.say("robot meshes and collision fits")
        made["robot"] = robot_model(asm, theta_max_rad, shapes=collision_shapes(asm, fits))
        return dict(fits), write_robot_meshes(made["robot"], folder / "robot" / "meshes")

    kept, mesh_files = run.run(ROBOT_GEOMETRY, make)
    run.say("robot model (B-rep inertials)")
    robot = (
        made["robot"]
        if "robot" in made
        else robot_model(asm, theta_max_rad, shapes=collision_shapes(asm, kept))
    )
    return write_robot(robot, run.folder, run.say, asm.spec.cart, mesh_files)


def _robot_before_wait(
    run: Runner,
    asm: Assembly,
    analyses: Analyses,
    checks: Checks,
    manifest: dict,
    robot: dict | None,
    fits: dict[str, CylinderFit],
) -> dict | None:
    """Before the wait for the analyses: the robot's files if the joint limits have come since the
    checks started (else the collision fits now, what needs no limits, and the files after the
    analyses), and their checks here unless the checks' process has begun them (whichever process is
    free first)."""
    late = robot is None
    if late:
        with run.timed(ROBOT_FILES):
            limits = analyses.limits_ahead()
            if limits is None:
                if run.hit(ROBOT_GEOMETRY) is None:
                    collision_shapes(asm, fits)
                return None
            robot = _robot_files(run, asm, limits, fits)
    with run.timed(CHECKS):
        checks.robot_ahead(as_written({**manifest, **robot}))
    return robot


def _drawings(asm: Assembly, mold_set, folder: Path) -> None:
    """The drawing sheets' views and hole tables (their title blocks are stamped at every build)."""
    write_drawing_sheets(asm, mold_set, folder)


def _view(asm: Assembly, mold_view, twin_view, folder: Path, say: Progress) -> dict:
    """The interactive 3D view: the scenes' GLB files and the viewer page."""
    scenes = viewer_scenes(asm, mold_view, twin_view, progress=say)
    glb = {s.name: scene_glb(s) for s in scenes}
    entries = write_scenes(folder, scenes, glb)
    return {**entries, **write_viewer(folder, entries["scenes"]["files"], glb)}
