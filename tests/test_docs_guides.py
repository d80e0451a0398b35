"""The user guides' generated parts: the designer's figure of the paper's symbols and the lab's
table of measurement quantities (docs/hooks/guides.py)."""

from __future__ import annotations

import importlib.util
import re
import tomllib
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SVG = "{http://www.w3.org/2000/svg}"
#: The paper's Table I and II: symbol -> (table, key) of params/bvsr.toml, written out here, not
#: read from the drawing code.
SYMBOL_KEYS = {
    "H_j": ("joint", "joint_height_mm"),
    "H_a": ("joint", "gap_mm"),
    "D_a": ("joint", "pitch_diameter_mm"),
    "D_p": ("joint", "panel_diameter_mm"),
    "D_b": ("joint", "base_diameter_mm"),
    "H": ("soa", "height_mm"),
    "a": ("soa", "short_side_mm"),
    "b": ("soa", "long_side_mm"),
}
#: The paper's printed values (Tables I and II), for the shipped file.
PAPER_MM = {
    "H_j": 42.51,
    "H_a": 36.51,
    "D_a": 45.87,
    "D_p": 70.94,
    "D_b": 24.32,
    "H": 37.60,
    "a": 5.30,
    "b": 18.21,
}


def _hook():
    spec = importlib.util.spec_from_file_location("guides_hook", ROOT / "docs/hooks/guides.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def figure() -> ET.Element:
    return ET.fromstring(_hook().parameter_figure_svg(ROOT / "params" / "bvsr.toml"))


def _text(el: ET.Element) -> str:
    return "".join(el.itertext()).strip()


def test_figure_prints_each_symbol_at_its_parameter_value(figure):
    """Each dimension's printed value equals its key's value in params/bvsr.toml (and the paper's
    table), and each symbol is dimensioned exactly once."""
    data = tomllib.loads((ROOT / "params" / "bvsr.toml").read_text(encoding="utf-8"))
    dims = {g.get("data-symbol"): g for g in figure.iter(f"{SVG}g") if g.get("class") == "dim"}
    assert sorted(dims) == sorted(SYMBOL_KEYS)
    for symbol, (table, key) in SYMBOL_KEYS.items():
        printed = _text(dims[symbol].find(f"{SVG}text"))
        name, value = (s.strip() for s in printed.split("="))
        assert name == symbol.replace("_", "")  # the subscript is a lowered tspan
        assert float(value) == pytest.approx(data[table][key], abs=0.005), symbol
        assert float(value) == pytest.approx(PAPER_MM[symbol], abs=0.005), symbol


def test_figure_legend_names_each_symbol_with_its_key(figure):
    rows = {
        g.get("data-symbol"): g for g in figure.iter(f"{SVG}g") if g.get("class") == "legend-row"
    }
    assert sorted(rows) == sorted(SYMBOL_KEYS)
    data = tomllib.loads((ROOT / "params" / "bvsr.toml").read_text(encoding="utf-8"))
    for symbol, (table, key) in SYMBOL_KEYS.items():
        texts = [_text(t) for t in rows[symbol].findall(f"{SVG}text")]
        assert f"{table}.{key}" in texts
        assert f"{data[table][key]:.2f} mm" in texts


def test_schema_docs_name_the_same_symbols():
    """The schema's doc of each key begins with the paper's symbol the figure puts beside it."""
    from bvsr_cad.exporters.parameter_figure import PAPER_SYMBOLS

    schema = tomllib.loads(
        (ROOT / "bvsr_cad/parameters/data/schema.toml").read_text(encoding="utf-8")
    )
    tables = {"joint": "JointTable", "soa": "SoaTable"}
    for symbol, (table, key) in SYMBOL_KEYS.items():
        assert PAPER_SYMBOLS[symbol][0] == f"{table}.{key}"
        assert schema[tables[table]][key]["doc"].startswith(f"{symbol},"), symbol


def test_figure_follows_an_edited_file(tmp_path):
    """A file with other Table I/II values gives a figure that prints those values."""
    text = (ROOT / "params" / "bvsr.toml").read_text(encoding="utf-8")
    text = text.replace("panel_diameter_mm = 70.94", "panel_diameter_mm = 72.00")
    text = text.replace("long_side_mm = 18.21", "long_side_mm = 18.00")
    edited = tmp_path / "params" / "edited.toml"
    edited.parent.mkdir()
    edited.write_text(text, encoding="utf-8")
    root = ET.fromstring(_hook().parameter_figure_svg(edited))
    printed = {
        g.get("data-symbol"): _text(g.find(f"{SVG}text")).split("=")[1].strip()
        for g in root.iter(f"{SVG}g")
        if g.get("class") == "dim"
    }
    assert printed["D_p"] == "72.00" and printed["b"] == "18.00"
    assert printed["H_j"] == "42.51"


def _table_rows(markdown: str) -> dict[str, list[str]]:
    rows = {}
    for line in markdown.splitlines()[2:]:
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line)[1:-1]]
        rows[cells[0].split("`")[1]] = cells
    return rows


def test_measurement_table_has_every_quantity_with_its_unit_and_keys():
    """One row per quantity the loader accepts, with the unit string and every condition key a
    row must give (checked against a CSV the loader reads)."""
    from bvsr_cad.parameters.measurements import QUANTITIES, load_measurements

    rows = _table_rows(_hook().measurement_quantities_markdown())
    assert sorted(rows) == sorted(QUANTITIES)
    # The paper's data file: every quantity it uses, with the unit and the condition keys the table
    # gives, is what the loader accepted.
    for m in load_measurements(ROOT / "data" / "paper_bvsr.csv"):
        cells = rows[m.quantity]
        assert cells[1] == f"`{m.unit}`"
        assert sorted(re.findall(r"`([a-z_]+)`", cells[2])) == sorted(k for k, _v in m.conditions)
    # The workspace's conditions, as the loader's QUANTITIES declares them.
    assert re.findall(r"`([a-z_]+)`", rows["tip_workspace_radius"][2]) == [
        "segments",
        "pressurised_max_kpa_abs",
        "depressurised_min_kpa_abs",
    ]


def test_measurement_table_names_the_values_each_quantity_informs():
    """The calibration's own rule (its module docstring): quasi-static rows identify A and the
    rod's E I, dynamic rows the valve's conductance, the damping only on request; the SOA stiffness
    line is a check of the tables' values."""
    rows = _table_rows(_hook().measurement_quantities_markdown())
    informs = {q: cells[4] for q, cells in rows.items()}
    assert informs["segment_max_angle"] == ("`effective_area_mm2`, `rod_flexural_rigidity_n_mm2`")
    assert informs["segment_peak_velocity"] == (
        "`valve_sonic_conductance_l_s_bar`; with `--fit`: `damping_n_s_per_m`"
    )
    assert informs["soa_stiffness"].startswith("none")
    assert "damping_n_s_per_m" not in informs["segment_blocked_force"]
    assert informs["tip_workspace_radius"].startswith(
        "`effective_area_mm2`, `rod_flexural_rigidity_n_mm2`, `valve_sonic_conductance_l_s_bar`"
    )


def test_every_quantity_says_how_to_measure_it():
    from bvsr_cad.parameters.measurements import HOW_TO_MEASURE, QUANTITIES

    assert set(HOW_TO_MEASURE) == set(QUANTITIES)
    rows = _table_rows(_hook().measurement_quantities_markdown())
    for q, how in HOW_TO_MEASURE.items():
        assert rows[q][3] == re.sub(r"``([^`]+)``", r"`\1`", how).replace("|", "\\|")
