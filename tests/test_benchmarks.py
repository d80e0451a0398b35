"""The benchmark scripts run against the package as it is: a helper moved or renamed breaks a
benchmark here, not when it is next run by hand. Each runs with its builds stood in."""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

import pytest

from bvsr_cad.build.publish import BuildResult
from bvsr_cad.parameters.layout import key_value
from bvsr_cad.parameters.load import load_spec

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
    import bvsr_cad.build._runtime.worker
    import bvsr_cad.build.pipeline

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

    monkeypatch.setattr(bvsr_cad.build.pipeline, "build_export", fake_build)
    monkeypatch.setattr(bench, "command_seconds", fake_command)
    loops = iter([0.91, 0.97])  # the reference loop, before and after
    monkeypatch.setattr(bench, "reference_loop_s", lambda: next(loops))
    monkeypatch.setattr(
        bvsr_cad.build._runtime.worker.SecondProcess,
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
    import bvsr_cad.build._runtime.worker
    import bvsr_cad.build.pipeline

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

    monkeypatch.setattr(bvsr_cad.build.pipeline, "build_export", fake_build)
    monkeypatch.setattr(bench, "command_seconds", lambda path, out: (0.5, 0.4, [], {"build": 0.3}))
    monkeypatch.setattr(bench, "reference_loop_s", lambda: 0.9)
    monkeypatch.setattr(
        bvsr_cad.build._runtime.worker.SecondProcess,
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
    "name", ["clearance_bench", "dynamics_crosscheck", "rebuild_bench", "sim_bench"]
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


def test_sim_bench_runs_on_the_cpu_and_says_profile_needs_cuda(bvsr_export, capsys, monkeypatch):
    """The benchmark end to end on a machine without a CUDA GPU (CI): CPU MuJoCo's rate at the
    exported step, Warp's CPU batch checked against CPU MuJoCo, and --profile declining in one
    line."""
    pytest.importorskip("warp", reason="needs the optional extra .[gpu]")
    pytest.importorskip("mujoco_warp", reason="needs the optional extra .[gpu]")
    import mujoco

    from bvsr_cad.simulation import sim_gpu

    bench = benchmark_script("sim_bench")
    monkeypatch.setattr(bench, "cuda_present", lambda: None)
    assert (
        bench.main(
            [
                str(bvsr_export),
                "--no-mjx",
                "--cpu-batches",
                "2",
                "--steps",
                "3",
                "--cpu-seconds",
                "0.2",
                "--profile",
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    step_ms = mujoco.MjModel.from_xml_path(str(sim_gpu.scene_path(bvsr_export))).opt.timestep * 1e3
    assert (
        f"time step {step_ms:g} ms" in out and "real-time factor" in out and "WARNINGS" not in out
    )
    warp_line = next(line for line in out.splitlines() if "warp  batch     2:" in line)
    assert (
        float(warp_line.rsplit("max|dqpos| ", 1)[1].split()[0]) < 1e-5
        and "PROBLEMS" not in warp_line
    )
    assert out.rstrip().endswith(
        "--profile: per-kernel times need MuJoCo Warp on a CUDA GPU; skipped"
    )
