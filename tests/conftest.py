from __future__ import annotations

import copy
import importlib.util
import tomllib
from pathlib import Path

import pytest
from hypothesis import settings

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
    import os
    import tempfile

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


#: Tests over about 3 s that use no whole build (``bvsr_export``): property searches over many
#: files, fresh interpreters, the documentation site, posed clearances. Measured with
#: ``pytest -n 2 --durations=60`` on 2 cores at load 3 (each 3.4 to 89 s; the rest of the fast
#: suite is under 3.3 s each). By node id, a parametrised test's cases together.
SLOW = frozenset(
    {
        "tests/test_params_property.py::test_loaded_samples_build_with_every_generator",
        "tests/test_params_property.py::test_every_sample_loads_or_is_refused_naming_a_key",
        "tests/test_workspace_clearance.py::test_clearance_over_is_certified_and_limits_are_conservative",
        "tests/test_workspace_clearance.py::test_a_posed_tail_read_back_from_its_pickle_gives_the_same_clearances",
        "tests/test_workspace_clearance.py::test_bound_is_conservative_and_exact_at_rest",
        "tests/test_workspace_clearance.py::test_analyses_given_the_rest_geometry_make_no_solid_and_give_the_same_results",
        "tests/test_workspace_clearance.py::test_a_gap_between_parallel_faces_is_taken_from_the_boxes_where_attained",
        "tests/test_spec.py::test_library_imports_pause_the_garbage_collector",
        "tests/test_deferred.py::test_sklearn_cluster_loads_when_used_and_is_the_real_one",
        "tests/test_deferred.py::test_importing_the_library_changes_nothing_in_the_process",
        "tests/test_feasibility.py::test_every_file_inside_the_ranges_loads_feasible_or_is_refused_naming_a_changed_key",
        "tests/test_docs.py::test_docs_build_strict_with_every_parameter",
        "tests/test_viewer.py::test_tail_scene_meshes_do_not_depend_on_earlier_tessellations",
        "tests/test_viewer.py::test_build_twin_scene_is_the_rigid_robots_visual_meshes",
        "tests/test_viewer.py::test_every_scene_written_as_glb_in_metres",
        "tests/test_molds.py::test_variant_with_three_pleats_and_thinner_wall_passes",
        "tests/test_drawings.py::test_the_title_block_is_the_same_bytes_in_a_fresh_process",
        "tests/test_api.py::test_assembly_step_is_the_same_after_other_writes",
        "tests/test_api.py::test_readme_api_example_runs",
        "tests/test_api.py::test_posed_keeps_every_volume_and_bends_the_soas_and_rods",
        "tests/test_parts.py::test_solid_properties_are_build123d_s_three_properties_to_the_bit",
        "tests/test_parts.py::test_bounds_is_bounding_box_and_keeps_the_triangulation",
        "tests/test_ocp_viewer.py::test_the_standalone_viewer_receives_every_instance_named_and_coloured",
        "tests/test_impact.py::test_impact_steps_clean_and_shallow",
        "tests/test_robot.py::test_cart_scene_agrees_with_eq_20_22",
        "tests/test_calibration.py::test_holdout_rows_do_not_move_the_fit",
        "tests/test_sweep.py::test_lateral_stiffness_rises_with_the_rod_and_the_invertebrate_is_softest",
    }
)


def pytest_collection_modifyitems(config, items):
    """``slow``: a test that needs the full default build (``bvsr_export``, about 30 s or more) or
    is named in :data:`SLOW`. ``pytest -m "not slow"`` stays a fast suite of in-memory tests, the
    inner loop of docs/contributing.md (tools/mutate.py runs it per fault)."""
    for item in items:
        if "bvsr_export" in getattr(item, "fixturenames", ()) or item.nodeid.split("[")[0] in SLOW:
            item.add_marker(pytest.mark.slow)


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
    from bvsr_cad.build.pipeline import build_export

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
