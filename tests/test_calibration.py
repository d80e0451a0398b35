"""`bvsr calibrate`: bad data files exit 2 naming the row and the column; holdout rows never move a
fitted value; fitted values reach the models through their one home."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from bvsr_cad.cli import main

from .conftest import PARAMS

HEADER = "experiment,quantity,conditions,value,unit,role,source\n"
GOOD = "T3,segment_max_angle,motion=extension,51.9,deg,fit,Table III\n"


@pytest.mark.parametrize(
    "row,expected",
    [
        (
            "T3,segment_max_angel,motion=extension,51.9,deg,fit,s\n",
            "row 2, column quantity = 'segment_max_angel'",
        ),
        ("T3,segment_max_angle,motion=extension,51.9,,fit,s\n", "row 2, column unit: missing"),
        (
            "T3,segment_max_angle,motion=extension,fifty,deg,fit,s\n",
            "row 2, column value = 'fifty': not a number",
        ),
        (
            "T3,segment_max_angle,motion=sideways,51.9,deg,fit,s\n",
            "row 2, column conditions: motion = 'sideways'",
        ),
        (
            "T3,segment_max_angle,motion=extension,51.9,deg,maybe,s\n",
            "row 2, column role = 'maybe'",
        ),
        ("T3,segment_max_angle,motion=extension,51.9,rad,fit,s\n", "row 2, column unit = 'rad'"),
        # Conditions a model cannot be asked (a protocol range upside down crashed the analyses).
        (
            "W,tip_workspace_radius,segments=2; pressurised_max_kpa_abs=50; "
            "depressurised_min_kpa_abs=150,100,mm,fit,s\n",
            "row 2, column conditions: depressurised_min_kpa_abs = 150 exceeds "
            "pressurised_max_kpa_abs = 50",
        ),
        (
            "W,tip_workspace_radius,segments=2.5; pressurised_max_kpa_abs=150; "
            "depressurised_min_kpa_abs=50,100,mm,fit,s\n",
            "row 2, column conditions: segments = 2.5; allowed: whole numbers 1 to 3",
        ),
        (
            "P,segment_peak_velocity,motion=extension; pressure_bar=-6,678.6,deg/s,fit,s\n",
            "row 2, column conditions: pressure_bar = -6; allowed: 0.01 to 10",
        ),
    ],
)
def test_bad_data_exits_2_naming_row_and_column(tmp_path, capsys, row, expected):
    data = tmp_path / "bad.csv"
    data.write_text(HEADER + row)
    out = tmp_path / "cal.toml"
    assert main(["calibrate", str(PARAMS / "bvsr.toml"), str(data), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert expected in err and "bad.csv" in err
    assert not out.exists()


def test_no_fit_rows_exits_2(tmp_path, capsys):
    data = tmp_path / "holdout_only.csv"
    data.write_text(HEADER + GOOD.replace(",fit,", ",holdout,"))
    assert main(["calibrate", str(PARAMS / "bvsr.toml"), str(data), "-q"]) == 2
    assert "column role: no row is 'fit'" in capsys.readouterr().err


def test_missing_column_exits_2(tmp_path, capsys):
    data = tmp_path / "no_unit.csv"
    data.write_text(
        "experiment,quantity,conditions,value,role,source\nT3,segment_max_angle,motion=extension,51.9,fit,s\n"
    )
    assert main(["calibrate", str(PARAMS / "bvsr.toml"), str(data), "-q"]) == 2
    assert "row 1 (header): missing column(s) unit" in capsys.readouterr().err


def test_holdout_rows_do_not_move_the_fit(tmp_path, capsys):
    """Two data files that differ only in their holdout rows give the same fitted values to the
    bit."""
    rows = (
        "T3,segment_max_angle,motion=extension,51.9,deg,fit,Table III\n"
        "T3,segment_blocked_force,motion=extension,19.7,N,fit,Table III\n"
    )
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    a.write_text(HEADER + rows + "T3,segment_max_angle,motion=flexion,46.5,deg,holdout,Table III\n")
    b.write_text(
        HEADER + rows + "T3,segment_max_angle,motion=flexion,10.0,deg,holdout,changed\n"
        "T3,segment_blocked_force,motion=waggle,99.0,N,holdout,added\n"
    )
    fits = []
    for data in (a, b):
        assert (
            main(
                [
                    "calibrate",
                    str(PARAMS / "bvsr.toml"),
                    str(data),
                    "--json",
                    "-q",
                    "--fit",
                    "effective_area_mm2,rod_flexural_rigidity_n_mm2",
                ]
            )
            == 0
        )
        fits.append(json.loads(capsys.readouterr().out))
    assert fits[0]["fitted"] == fits[1]["fitted"]
    assert fits[0]["rms_rel_fit"] == fits[1]["rms_rel_fit"]
    assert fits[0]["rms_rel_holdout"] != fits[1]["rms_rel_holdout"]
    # The fit moved the values and improved the fit rows.
    assert fits[0]["rms_rel_fit"] < 0.5 * fits[0]["rms_rel_fit_uncalibrated"]
    assert {r["role"] for r in fits[1]["rows"]} == {"fit", "holdout"} and len(fits[1]["rows"]) == 4


def test_fitted_values_reach_every_home(bvsr_spec):
    from bvsr_cad.assembly.robot import actuation_si
    from bvsr_cad.models.actuator import soa_force_law
    from bvsr_cad.models.rod import rod_section
    from bvsr_cad.models.statics import TailStatics

    spec = bvsr_spec
    fitted = {
        "effective_area_mm2": 200.0,
        "rod_flexural_rigidity_n_mm2": 5.0e4,
        "damping_n_s_per_m": 10.0,
    }
    cal = dataclasses.replace(
        spec, calibration=dataclasses.replace(spec.calibration, fitted=fitted)
    )
    assert soa_force_law(cal).area_m2 == pytest.approx(200e-6)
    assert soa_force_law(cal).damping_n_s_per_m == 10.0
    assert rod_section(cal).flexural_rigidity_n_mm2 == 5.0e4
    assert TailStatics.from_spec(cal).rod_nmm_per_rad == pytest.approx(5.0e4 / spec.joint.gap_mm)
    si = actuation_si(cal)
    assert si.law.area_m2 == pytest.approx(200e-6)
    assert si.rod_bending_stiffness_nm_rad == pytest.approx(5.0e4 / spec.joint.gap_mm / 1e3)


def test_every_quantity_has_a_prediction_with_its_conditions():
    """The measurement schema and the predictor agree name for name, condition for condition."""
    import inspect

    from bvsr_cad.analysis.predict import Predictor
    from bvsr_cad.parameters.measurements import QUANTITIES

    for name, (_unit, conditions, _doc) in QUANTITIES.items():
        method = getattr(Predictor, name)
        params = [p for p in inspect.signature(method).parameters if p != "self"]
        assert sorted(params) == sorted(conditions), name


def test_shipped_files_carry_the_calibration_of_the_shipped_data(bvsr_data):
    """params/bvsr.toml was calibrated on data/paper_bvsr.csv as it is now (same SHA-256), and
    BVSR_L inherits the same fitted values (same SOAs, rods and valves)."""
    import tomllib

    from bvsr_cad.parameters.measurements import data_sha256

    from .conftest import PARAMS, ROOT

    bvsr_l = tomllib.loads((PARAMS / "bvsr_l.toml").read_text())
    cal, cal_l = bvsr_data["calibration"], bvsr_l["calibration"]
    assert (PARAMS / cal["data_file"]).resolve() == (ROOT / "data" / "paper_bvsr.csv").resolve()
    assert cal["data_sha256"] == data_sha256(ROOT / "data" / "paper_bvsr.csv")
    assert cal["measured_tail"] == bvsr_data["name"] == "bvsr" and cal_l["measured_tail"] == "bvsr"
    assert cal_l["fitted"] == cal["fitted"] and cal_l["data_sha256"] == cal["data_sha256"]
    assert set(cal["fitted"]) == {
        "effective_area_mm2",
        "rod_flexural_rigidity_n_mm2",
        "valve_sonic_conductance_l_s_bar",
    }
    assert cal["rms_rel_holdout"] < 0.5 * cal["rms_rel_holdout_uncalibrated"]


def test_shipped_fitted_rigidity_reaches_the_mjcf(bvsr_data, bvsr_spec):
    """Both MJCF chains carry the file's fitted E I (hand calculation, SI): the exact chain's
    half-angle hinges 2 E I / L each, and the reduced chain's four pivot hinges per joint 2 E I / L
    each (a pure bend turns both pivots' hinges by theta / 2: their energies add up to (1/2)(E I /
    L) theta^2). The per-segment file's hinges carry exactly that. The default file's hinges carry
    the joint's shear spring besides (:class:`~bvsr_cad.models.reduced_chain.HingeShare`), whose
    rod part is the fixed-guided beam's beyond the pivots' bend: (g - 1) E I / L with
    g = 3 (1 - 2 f)^2 = 4/3 for pivots at f = L/6, and 2 of it on each hinge. So E I reaches each
    of those hinges as 2 g E I / L = 8/3 E I / L, seen here as the difference E I makes (doubled),
    while the SOAs' springs can give up the whole shear spring (none left on a shear tendon)."""
    import mujoco

    from bvsr_cad.assembly.assemble import build_assembly
    from bvsr_cad.assembly.robot import robot_model
    from bvsr_cad.exporters.mjcf import hinge_share, mjcf_tree

    from .test_truth import _mesh_files, _without_meshes

    ei_nmm2 = bvsr_data["calibration"]["fitted"]["rod_flexural_rigidity_n_mm2"]
    ei_l = ei_nmm2 * 1e-6 / (bvsr_data["joint"]["gap_mm"] / 1000.0)  # N mm^2 = 1e-6 N m^2
    robot = robot_model(build_assembly(bvsr_spec), [0.5] * bvsr_spec.joints)
    n = bvsr_spec.joints
    reduced = [f"j{k}_{h}" for k in (1, n) for h in ("ax", "ay", "bx", "by")]

    def stiffness(robot, per_segment, chain, names):
        tree, _ = mjcf_tree(robot, _mesh_files(robot), per_segment, chain=chain)
        m = mujoco.MjModel.from_xml_string(_without_meshes(tree.getroot()))
        return np.array([m.jnt_stiffness[m.joint(name).id] for name in names])

    exact = ["j1_theta_a", "j1_theta_b", f"j{n}_theta_a", f"j{n}_theta_b"]
    np.testing.assert_allclose(stiffness(robot, False, "exact", exact), 2 * ei_l, rtol=1e-9)
    np.testing.assert_allclose(stiffness(robot, True, "reduced", reduced), 2 * ei_l, rtol=1e-9)
    # the default file: the rod's part is the difference that E I makes
    stiffer = dataclasses.replace(
        robot,
        actuation=dataclasses.replace(
            robot.actuation,
            rod_bending_stiffness_nm_rad=2 * robot.actuation.rod_bending_stiffness_nm_rad,
        ),
    )
    assert all(
        hinge_share(r, k).shear_tendon_nm_rad == 0.0 for r in (robot, stiffer) for k in (1, n)
    )
    g = 3 * (1 - 2 / 6) ** 2
    np.testing.assert_allclose(
        stiffness(stiffer, False, "reduced", reduced) - stiffness(robot, False, "reduced", reduced),
        2 * g * ei_l,
        rtol=1e-9,
    )


def test_inherited_calibration_compares_only_the_rows_of_its_own_tail(bvsr_spec):
    """A tail that takes another tail's fitted values compares the rows that name its segment count,
    and no other: BVSR_L (3 segments) the BVSR_L workspace row, with the tables' and the fitted
    values (here through a stand-in for the simulator that records what it was asked); a tail no row
    measured gets a note. The BVSR build's rows are the others, each row in exactly one of the
    two."""
    from types import SimpleNamespace

    from bvsr_cad.analysis.calibrate import uncalibrated
    from bvsr_cad.analysis.measured import compare_measurements, rows_of_tail
    from bvsr_cad.assembly.assemble import build_assembly
    from bvsr_cad.parameters.load import load_spec
    from bvsr_cad.parameters.measurements import load_measurements

    from .conftest import PARAMS, ROOT

    data = load_measurements(ROOT / "data" / "paper_bvsr.csv")
    bvsr, bvsr_others = rows_of_tail(data, 2, inherited=False)
    bvsr_l, bvsr_l_others = rows_of_tail(data, 3, inherited=True)
    assert [m.row for m in bvsr_l] == [m.row for m in bvsr_others] == [
        m.row for m in data if m.condition("segments") == 3
    ] and len(bvsr_l) == 1
    assert sorted(m.row for m in bvsr + bvsr_l) == [m.row for m in data]
    assert [m.row for m in bvsr_l_others] == [m.row for m in bvsr]

    spec_l = load_spec(PARAMS / "bvsr_l.toml")
    asked = []

    def sim(asm, spec, limits):
        asked.append(
            (
                asm.spec.segments,
                spec.segments,
                spec.actuation.workspace_pressurised_max_kpa_abs,
                spec.actuation.workspace_depressurised_min_kpa_abs,
                bool(spec.calibration.fitted),
                tuple(limits),
            )
        )
        return 310.0 if spec.calibration.fitted else 300.0

    limits = [0.9] * spec_l.joints
    res = compare_measurements(build_assembly(spec_l), PARAMS / "bvsr_l.toml", None, sim, limits)
    assert [r["row"] for r in res.rows] == [bvsr_l[0].row]
    assert "inherited from the bvsr tail" in res.note and "3-segment tail" in res.note
    assert [(r["uncalibrated"], r["calibrated"]) for r in res.rows] == [(300.0, 310.0)]
    assert sorted(a[:5] for a in asked) == [(3, 3, 251.0, 21.0, False), (3, 3, 251.0, 21.0, True)]
    assert all(a[5] == tuple(limits) for a in asked)
    assert res.fitted == dict(bvsr_spec.calibration.fitted)
    assert res.to_json()["holdout_landed"] == [1, 1] and "rms_rel_fit" not in res.to_json()

    nobody = dataclasses.replace(bvsr_spec, name="bvsr_4", segments=4)
    res = compare_measurements(SimpleNamespace(spec=nobody), PARAMS / "bvsr_l.toml")
    assert res is not None and not res.rows and "inherited from the bvsr tail" in res.note
    assert compare_measurements(SimpleNamespace(spec=uncalibrated(bvsr_spec)), None) is None


def test_another_rod_is_noted_not_compared(bvsr_spec):
    """The data measured the tail with the rod the calibration records; a file with another rod is
    another tail: a note, no predictions of measurements it was not part of."""
    from types import SimpleNamespace

    from bvsr_cad.analysis.measured import compare_measurements

    assert (bvsr_spec.calibration.rod_material, bvsr_spec.calibration.rod_diameter_mm) == (
        bvsr_spec.vertebra.material,
        bvsr_spec.vertebra.diameter_mm,
    )
    for vertebra in (
        dataclasses.replace(bvsr_spec.vertebra, material="PVC"),
        dataclasses.replace(bvsr_spec.vertebra, diameter_mm=5.0),
    ):
        res = compare_measurements(
            SimpleNamespace(spec=dataclasses.replace(bvsr_spec, vertebra=vertebra)),
            "params/bvsr.toml",
        )
        assert res is not None and not res.rows and "another tail" in res.note
        assert f"{vertebra.material} {vertebra.diameter_mm:g} mm" in res.note
        assert res.fitted == dict(bvsr_spec.calibration.fitted)


def test_rows_predicted_in_threads_equal_rows_predicted_one_by_one(bvsr_spec):
    """compare_rows predicts in threads (the workspace protocol steps beside the other rows, which
    take one thread of their own): the table is the same, value for value, with one thread."""
    from bvsr_cad.analysis.calibrate import compare_rows, uncalibrated
    from bvsr_cad.analysis.predict import Predictor
    from bvsr_cad.assembly.assemble import build_assembly
    from bvsr_cad.parameters.measurements import load_measurements

    from .conftest import ROOT

    rows = [
        m
        for m in load_measurements(ROOT / "data" / "paper_bvsr.csv")
        if m.quantity
        in (
            "segment_max_angle",
            "segment_peak_velocity",
            "velocity_pressure_exponent",
            "root_peak_torque",
            "root_peak_force",
            "soa_stiffness",
        )
    ]
    assert len(rows) >= 8
    asm = build_assembly(bvsr_spec)

    def table(threads: int) -> list[dict]:
        pred = Predictor(asm, bvsr_spec)
        return compare_rows(pred.with_spec(uncalibrated(bvsr_spec)), pred, rows, threads=threads)

    one, many = table(1), table(6)
    assert [r["row"] for r in many] == [m.row for m in rows]
    assert json.dumps(many, sort_keys=True) == json.dumps(one, sort_keys=True)


def test_a_memo_entry_asked_from_many_threads_is_made_once():
    """The Predictor's memo (shared by the protocol rows' threads and the thread preparing their
    geometry): threads asking for one entry at once wait for the first, which makes it once."""
    import threading
    import time

    from bvsr_cad.analysis.predict import _Locks

    locks, store, made, start = _Locks(), {}, [], threading.Barrier(9)

    def make(key: str) -> str:
        made.append(key)
        time.sleep(0.05)  # long enough for every other thread to arrive
        return key.upper()

    got = []

    def ask(key: str) -> None:
        start.wait()
        got.append(locks.once(store, key, lambda: make(key)))

    threads = [threading.Thread(target=ask, args=(k,)) for k in ["a"] * 8 + ["b"]]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(made) == ["a", "b"]
    assert sorted(got) == ["A"] * 8 + ["B"]
    assert store == {"a": "A", "b": "B"}
