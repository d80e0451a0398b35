"""`bvsr build` and `bvsr check` end to end: manifest, checks, atomic publish."""

from __future__ import annotations

import contextlib
import hashlib
import json
import resource
import shutil
from pathlib import Path

import numpy as np
import pytest
import trimesh

from bvsr_cad import cli
from bvsr_cad.assembly.assemble import build_assembly
from bvsr_cad.cli import main
from bvsr_cad.parameters import paper
from bvsr_cad.process import build_processes

from .conftest import PARAMS, write_toml

pytestmark = pytest.mark.slow


def _tree_digest(root: Path) -> str:
    h = hashlib.sha256()
    for p in sorted(root.rglob("*")):
        h.update(str(p.relative_to(root)).encode())
        if p.is_file():
            h.update(p.read_bytes())
    return h.hexdigest()


def test_manifest_round_trips(bvsr_export, bvsr_spec):
    m = json.loads((bvsr_export / "manifest.json").read_text())
    assert m["name"] == "bvsr" and m["version"] == "0.1.0"
    assert m["params_sha256"] == hashlib.sha256((PARAMS / "bvsr.toml").read_bytes()).hexdigest()
    assert (bvsr_export / m["params_file"]).read_bytes() == (PARAMS / "bvsr.toml").read_bytes()
    asm = build_assembly(bvsr_spec)
    # The rigid comparison tail's pieces are listed too (kind rigid_tail); they are not part of the
    # BVSR.
    tail_parts = [p for p in m["parts"] if p["kind"] != "rigid_tail"]
    by_name = {p["name"]: p for p in tail_parts}
    assert set(by_name) == set(asm.parts)
    for name, part in by_name.items():
        for rel in part["files"].values():
            assert (bvsr_export / rel).is_file(), rel
        assert part["count"] == len(part["instances"]) == len(asm.instances_of(name))
        assert part["mass_g"] == pytest.approx(asm.mass_g(name), rel=1e-9)
    assert by_name["soa"]["count"] == 30
    # Tail mass = sum of instance masses; segments (shared panel split) add up to it.
    assert m["mass_g"]["tail"] == pytest.approx(
        sum(p["count"] * p["mass_g"] for p in tail_parts), rel=1e-12
    )
    assert sum(m["mass_g"]["segments"]) == pytest.approx(m["mass_g"]["tail"], rel=1e-12)
    # Standalone segment 1: panels 0-3, 15 SOAs, rod_s1.
    standalone = (
        sum(by_name[f"panel{k}"]["mass_g"] for k in range(4))
        + 15 * by_name["soa"]["mass_g"]
        + by_name["rod_s1"]["mass_g"]
    )
    assert m["mass_g"]["segment_standalone"] == pytest.approx(standalone, rel=1e-12)
    # Measured length equals Table I's N H_a + (N + 1) t.
    assert m["length_mm"] == pytest.approx(6 * 36.51 + 7 * (42.51 - 36.51), abs=1e-6)
    assert all(c["passed"] is not False for c in m["checks"])


def test_default_segment_within_ten_percent_of_paper(bvsr_export):
    m = json.loads((bvsr_export / "manifest.json").read_text())
    ref = paper.SEGMENT_STANDALONE_MASS.value
    assert abs(m["mass_g"]["segment_standalone"] - ref) <= paper.SEGMENT_MASS_TOLERANCE * ref


def test_print_stls_lie_on_the_bed(bvsr_export):
    m = json.loads((bvsr_export / "manifest.json").read_text())
    for part in m["parts"]:
        mesh = trimesh.load(bvsr_export / part["files"]["stl"])
        assert mesh.bounds[0][2] == pytest.approx(0.0, abs=1e-9), part["name"]


def test_assembly_step_names_every_instance(bvsr_export):
    text = (bvsr_export / "step" / "assembly.step").read_text(errors="replace")
    m = json.loads((bvsr_export / "manifest.json").read_text())
    for inst in m["assembly"]["instances"]:
        assert f"'{inst['name']}'" in text, inst["name"]
    assert "COLOUR_RGB" in text
    assert "SI_UNIT(.MILLI.,.METRE.)" in text


def test_check_json_passes(bvsr_export, capsys):
    assert main(["check", str(bvsr_export), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["passed"] is True
    names = {c["name"] for c in out["checks"]}
    assert {
        "stl_watertight:soa",
        "mass_parts_sum_to_tail",
        "pentagon_spacing:panel1:upper",
        "paper:segment_standalone_mass",
    } <= names
    info = [c for c in out["checks"] if c["name"].startswith("paper:")]
    assert info and all(c["passed"] is None for c in info)
    for c in out["checks"]:
        assert set(c) >= {"name", "passed", "value", "limit", "unit", "where"}


def test_check_fails_on_a_broken_stl(bvsr_export, tmp_path, capsys):
    broken = tmp_path / "broken"
    shutil.copytree(bvsr_export, broken)
    mesh = trimesh.load(broken / "stl" / "soa.stl")
    mesh.update_faces(np.arange(len(mesh.faces)) % 50 != 0)  # punch holes
    mesh.export(broken / "stl" / "soa.stl")
    assert main(["check", str(broken), "--json"]) == 1
    out = json.loads(capsys.readouterr().out)
    failed = {c["name"] for c in out["checks"] if c["passed"] is False}
    assert "stl_watertight:soa" in failed and "stl_volume:soa" in failed
    # The summary without --json: the failing group, and each failure in full.
    assert main(["check", str(broken), "-q"]) == 1
    lines = capsys.readouterr().out.splitlines()
    assert any(line.startswith("FAIL  stl ") for line in lines)
    assert any(line.startswith("FAIL  stl_watertight:soa: ") for line in lines)


@pytest.mark.second_processes
def test_checks_started_early_see_a_file_changed_before_they_finish(small_export, tmp_path):
    """A build runs the CAD files' checks before its analyses are in (Checks.start) and the rest
    after (Checks.finish): a file changed in between is checked again, so the verdicts are those of
    the final export, the same as one run of every check."""
    from bvsr_cad.pipeline.processes.checks_process import run_checks, start_checks

    copy = tmp_path / "copy"
    shutil.copytree(small_export, copy)
    checks = start_checks(copy, parallel=False)
    mesh = trimesh.load(copy / "stl" / "soa.stl")
    mesh.update_faces(np.arange(len(mesh.faces)) % 50 != 0)  # punch holes after the start
    mesh.export(copy / "stl" / "soa.stl")
    late = checks.finish()
    assert {"stl_watertight:soa", "stl_volume:soa"} <= {r.name for r in late if r.passed is False}
    assert [r.to_json() for r in late] == [r.to_json() for r in run_checks(copy, parallel=False)]


@pytest.mark.second_processes
def test_part_mesh_checks_beside_run_in_the_second_process_and_see_a_file_changed(
    small_export, small_verdicts, tmp_path
):
    """A build sends the part meshes' and the masses' checks to the printability process too
    (``meshes_beside``): unchanged, their verdicts come from there (none of them runs here); a
    part's STL changed after that process read it is checked again here, and the results are one
    run of every check's."""
    import time

    from bvsr_cad.pipeline.processes.checks_process import run_checks, start_checks

    if build_processes() < 2:
        pytest.skip("one core: the checks never leave the process")
    said: list[str] = []
    checks = start_checks(small_export, said.append, meshes_beside=True)
    assert checks._printability.proc is not None and not any(m.startswith("mesh ") for m in said)
    kept = checks.finish()
    assert not any(m.startswith("mesh ") or m == "masses" for m in said), said
    assert json.dumps([r.to_json() for r in kept]) == small_verdicts
    copy = tmp_path / "copy"
    shutil.copytree(small_export, copy)
    said.clear()
    checks = start_checks(copy, said.append, meshes_beside=True)
    while checks._printability.proc.running:  # until the second process has read every mesh
        time.sleep(0.1)
    mesh = trimesh.load(copy / "stl" / "soa.stl")
    mesh.update_faces(np.arange(len(mesh.faces)) % 50 != 0)  # punch holes after it read them
    mesh.export(copy / "stl" / "soa.stl")
    late = checks.finish()
    assert "mesh soa" in said and "mesh panel0" not in said
    assert {"stl_watertight:soa", "stl_volume:soa"} <= {r.name for r in late if r.passed is False}
    assert [r.to_json() for r in late] == [r.to_json() for r in run_checks(copy, parallel=False)]


@pytest.mark.second_processes
def test_mold_checks_in_the_second_process_see_a_mold_file_changed_before_they_finish(
    small_export, tmp_path
):
    """The mold checks run in the printability process from Checks.start; a mold file changed before
    Checks.finish (whether that process had read it yet or not) is checked again, on the file as it
    is."""

    from bvsr_cad.checks.export import Export
    from bvsr_cad.checks.molds import check_molds
    from bvsr_cad.pipeline.processes.checks_process import start_checks

    if build_processes() < 2:
        pytest.skip("one core: the mold checks never leave the process")
    copy = tmp_path / "copy"
    shutil.copytree(small_export, copy)
    said: list[str] = []
    checks = start_checks(copy, said.append)
    assert checks._printability.proc is not None
    half = copy / "molds" / "assembled" / "half_a.stl"
    mesh = trimesh.load(half)
    mesh.apply_translation(-3.0 * mesh.centroid / np.linalg.norm(mesh.centroid))  # into the cavity
    mesh.export(half)
    late = checks.finish()
    molds = check_molds(Export.open(copy))
    names = {r.name for r in molds}
    assert "mold_intrusion" in {r.name for r in molds if r.passed is False}
    assert [r.to_json() for r in late if r.name in names] == [r.to_json() for r in molds]
    # Unchanged, the mold verdicts are the second process's.
    said.clear()
    checks = start_checks(small_export, said.append)
    kept = checks.finish()
    assert any(m.startswith("printability and molds: done in the second process") for m in said), (
        said
    )
    assert "molds" not in said
    assert {r.name for r in kept} >= names


@pytest.mark.second_processes
def test_checks_handed_the_manifest_need_no_manifest_file(small_export, small_verdicts, tmp_path):
    """A build hands its checks the manifest as its file will hold it and writes the file once, at
    the end: checks started, given the robot's and finished on a folder without manifest.json, the
    manifest handed to both processes, give the verdicts of one run of every check on the published
    export (which reads its file)."""

    from bvsr_cad.pipeline.processes.checks_process import finish_checks, start_checks

    copy = tmp_path / "copy"
    shutil.copytree(small_export, copy)
    manifest = json.loads((copy / "manifest.json").read_text())
    (copy / "manifest.json").unlink()
    said: list[str] = []
    checks = start_checks(
        copy, said.append, meshes_beside=True, robot_beside=True, manifest=manifest
    )
    checks.robot_ahead(manifest)
    got = finish_checks(checks, None, manifest)
    if build_processes() >= 2:
        assert any(m.startswith("printability and molds: done in the second process") for m in said)
    assert not (copy / "manifest.json").exists()
    assert json.dumps([r.to_json() for r in got]) == small_verdicts


def test_check_moved_pocket_fails_the_pentagon(bvsr_export, tmp_path, capsys):
    moved = tmp_path / "moved"
    shutil.copytree(bvsr_export, moved)
    m = json.loads((moved / "manifest.json").read_text())
    part = next(p for p in m["parts"] if p["name"] == "panel1")
    mesh = trimesh.load(moved / part["files"]["stl"])
    mesh.apply_transform(trimesh.transformations.rotation_matrix(np.radians(2.0), [0, 0, 1]))
    mesh.export(moved / part["files"]["stl"])
    assert main(["check", str(moved), "--json"]) == 1
    failed = {
        c["name"] for c in json.loads(capsys.readouterr().out)["checks"] if c["passed"] is False
    }
    assert (
        "pentagon_soa1_dorsal:panel1:upper" in failed
        and "pentagon_mirror_yz:panel1:lower" in failed
    )


def test_check_bad_folder_exit_2(tmp_path, capsys):
    assert main(["check", str(tmp_path)]) == 2
    assert "no manifest.json" in capsys.readouterr().err


def test_failed_build_leaves_earlier_export_untouched(bvsr_export, tmp_path, data, monkeypatch):
    out = tmp_path / "exports" / "bvsr"
    shutil.copytree(bvsr_export, out)
    before = _tree_digest(out)
    # Bad parameters: exit 2, nothing written.
    data["joint"]["pitch_diameter_mm"] = 40.0
    assert main(["build", str(write_toml(tmp_path / "bad.toml", data)), "-o", str(out), "-q"]) == 2
    assert _tree_digest(out) == before
    # A failure half-way through writing: the earlier export survives, no temp folder is left.
    import bvsr_cad.pipeline.stages as stages

    calls = {"n": 0}
    real = stages.write_part_stl

    def flaky(part, path):
        calls["n"] += 1
        if calls["n"] == 3:
            raise OSError("disk full (simulated)")
        real(part, path)

    monkeypatch.setattr(stages, "write_part_stl", flaky)
    with pytest.raises(OSError, match="simulated"):
        stages.build_export(PARAMS / "bvsr.toml", out, use_cache=False)
    assert _tree_digest(out) == before
    assert sorted(p.name for p in out.parent.iterdir()) == ["bvsr"]


def test_build_refuses_to_replace_a_foreign_folder(tmp_path, capsys):
    foreign = tmp_path / "mine"
    foreign.mkdir()
    (foreign / "thesis.tex").write_text("precious")
    assert main(["build", str(PARAMS / "bvsr.toml"), "-o", str(foreign), "-q"]) == 2
    assert (foreign / "thesis.tex").read_text() == "precious"
    assert "refusing" in capsys.readouterr().err


@pytest.mark.second_processes
def test_second_process_errors_come_back_and_a_lost_one_is_replaced(tmp_path, monkeypatch):
    from bvsr_cad.parameters.load import ParamError
    from bvsr_cad.pipeline.processes import worker

    changed = write_toml(tmp_path / "edited.toml", {"name": "edited"})
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = worker.SecondProcess.start(
        "bvsr_cad.pipeline.processes.analyses_process",
        [str(changed), "sha256 of what the build read"],
        tmp_path,
    )
    if proc is None:
        pytest.skip("one core: the analyses never leave the process")
    assert proc.cpu_s is None
    # The child's exception is raised here, as it was raised there.
    with pytest.raises(ParamError, match=r"edited.toml(.|\n)*changed while the build was running"):
        proc.result()
    assert not proc.running
    # With the CPU seconds it used (its imports of the pipeline), as the kernel counted them but for
    # its last steps (pickling the answer, leaving).
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    counted = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    assert counted > 0.5 and counted - 0.2 <= proc.cpu_s <= counted, (proc.cpu_s, counted)
    # A process that dies without a result: the work runs here instead.
    monkeypatch.setattr(worker.sys, "executable", shutil.which("false") or "/bin/false")
    lost = worker.SecondProcess.start("bvsr_cad.pipeline.processes.analyses_process", [], tmp_path)
    said: list[str] = []
    assert worker.result_or(
        lost, lambda: {"analysis": "computed here"}, said.append, "analyses"
    ) == {"analysis": "computed here"}
    assert any("without a result; running them here" in m for m in said), said
    assert lost.cpu_s is None


@pytest.mark.second_processes
def test_a_standby_second_process_takes_its_work_or_leaves(tmp_path, monkeypatch):
    """`bvsr build` starts the analyses' process before it imports the pipeline: given its work it
    answers as a process started with it (even from a working folder that is gone); closed without
    work it exits; once gone it takes none."""
    from bvsr_cad.parameters.load import ParamError
    from bvsr_cad.pipeline.processes import worker

    changed = write_toml(tmp_path / "edited.toml", {"name": "edited"})
    gone = tmp_path / "gone"
    gone.mkdir()
    monkeypatch.chdir(gone)
    gone.rmdir()
    standby = worker.SecondProcess.standby("bvsr_cad.pipeline.processes.analyses_process")
    if standby is None:
        pytest.skip("one core: the analyses never leave the process")
    assert standby.begin([str(changed), "sha256 of what the build read"], tmp_path)
    with pytest.raises(ParamError, match=r"edited.toml(.|\n)*changed while the build was running"):
        standby.result()
    # A relative working folder is this process's, not the child's (`bvsr build -o exports/x` names
    # the build's temporary folder relative to where the user stands; the child started in /tmp).
    here = tmp_path / "here"
    (here / "exports").mkdir(parents=True)
    monkeypatch.chdir(here)
    relative = worker.SecondProcess.standby("bvsr_cad.pipeline.processes.analyses_process")
    assert relative.begin([str(changed), "sha256 of what the build read"], Path("exports"))
    with pytest.raises(ParamError, match=r"edited.toml(.|\n)*changed while the build was running"):
        relative.result()
    idle = worker.SecondProcess.standby("bvsr_cad.pipeline.processes.analyses_process")
    idle.proc.stdin.close()  # no work: it imports, reads the end of its input and exits quietly
    assert idle.proc.wait(timeout=300) == 0
    assert not idle.begin([str(changed), "x"], tmp_path)  # gone: the build starts another
    idle.close()
    assert idle.proc is None


@pytest.mark.second_processes
def test_the_standby_head_start_is_used_only_for_the_bytes_it_was_built_from(tmp_path, monkeypatch):
    """`bvsr build` names the file to its standby analyses' process, which builds the assembly while
    the build reads its cache; the work that comes uses it only if it names the same file with the
    same SHA-256, else it builds the file as it is now."""
    from bvsr_cad.analysis import run
    from bvsr_cad.parameters.load import params_sha256
    from bvsr_cad.pipeline.processes import analyses_process

    params = tmp_path / "tail.toml"
    shutil.copyfile(PARAMS / "bvsr.toml", params)
    monkeypatch.setattr(
        run, "run_analyses", lambda asm, *_a, **_k: asm
    )  # the analyses' input, handed back
    monkeypatch.setattr(analyses_process, "_PREPARED", {})
    analyses_process._prepare_analyses(str(params))
    first = params_sha256(params)
    prepared = analyses_process._PREPARED[str(params.resolve()), first]
    used, drawn = analyses_process._analyses_process(str(params), first)
    assert used is prepared and not drawn  # used, and taken (used once); no pictures asked for
    assert analyses_process._PREPARED == {}
    analyses_process._prepare_analyses(str(params))
    params.write_text(params.read_text().replace('name = "bvsr"', 'name = "edited"', 1))
    built, _drawn = analyses_process._analyses_process(str(params), params_sha256(params))
    assert (
        built.spec.name == "edited"
        and built is not analyses_process._PREPARED[str(params.resolve()), first]
    )


@pytest.mark.second_processes
def test_the_analyses_process_leaves_the_joint_limits_before_its_other_analyses(
    tmp_path, monkeypatch
):
    """The analyses' process puts its geometry analyses (the joint limits) into the build's folder
    as soon as it has them, whole (never a half-written file under the name the build reads), before
    its other analyses: the build writes and checks the robot files while those go on. The build
    takes the file once (:func:`~bvsr_cad.pipeline.processes.analyses_process.take_geometry_ahead`
    removes it)."""
    from bvsr_cad.analysis import run
    from bvsr_cad.analysis.limits import per_joint_rad
    from bvsr_cad.parameters.load import load_spec, params_sha256
    from bvsr_cad.pipeline.processes import analyses_process

    class Reached(Exception):
        pass

    seen: list = []

    def workspace(*_args, **_kw):  # the first analysis after the geometry's
        seen.append(sorted(p.name for p in tmp_path.iterdir()))
        seen.append(analyses_process.take_geometry_ahead(tmp_path))
        raise Reached

    monkeypatch.setattr(run, "run_workspace", workspace)
    monkeypatch.setattr(
        run, "compare_measurements", lambda *_a, **_k: None
    )  # the measurements' thread
    params = PARAMS / "bvsr.toml"
    with pytest.raises(Reached):
        analyses_process._analyses_process(
            str(params), params_sha256(params), "", "", str(tmp_path), "bvsr"
        )
    names, geo = seen
    # Beside it the rest geometry (for the build's cache), and no part file left beside either.
    assert names == sorted([analyses_process.GEOMETRY_AHEAD_FILE, analyses_process.REST_AHEAD_FILE])
    assert isinstance(geo, run.GeometryAnalyses)
    assert [p.name for p in tmp_path.iterdir()] == [analyses_process.REST_AHEAD_FILE]
    limits = per_joint_rad(geo.limits)
    assert len(limits) == load_spec(params).joints and all(
        0 < t <= run.THETA_SEARCH_MAX_RAD for t in limits
    )
    assert analyses_process.take_geometry_ahead(tmp_path) is None  # taken once
    # The build moves the rest geometry into its cache entry of the geometry analyses; the next
    # build's analyses read it from there: the posed tail and every part's mass properties.
    entry = tmp_path / "entry"
    entry.mkdir()
    analyses_process.keep_rest(tmp_path, entry)
    rest = analyses_process.read_rest(str(entry / "geometry.pkl"))
    assert [p.name for p in entry.iterdir()] == [analyses_process.REST_FILE]
    assert len(rest.posed.pairs) == len(rest.posed.rest_mm) > 0 and rest.posed.rest_bvh == {}
    assert sorted(rest.properties) == sorted(build_assembly(load_spec(params), solids=False).parts)
    analyses_process.drop_geometry_ahead(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["entry"]


def test_the_export_holds_the_robot_files_made_with_the_analyses_joint_limits(bvsr_export):
    """The build writes the robot files with the joint limits the analyses' process left ahead; they
    are the limits of the export's analysis (the minimum over each joint's bending planes), and the
    file they came in is not published."""
    from bvsr_cad.pipeline.processes.analyses_process import GEOMETRY_AHEAD_FILE

    manifest = json.loads((bvsr_export / "manifest.json").read_text())
    analysis = json.loads((bvsr_export / "analysis" / "limits.json").read_text())
    assert [b["theta_max_rad"] for b in manifest["robot"]["bending_joints"]] == [
        min(j["theta_max_rad"]) for j in analysis["joints"]
    ]
    assert not (bvsr_export / GEOMETRY_AHEAD_FILE).exists()
    assert not list(bvsr_export.rglob(GEOMETRY_AHEAD_FILE + "*"))


@pytest.mark.second_processes
def test_the_robot_checks_run_once_in_whichever_process_claims_them(bvsr_export, tmp_path):
    """The build's robot checks come in two parts, each to whichever of its processes is free first
    (the checks' process, given them at its start, or the build's own, at its wait for the
    analyses): the first to claim a part takes it and no later one does. The export holds every
    robot check once, in the order and with the verdicts of the checks run in one go, and no
    claim."""
    from bvsr_cad.checks.export import Export
    from bvsr_cad.checks.robot import ROBOT_PARTS, check_robot
    from bvsr_cad.checks.run import ROBOT_CLAIM_FILES, claim_robot_checks

    assert len(ROBOT_PARTS) == len(ROBOT_CLAIM_FILES) == 2
    for part in range(len(ROBOT_PARTS)):
        assert claim_robot_checks(tmp_path, part) and not claim_robot_checks(tmp_path, part)
        assert not claim_robot_checks(str(tmp_path), part)
    manifest = json.loads((bvsr_export / "manifest.json").read_text())
    names = [c["name"] for c in manifest["checks"]]
    assert len(names) == len(set(names))
    alone = check_robot(Export.open(bvsr_export))
    robot = {r.name for r in alone}
    assert len(alone) > 50 and len(robot) == len(alone)
    assert [(c["name"], c["passed"]) for c in manifest["checks"] if c["name"] in robot] == [
        (r.name, r.passed) for r in alone
    ]
    assert not any((bvsr_export / claim).exists() for claim in ROBOT_CLAIM_FILES)


@pytest.mark.second_processes
def test_the_analyses_process_is_told_where_to_draw_as_an_absolute_folder(tmp_path, monkeypatch):
    """The analyses' process draws their pictures into the build's temporary folder, working in
    another folder than the build's: a build into a relative output folder (``make exports``: ``-o
    exports/bvsr``) names it by its absolute path (a relative one made the process fail: the folder
    was not found)."""
    from bvsr_cad.pipeline import stages
    from bvsr_cad.pipeline.processes import worker

    class Reached(Exception):
        pass

    given: list[list[str]] = []

    def start(cls, module, args, *_rest, **_kw):
        given.append([module, *args])
        return None

    def first_stage(*_args, **_kw):
        raise Reached

    monkeypatch.setattr(worker.SecondProcess, "start", classmethod(start))
    monkeypatch.setattr(stages, "build_assembly", first_stage)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(Reached):
        stages.build_export(PARAMS / "bvsr.toml", Path("exports") / "bvsr", use_cache=False)
    ((module, *_rest, pictures, name),) = given
    assert module == "bvsr_cad.pipeline.processes.analyses_process" and name == "bvsr"
    assert Path(pictures).is_absolute() and Path(pictures).parent == tmp_path / "exports"
    assert Path(pictures).name.startswith(".bvsr.tmp-")


@pytest.mark.second_processes
@pytest.mark.parametrize("during", ["a command", "a C extension's import"])
def test_ctrl_c_exits_130_with_one_line_not_a_traceback(monkeypatch, capsys, during):
    """Ctrl-C during OCP's import reaches Python as ``ImportError: initialization failed`` raised
    from the KeyboardInterrupt (pybind11); unless treated as an interrupt it would end in exit code
    1 and a second ImportError's traceback (the error classes import OCP again). Both forms are an
    interrupt."""

    def interrupted(args):
        if during == "a command":
            raise KeyboardInterrupt
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as exc:
            raise ImportError("initialization failed") from exc

    monkeypatch.setattr(cli, "cmd_build", interrupted)
    monkeypatch.setattr(
        cli,
        "_bad_input_message",
        lambda *a: pytest.fail("an interrupt is not an error to classify"),
    )
    assert cli.main(["build", "params/bvsr.toml"]) == 130
    assert capsys.readouterr().err == "bvsr: interrupted; nothing was published\n"


#: The ``read`` system call's number, by machine (what ``/proc/PID/syscall`` shows for a process
#: waiting on it).
_READ_SYSCALL = {"x86_64": "0", "aarch64": "63"}


def _reads_stdin(pid: int) -> bool | None:
    """Whether the process is blocked reading its standard input (its main thread in ``read(0,
    ...)``); None where ``/proc/PID/syscall`` cannot tell (another system, another machine)."""
    import platform

    try:
        fields = Path(f"/proc/{pid}/syscall").read_text().split()
    except OSError:
        return None
    number = _READ_SYSCALL.get(platform.machine())
    if number is None or not fields:
        return None
    return fields[:2] == [number, "0x0"]


@contextlib.contextmanager
def _sigint_reaches_children():
    """Children started in the block get SIGINT's default action whatever this process has: a runner
    that ignores it (a background job of a shell script, nohup: how CI was run here) hands SIG_IGN
    on to every child, and an ignored Ctrl-C stops nothing (as it should: ``nohup bvsr build &`` is
    not to be interrupted)."""
    import signal

    before = signal.signal(
        signal.SIGINT, signal.default_int_handler
    )  # handled here: default after exec
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


@pytest.mark.second_processes
def test_ctrl_c_leaves_a_waiting_standby_process_quietly(tmp_path):
    """Ctrl-C reaches the standby analyses process too (same process group): it leaves with 130 and
    no KeyboardInterrupt traceback (from its wait on stdin) among the build's lines. Under a
    background job the child would inherit an ignored SIGINT, so it is given the default
    (:func:`_sigint_reaches_children`). It waits until the child is blocked on its stdin, not until
    its CPU time stands still for a second (which a process waiting for a core shows too)."""
    import signal
    import time

    from bvsr_cad.pipeline.processes import worker

    lines: list[str] = []
    with _sigint_reaches_children():
        standby = worker.SecondProcess.standby(
            "bvsr_cad.pipeline.processes.analyses_process", progress=lines.append
        )
    if standby is None:
        pytest.skip("one core: the analyses never leave the process")
    pid, last, still = standby.proc.pid, None, 0
    deadline = time.time() + 300
    while time.time() < deadline:
        time.sleep(0.1)
        waiting = _reads_stdin(pid)
        if waiting is None:  # no /proc/PID/syscall: its CPU time stands still (less sure)
            fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
            now = int(fields[11]) + int(fields[12])
            still, last = (still + 1 if now == last else 0), now
            waiting = still >= 10
        if waiting:
            break
    assert standby.running, lines
    standby.proc.send_signal(signal.SIGINT)
    assert standby.proc.wait(timeout=60) == 130
    time.sleep(0.5)  # the relay thread's last lines
    assert not any("Traceback" in line or "KeyboardInterrupt" in line for line in lines), lines
    standby.close()


def test_an_interrupt_is_held_through_imports_that_catch_base_exception():
    """trimesh's optional imports catch ``BaseException``: a Ctrl-C landing in one was swallowed and
    ``bvsr build`` ran on. :func:`~bvsr_cad.process.interrupts_held` delivers it when
    the block ends."""
    import os
    import signal
    import threading

    from bvsr_cad.process import interrupts_held

    def optional_import() -> (
        bool
    ):  # trimesh's pattern (trimesh/grouping.py): True when it swallowed one
        try:
            os.kill(os.getpid(), signal.SIGINT)
            for _ in range(1000):  # the handler runs between bytecodes
                pass
        except BaseException:  # noqa: BLE001
            return True
        return False

    assert threading.current_thread() is threading.main_thread()
    before = signal.signal(
        signal.SIGINT, signal.default_int_handler
    )  # pytest-xdist's worker may have its own
    try:
        assert optional_import()  # the premise: unheld, the interrupt is lost in the library
        swallowed = None
        with pytest.raises(KeyboardInterrupt):
            with interrupts_held():
                swallowed = optional_import()
        assert swallowed is False
        assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
        with interrupts_held():  # no interrupt: nothing raised
            pass
        with pytest.raises(
            KeyboardInterrupt
        ) as info:  # an interrupt wins over the block's own error
            with interrupts_held():
                optional_import()
                raise ImportError("a library's import failed after the Ctrl-C")
        assert isinstance(info.value.__context__, ImportError)
        with pytest.raises(ImportError):  # without one, the block's error as it was
            with interrupts_held():
                raise ImportError("a library's import failed")
    finally:
        signal.signal(signal.SIGINT, before)


#: When the Ctrl-C comes, in seconds after the command started: through the command's and its
#: second process's imports (about 1 s on a quiet machine, several on a loaded one) into the first
#: stages. From 0.1 s: the interpreter's own start before any code of bvsr_cad runs (site's imports,
#: 10 to 20 ms at load 1.5 here; a Ctrl-C there prints Python's traceback, as for any Python
#: program) is left out with a margin of five times that.
INTERRUPT_AFTER_S = (0.1, 0.15, 0.2, 0.3, 0.5, 0.7, 1.0, 1.2, 1.6, 2.2, 3.0, 4.5)


def _bvsr_command() -> list[str]:
    import sys

    bvsr = Path(sys.executable).with_name("bvsr")
    return [str(bvsr)] if bvsr.exists() else [sys.executable, "-m", "bvsr_cad.cli"]


def _helpers_of(pid: int) -> list[int]:
    """The live processes a build with PID ``pid`` started (its second processes and theirs): they
    carry its PID in their environment (bvsr_cad.pipeline.processes.worker.PARENT_PID_ENV); they run
    in process groups of their own."""
    from bvsr_cad.pipeline.processes.worker import PARENT_PID_ENV

    mark = f"{PARENT_PID_ENV}={pid}".encode()
    found = []
    for proc in Path("/proc").glob("[0-9]*"):
        try:
            if mark in (proc / "environ").read_bytes().split(b"\0"):
                state = (proc / "stat").read_text().rsplit(")", 1)[1].split()[0]
                if state != "Z":  # a zombie has ended; its parent has not collected it yet
                    found.append(int(proc.name))
        except OSError:  # ended meanwhile, or not ours
            pass
    return found


def _interrupted_build(out: Path, cache: Path, after_s: float) -> str:
    """``bvsr build`` of the default tail into ``out``, sent Ctrl-C (SIGINT to its process group, as
    a terminal sends it) ``after_s`` seconds after it started; what went wrong, or "" if it stopped
    quietly: exit status 130 as a shell reports it, one line on stderr, nothing published, no
    process of it left."""
    import os
    import signal
    import subprocess
    import time

    env = {**os.environ, "BVSR_CACHE": str(cache)}  # a cold cache: the pipeline is imported
    with _sigint_reaches_children():
        build = subprocess.Popen(
            [*_bvsr_command(), "build", str(PARAMS / "bvsr.toml"), "-o", str(out)],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
            start_new_session=True,
        )
    try:
        time.sleep(after_s)
        os.killpg(build.pid, signal.SIGINT)
        _, err = build.communicate(timeout=120)
    finally:
        if build.poll() is None:
            os.killpg(build.pid, signal.SIGKILL)
    where = f"Ctrl-C after {after_s} s: "
    # -SIGINT: killed by it before the interpreter installed its handler (the first milliseconds),
    # which a shell reports as 130 too, and silently
    if build.returncode not in (130, -signal.SIGINT):
        return f"{where}exit status {build.returncode}\n{err}"
    lines = err.rstrip().splitlines()
    if build.returncode == 130 and lines[-1:] != ["bvsr: interrupted; nothing was published"]:
        return f"{where}last line not the interrupt's\n{err}"
    if any(word in err for word in ("Traceback", "KeyboardInterrupt", "Error")):
        return f"{where}a traceback or an error\n{err}"
    if out.exists():
        return f"{where}{out} was published"
    deadline = time.time() + 10  # SIGTERM'd helpers end within this, on a loaded machine
    while _helpers_of(build.pid) and time.time() < deadline:
        time.sleep(0.1)
    if _helpers_of(build.pid):
        return f"{where}a helper process outlived the interrupted build"
    return ""


@pytest.mark.second_processes
@pytest.mark.slow
def test_ctrl_c_at_any_instant_of_a_loaded_build_stops_it_quietly(tmp_path):
    """Ctrl-C early in ``bvsr build``, at a spread of instants (:data:`INTERRUPT_AFTER_S`), while
    the command and its second process start and import their libraries (trimesh's optional
    imports catch ``BaseException``, so an interrupt there would be swallowed, or print the second
    process's traceback), with a BVSR_L build beside it keeping both cores busy (under load a
    second process still importing ``bvsr_cad`` printed a traceback). Each ends with exit status
    130, one line, nothing published and no process left."""
    import os
    import signal
    import subprocess

    load = subprocess.Popen(
        [*_bvsr_command(), "build", str(PARAMS / "bvsr_l.toml"), "-o", str(tmp_path / "load")]
        + ["--no-cache", "-q"],
        env={**os.environ, "BVSR_CACHE": str(tmp_path / "load-cache")},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )
    try:
        faults = [
            _interrupted_build(tmp_path / f"exp-{i}", tmp_path / f"cache-{i}", after_s)
            for i, after_s in enumerate(INTERRUPT_AFTER_S)
        ]
        assert load.poll() is None, "the load ended before the last interrupt: lengthen it"
    finally:
        os.killpg(load.pid, signal.SIGKILL)
        load.wait()
        for pid in _helpers_of(load.pid):
            os.kill(pid, signal.SIGKILL)
    assert not [f for f in faults if f], "\n\n".join(f for f in faults if f)
