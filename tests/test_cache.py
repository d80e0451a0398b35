"""The artifact cache: atomic entries, least-recently-used eviction, keys that follow their inputs,
and cached builds equal to builds from scratch, file for file."""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import threading
import time
import tomllib
from pathlib import Path

import pytest

from bvsr_cad.pipeline.cache import ArtifactCache, spec_without, stage_key
from bvsr_cad.process import PROCESSES_VARIABLE, build_processes

from .conftest import PARAMS, REBUILD_BENCH, script, write_toml

#: Two exports compared file for file, the manifest's volatile section aside (also
#: tools/wheel_check.sh's).
differences = script("tools", "compare_exports").differences


def test_put_get_and_concurrent_puts_of_one_key(tmp_path):
    cache = ArtifactCache(tmp_path / "c", max_bytes=1e9)
    assert cache.get("ab" * 32) is None
    started = threading.Barrier(2)

    def fill(folder: Path, text: str) -> None:
        started.wait()
        (folder / "f.txt").write_text(text)
        time.sleep(0.05)

    threads = [
        threading.Thread(target=cache.put, args=("ab" * 32, lambda d, t=t: fill(d, t)))
        for t in "xy"
    ]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    entry = cache.get("ab" * 32)
    assert entry is not None and (entry / "f.txt").read_text() in ("x", "y")
    assert not list(entry.parent.glob("*.tmp-*"))  # the loser's copy is gone


def test_a_failed_fill_leaves_no_entry(tmp_path):
    cache = ArtifactCache(tmp_path / "c")

    def fill(folder: Path) -> None:
        (folder / "half.txt").write_text("half")
        raise OSError("disk full (simulated)")

    with pytest.raises(OSError):
        cache.put("cd" * 32, fill)
    assert cache.get("cd" * 32) is None and not list((tmp_path / "c").rglob("half.txt"))


def test_least_recently_used_entries_go_first(tmp_path):
    cache = ArtifactCache(tmp_path / "c", max_bytes=2500)
    for i, key in enumerate(("a1" * 32, "b2" * 32)):
        cache.put(key, lambda d: (d / "blob").write_bytes(b"x" * 1000))
        os.utime(cache.get(key) / ".done", (1000 + i, 1000 + i))
    cache.get("a1" * 32)  # used now: b2 is the least recently used
    cache.put("c3" * 32, lambda d: (d / "blob").write_bytes(b"x" * 1000))
    assert cache.get("b2" * 32) is None
    assert cache.get("a1" * 32) is not None and cache.get("c3" * 32) is not None


def test_keys_follow_exactly_the_declared_inputs(bvsr_spec):
    """The pipeline's declarations: the rod's material moves no solid (the part files' key stays),
    its diameter and the tail's name (the assembly STEP's product) do; the analyses read the
    material."""
    import dataclasses

    from bvsr_cad.pipeline.stages import ANALYSES_IGNORE, PART_FILES_IGNORE

    def key(stage, spec, ignore):
        return stage_key(stage, spec=spec_without(spec, *ignore))

    pvc = dataclasses.replace(
        bvsr_spec, vertebra=dataclasses.replace(bvsr_spec.vertebra, material="PVC")
    )
    thin = dataclasses.replace(
        bvsr_spec, vertebra=dataclasses.replace(bvsr_spec.vertebra, diameter_mm=5.0)
    )
    renamed = dataclasses.replace(bvsr_spec, name="other")
    base = key("part_files", bvsr_spec, PART_FILES_IGNORE)
    assert key("part_files", pvc, PART_FILES_IGNORE) == base
    assert key("part_files", thin, PART_FILES_IGNORE) != base
    assert key("part_files", renamed, PART_FILES_IGNORE) != base
    assert key("analyses", pvc, ANALYSES_IGNORE) != key("analyses", bvsr_spec, ANALYSES_IGNORE)
    assert key("analyses", renamed, ANALYSES_IGNORE) != key("analyses", bvsr_spec, ANALYSES_IGNORE)
    # The geometry analyses (joint limits, clearance map): the solids, not the material or the name.
    from bvsr_cad.pipeline.stages import ANALYSIS_GEOMETRY_IGNORE as GEO

    assert key("analysis_geometry", pvc, GEO) == key("analysis_geometry", bvsr_spec, GEO)
    assert key("analysis_geometry", renamed, GEO) == key("analysis_geometry", bvsr_spec, GEO)
    assert key("analysis_geometry", thin, GEO) != key("analysis_geometry", bvsr_spec, GEO)
    # The robot's meshes and collision fits: the solids and which collision shapes, not the
    # material, the name or the robot table's other values.
    from bvsr_cad.pipeline.stages import robot_geometry_key

    robot = robot_geometry_key(bvsr_spec)
    assert robot_geometry_key(pvc) == robot_geometry_key(renamed) == robot
    assert (
        robot_geometry_key(
            dataclasses.replace(
                bvsr_spec,
                robot=dataclasses.replace(
                    bvsr_spec.robot, velocity_margin=2 * bvsr_spec.robot.velocity_margin
                ),
            )
        )
        == robot
    )
    assert robot_geometry_key(thin) != robot
    assert (
        robot_geometry_key(
            dataclasses.replace(
                bvsr_spec, robot=dataclasses.replace(bvsr_spec.robot, collision_geometry="convex")
            )
        )
        != robot
    )


def test_keys_follow_the_libraries_the_results_are_computed_with(monkeypatch):
    """Every runtime dependency of pyproject.toml (and the OCP builds under build123d and CadQuery)
    is in the code's fingerprint: another installed MuJoCo, or OCP, gives every stage another
    key."""
    import re
    from importlib import metadata

    from bvsr_cad.pipeline import cache

    project = tomllib.loads((PARAMS.parent / "pyproject.toml").read_text())["project"]
    computing = project["dependencies"] + [
        r
        for extra in ("studies", "crosscheck")  # a study's table, a check
        for r in project["optional-dependencies"][extra]
    ]
    declared = {re.split(r"[ ;=<>!~\[]", r, maxsplit=1)[0].lower() for r in computing}
    assert declared | {"cadquery", "cadquery-ocp", "cadquery-ocp-novtk"} == set(
        cache.RESULT_DISTRIBUTIONS
    )
    base = stage_key("analyses", x=1)
    real = metadata.version
    try:
        for name in ("mujoco", "cadquery-ocp-novtk"):
            monkeypatch.setattr(
                metadata, "version", lambda n, name=name: "0.0.1" if n == name else real(n)
            )
            cache.code_fingerprint.cache_clear()
            assert stage_key("analyses", x=1) != base, name
        monkeypatch.setattr(metadata, "version", real)
        cache.code_fingerprint.cache_clear()
        assert stage_key("analyses", x=1) == base
    finally:  # the later tests of this process key with the libraries as installed
        monkeypatch.setattr(metadata, "version", real)
        cache.code_fingerprint.cache_clear()


def test_check_verdicts_follow_the_bytes_of_the_files_they_read(tmp_path):
    """A group's verdicts are reused while its files' bytes and manifest values are unchanged (a
    file rewritten with the same bytes too), and computed again when either changes."""
    from bvsr_cad.checks.export import Export
    from bvsr_cad.checks.memo import CheckMemo
    from bvsr_cad.checks.result import CheckResult
    from bvsr_cad.pipeline.runner import cache_memo

    (tmp_path / "manifest.json").write_text(json.dumps({"name": "t", "parts": [], "mass_g": {}}))
    (tmp_path / "a.stl").write_bytes(b"solid a")
    cache = ArtifactCache(tmp_path / "c")
    runs = []

    def verdicts(value):
        memo = CheckMemo(Export.open(tmp_path), cache_memo(cache))
        return memo(
            "g",
            (["a.stl"], {"limit": value}),
            lambda: runs.append(1) or [CheckResult("c", True, (1, 2), value, "mm", "a.stl")],
        )

    first = verdicts(1.0)
    (tmp_path / "a.stl").write_bytes(b"solid a")  # rewritten, same bytes
    assert verdicts(1.0) == first and len(runs) == 1
    verdicts(2.0)
    (tmp_path / "a.stl").write_bytes(b"solid b")
    verdicts(2.0)
    assert len(runs) == 3


def test_a_writers_step_follows_its_inputs_and_the_bytes_of_its_files(tmp_path):
    """The memo a build hands its writers (cache_memo): a step's files and value come back from the
    cache while its inputs and its files' bytes are unchanged (a file rewritten with the same bytes
    too), and the step runs again when either changes; its files are copied into the new ``dst``."""
    from bvsr_cad.pipeline.runner import cache_memo

    memo = cache_memo(ArtifactCache(tmp_path / "c"))
    source = tmp_path / "part.stl"
    source.write_bytes(b"solid a")
    runs = []

    def draw(dst: Path) -> int:
        runs.append(1)
        (dst / "pic.png").write_bytes(source.read_bytes() + b" drawn")
        return len(runs)

    def step(dst: Path, inputs: dict) -> tuple[int, bool]:
        dst.mkdir(exist_ok=True)
        return memo("picture", inputs, draw, dst, files=[source])

    assert step(tmp_path / "one", {"view": 1}) == (1, False)
    source.write_bytes(b"solid a")  # rewritten, same bytes
    assert step(tmp_path / "two", {"view": 1}) == (1, True)
    assert (tmp_path / "two" / "pic.png").read_bytes() == b"solid a drawn"
    assert step(tmp_path / "three", {"view": 2}) == (2, False)
    source.write_bytes(b"solid b")
    assert step(tmp_path / "four", {"view": 2}) == (3, False)
    assert (tmp_path / "four" / "pic.png").read_bytes() == b"solid b drawn"


def test_the_in_memory_memo_gives_a_value_again_only_for_the_same_inputs():
    """memo.InMemory (the memo of the check groups a build runs early): a name's last value comes
    back for the same inputs, a changed input runs the step again and is remembered; it keeps values
    only."""
    from bvsr_cad.memo import InMemory

    memo, runs = InMemory(), []

    def step(v: int) -> int:
        runs.append(v)
        return v

    assert memo("g", {"reads": "a"}, lambda: step(1)) == (1, False)
    assert memo("g", {"reads": "a"}, lambda: step(2)) == (1, True)
    assert memo("g", {"reads": "b"}, lambda: step(3)) == (3, False)
    assert memo("g", {"reads": "b"}, lambda: step(4)) == (3, True)
    assert memo("h", {"reads": "b"}, lambda: step(5)) == (5, False)
    assert runs == [1, 3, 5]
    with pytest.raises(ValueError):
        memo("g", {"reads": "b"}, lambda _dst: 0, Path("dst"))


def test_two_exports_differ_by_their_files_not_by_the_manifests_volatile_section(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    for root, when in ((a, "10:00"), (b, "11:00")):
        (root / "stl").mkdir(parents=True)
        (root / "stl" / "soa.stl").write_bytes(b"solid soa")
        (root / "manifest.json").write_text(
            json.dumps({"name": "t", "volatile": {"built_at": when}})
        )
    assert differences(a, b) == []
    (b / "stl" / "soa.stl").write_bytes(b"solid SOA")
    (b / "stl" / "rod.stl").write_bytes(b"solid rod")
    assert differences(a, b) == ["stl/rod.stl", "stl/soa.stl"]


@pytest.mark.second_processes
@pytest.mark.slow
def test_noop_rebuild_is_reused_and_a_cached_edit_equals_a_fresh_build(
    small_tail, tmp_path, monkeypatch
):
    """The CI-sized tail's cache holds its build: the same file again is one reused stage; the
    benchmark's rod-material edit, built by two command-line builds at once through that cache,
    equals file for file the same edit built with --no-cache (the manifest's volatile section
    aside), built in one process (``BVSR_PROCESSES=1``) where the two commands run their second
    processes."""
    from bvsr_cad.pipeline.stages import build_export

    monkeypatch.setenv("BVSR_CACHE", str(small_tail / "cache"))
    base = small_tail / "params" / "base.toml"
    noop = build_export(base, tmp_path / "noop")
    assert [(s["stage"], s["status"]) for s in noop.stages] == [("export", "reused")]
    assert differences(small_tail / "base", tmp_path / "noop") == []

    table, key, value = REBUILD_BENCH.EDITS["rod material"]
    edit = small_tail / "params" / "rod_material_cli.toml"  # beside its calibration data
    edit.write_text(REBUILD_BENCH.edited(base.read_text(), table, key, value))
    bvsr = Path(sys.executable).with_name("bvsr")
    cmd = [str(bvsr)] if bvsr.exists() else [sys.executable, "-m", "bvsr_cad.cli"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    runs = [
        subprocess.Popen(
            [*cmd, "build", str(edit), "-o", str(tmp_path / f"cached{i}"), "--json", "-q"],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        for i in (1, 2)
    ]
    outs = [r.communicate(timeout=1200) for r in runs]
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    assert [r.returncode for r in runs] == [0, 0], [o[1][-2000:] for o in outs]
    summaries = [json.loads(o[0]) for o in outs]
    stages = {s["stage"]: s["status"] for s in summaries[0]["stages"]}
    # The rod's material moves no solid: nothing is meshed or fitted again, no rest distance
    # measured again.
    assert (
        stages["part files"]
        == stages["previews"]
        == stages["robot meshes, collision fits"]
        == "reused"
    )
    assert stages["analysis geometry (joint limits, clearance map)"] == "reused"
    # The CPU seconds each build reports by process (its own since it opened, each second process's
    # own) against the kernel's count of the two commands and everything they started: all of it but
    # their interpreters' start, imports and parameter loading, the tools the checks run, and a
    # standby analyses' process closed unused where a build took the analyses from the other's cache
    # entry (measured: 43.8 of 46.6 s, both building them; without its analyses' process a build
    # would report about half of it).
    for summary in summaries:
        cpu = summary["cpu_seconds"]
        built = {s["stage"] for s in summary["stages"] if s["status"] == "built"}
        expected = {"build"} | ({"analyses", "checks"} if build_processes() > 1 else set())
        assert set(cpu) == (expected if "analyses" in built else expected - {"analyses"}), (
            cpu,
            built,
        )
        assert all(v > 0 for v in cpu.values()), cpu
    reported = sum(v for summary in summaries for v in summary["cpu_seconds"].values())
    counted = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    assert 0.8 * counted <= reported <= counted + 0.05, (
        reported,
        counted,
    )  # rounded to 0.01 s each
    # The fresh build in one process: a build's second processes change none of its files.
    monkeypatch.setenv(PROCESSES_VARIABLE, "1")
    assert main_no_cache(edit, tmp_path / "fresh") == 0
    for i in (1, 2):
        assert differences(tmp_path / f"cached{i}", tmp_path / "fresh") == []


#: Its edits on the CI-sized tail: the segment count goes to two; the rod material is
#: :func:`test_noop_rebuild_is_reused_and_a_cached_edit_equals_a_fresh_build`'s edit.
SMALL_TAIL_EDITS = {
    **{k: v for k, v in REBUILD_BENCH.EDITS.items() if k != "rod material"},
    "segment count": ("", "segments", "2"),
}


@pytest.mark.slow
@pytest.mark.parametrize("name", list(SMALL_TAIL_EDITS))
def test_every_benchmark_edit_built_from_the_cache_equals_a_fresh_build(
    small_tail, tmp_path, monkeypatch, name
):
    """Each one-parameter edit of the rebuild benchmark (:data:`SMALL_TAIL_EDITS`: rod diameter,
    pocket clearance, taper, segment count, casting shrinkage, printer volume, effective area),
    built through a cache that holds the unedited file's build, equals the same file built with the
    cache off, file for file (the manifest's volatile section aside); each reuses at least one stage
    and rebuilds at least one. A CI-sized tail (:data:`SMALL_TAIL`) in a cache of its own, its base
    built once per session and the edits spread over the workers (the other edits' entries may
    join the cache meanwhile: their keys differ from this edit's in the key edited)."""
    from bvsr_cad.pipeline.stages import build_export

    monkeypatch.setenv("BVSR_CACHE", str(small_tail / "cache"))
    table, key, value = SMALL_TAIL_EDITS[name]
    text = (small_tail / "params" / "base.toml").read_text()
    # beside the base file: the calibration's data file is found where its relative path leads
    edit = small_tail / "params" / f"{name.replace(' ', '_')}.toml"
    edit.write_text(REBUILD_BENCH.edited(text, table, key, value))
    cached = build_export(edit, tmp_path / "cached")
    fresh = build_export(edit, tmp_path / "fresh", use_cache=False)
    statuses = {s["status"] for s in cached.stages}
    assert statuses == {"built", "reused"}, (name, cached.stages)
    assert {s["status"] for s in fresh.stages} == {"built"}, name
    assert differences(tmp_path / "cached", tmp_path / "fresh") == [], name


def _edit_beside_its_data(tmp_path: Path, data: dict) -> Path:
    """``data`` written as ``tmp_path/params/bvsr.toml``, with the calibration's data file where its
    relative path leads (so that the edit's analyses compare the same rows as the default
    file's)."""
    (tmp_path / "params").mkdir()
    (tmp_path / "data").mkdir()
    data_file = (PARAMS / data["calibration"]["data_file"]).resolve()
    (tmp_path / "data" / data_file.name).write_bytes(data_file.read_bytes())
    return write_toml(tmp_path / "params" / "bvsr.toml", data)


class _StageReached(Exception):
    """Raised where a test stops a build: at its first stage, the assembly."""


@pytest.mark.second_processes
@pytest.mark.slow
def test_a_build_whose_analyses_are_cached_stops_its_standby_before_its_stages(
    bvsr_export, tmp_path, data, monkeypatch
):
    """bvsr_export filled the session's cache. A printer-volume edit reads the same analyses: the
    build takes them from the cache and stops its standby analyses' process before the assembly, so
    that its imports and head start do not take a core from the build's stages. Without the cache it
    is given the analyses, and runs beside them."""
    from bvsr_cad.pipeline import stages
    from bvsr_cad.pipeline.processes import worker

    data["fabrication_package"]["printer_x_mm"] = 220.0
    edit = _edit_beside_its_data(tmp_path, data)
    seen: list[bool] = []

    def first_stage(*_args, **_kw):
        seen.append(standby.running)
        raise _StageReached

    monkeypatch.setattr(stages, "build_assembly", first_stage)
    for use_cache in (True, False):
        standby = worker.SecondProcess.standby(
            "bvsr_cad.pipeline.processes.analyses_process", None, [str(edit)]
        )
        if standby is None:
            pytest.skip("one core: the analyses never leave the process")
        with pytest.raises(_StageReached):
            stages.build_export(edit, tmp_path / "out", use_cache=use_cache, standby=standby)
        assert standby.proc is None  # closed by the build either way
    assert seen == [False, True]


@pytest.mark.second_processes
@pytest.mark.slow
def test_analyses_take_both_cores_when_the_geometry_is_cached(
    bvsr_export, tmp_path, data, monkeypatch
):
    """bvsr_export filled the session's cache. An effective-area edit moves no solid: its geometry
    analyses (and so the part files, previews and drawings) come from the cache and the analyses'
    process is told to run the protocol's two simulations side by side (BESIDE_IDLE_BUILD_THREADS);
    without the cache the build's own stages share the cores with it (BESIDE_BUILD_THREADS). The
    table is the same either way (compare_rows); measured on the default tail, 2 cores: 22.9-24.4 s
    with 2 threads, 19.0-20.1 with 3."""
    from bvsr_cad.analysis.run import BESIDE_BUILD_THREADS, BESIDE_IDLE_BUILD_THREADS
    from bvsr_cad.pipeline import stages
    from bvsr_cad.pipeline.processes import worker

    data["actuation"]["effective_area_mm2"] = 150.0
    edit = _edit_beside_its_data(tmp_path, data)
    given: list[list[str]] = []

    def start(cls, module, args, *_rest, **_kw):
        given.append(list(args))
        return None  # no second process: the build would run its analyses itself, after its stages

    def first_stage(*_args, **_kw):
        raise _StageReached

    monkeypatch.setattr(worker.SecondProcess, "start", classmethod(start))
    monkeypatch.setattr(stages, "build_assembly", first_stage)
    for use_cache in (True, False):
        with pytest.raises(_StageReached):
            stages.build_export(edit, tmp_path / "out", use_cache=use_cache)
    assert [(bool(args[2]), args[3]) for args in given] == [
        (True, str(BESIDE_IDLE_BUILD_THREADS)),
        (False, str(BESIDE_BUILD_THREADS)),
    ]
    assert BESIDE_IDLE_BUILD_THREADS > BESIDE_BUILD_THREADS


#: What a rebuild that finds its whole export in the cache must not import (seconds of the command's
#: time).
HEAVY_MODULES = {
    "build123d",
    "OCP",
    "cadquery",
    "trimesh",
    "manifold3d",
    "scipy",
    "mujoco",
    "matplotlib",
    "pyvista",
    "bvsr_cad.pipeline.stages",
    "bvsr_cad.assembly",
    "bvsr_cad.checks.printability",
}


@pytest.mark.slow
def test_a_noop_build_command_publishes_the_cached_export_before_the_cad_imports(
    bvsr_export, tmp_path
):
    """`bvsr build` of a file the cache holds whole (bvsr_export filled the session's cache)
    publishes that export from the parameters, the cache and the checks' environment alone: the
    command's interpreter never imports the CAD kernel, the mesh libraries, the simulator or the
    pipeline (``-X importtime`` lists every module it imported), and the export equals the first
    build's, file for file."""
    out = tmp_path / "again"
    done = subprocess.run(
        [
            sys.executable,
            "-X",
            "importtime",
            "-m",
            "bvsr_cad.cli",
            "build",
            str(PARAMS / "bvsr.toml"),
            "-o",
            str(out),
            "--json",
            "-q",
        ],
        capture_output=True,
        text=True,
        timeout=600,
        cwd=PARAMS.parent,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    assert [(s["stage"], s["status"]) for s in json.loads(done.stdout)["stages"]] == [
        ("export", "reused")
    ]
    imported = {
        line.rsplit("|", 1)[1].strip()
        for line in done.stderr.splitlines()
        if line.startswith("import time:")
    }
    assert "bvsr_cad.pipeline.publish" in imported  # the listing is there to read
    assert not imported & HEAVY_MODULES
    assert differences(bvsr_export, out) == []


def main_no_cache(params: Path, out: Path) -> int:
    from bvsr_cad.cli import main

    return main(["build", str(params), "-o", str(out), "--no-cache", "-q"])
