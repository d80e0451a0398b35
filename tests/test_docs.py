"""The documentation: its generated references hold every key, and the README stays a README."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import os
import re
import subprocess
import sys
import tomllib
import typing
from html import unescape
from pathlib import Path

import pytest

from bvsr_cad.parameters.tables import TailSpec

ROOT = Path(__file__).resolve().parents[1]
SCHEMA = ROOT / "bvsr_cad" / "parameters" / "data" / "schema.toml"


def _generator():
    spec = importlib.util.spec_from_file_location(
        "docs_generate", ROOT / "docs" / "hooks" / "generate.py"
    )
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def schema_keys() -> set[str]:
    """Every dotted key a parameter file may hold, read from schema.toml itself (the tables' names
    from TailSpec's field types: which table of the schema each key of a file opens)."""
    schema = tomllib.loads(SCHEMA.read_text(encoding="utf-8"))
    hints = typing.get_type_hints(TailSpec)
    keys = set()
    for name in schema["TailSpec"]:
        typ = hints[name]
        if dataclasses.is_dataclass(typ):
            for sub, subrule in schema[typ.__name__].items():
                if "keys" in subrule:  # a table of named values, each with its own rule
                    keys |= {f"{name}.{sub}.{k}" for k in schema[subrule["keys"]]}
                else:
                    keys.add(f"{name}.{sub}")
        elif typing.get_origin(typ) is dict:  # the material table, one entry per material name
            keys |= {f"{name}.<name>.{k}" for k in schema[typing.get_args(typ)[1].__name__]}
        else:
            keys.add(name)
    return keys


def test_schema_keys_are_many():
    # The walk above must see the nested tables: the shipped schema has well over a hundred keys.
    assert len(schema_keys()) > 100
    assert {
        "joint.gap_mm",
        "materials.<name>.density_g_cm3",
        "calibration.fitted.effective_area_mm2",
    } <= schema_keys()


def test_parameter_reference_lists_every_schema_key():
    page = _generator().parameters_markdown()
    listed = set(re.findall(r"^\| `([^`]+)` \|", page, re.MULTILINE))
    assert schema_keys() - listed == set(), "schema keys missing from the parameter reference"
    assert listed - schema_keys() == set(), (
        "keys in the parameter reference that the schema does not hold"
    )


def test_parameter_reference_rows_carry_the_rules():
    """Each row shows the schema's own bounds, choices and defaults (read here from the TOML
    text)."""
    schema = tomllib.loads(SCHEMA.read_text(encoding="utf-8"))
    rows = {r["key"]: r for r in _generator().parameter_rows()}
    gap = rows["joint.gap_mm"]
    assert (gap["unit"], gap["allowed"].partition("; ")[0]) == ("mm", "> 0 and ≤ 200")
    assert "36.51" in gap["default"]  # required: the shipped file's value beside it
    assert rows["vertebra.socket"]["allowed"] == "one of `'threaded'`, `'set_screw'`"
    assert rows["pneumatics.model"]["default"] == "`'valve'`"
    assert rows["actuation.pressure_min_kpa"]["allowed"] == "≥ -101.325 and < 0"
    for key, row in rows.items():
        rule = schema[_table_of(key)][key.rsplit(".", 1)[-1]]
        for bound, sym in (("gt", ">"), ("ge", "≥"), ("lt", "<"), ("le", "≤")):
            if bound in rule:
                value = rule[bound]
                text = str(int(value)) if float(value).is_integer() else format(value, "g")
                assert f"{sym} {text}" in row["allowed"], (key, bound, row["allowed"])
        for choice in rule.get("choices", []):
            assert repr(choice) in row["allowed"], (key, choice)
        for other in rule.get("depends_on", []):  # the keys that narrow the range further
            assert f"`{other}`" in row["allowed"].partition("; narrowed by ")[2], (key, other)


def _table_of(key: str) -> str:
    """The schema table that holds a dotted key's rule."""
    if "." not in key:
        return "TailSpec"
    if key.startswith("calibration.fitted."):
        return "calibratable"
    typ = typing.get_type_hints(TailSpec)[key.split(".")[0]]
    return typing.get_args(typ)[1].__name__ if typing.get_origin(typ) is dict else typ.__name__


#: Float keys that are ratios or exponents: no unit in their name, on purpose.
DIMENSIONLESS = {
    "robot.velocity_margin",
    "fabrication_package.tube_bend_allowance",
    "pneumatics.valve_critical_pressure_ratio",
    "pneumatics.polytropic_index",
    "calibration.rms_rel_fit",
    "calibration.rms_rel_holdout",
    "calibration.rms_rel_holdout_uncalibrated",
}


def test_every_float_key_has_a_unit():
    """A new float key must carry its unit in its name (or be a declared ratio): the reference reads
    it there."""
    hints = typing.get_type_hints(TailSpec)
    floats = set()
    for name, typ in hints.items():
        if dataclasses.is_dataclass(typ):
            floats |= {f"{name}.{f}" for f, t in typing.get_type_hints(typ).items() if t is float}
    rows = {r["key"]: r for r in _generator().parameter_rows()}
    unitless = {k for k in floats if rows[k]["unit"] == "—"}
    assert unitless == DIMENSIONLESS


def test_moves_column_follows_the_stage_keys():
    """The outputs a key moves come from the build's own ignore lists: a casting allowance moves the
    mold set and its drawings only, a material's modulus the analyses but no geometry, a robot
    setting no cached stage."""
    gen = _generator()
    assert gen.stage_readers("casting.shrinkage_percent") == ["drawings", "mold set"]
    assert gen.stage_readers("materials.<name>.youngs_modulus_mpa") == ["analyses"]
    assert gen.stage_readers("robot.timestep_s") == []
    assert "robot meshes" in gen.stage_readers("robot.collision_geometry")
    assert "part files" in gen.stage_readers("vertebra.material")  # "none" removes the rod part


def test_sphinx_roles_render_as_code():
    spec = importlib.util.spec_from_file_location(
        "docs_roles", ROOT / "docs" / "hooks" / "sphinx_roles.py"
    )
    roles = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(roles)
    text = (
        "Uses :func:`~bvsr_cad.api.load`, :data:`bvsr_cad.pipeline.stages.X` and ``a``. "
        "Example::\n\n    x = 1"
    )
    assert (
        roles.markdown(text)
        == "Uses `load`, `bvsr_cad.pipeline.stages.X` and `a`. Example:\n\n    x = 1"
    )


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    """The docs site built once with `mkdocs build --strict` from the committed export summary (a
    broken link or reference fails it)."""
    mkdocs = Path(sys.executable).parent / "mkdocs"
    if not mkdocs.exists():
        pytest.skip("mkdocs not installed (the docs extra)")
    out = tmp_path_factory.mktemp("site")
    env = {k: v for k, v in os.environ.items() if k != "BVSR_DOCS_EXPORT"}
    run = subprocess.run(
        [str(mkdocs), "build", "--strict", "-q", "-d", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=300,
        env=env | {"NO_MKDOCS_2_WARNING": "1"},
    )
    assert run.returncode == 0, run.stderr[-3000:]
    return out


def _codes(html: str) -> set[str]:
    """The text of every ``<code>`` element of a page, unescaped."""
    return {unescape(c) for c in re.findall(r"<code>(.*?)</code>", html, re.DOTALL)}


def test_docs_build_strict_with_every_parameter(site):
    """The built parameter page holds every schema key."""
    html = (site / "reference" / "parameters" / "index.html").read_text(encoding="utf-8")
    assert schema_keys() - _codes(html) == set()


#: Keys the reference must show by their real names (issue 68: a digit in a key's name made it
#: ``<name>``), and name-keyed tables with their placeholders.
REAL_NAMES = {
    "params_sha256",
    "robot.ros2_package.urdf",
    "robot.ros2_package.meshes",
    "robot.chains.<file>.timestep_s",
    "robot.chains.<file>.tip_error_vs_eq2_mm",
    "robot.joint_limits.<joint>.effort",
    "robot.supply_lag_s.<line>",
    "robot.virtual_link_mass_kg",
    "parts[].density_g_cm3",
    "print_jobs[].files.3mf",
}


def _manifest_rows(site: Path) -> dict[str, list[str]]:
    """The export reference's manifest table as built: key -> its cells (type, unit, value)."""
    html = (site / "reference" / "export" / "index.html").read_text(encoding="utf-8")
    table = html[html.index('id="every-key-of-manifestjson"') :]
    rows = {}
    for row in re.findall(r"<tr>(.*?)</tr>", table, re.DOTALL):
        cells = [
            unescape(re.sub(r"<[^>]+>", "", c)).strip()
            for c in re.findall(r"<td>(.*?)</td>", row, re.DOTALL)
        ]
        if cells:
            rows[cells[0]] = cells[1:]
    return rows


def test_manifest_reference_types_and_names(site):
    """Real names, one type each (no ``list of list of ...``), a unit for every number."""
    rows = _manifest_rows(site)
    assert REAL_NAMES <= rows.keys(), sorted(REAL_NAMES - rows.keys())
    assert not [k for k in rows if "<name>" in k and not k.startswith("bom.")], (
        "keys lost to <name>"
    )
    assert {k: t for k, (t, _u, _v) in rows.items() if "list of list" in t} == {}
    assert rows["robot.chains.<file>.timestep_s"][:2] == ["number", "s"]
    assert rows["robot.ros2_package.meshes"][:2] == ["number", "count"]
    assert rows["assembly.instances[].transform[]"][:2] == ["list of number", "4 x 4 transform, mm"]
    assert rows["robot.joint_limits.<joint>.lower"][0] == "null or number"  # phi: continuous


@pytest.mark.slow
def test_every_manifest_key_is_in_the_site(bvsr_export, site):
    """Each key of a freshly built default manifest, generalised only where its table is keyed by
    names (a file, a joint, a line), is a row of the built export reference."""
    gen = _generator()
    manifest = json.loads((bvsr_export / "manifest.json").read_text(encoding="utf-8"))
    keys = set()

    def walk(v, path):
        if isinstance(v, dict):
            for k, x in v.items():
                name = gen.NAME_KEYED.get(path, "<name>" if "/" in k or " " in k else k)
                walk(x, f"{path}.{name}" if path else name)
        elif isinstance(v, list) and any(isinstance(x, (dict, list)) for x in v):
            for x in v:
                walk(x, path + "[]")
        else:
            keys.add(path)

    walk(manifest, "")
    keys = {k for k in keys if not any(o.startswith(k + "[]") for o in keys)}  # empty here only
    assert len(keys) > 200
    missing = keys - _manifest_rows(site).keys()
    assert missing == set(), (
        f"manifest keys missing from the built export reference: {sorted(missing)}"
    )


def test_cli_reference_lists_every_command_and_flag(site):
    """Every command of the parser `bvsr` runs, and every flag and positional of each, appears in
    the built command reference under that command's heading."""
    import argparse

    from bvsr_cad.cli import make_parser

    top = make_parser()
    sub = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
    html = (site / "reference" / "cli" / "index.html").read_text(encoding="utf-8")
    sections = dict(re.findall(r'<h3 id="bvsr-([a-z]+)">(.*?)(?=<h[23] |\Z)', html, re.DOTALL))
    assert set(sections) == set(sub.choices), "commands missing from (or extra in) the reference"
    assert len(sub.choices) >= 11
    missing = []
    for name, parser in sub.choices.items():
        cells = {part.strip() for code in _codes(sections[name]) for part in code.split(",")}
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            for flag in action.option_strings or [action.metavar or action.dest]:
                if flag not in cells:
                    missing.append(f"bvsr {name} {flag}")
    assert missing == []
    # the four that issue 68 found missing from the hand-written table
    for name, flag in (
        ("init", "--force"),
        ("simulate", "-o"),
        ("workspace", "--seed"),
        ("sweep", "-o"),
    ):
        assert f"bvsr {name} {flag}" not in missing and name in sections


@pytest.mark.slow
def test_export_summary_matches_the_default_build(bvsr_export):
    """The docs' export reference and paper tables read docs/data/export_summary.json: its files,
    manifest keys (type and unit), paper checks and measurement rows must be those the default file
    builds now (refresh: python docs/hooks/generate.py EXPORT). Figures may move with the models;
    names may not."""
    gen = _generator()
    fresh = json.loads(json.dumps(gen.export_summary(bvsr_export)))
    committed = json.loads(gen.EXPORT_SUMMARY.read_text(encoding="utf-8"))
    hint = "run: python docs/hooks/generate.py EXPORT on a fresh default export"
    assert fresh["files"] == committed["files"], hint
    # The volatile section's CPU seconds name the processes that ran: a build whose analyses came
    # from the session's cache (another test built the default file first) has no analyses' process.
    ran = "volatile.cpu_seconds."
    shape = {k: (v["type"], v["unit"]) for k, v in fresh["manifest_keys"].items()}
    documented = {k: (v["type"], v["unit"]) for k, v in committed["manifest_keys"].items()}
    assert {k for k in shape if k.startswith(ran)} <= {k for k in documented if k.startswith(ran)}
    assert {k: v for k, v in shape.items() if not k.startswith(ran)} == {
        k: v for k, v in documented.items() if not k.startswith(ran)
    }, hint
    assert [c["name"] for c in fresh["paper_checks"]] == [
        c["name"] for c in committed["paper_checks"]
    ], hint
    rows = [(r["row"], r["label"], r["role"]) for r in fresh["measurements"]["rows"]]
    assert rows == [(r["row"], r["label"], r["role"]) for r in committed["measurements"]["rows"]], (
        hint
    )
    assert [k for k, (t, u) in shape.items() if t.endswith("number") and u == "?"] == [], (
        "manifest numbers without a unit"
    )


def test_readme_is_short_and_undated():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.splitlines()) <= 150
    assert "make exports" in text and "make test" in text
    assert not re.search(r"\b20\d\d-\d\d-\d\d\b", text), "a date in the README"
    assert not re.search(r"\bat [0-9a-f]{7}\b", text), "a commit hash in the README"
    for link in re.findall(r"\]\(([^)#]+)", text):
        if not link.startswith("http"):
            assert (ROOT / link).exists(), link


def guide_snippet(page: str, heading: str) -> str:
    """The first ``python`` block under a guide's ``## heading``."""
    text = (ROOT / "docs" / "guides" / page).read_text(encoding="utf-8")
    section = text.split(f"\n## {heading}\n", 1)[1].split("\n## ", 1)[0]
    return re.search(r"```python\n(.*?)```", section, re.DOTALL).group(1)


@pytest.mark.slow
def test_simulation_guide_drive_snippet_runs(bvsr_export, bvsr_data, tmp_path):
    """The guide's "Drive it" snippet, run as written from a folder whose exports/bvsr is a fresh
    default export: its actuators and control range are the manifest's and the parameter file's,
    the output is what the guide says, and 2 bar on SOA 1 of every joint lowers the tip far more
    than gravity alone does (2 cm in a second)."""
    (tmp_path / "exports").mkdir()
    (tmp_path / "exports" / "bvsr").symlink_to(bvsr_export)
    run = subprocess.run(
        [sys.executable, "-c", guide_snippet("simulation.md", "Drive it")],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr[-2000:]
    head, rest, after = run.stdout.splitlines()
    manifest = json.loads((bvsr_export / "manifest.json").read_text(encoding="utf-8"))
    joints, n = manifest["joints"], len(manifest["robot"]["soa_actuators"])
    low = bvsr_data["actuation"]["pressure_min_kpa"] * 1e3
    high = bvsr_data["robot"]["pulse_pressure_max_kpa"] * 1e3
    assert head == f"{n} actuators j1_soa1 ... j{joints}_soa5, control {low:.0f} to {high:.0f} Pa"
    guide = (ROOT / "docs" / "guides" / "simulation.md").read_text(encoding="utf-8")
    assert f"`{head}`" in guide
    at_rest = json.loads(rest.split(": ")[1])
    moved = json.loads(after.split(": ")[1])
    assert f"`{rest.split(': ')[1]}`" in guide
    drop_m = at_rest[2] - moved[2]
    assert 0.05 < drop_m < 0.15  # the guide: "about 9 cm lower"
    assert abs(moved[1]) < 1e-3  # SOA 1 lies in the sagittal plane: no sideways motion


def test_one_python_range():
    """The README and the docs home state the supported Python versions as pyproject.toml's
    requires-python says them, and no other range."""
    spec = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    low, high = re.fullmatch(r">=3\.(\d+),<3\.(\d+)", spec["project"]["requires-python"]).groups()
    stated = f"Python 3.{low} to 3.{int(high) - 1}"
    for page in ("README.md", "docs/index.md"):
        text = " ".join((ROOT / page).read_text(encoding="utf-8").split())
        assert stated in text, page
        assert set(re.findall(r"Python 3\.\d+(?: to 3\.\d+)?", text)) == {stated}, page


def _faq() -> str:
    return (ROOT / "docs" / "faq.md").read_text(encoding="utf-8")


def test_faq_quotes_the_missing_extra_message(monkeypatch, capsys):
    """`bvsr sweep` with the studies extra's modules hidden prints the FAQ's line, exit code 2."""
    from bvsr_cad.cli import main
    from bvsr_cad.extras import MODULES

    for module in MODULES["studies"]:
        monkeypatch.setitem(sys.modules, module, None)  # importlib finds no spec: "not installed"
    assert main(["sweep", str(ROOT / "studies" / "vertebra.toml")]) == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert line.startswith("bvsr: error: bvsr sweep needs the 'studies' extra")
    assert line in _faq()


def test_faq_quotes_the_no_viewer_message(monkeypatch, capsys):
    """`bvsr show` with nothing listening on the viewer's port prints the FAQ's line for that
    port, exit code 2."""
    import socket

    from bvsr_cad.cli import main

    with socket.socket() as s:  # a port nothing listens on once closed
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    monkeypatch.delenv("OCP_PORT", raising=False)
    assert main(["show", "--port", str(port)]) == 2
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert line.startswith("bvsr: error: no OCP CAD Viewer listens on port")
    assert line.replace(str(port), "3939") in _faq()


def test_faq_quotes_the_missing_slicer_message(monkeypatch):
    """Slicing without PrusaSlicer raises the FAQ's message before it reads any export."""
    from bvsr_cad.checks import slicer

    monkeypatch.setattr(slicer, "slicer_exe", lambda: None)
    with pytest.raises(slicer.SlicerMissingError) as err:
        slicer.slice_stls(None)
    assert f"bvsr: error: {err.value}" in _faq()
