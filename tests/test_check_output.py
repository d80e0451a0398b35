"""`bvsr check` reads at a glance: one line per check group, every failure in full, the paper
comparisons, and a missing tool named once. `--verbose` lists every check, `--json` every result."""

from __future__ import annotations

import json

import pytest

from bvsr_cad.checks.result import CheckResult, summary_lines
from bvsr_cad.cli import main

#: The issue's bound for a passing default export: a screen, not a log.
MAX_SUMMARY_LINES = 40


def _results() -> list[CheckResult]:
    ok = [
        CheckResult(f"stl_watertight:part{i}", True, 0, 0, "open edges", f"stl/part{i}.stl")
        for i in range(30)
    ]
    return ok + [
        CheckResult("stl_volume:part9", False, 12.5, 10.0, "mm3", "stl/part9.stl", "too big"),
        CheckResult("paper:tail_mass", None, 211.5, 283.0, "g", "Table IV", "computed 211.5"),
        CheckResult("print_overhang:a", None, 3.0, 0.0, "mm2", "print/a.stl"),
        CheckResult(
            "slice:a", None, None, 0, "errors", "print/a.stl", "prusa-slicer is not installed"
        ),
        CheckResult(
            "slice:b", None, None, 0, "errors", "print/b.stl", "prusa-slicer is not installed"
        ),
    ]


def test_the_summary_counts_each_group_and_prints_failures_and_paper_rows_in_full():
    lines = summary_lines(_results())
    # Counted by hand from _results(): 30 passing STL checks and one failing; one overhang row, two
    # slices.
    assert lines[0].split() == ["FAIL", "stl", "30", "passed,", "1", "failed"]
    assert lines[1].split() == ["INFO", "paper", "1", "informational"]
    assert lines[2].split() == ["INFO", "print", "1", "informational"]
    assert lines[3].split() == ["SKIP", "slice", "2", "skipped"]
    assert "FAIL  stl_volume:part9: 12.5 mm3 (limit 10 mm3) [stl/part9.stl]  too big" in lines
    assert "INFO  paper:tail_mass: 211.5 g (limit 283 g) [Table IV]  computed 211.5" in lines
    assert not any("print_overhang" in line for line in lines)  # counted in its group, not listed
    assert lines.count("slice: prusa-slicer is not installed") == 1  # one reason, said once
    assert not any("None" in line for line in lines)


def test_a_skipped_check_never_prints_none():
    row = CheckResult(
        "urdf_check_urdf", None, None, 0, "exit code", "robot/bvsr.urdf", "check_urdf not installed"
    )
    assert (
        row.skipped
        and row.line() == "SKIP  urdf_check_urdf [robot/bvsr.urdf]  check_urdf not installed"
    )


def test_a_passing_default_export_reads_at_a_glance(bvsr_export, capsys):
    assert main(["check", str(bvsr_export), "-q"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) <= MAX_SUMMARY_LINES, "\n".join(out)
    assert "None" not in "\n".join(out)
    assert main(["check", str(bvsr_export), "-q", "--json"]) == 0
    checks = json.loads(capsys.readouterr().out)["checks"]
    # Every group of the JSON result has its own line, and the paper rows are all listed.
    groups = {c["name"].split(":", 1)[0].split("_", 1)[0] for c in checks}
    assert {
        line.split()[1] for line in out if line[:4] in ("PASS", "INFO", "SKIP", "FAIL")
    } >= groups
    paper = [c["name"] for c in checks if c["name"].startswith("paper:")]
    assert paper and all(any(f"  {name}:" in line for line in out) for name in paper)
    assert main(["check", str(bvsr_export), "-q", "--verbose"]) == 0
    assert (
        len(capsys.readouterr().out.splitlines()) == len(checks) + 1
    )  # every check, then the total


def test_check_takes_the_builds_verdicts_of_unchanged_files_and_no_cache_runs_every_check(
    small_tail, small_export, tmp_path, capsys, monkeypatch
):
    """The build kept its check groups' verdicts in its artifact cache (the CI-sized tail's):
    `bvsr check` of a copy of its export takes the mold checks' verdicts from there (the checks
    themselves, broken here, never run) and gives the same JSON as `--no-cache`, which runs every
    check (and meets the broken one); a mold file changed by one byte is checked again."""
    import shutil

    from bvsr_cad.checks import run

    monkeypatch.setenv("BVSR_CACHE", str(small_tail / "cache"))
    copy = tmp_path / "copy"
    shutil.copytree(small_export, copy)
    assert main(["check", str(copy), "-q", "--json", "--no-cache"]) == 0
    fresh = json.loads(capsys.readouterr().out)["checks"]

    def broken(_exp):
        raise AssertionError("the mold checks ran")

    monkeypatch.setattr(run, "check_molds", broken)
    assert main(["check", str(copy), "-q", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["checks"] == fresh
    with pytest.raises(AssertionError, match="the mold checks ran"):
        main(["check", str(copy), "-q", "--json", "--no-cache"])
    mold = next((copy / "molds").rglob("*.stl"))
    mold.write_bytes(mold.read_bytes() + b"\n")
    with pytest.raises(AssertionError, match="the mold checks ran"):
        main(["check", str(copy), "-q", "--json"])
