"""`bvsr build`: parameters -> assembly -> files -> checks, published atomically.

Everything is written into a temporary folder beside the output and moved
into place only when every file was written; a failure (bad parameters, a
kernel error, a full disk, Ctrl-C) leaves any earlier export untouched and no
partial one.
"""

from __future__ import annotations

import shutil
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from .analysis.run import run_analyses
from .assembly.build import build_assembly
from .assembly.products import build_mold_set, build_rigid_twin, rigid_robot_model
from .assembly.robot import robot_model
from .checks.result import CheckResult
from .checks.run import run_checks
from .exporters.analysis_files import write_analyses
from .exporters.cad import write_assembly_step, write_part_step, write_part_stl
from .exporters.manifest import manifest_dict, write_manifest
from .exporters.mold_files import write_molds
from .exporters.fabrication_files import write_fabrication
from .exporters.render import render_previews
from .exporters.report import write_report
from .exporters.robot_files import write_robot
from .parameters.load import load_spec, params_sha256
from .worker import SecondProcess, result_or

Progress = Callable[[str], None]


class OutputError(ValueError):
    """The output path cannot take an export (exit code 2)."""


@dataclass
class BuildResult:
    out_dir: Path
    results: list[CheckResult]
    seconds: float


def _check_output(out_dir: Path) -> None:
    if out_dir.exists():
        if not out_dir.is_dir():
            raise OutputError(f"{out_dir}: exists and is not a folder; choose another -o")
        if any(out_dir.iterdir()) and not (out_dir / "manifest.json").is_file():
            raise OutputError(f"{out_dir}: a non-empty folder that is not a bvsr export (no manifest.json); "
                              "refusing to replace it; choose another -o")


def _publish(tmp: Path, out_dir: Path) -> None:
    old = None
    if out_dir.exists():
        old = out_dir.with_name(f".{out_dir.name}.old-{int(time.time() * 1000)}")
        out_dir.rename(old)
    try:
        tmp.rename(out_dir)
    except BaseException:
        if old is not None:
            old.rename(out_dir)
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def build_export(params: str | Path, out_dir: str | Path | None = None,
                 progress: Progress | None = None) -> BuildResult:
    """Build every part of the tail described by ``params`` into ``out_dir``.

    Raises:
        ParamError: the parameter file is unreadable or describes an impossible tail.
        OutputError: ``out_dir`` cannot be replaced.
        GeometryError: the CAD kernel failed.
    """
    say = progress or (lambda _m: None)
    t0 = time.perf_counter()
    params = Path(params)
    spec = load_spec(params)
    out = Path(out_dir) if out_dir is not None else Path("exports") / spec.name
    _check_output(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    say(f"building {spec.name}: {spec.segments} segments, {spec.joints} joints, {spec.panels} panels")
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.tmp-", dir=out.parent))
    analyses = None
    try:
        # The analyses (workspace, clearance, limits) need only the parameters: a second process
        # runs them from the file while this one builds, exports and fabricates.
        analyses = SecondProcess.start("bvsr_cad.analysis.run", [str(params.resolve()), params_sha256(params)],
                                       tmp, say)
        if analyses is not None:
            say("analyses: started in a second process")
        asm = build_assembly(spec, say)
        (tmp / "step").mkdir()
        (tmp / "stl").mkdir()
        files: dict[str, dict[str, str]] = {}
        for name, part in asm.parts.items():
            say(f"export {name} (STEP, STL)")
            files[name] = {"step": f"step/{name}.step", "stl": f"stl/{name}.stl"}
            write_part_step(part, tmp / files[name]["step"])
            write_part_stl(part, tmp / files[name]["stl"])
        say("export assembly STEP")
        write_assembly_step(asm, tmp / "step" / "assembly.step")
        shutil.copyfile(params, tmp / "params.toml")
        manifest = manifest_dict(asm, params_sha256(params), files, "step/assembly.step")
        say("previews (off-screen renders)")
        manifest["previews"] = render_previews(asm, tmp)
        say("SOA mold set")
        mold_set = build_mold_set(asm)
        molds = write_molds(asm, mold_set, tmp, say)
        say("rigid comparison tail")
        pieces = build_rigid_twin(asm)
        mold_files = {e["name"]: e["files"] for e in molds["molds"]["parts"]}
        fabrication = write_fabrication(asm, pieces, rigid_robot_model(asm, pieces), mold_set, files, mold_files,
                                        tmp, say)
        manifest["parts"] += fabrication.pop("rigid_parts")
        results = result_or(analyses, lambda: run_analyses(asm, say, str(params)), say, "analyses")
        manifest.update(write_analyses(results, tmp, spec.name))
        say("robot model (B-rep inertials)")
        robot = robot_model(asm, results.theta_max_per_joint())
        manifest.update(write_robot(robot, tmp, say, spec.cart))
        manifest.update(molds)
        manifest.update(fabrication)
        write_manifest(tmp, manifest)
        say("checks")
        results = run_checks(tmp, say)
        manifest["checks"] = [r.to_json() for r in results]
        say("report")
        manifest.update(write_report(tmp, manifest))
        manifest["build_seconds"] = time.perf_counter() - t0
        write_manifest(tmp, manifest)
        _publish(tmp, out)
    except BaseException:
        if analyses is not None:
            analyses.close()
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return BuildResult(out, results, time.perf_counter() - t0)
