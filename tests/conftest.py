from __future__ import annotations

import copy
import importlib.util
import os
import tomllib
from pathlib import Path

import pytest
from hypothesis import settings

from bvsr_cad.process import PROCESSES_VARIABLE

ROOT = Path(__file__).resolve().parents[1]
PARAMS = ROOT / "params"

# Hypothesis profiles (tests/test_feasibility.py's search for the frontier): "ci", loaded unless
# --hypothesis-profile names another, draws a fixed sequence of a bounded number of examples (about
# 30 CPU s on 2 cores); "long", by hand, a fresh random search twelve times as long (a case it finds
# goes into test_feasibility.FOUND as an @example, not into a database).
settings.register_profile(
    "ci", max_examples=100, derandomize=True, database=None, deadline=None, print_blob=True
)
settings.register_profile("long", max_examples=1200, database=None, deadline=None, print_blob=True)
settings.load_profile("ci")


def pytest_configure(config):
    """Every test session gets its own, empty artifact cache (never the user's ~/.cache/bvsr_cad): a
    test that means a cold build gets one, and tests cannot see a cache filled by other code."""
    import tempfile

    # A build in a test runs in one process (bvsr_cad.process.build_processes) unless the test is
    # marked second_processes: the workers keep every core busy, so a second process has no core of
    # its own and adds only its imports.
    os.environ.setdefault(PROCESSES_VARIABLE, "1")
    if "BVSR_TEST_KEEP_CACHE" in os.environ:
        return
    if hasattr(config, "workerinput"):
        # A pytest-xdist worker: it was started with the cache its controller made (the environment
        # is inherited), which the workers share as two concurrent builds share one; the controller
        # removes it.
        return
    config._bvsr_test_cache = tempfile.mkdtemp(prefix="bvsr-test-cache-")
    os.environ["BVSR_CACHE"] = config._bvsr_test_cache


def pytest_unconfigure(config):
    """The session's cache holds whole exports (tens of MB each): it goes with the session."""
    import shutil

    folder = getattr(config, "_bvsr_test_cache", None)
    if folder:
        shutil.rmtree(folder, ignore_errors=True)


#: Tests marked slow though they use no whole build: tests/slow_tests.txt (how it was measured is
#: in its head). By node id, a parametrised test's cases together.
SLOW = frozenset(
    line
    for line in (ROOT / "tests" / "slow_tests.txt").read_text().splitlines()
    if line and not line.startswith("#")
)


def pytest_collection_modifyitems(config, items):
    """``slow``: a test that needs a whole build (the default's, ``bvsr_export``, 30 s or more;
    the CI-sized tail's, ``small_tail``, about 10 s) or is named in :data:`SLOW`. ``pytest -m "not
    slow"`` stays a fast suite of in-memory tests, the inner loop of docs/contributing.md
    (tools/mutate.py runs it per fault)."""
    for item in items:
        if (
            not {"bvsr_export", "small_tail"}.isdisjoint(getattr(item, "fixturenames", ()))
            or item.nodeid.split("[")[0] in SLOW
            or item.nodeid.split("::")[0] in SLOW
        ):
            item.add_marker(pytest.mark.slow)


@pytest.fixture(autouse=True)
def _second_processes(request, monkeypatch):
    """A test marked ``second_processes`` gets builds that run their analyses and checks in second
    processes, one a core as a user's do (the session's others run in one process,
    :func:`pytest_configure`)."""
    if request.node.get_closest_marker("second_processes"):
        monkeypatch.delenv(PROCESSES_VARIABLE, raising=False)


@pytest.fixture(scope="session")
def bvsr_data() -> dict:
    return tomllib.loads((PARAMS / "bvsr.toml").read_text())


@pytest.fixture()
def data(bvsr_data) -> dict:
    """A fresh, mutable copy of the default parameters."""
    return copy.deepcopy(bvsr_data)


@pytest.fixture(scope="session")
def bvsr_spec():
    from bvsr_cad.parameters.load import load_spec

    return load_spec(PARAMS / "bvsr.toml")


def built_once(request, tmp_path_factory, name: str, make) -> Path:
    """``make(folder)`` run once per test session into ``folder`` (an empty folder of its own),
    which is returned; read-only to the tests that share it.

    Under pytest-xdist (``make test`` runs ``-n auto``) the workers share it too: the first to need
    it makes it under a lock in the session's common temporary folder, the others wait for it and
    read it. A worker's failed ``make`` leaves no mark: the next one tries again (in a fresh
    folder)."""
    import fcntl
    import shutil

    if not hasattr(request.config, "workerinput"):  # no pytest-xdist workers
        folder = tmp_path_factory.mktemp(name)
        make(folder)
        return folder
    shared = tmp_path_factory.getbasetemp().parent / f"shared-{name}"
    shared.mkdir(exist_ok=True)
    folder = shared / "made"
    with open(shared / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes, even if make fails
        if not (shared / ".done").exists():
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            make(folder)
            (shared / ".done").touch()
    return folder


@pytest.fixture(scope="session")
def bvsr_export(tmp_path_factory, request) -> Path:
    """One full default build shared by the export tests (read-only to them), in the session's
    cache (:func:`built_once`)."""
    from bvsr_cad.pipeline.stages import build_export

    def make(folder: Path) -> None:
        build_export(PARAMS / "bvsr.toml", folder / "bvsr")

    return built_once(request, tmp_path_factory, "exp", make) / "bvsr"


def script(folder: str, name: str):
    """``<folder>/<name>.py`` of the repository loaded as a module (benchmarks and tools are
    scripts, not a package)."""
    spec = importlib.util.spec_from_file_location(f"{folder}_{name}", ROOT / folder / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def benchmark_script(name: str):
    """``benchmarks/<name>.py`` loaded as a module."""
    return script("benchmarks", name)


def write_toml(path: Path, data: dict) -> Path:
    """Minimal TOML writer for the test fixtures (tables of scalars, one level of nesting)."""

    def scalar(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        return repr(v)

    lines = []
    tables = []
    for k, v in data.items():
        if isinstance(v, dict):
            tables.append((k, v))
        else:
            lines.append(f"{k} = {scalar(v)}")
    for name, table in tables:
        sub = [(k, v) for k, v in table.items() if isinstance(v, dict)]
        lines.append(f"[{name}]")
        lines += [f"{k} = {scalar(v)}" for k, v in table.items() if not isinstance(v, dict)]
        for k, v in sub:
            lines.append(f"[{name}.{k}]")
            lines += [f"{kk} = {scalar(vv)}" for kk, vv in v.items()]
    path.write_text("\n".join(lines) + "\n")
    return path


#: The CI-sized tail of the cache's edit tests, the build-order test and, through its export
#: (:func:`small_export`), the tests of how the checks run (tests/test_cache.py,
#: tests/test_ocp_viewer.py, tests/test_export.py, tests/test_fabrication.py,
#: tests/test_check_output.py): the default file with one segment of two joints, the schema's fewest
#: (the segment-count edit then goes to two segments), and the schema's smallest workspace protocol
#: and samples; the stages, their keys and their code are the default tail's, and every kind of
#: panel (root, intermediate, tip) is in it. Its taper is fixed near the default's (``auto`` gives
#: 0.29 deg over fifteen joints): over two joints ``auto`` would steepen it to reach the same tip,
#: and the rigid twin's plates would come out under the 0.6 mm FDM minimum (0.58 mm), failing a
#: check. Build times: benchmarks/RESULTS.md, "Test suite".
SMALL_TAIL = (
    ("", "segments", "1"),
    ("", "joints_per_segment", "2"),
    ("taper", "half_angle_deg", "0.3"),
    ("analysis", "workspace_protocol_cycles", "10"),
    ("analysis", "build_workspace_samples", "100"),
    ("analysis", "build_clearance_poses", "100"),
)

#: The rebuild benchmark: its edits and its editor of parameter text (one source).
REBUILD_BENCH = benchmark_script("rebuild_bench")


@pytest.fixture(scope="session")
def small_tail(request, tmp_path_factory) -> Path:
    """A folder with ``params/base.toml`` (:data:`SMALL_TAIL`, its calibration data beside it) and
    ``cache``, a cache of its own that holds that file's build, built once per session
    (:func:`built_once`)."""
    from bvsr_cad.pipeline.stages import build_export

    def make(folder: Path) -> None:
        (folder / "params").mkdir()
        (folder / "data").mkdir()
        text = (PARAMS / "bvsr.toml").read_text()
        data_file = (PARAMS / tomllib.loads(text)["calibration"]["data_file"]).resolve()
        (folder / "data" / data_file.name).write_bytes(data_file.read_bytes())
        for table, key, value in SMALL_TAIL:
            text = REBUILD_BENCH.edited(text, table, key, value)
        base = folder / "params" / "base.toml"
        base.write_text(text)
        before = os.environ.get("BVSR_CACHE")
        os.environ["BVSR_CACHE"] = str(folder / "cache")
        try:
            stages = build_export(base, folder / "base").stages
        finally:
            if before is None:
                del os.environ["BVSR_CACHE"]
            else:
                os.environ["BVSR_CACHE"] = before
        assert {s["status"] for s in stages} == {"built"}

    return built_once(request, tmp_path_factory, "small-tail", make)


@pytest.fixture(scope="session")
def small_export(small_tail) -> Path:
    """The CI-sized tail's export (:func:`small_tail`'s ``base``), read-only: the export of the
    tests of how the checks run (started early, beside in a second process, handed the manifest),
    where the default's five segments would add only more instances of the same checks."""
    return small_tail / "base"


@pytest.fixture(scope="session")
def small_verdicts(small_export, tmp_path_factory, request) -> str:
    """Every check of :func:`small_export` run once in one process (``run_checks(parallel=False)``),
    as the JSON text of their results: the reference that the tests of checks run early, beside or
    from a manifest in memory compare with (as text: a NaN equals itself only there)."""
    import json

    from bvsr_cad.pipeline.processes.checks_process import run_checks

    def make(folder: Path) -> None:
        verdicts = [r.to_json() for r in run_checks(small_export, parallel=False)]
        (folder / "verdicts.json").write_text(json.dumps(verdicts))

    return (built_once(request, tmp_path_factory, "verdicts", make) / "verdicts.json").read_text()
