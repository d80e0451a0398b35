"""The fabrication package: rigid twin, print files, 3MF, BOM, printability, report.

Uses the session's default export (``bvsr_export`` in conftest: one full build).
"""

from __future__ import annotations

import csv
import json
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest
import trimesh

from bvsr_cad.checks import printability, slicer
from bvsr_cad.checks.export import Export
from bvsr_cad.checks.printability import (
    _SurfaceIndex,
    check_envelope,
    min_hole_mm,
    overhang_regions,
)
from bvsr_cad.checks.slicer import SLICER, check_slicing, slice_items, slice_stls
from bvsr_cad.cli import main
from bvsr_cad.pipeline.cache import ArtifactCache
from bvsr_cad.pipeline.processes.checks_process import run_checks
from bvsr_cad.process import build_processes


@pytest.fixture(scope="module")
def manifest(bvsr_export) -> dict:
    return json.loads((bvsr_export / "manifest.json").read_text())


def _checks(manifest: dict, prefix: str) -> list[dict]:
    return [c for c in manifest["checks"] if c["name"].startswith(prefix)]


def test_rigid_pieces_one_per_joint_and_fit_the_printer(manifest, bvsr_export):
    pieces = [p for p in manifest["parts"] if p["kind"] == "rigid_tail"]
    assert [p["name"] for p in pieces] == [
        f"rigid_j{k}" for k in range(1, manifest["joints"] + 1)
    ] + ["rigid_tip"]
    vx, vy, vz = manifest["rigid_tail"]["printer_volume_mm"]
    assert (vx, vy, vz) == (250.0, 210.0, 210.0)
    for p in pieces:
        assert p["process"] == "FDM" and p["material"] == "PLA" and p["count"] == 1
        lo, hi = trimesh.load(bvsr_export / p["files"]["stl"]).bounds
        x, y, z = hi - lo
        assert z <= vz and ((x <= vx and y <= vy) or (x <= vy and y <= vx)), p["name"]
        assert abs(lo[2]) < 1e-6


def test_rigid_pieces_stack_to_the_tail_length(manifest):
    pieces = [p for p in manifest["parts"] if p["kind"] == "rigid_tail"]
    top = max(p["tail_transform"][2][3] + p["info"]["size_mm"][2] for p in pieces)
    assert top == pytest.approx(
        6 * 36.51 + 7 * (42.51 - 36.51), abs=1e-6
    )  # Table I: N H_a + (N + 1) t


def test_rigid_envelope_equals_bvsr_at_rest(bvsr_export, manifest):
    tol = manifest["rigid_tail"]["envelope_tolerance_mm"]
    results = check_envelope(Export.open(bvsr_export), samples=3000, seed=7)
    assert len(results) == 2
    for r in results:
        assert r.passed and r.value <= tol, r.line()


def test_rigid_pieces_need_no_support(manifest):
    over = _checks(manifest, "print_overhang:FDM_PLA/rigid")
    assert len(over) == manifest["joints"] + 1
    assert all(c["passed"] is True and c["value"] == 0 for c in over)


def test_overhang_map_finds_a_flat_ceiling():
    # A table: a 40 x 40 top on one 5 x 5 leg; the top's underside needs support, 35 mm > 10 mm
    # bridge.
    leg = trimesh.creation.box((5, 5, 20))
    leg.apply_translation((0, 0, 10))
    top = trimesh.creation.box((40, 40, 3))
    top.apply_translation((0, 0, 21.5))
    regions = overhang_regions(trimesh.boolean.union([leg, top], engine="manifold"), 45.0)
    widest = max(r["width_mm"] for r in regions)
    assert widest == pytest.approx(40.0, abs=0.01)
    assert max(r["area_mm2"] for r in regions) == pytest.approx(40 * 40 - 25, abs=0.01)


def test_print_jobs_lie_on_the_bed_with_quantities(manifest, bvsr_export):
    jobs = {j["name"]: j for j in manifest["print_jobs"]}
    assert set(jobs) == {"MJF_PA12", "FDM_PLA", "FDM_PVA"}
    counts = {p["name"]: p["count"] for p in manifest["parts"]}
    soa = counts["soa"]
    for j in jobs.values():
        for it in j["items"]:
            mesh = trimesh.load(bvsr_export / it["stl"])
            assert abs(mesh.bounds[0][2]) < 1e-6, it["stl"]
            if it["part"] in counts:
                assert it["quantity"] == counts[it["part"]]
    assert sum(it["quantity"] for it in jobs["MJF_PA12"]["items"]) == manifest["panels"]
    assert jobs["FDM_PVA"]["items"][0]["quantity"] == soa == 5 * manifest["joints"]


def test_3mf_round_trips_with_names_and_millimetres(manifest, bvsr_export):
    for job in manifest["print_jobs"]:
        path = bvsr_export / job["files"]["3mf"]
        with zipfile.ZipFile(path) as z:
            model = z.read("3D/3dmodel.model").decode()
        assert 'unit="millimeter"' in model
        scene = trimesh.load(path, file_type="3mf")
        names = {it["part"] for it in job["items"]}
        assert set(scene.geometry) == names
        for it in job["items"]:
            stl = trimesh.load(bvsr_export / it["stl"])
            assert scene.geometry[it["part"]].volume == pytest.approx(stl.volume, rel=1e-6)


def test_bom_counts_equal_the_assembly(manifest, bvsr_export):
    rows = list(csv.DictReader((bvsr_export / "bom.csv").open()))
    by_item = {r["item"]: r for r in rows}
    for p in manifest["parts"]:
        assert float(by_item[p["name"]]["quantity"]) == p["count"], p["name"]
    assert float(by_item["soa"]["quantity"]) == 30
    assert (
        sum(float(r["quantity"]) for r in rows if r["item"].startswith("panel"))
        == manifest["panels"]
        == 7
    )
    assert float(by_item["solenoid valve"]["quantity"]) == 20  # 2 per line, 10 lines
    assert float(by_item["dowel pin"]["quantity"]) == 5 * manifest["joints"]
    tubes = [r for r in rows if r["item"].startswith("tube s")]
    assert len(tubes) == 5 * manifest["segments"]
    total = next(r for r in rows if r["category"] == "total" and r["item"] == "tube")
    assert float(total["quantity"]) == pytest.approx(
        sum(float(r["quantity"]) for r in tubes), abs=0.1
    )
    modelled = next(r for r in rows if r["item"] == "BVSR modelled mass")
    assert float(modelled["mass_total_g"]) == pytest.approx(manifest["mass_g"]["tail"], abs=0.01)
    assert (bvsr_export / "bom.md").read_text().count("| qty |") >= 3


def test_segment_two_tubes_reach_the_boundary_port(manifest, bvsr_export):
    from bvsr_cad.assembly.assemble import build_assembly
    from bvsr_cad.assembly.pneumatic_lines import tube_routes_mm
    from bvsr_cad.parameters.load import load_spec

    spec = load_spec(bvsr_export / "params.toml")
    routes = tube_routes_mm(build_assembly(spec))
    t = spec.joint.panel_thickness_mm
    port_z = spec.joints_per_segment * spec.joint.joint_height_mm + spec.tubes.port_depth_mm
    for i in range(1, 6):
        assert routes[f"s1_line{i}"] == 0.0
        # Straight along z at rest, plus the small radial step of the taper.
        assert routes[f"s2_line{i}"] == pytest.approx(port_z, abs=0.05)
    assert t > 0


def test_printability_and_slicing_pass(manifest):
    prints = _checks(manifest, "print_")
    n_stl = sum(len(j["items"]) for j in manifest["print_jobs"])
    assert len(_checks(manifest, "print_fits_volume:")) == n_stl
    assert all(c["passed"] is not False for c in prints)
    slices = _checks(manifest, "slice:")
    assert len(slices) == n_stl
    # The build never slices: each STL reports its cached result or that it was not sliced.
    for c in slices:
        assert c["passed"] is True or (c["passed"] is None and "--slice" in c["note"]), c


def _no_slicer_started(monkeypatch) -> None:
    def refuse(*_a, **_k):
        raise AssertionError("the checks started the slicer")

    monkeypatch.setattr(slicer, "_slice", refuse)
    monkeypatch.setattr(slicer, "_slicer_version", refuse)
    monkeypatch.setattr(slicer.subprocess, "run", refuse)


def test_slicing_not_in_the_cache_is_null_with_the_command(
    bvsr_export, manifest, monkeypatch, tmp_path
):
    monkeypatch.setenv("BVSR_CACHE", str(tmp_path / "empty_cache"))
    _no_slicer_started(monkeypatch)
    results = check_slicing(Export.open(bvsr_export))
    assert len(results) == sum(len(j["items"]) for j in manifest["print_jobs"])
    for r in results:
        assert r.name.startswith("slice:") and r.passed is None and r.value is None, r.line()
        assert "bvsr check EXPORT --slice" in r.note, (
            r.note
        )  # the same in every folder (reused builds)
        assert "not sliced in the build" in r.note or "not installed" in r.note


def test_slice_one_stl_as_check_slice_does(bvsr_export, monkeypatch, tmp_path):
    if shutil.which(SLICER) is None:
        pytest.skip(f"{SLICER} is not installed (apt-get install prusa-slicer)")
    monkeypatch.setenv("BVSR_CACHE", str(tmp_path / "cache"))
    exp = Export.open(bvsr_export)
    core = [it for it in slice_items(exp) if it.name == "FDM_PVA/mold_core"]
    assert len(core) == 1
    said: list[str] = []
    done = slice_stls(
        exp, core, progress=said.append
    )  # what `bvsr check --slice` runs, on one small STL
    assert done["FDM_PVA/mold_core"]["ok"] is True and done["FDM_PVA/mold_core"]["layers"] > 0, done
    assert any(m.startswith("slice 1/1 print/FDM_PVA/mold_core.stl: ok, ") for m in said), said
    (now,) = check_slicing(exp, core, sliced_now=done)
    assert now.passed is True and "sliced now" in now.note, now.line()
    # Later checks (a build, `bvsr check`) find it in the cache without starting the slicer.
    _no_slicer_started(monkeypatch)
    by_name = {r.name: r for r in check_slicing(exp)}
    cached = by_name["slice:FDM_PVA/mold_core"]
    assert cached.passed is True and "cached result of" in cached.note, cached.line()
    layers = int(cached.note.split(": ")[1].split(" layers")[0])
    assert layers == done["FDM_PVA/mold_core"]["layers"] > 0
    assert all(r.passed is None for n, r in by_name.items() if n != "slice:FDM_PVA/mold_core")


def test_check_slice_without_the_slicer_exits_2(bvsr_export, monkeypatch, tmp_path, capsys):
    monkeypatch.setenv("PATH", str(tmp_path))  # no prusa-slicer on it
    monkeypatch.setenv("BVSR_CACHE", str(tmp_path / "cache"))
    assert main(["check", str(bvsr_export), "--slice", "-q"]) == 2
    err = capsys.readouterr().err
    assert (
        "prusa-slicer" in err and "not on PATH" in err and "apt-get install prusa-slicer" in err
    ), err


@pytest.mark.second_processes
def test_printability_in_a_second_process_gives_the_same_results(small_export, small_verdicts):
    said: list[str] = []
    beside = run_checks(small_export, said.append)
    assert json.dumps([r.to_json() for r in beside]) == small_verdicts
    if build_processes() >= 2:
        assert any(
            m.startswith("printability and molds: done in the second process") for m in said
        ), said


def test_a_relative_cache_is_where_the_user_stands_not_in_the_export(
    bvsr_export, monkeypatch, tmp_path
):
    """`BVSR_CACHE=cache bvsr build ...`: the cache is `cache/` where the command runs, for the
    printability process too, which works in the export's folder (handed the path as written, it
    once filed its entries in a `cache/` inside the export)."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("BVSR_CACHE", "relative_cache")
    before = sorted(p.relative_to(bvsr_export) for p in bvsr_export.rglob("*"))
    run_checks(bvsr_export, cache=ArtifactCache())
    assert sorted(p.relative_to(bvsr_export) for p in bvsr_export.rglob("*")) == before
    assert any((tmp_path / "relative_cache" / "artifacts").rglob(".done"))


@pytest.mark.second_processes
def test_a_second_process_in_another_folder_reads_the_slice_cache_the_user_names(
    monkeypatch, tmp_path
):
    """With a relative BVSR_CACHE, a child started in another working folder (as the printability
    process is, in the export's) finds slices.json where the user stands, not under its own
    folder."""
    from bvsr_cad.checks.environment import slice_cache_path
    from bvsr_cad.pipeline.processes.worker import child_env

    (tmp_path / "user").mkdir()
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "user")
    monkeypatch.setenv("BVSR_CACHE", "relative_cache")
    here = slice_cache_path()
    assert here == tmp_path / "user" / "relative_cache" / "slices.json"
    there = subprocess.run(
        [
            sys.executable,
            "-c",
            "from bvsr_cad.checks.environment import slice_cache_path; print(slice_cache_path())",
        ],
        cwd=tmp_path / "elsewhere",
        env=child_env(),
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()
    assert Path(there) == here


@pytest.mark.second_processes
def test_printability_runs_here_when_the_second_process_fails(bvsr_export, monkeypatch):
    from bvsr_cad.checks import run
    from bvsr_cad.pipeline.processes import worker
    from bvsr_cad.pipeline.processes.checks_process import beside

    if build_processes() < 2:
        pytest.skip("one core: the printability checks never leave the process")
    monkeypatch.setattr(
        worker.sys, "executable", shutil.which("false") or "/bin/false"
    )  # exits, no results
    monkeypatch.setattr(
        run, "check_printability", lambda exp, sliced_now=(), memo=None: ["ran here"]
    )
    said: list[str] = []
    checks = run.Checks.start(bvsr_export, said.append, beside=beside(None))
    proc = checks._printability.proc
    assert proc is not None
    results = checks.finish()
    assert results.count("ran here") == 1
    assert any("without a result; running them here" in m for m in said), said
    assert "printability" in said and "molds" in said  # each group it had taken, run here
    assert not proc.running


def test_min_hole_sections_agree_with_trimesh():
    # A plate with a 3 mm and a 5 mm hole along z and a 2.5 mm hole along x.
    plate = trimesh.creation.box((40, 20, 8))
    cut = [
        trimesh.creation.cylinder(1.5, 30, sections=48),
        trimesh.creation.cylinder(2.5, 30, sections=48),
    ]
    cut[0].apply_translation((-10, 0, 0))
    cut[1].apply_translation((10, 0, 0))
    side = trimesh.creation.cylinder(1.25, 60, sections=32)
    side.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [0, 1, 0]))
    side.apply_translation((0, 6, 0))
    mesh = plate.difference(trimesh.util.concatenate(cut + [side]), engine="manifold")
    mesh.apply_translation(-mesh.bounds[0])
    d, where = min_hole_mm(mesh)
    assert d == pytest.approx(2.5 * np.cos(np.pi / 32), abs=0.01) and where.startswith("x = ")
    solid = printability._manifold(mesh)
    assert solid is not None
    heights = np.linspace(0.5, 7.5, 5)
    for axis in range(3):
        fast = printability._section_voids(mesh, solid, axis, heights)
        slow = printability._section_voids(mesh, None, axis, heights)  # trimesh's sections
        for a, b in zip(fast, slow):
            assert sorted(round(v[1], 6) for v in a) == sorted(round(v[1], 6) for v in b)


def test_closest_points_as_trimesh_computes_them():
    mesh = trimesh.creation.annulus(3.0, 8.0, 5.0, sections=40)
    rng = np.random.default_rng(3)
    pts = np.vstack(
        [rng.uniform(-10, 10, (300, 3)), trimesh.sample.sample_surface(mesh, 300, seed=4)[0]]
    )
    index = _SurfaceIndex(mesh)
    _, d, _ = index.closest_point(pts)
    assert np.allclose(d, trimesh.proximity.closest_point(mesh, pts)[1], atol=1e-12)
    assert np.allclose(
        index.signed_distance(pts), trimesh.proximity.signed_distance(mesh, pts), atol=1e-12
    )


def test_rigid_robot_loads_in_mujoco(manifest, bvsr_export):
    mujoco = pytest.importorskip("mujoco")
    rt = manifest["rigid_tail"]
    for key in ("mjcf", "urdf"):
        model = mujoco.MjModel.from_xml_path(str(bvsr_export / rt["robot"][key]))
        assert model.njnt == 0
        assert float(model.body_mass.sum()) == pytest.approx(rt["robot"]["mass_kg"], rel=1e-6)
    solid_g = sum(p["mass_g"] for p in manifest["parts"] if p["kind"] == "rigid_tail")
    assert rt["robot"]["mass_kg"] * 1000 == pytest.approx(solid_g, rel=2e-3)


def test_model_against_measurements(manifest, bvsr_export):
    """The shipped file is calibrated on data/paper_bvsr.csv: the build predicts every row that
    measured the 2-segment tail (all but those naming another segment count, which the note names)
    with the tables' and the fitted values; the SOA stiffness rows are the paper's k = 9.4 P + 2918
    N/m (P in kPa, a closed form); the counts and RMS in the report are those of the rows."""
    import csv

    from .conftest import ROOT

    meas = json.loads((bvsr_export / manifest["analysis"]["measurements"]).read_text())
    with open(ROOT / "data" / "paper_bvsr.csv", newline="") as fh:
        data = [r for r in csv.reader(line for line in fh if not line.startswith("#"))][1:]
    other = [
        n for n, r in enumerate(data, start=2) if "segments=" in r[2] and "segments=2" not in r[2]
    ]
    assert other and [r["row"] for r in meas["rows"]] == [
        n for n in range(2, len(data) + 2) if n not in other
    ]
    assert f"row {other[0]} measured a 3-segment tail" in meas["note"] and len(other) == 1
    for r in meas["rows"]:
        if r["quantity"] == "soa_stiffness":
            p_kpa = float(r["label"].split("pressure_kpa=")[1].rstrip(")"))
            assert r["calibrated"] == pytest.approx(9.4 * p_kpa + 2918, rel=1e-9)
    hold = [r for r in meas["rows"] if r["role"] == "holdout"]
    assert meas["holdout_landed"] == [
        sum(abs(r["rel_calibrated"]) <= 0.30 for r in hold),
        len(hold),
    ]
    assert meas["rms_rel_holdout"] < 0.5 * meas["rms_rel_holdout_uncalibrated"]
    html = (bvsr_export / "report.html").read_text()
    assert "Model against measurements" in html
    assert f"{meas['holdout_landed'][0]} of {meas['holdout_landed'][1]} holdout rows" in html


def test_report_has_its_pictures(manifest, bvsr_export):
    html = (bvsr_export / "report.html").read_text()
    import re

    srcs = re.findall(r'<img src="([^"]+)"', html)
    assert srcs and all((bvsr_export / s).is_file() for s in srcs)
    for part in manifest["parts"]:
        assert (
            f"report/parts/{part['name']}.png" in srcs or f"report/parts/{part['name']}.png" in html
        )
    assert "Against the paper" in html and "not computed here" in html and "678.6" in html
    # The interactive view: its scripts are in the export, nothing is fetched from a network.
    assert (
        "bvsr-viewer" in html
        and "http://" not in html.replace('xmlns="http://', "")
        and "https://" not in html
    )
    assert (bvsr_export / "report" / "viewer.js").is_file() and {
        s["name"] for s in manifest["viewer"]["scenes"]
    } >= {"rest", "extension", "flexion", "waggle", "molds", "rigid_twin"}
    for png in ("analysis/workspace.png", "molds/exploded.png", "analysis/measurements.png"):
        if (bvsr_export / png).is_file():
            assert png in srcs
    assert manifest["report"]["problems"] == []
    # The analyses in words: the certified minimum clearance and a limit per joint, as in the files.
    cl = json.loads((bvsr_export / manifest["analysis"]["clearance"]).read_text())
    assert f"{cl['min_clearance_mm']:.3f} mm between {cl['pair'][0]} and {cl['pair'][1]}" in html
    joints = json.loads((bvsr_export / manifest["analysis"]["limits"]).read_text())["joints"]
    assert all(f"joint {j['joint']}: bending limit" in html for j in joints)
