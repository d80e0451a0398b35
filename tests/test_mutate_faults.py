"""``tools/mutate.py`` checks that the tests catch physically wrong answers by applying each of its
faults to the source: a fault whose snippet no longer occurs in the code (the code moved on) checks
nothing and fails silently. Each must apply, exactly once, and name the tests that catch it
(``--targeted`` runs each fault against those alone): every named test must exist."""

from __future__ import annotations

import ast
import importlib.util
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def mutate():
    spec = importlib.util.spec_from_file_location("bvsr_mutate", ROOT / "tools" / "mutate.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["bvsr_mutate"] = module  # its dataclasses look their module up
    try:
        spec.loader.exec_module(module)
        yield module
    finally:
        sys.modules.pop("bvsr_mutate", None)


def test_every_fault_of_the_mutation_check_applies_to_the_code_as_it_is(mutate):
    assert len(mutate.FAULTS) >= 40
    assert len({f.name for f in mutate.FAULTS}) == len(mutate.FAULTS)
    assert mutate.snippet_problems(ROOT, mutate.FAULTS) == []


def _test_functions(path: Path) -> dict[str, bool]:
    """Module-level test functions of a test file -> whether it is parametrised."""
    tree = ast.parse(path.read_text())
    return {
        node.name: any("parametrize" in ast.unparse(d) for d in node.decorator_list)
        for node in tree.body
        if isinstance(node, ast.FunctionDef) and node.name.startswith("test_")
    }


def test_every_fault_names_catchers_that_exist(mutate):
    """A node id ``tests/file.py::test_name`` or ``...::test_name[case]`` (a case only of a
    parametrised test); the self-test is no catcher (it fails under every fault)."""
    files: dict[str, dict[str, bool]] = {}
    for f in mutate.FAULTS:
        assert f.catchers, f"fault {f.name} names no test that catches it"
        for c in f.catchers:
            path, _, name = c.partition("::")
            assert path != mutate.SELF_TEST, c
            assert (ROOT / path).is_file(), f"fault {f.name}: {path} does not exist"
            funcs = files.setdefault(path, _test_functions(ROOT / path))
            func, case = name.split("[", 1) if "[" in name else (name, None)
            assert func in funcs, f"fault {f.name}: no test {func} in {path}"
            assert case is None or (funcs[func] and case.endswith("]")), (
                f"fault {f.name}: {c} is not a case"
            )


def test_a_catcher_id_without_its_case_stands_for_every_case(mutate):
    failed = {"tests/a.py::test_x[1]", "tests/a.py::test_y", "tests/a.py::test_zz"}
    assert mutate.missed_catchers(
        ("tests/a.py::test_x", "tests/a.py::test_y", "tests/a.py::test_z", "tests/a.py::test_x[2]"),
        failed,
    ) == ["tests/a.py::test_z", "tests/a.py::test_x[2]"]
    summary = (
        "FAILED tests/a.py::test_x[1] - AssertionError: 1 != 2\n"
        "ERROR tests/b.py::test_y - RuntimeError\nPASSED tests/c.py::test_z\n"
    )
    assert mutate.failed_ids(summary) == {"tests/a.py::test_x[1]", "tests/b.py::test_y"}


def test_a_targeted_run_catches_names_a_catcher_that_stopped_and_never_touches_the_tree(
    mutate, tmp_path, monkeypatch, capsys
):
    """On a two-file project: a fault both its catchers catch is caught; one of whose catchers
    passes is PARTIAL (exit 1); the project's files are the same bytes afterwards (faults go to
    private copies)."""
    (tmp_path / "tests").mkdir()
    (tmp_path / "area.py").write_text("def square_mm2(side_mm):\n    return side_mm * side_mm\n")
    (tmp_path / "tests" / "test_area.py").write_text(
        "from area import square_mm2\n\n\n"
        "def test_by_hand():\n    assert square_mm2(3.0) == 9.0\n\n\n"
        "def test_positive():\n    assert square_mm2(-2.0) > 0\n"
    )
    before = {p: p.read_bytes() for p in tmp_path.rglob("*.py")}
    monkeypatch.setattr(
        mutate,
        "FAULTS",
        [
            mutate.Fault(
                "cubed",
                "area.py",
                "side_mm * side_mm",
                "side_mm * side_mm * side_mm",
                "a cube",
                catchers=("tests/test_area.py::test_by_hand", "tests/test_area.py::test_positive"),
            ),
            mutate.Fault(
                "doubled",
                "area.py",
                "side_mm * side_mm",
                "2 * side_mm * side_mm",
                "twice the area",
                catchers=("tests/test_area.py::test_by_hand", "tests/test_area.py::test_positive"),
            ),
        ],
    )
    monkeypatch.setattr(
        mutate.signal, "signal", lambda *a: None
    )  # this test session keeps its own handlers
    assert mutate.main(["--root", str(tmp_path), "--targeted", "--jobs", "2", "--json"]) == 1
    report = json.loads(capsys.readouterr().out)
    rows = {r["name"]: r for r in report["faults"]}
    assert rows["cubed"]["result"] == "caught" and rows["cubed"]["missed"] == []
    assert rows["doubled"]["result"] == "PARTIAL"
    assert rows["doubled"]["missed"] == ["tests/test_area.py::test_positive"]
    assert report["baseline"]["result"] == "passed"
    assert {p: p.read_bytes() for p in tmp_path.rglob("*.py")} == before
