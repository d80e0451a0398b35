"""`bvsr sweep`: study files, the no-vertebra tail, the rod calibration's carry-over, and studies on
a two-worker Dask LocalCluster (one with a worker killed mid-task; one Optuna search), resumed."""

from __future__ import annotations

import copy
import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BVSR = [sys.executable, "-m", "bvsr_cad.cli"]


def _study(tmp_path: Path, text: str, name: str = "s.toml") -> Path:
    path = tmp_path / name
    path.write_text(f'base = "{ROOT / "params" / "bvsr.toml"}"\n' + text)
    return path


# -- the study file
# ------------------------------------------------------------------------------------


def test_a_bad_study_names_every_key_at_load(tmp_path):
    from bvsr_cad.parameters.study import StudyError, load_study

    path = _study(
        tmp_path,
        'metrics = ["mass"]\nspeed = 3\n[grid]\n"vertebra.materal" = ["nylon"]\n'
        '"lightening.hole_diameter_mm" = []\n[random]\nsamples = 0\n[random.space]\n'
        '"soa.facet_thickness_mm" = { low = 2.0, high = 1.0 }\n',
    )
    with pytest.raises(StudyError) as err:
        load_study(path)
    text = str(err.value)
    assert "speed: unknown key" in text
    assert "'vertebra.materal': not a parameter; did you mean vertebra.material" in text
    assert "grid.lightening.hole_diameter_mm = []" in text
    assert "random.samples = 0" in text
    assert "low = 2.0 must be below high = 1.0" in text


def test_an_unknown_metric_is_a_study_error_and_the_cli_exits_2(tmp_path):
    path = _study(
        tmp_path, 'metrics = ["mass", "stifness"]\n[grid]\n"vertebra.material" = ["nylon"]\n'
    )
    run = subprocess.run(
        [*BVSR, "sweep", str(path), "-o", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=120,
    )
    assert run.returncode == 2, run.stderr
    assert "metrics 'stifness': not a metric" in run.stderr
    assert not (tmp_path / "out" / "results.csv").exists()


def test_variants_grid_listed_and_keys(tmp_path):
    from bvsr_cad.parameters.study import load_study

    path = _study(
        tmp_path,
        'metrics = ["mass"]\nbaseline = true\n[set]\n"fabrication_package.tie_rod_thread" = 2.0\n'
        '[grid]\n"vertebra.material" = ["nylon", "PVC"]\n"vertebra.diameter_mm" = [5.0, 6.0]\n'
        '[[variants]]\nlabel = "no rod"\n"vertebra.material" = "none"\n'
        '[[variants]]\n"vertebra.material" = "nylon"\n"vertebra.diameter_mm" = 6.0\n',
    )
    study = load_study(path)
    variants = study.variants()
    # base, 4 grid points, 2 listed; the grid's nylon 6 mm and the last listed variant are the base
    # itself (with [set]): a variant is its parameters, so each tail runs once, under its first
    # label
    labels = [v.label for v in variants]
    assert labels == [
        "base",
        "vertebra.material=nylon, vertebra.diameter_mm=5",
        "vertebra.material=PVC, vertebra.diameter_mm=5",
        "vertebra.material=PVC, vertebra.diameter_mm=6",
        "no rod",
    ]
    assert len({v.key for v in variants}) == len(variants)
    assert all(v.data["fabrication_package"]["tie_rod_thread"] == 2.0 for v in variants)
    # the data file of the base's calibration is absolute, so a variant means the same file anywhere
    assert Path(variants[0].data["calibration"]["data_file"]).is_absolute()
    assert Path(variants[0].data["calibration"]["data_file"]).exists()


# -- the model side
# ------------------------------------------------------------------------------------


def test_no_vertebra_keeps_the_sockets_and_drops_the_rod(bvsr_data):
    from bvsr_cad.assembly.assemble import build_assembly
    from bvsr_cad.models.rod import rod_section
    from bvsr_cad.parameters.load import ParamError, spec_from_dict

    data = copy.deepcopy(bvsr_data)
    data["vertebra"]["material"] = "none"
    spec = spec_from_dict(data)
    base = spec_from_dict(bvsr_data)
    asm, asm0 = build_assembly(spec), build_assembly(base)
    assert [i.name for i in asm.instances if i.role == "rod"] == []
    assert len(asm.instances) == len(asm0.instances) - spec.segments
    # the panels (with their rod bores) are the same solids
    assert asm.parts["panel0"].solid.volume == pytest.approx(
        asm0.parts["panel0"].solid.volume, rel=1e-12
    )
    rod = rod_section(spec)
    assert rod.flexural_rigidity_n_mm2 == 0.0 and rod.mass_g(100.0) == 0.0
    data["vertebra"]["material"] = "unobtainium"
    with pytest.raises(ParamError, match=r"vertebra.material = 'unobtainium'.*or 'none': no rod"):
        spec_from_dict(data)


def test_a_fitted_rod_stiffness_carries_over_as_its_ratio(bvsr_data):
    from bvsr_cad.models.rod import rod_section
    from bvsr_cad.parameters.load import spec_from_dict

    base = spec_from_dict(bvsr_data)
    fitted = bvsr_data["calibration"]["fitted"]["rod_flexural_rigidity_n_mm2"]
    assert (base.calibration.rod_material, base.calibration.rod_diameter_mm) == ("nylon", 6.0)
    assert (
        rod_section(base).flexural_rigidity_n_mm2 == fitted
    )  # the measured rod: exactly as fitted
    data = copy.deepcopy(bvsr_data)
    data["vertebra"].update(material="PVC", diameter_mm=5.0)
    spec = spec_from_dict(data)
    e = {k: bvsr_data["materials"][k]["youngs_modulus_mpa"] for k in ("nylon", "PVC")}
    expected = fitted * (e["PVC"] * 5.0**4) / (e["nylon"] * 6.0**4)
    assert rod_section(spec).flexural_rigidity_n_mm2 == pytest.approx(expected, rel=1e-12)


def test_lateral_stiffness_rises_with_the_rod_and_the_invertebrate_is_softest(bvsr_data):
    from bvsr_cad.analysis.metrics import model_metrics
    from bvsr_cad.parameters.load import spec_from_dict

    stiff = {}
    for material, d in (("none", 6.0), ("TPU", 6.0), ("nylon", 5.0), ("nylon", 6.0)):
        data = copy.deepcopy(bvsr_data)
        data["vertebra"].update(material=material, diameter_mm=d)
        m = model_metrics(spec_from_dict(data), ["statics"])
        stiff[(material, d)] = m["lateral_stiffness_n_per_mm"]
        assert m["max_angle_extension_deg"] > 0
    order = [stiff[k] for k in (("none", 6.0), ("TPU", 6.0), ("nylon", 5.0), ("nylon", 6.0))]
    assert order == sorted(order) and order[0] > 0


# -- studies on Dask
# -----------------------------------------------------------------------------------


def _variant_processes(study: str) -> list:
    """The processes running a variant of ``study`` (python -m bvsr_cad.studies.sweep - STUDY)."""
    import psutil

    out = []
    for p in psutil.process_iter(["cmdline", "ppid"]):
        cmd = p.info["cmdline"] or []
        if cmd[-3:] == ["bvsr_cad.studies.sweep", "-", study]:
            out.append(p)
    return out


@pytest.mark.slow
def test_a_grid_study_survives_a_killed_worker_and_resumes(tmp_path):
    """Two workers; the worker running the first variant is SIGKILLed mid-task: Dask reruns its
    task, every variant is in the table exactly once, nothing is left running, and a rerun computes
    nothing."""
    import pandas as pd

    path = _study(
        tmp_path,
        'name = "kill"\nmetrics = ["mass"]\nbaseline = false\n[set]\nsegments = 1\n'
        '[grid]\n"vertebra.material" = ["nylon", "none", "PVC"]\n'
        '[[variants]]\nlabel = "impossible"\n"joint.panel_diameter_mm" = 40.0\n',
    )
    out = tmp_path / "out"
    proc = subprocess.Popen(
        [*BVSR, "sweep", str(path), "-o", str(out), "--workers", "2", "--json"],
        cwd=ROOT,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    killed = None
    deadline = time.time() + 240
    while killed is None and time.time() < deadline and proc.poll() is None:
        running = _variant_processes("kill")
        if running:
            victim = running[0].ppid()  # the Dask worker that started the variant's process
            os.kill(victim, signal.SIGKILL)
            killed = victim
        time.sleep(0.2)
    stdout, stderr = proc.communicate(timeout=600)
    assert killed is not None, "no variant process was seen"
    assert proc.returncode == 0, stderr
    summary = json.loads(stdout)
    assert summary["status"] == {"ok": 3, "infeasible": 1, "timeout": 0, "error": 0}
    table = pd.read_parquet(out / "results.parquet")
    assert sorted(table["label"]) == sorted(
        ["vertebra.material=nylon", "vertebra.material=none", "vertebra.material=PVC", "impossible"]
    )
    assert table["key"].is_unique
    csv = pd.read_csv(out / "results.csv")
    assert list(csv["key"]) == list(table["key"])
    journal = [json.loads(line) for line in (out / "results.jsonl").read_text().splitlines()]
    assert sorted(r["key"] for r in journal) == sorted(
        table["key"]
    )  # once each, the killed try left no row
    rows = table.set_index("label")
    assert "joint.panel_diameter_mm = 40.0" in rows.loc["impossible", "reason"]
    assert (
        rows.loc["vertebra.material=none", "mass_g"]
        < rows.loc["vertebra.material=nylon", "mass_g"]
        < rows.loc["vertebra.material=PVC", "mass_g"]
    )  # no rod; nylon 1.14 g/cm3; PVC 1.39 g/cm3
    assert rows.loc["vertebra.material=none", "rod_flexural_rigidity_n_mm2"] == 0.0
    assert (out / "report.html").exists() and (out / "plots" / "mass_g.png").stat().st_size > 1000
    assert not _variant_processes("kill"), "a variant process outlived the study"
    again = subprocess.run(
        [*BVSR, "sweep", str(path), "-o", str(out), "--workers", "1", "--json", "-q"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert again.returncode == 0, again.stderr
    resumed = json.loads(again.stdout)
    assert resumed["reused"] == 4 and resumed["computed"] == 0


@pytest.mark.slow
def test_an_optuna_study_records_trials_and_resumes(tmp_path):
    import optuna
    import pandas as pd
    from optuna.storages import JournalStorage
    from optuna.storages.journal import JournalFileBackend

    path = _study(
        tmp_path,
        'name = "opt"\nmetrics = ["mass"]\n[set]\nsegments = 1\n[optuna]\ntrials = 3\nseed = 3\n'
        'objectives = [{ metric = "mass_g", direction = "minimize" }]\n'
        'constraints = [{ metric = "rod_flexural_rigidity_n_mm2", min = 1.0 }]\n'
        '[optuna.space]\n"vertebra.material" = ["nylon", "none", "TPU"]\n',
    )
    out = tmp_path / "out"
    run = subprocess.run(
        [*BVSR, "sweep", str(path), "-o", str(out), "--workers", "2", "--json", "-q"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert summary["variants"] >= 1 and summary["status"]["error"] == 0
    ost = optuna.load_study(
        study_name="opt", storage=JournalStorage(JournalFileBackend(str(out / "optuna.journal")))
    )
    trials = ost.get_trials(deepcopy=False)
    assert len(trials) == 3
    assert trials[0].params == {"vertebra.material": "nylon"} and trials[0].user_attrs.get(
        "baseline"
    )  # the base
    table = pd.read_parquet(out / "results.parquet")
    assert set(table["trial"]) <= {0, 1, 2} and len(table) == table["key"].nunique()
    # the best feasible trial: the lightest tail that has a rod (the constraint rules the
    # invertebrate out)
    feasible = table[table["rod_flexural_rigidity_n_mm2"] >= 1.0]
    assert summary["best"]["value"] == pytest.approx(feasible["mass_g"].min())
    assert (out / "plots" / "optuna_history.png").exists() and (
        out / "plots" / "pareto_front.png"
    ).exists()
    again = subprocess.run(
        [*BVSR, "sweep", str(path), "-o", str(out), "--workers", "1", "--json", "-q"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert again.returncode == 0, again.stderr
    assert json.loads(again.stdout)["computed"] == 0
    assert (
        len(
            optuna.load_study(
                study_name="opt",
                storage=JournalStorage(JournalFileBackend(str(out / "optuna.journal"))),
            ).get_trials()
        )
        == 3
    )


def test_pareto_mask_closed_form():
    import numpy as np

    from bvsr_cad.exporters.study_report import pareto_mask

    pts = np.array([[1.0, 1.0], [2.0, 3.0], [3.0, 2.0], [2.0, 2.0], [0.5, 0.5]])
    # minimise the first, maximise the second: (0.5,0.5), (1,1), (2,3) are not dominated
    assert pareto_mask(pts, (False, True)).tolist() == [True, True, False, False, True]
    assert math.isclose(pts[pareto_mask(pts, (True, True))][:, 0].max(), 3.0)


@pytest.mark.parametrize("name", ["vertebra", "optimise"])
def test_the_shipped_studies_load_and_every_variant_and_search_bound_is_a_tail(name):
    """The README's `bvsr sweep studies/*.toml`: each shipped study loads against the current
    schema, and every tail it will build loads too (the grid and listed variants; each search
    dimension at its choices or at both ends of its range, the other keys at the base's values)."""
    from bvsr_cad.parameters.layout import key_value
    from bvsr_cad.parameters.load import spec_from_dict
    from bvsr_cad.parameters.study import load_study

    study = load_study(ROOT / "studies" / f"{name}.toml")
    tails = list(study.variants())
    for d in study.space:
        for value in d.choices if d.choices is not None else (d.low, d.high):
            tails.append(study.variant({d.key: value}))
    assert len(tails) >= (13 if name == "vertebra" else 1 + 3 + 2 + 2 + 2)
    for v in tails:
        spec = spec_from_dict(v.data, v.label)
        for key, value in v.overrides.items():
            assert key_value(spec, key) == value, (v.label, key)
