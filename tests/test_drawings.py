"""Drawings: a sheet per panel and per mold part, whose hole table equals the bores found
independently on the part's B-rep (its cylindrical faces), with the params SHA-256 in the title
block."""

from __future__ import annotations

import hashlib
import json
import xml.etree.ElementTree as ET
from pathlib import Path

import build123d as bd
import numpy as np
import pytest

NS = {"s": "http://www.w3.org/2000/svg"}


def _rows(svg: Path) -> list[list[str]]:
    root = ET.parse(svg).getroot()  # parses: a well-formed SVG document
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    table = root.find(".//s:g[@id='hole-table']", NS)
    return [
        [t.text for t in g.findall("s:text", NS)]
        for g in table.findall("s:g[@class='hole-row']", NS)
    ]


def _bores(solid: bd.Solid) -> tuple[list[float], list[float]]:
    """(hole diameters, pin diameters) from the B-rep alone: cylindrical faces grouped into one bore
    per radius, axis line and connected axial span; a hole's face points at its axis, a pin's away
    from it."""
    groups: list[dict] = []
    for f in solid.faces():
        if f.geom_type != bd.GeomType.CYLINDER:
            continue
        ax = f.axis_of_rotation
        p, d = np.array([*ax.position]), np.array([*ax.direction])
        on = np.array([*f.center()])  # a point of the face
        radial = (on - p) - ((on - p) @ d) * d
        inward = float(np.array([*f.normal_at(f.center())]) @ radial) < 0
        s = sorted(float((np.array([*v]) - p) @ d) for v in f.vertices())
        for g in groups:
            off = p - g["p"]
            if (
                abs(g["r"] - f.radius) < 1e-4
                and abs(abs(g["d"] @ d) - 1) < 1e-6
                and np.linalg.norm(off - (off @ g["d"]) * g["d"]) < 1e-3
            ):
                shift = float(off @ g["d"])
                lo, hi = sorted(x * float(g["d"] @ d) + shift for x in (s[0], s[-1]))
                if lo <= g["hi"] + 1e-3 and hi >= g["lo"] - 1e-3:
                    g["lo"], g["hi"] = min(g["lo"], lo), max(g["hi"], hi)
                    break
        else:
            groups.append({"p": p, "d": d, "r": f.radius, "lo": s[0], "hi": s[-1], "in": inward})
    holes = sorted(round(2 * g["r"], 3) for g in groups if g["in"])
    pins = sorted(round(2 * g["r"], 3) for g in groups if not g["in"])
    return holes, pins


@pytest.fixture(scope="module")
def sheets(bvsr_export) -> dict:
    manifest = json.loads((bvsr_export / "manifest.json").read_text())
    return {"manifest": manifest, "by_item": {s["item"]: s for s in manifest["drawings"]["sheets"]}}


def test_a_sheet_per_panel_and_mold_part_listed_with_its_sha256(bvsr_export, sheets):
    manifest = sheets["manifest"]
    panels = [p["name"] for p in manifest["parts"] if p["kind"] == "panel"]
    molds = [f"mold_{p['name']}" for p in manifest["molds"]["parts"]]
    assert len(panels) == manifest["panels"] and len(molds) == 5
    assert sorted(sheets["by_item"]) == sorted(panels + molds)
    for s in sheets["by_item"].values():
        assert hashlib.sha256((bvsr_export / s["svg"]).read_bytes()).hexdigest() == s["sha256"]
    report = (bvsr_export / "report.html").read_text()
    assert all(f"href='{s['svg']}'" in report for s in sheets["by_item"].values())


def test_hole_tables_equal_the_bores_of_the_brep(bvsr_export, sheets):
    for item, s in sheets["by_item"].items():
        folder, name = (
            ("molds/step", item.removeprefix("mold_"))
            if item.startswith("mold_")
            else ("step", item)
        )
        solid = bd.import_step(bvsr_export / folder / f"{name}.step").solids()[0]
        holes, pins = _bores(solid)
        rows = _rows(bvsr_export / s["svg"])
        assert len(rows) == s["holes"]
        table_holes = sorted(round(float(r[6]), 3) for r in rows if not r[0].startswith("P"))
        table_pins = sorted(round(float(r[6]), 3) for r in rows if r[0].startswith("P"))
        # the table gives 2 decimals
        assert table_holes == pytest.approx(holes, abs=5.1e-3), item
        if item.startswith(
            "mold_"
        ):  # a mold part's only outer cylinders are its pins (a panel's rim is a cone)
            assert table_pins == pytest.approx(pins, abs=5.1e-3), item
        else:
            assert table_pins == []


def test_hole_table_says_thread_and_tap_drill_and_through_or_blind(bvsr_export, sheets, bvsr_spec):
    from bvsr_cad.parameters.standard_parts import metric

    root = _rows(bvsr_export / sheets["by_item"]["panel0"]["svg"])
    rod = metric(bvsr_spec.vertebra.diameter_mm)
    bore = next(r for r in root if r[1] == "rod_bore")
    assert (
        bore[7] == "through"
        and bore[8] == f"M{rod.diameter_mm:g}x{rod.pitch_mm:g} tap, drill {rod.tap_drill_mm:g}"
    )
    assert float(bore[6]) == pytest.approx(
        rod.tap_drill_mm + bvsr_spec.fabrication.hole_compensation_mm
    )
    ports = [r for r in root if r[1].startswith("fitting_port")]
    assert len(ports) == 5 and all(
        r[8].startswith("M5x0.8 tap") and r[7] == "through" for r in ports
    )
    inserts = [r for r in root if r[1].startswith("mount_insert")]
    assert [r[7] for r in inserts] == [f"blind, {bvsr_spec.mount.insert_depth_mm:.2f} deep"] * 5
    plate = _rows(bvsr_export / sheets["by_item"]["mold_bottom_plate"]["svg"])
    bolts = [r for r in plate if r[1].startswith("bolt")]
    assert len(bolts) == 4 and all(r[7] == "through" and r[8] == "clearance M3" for r in bolts)


def test_title_block_carries_the_params_sha256_material_and_process(bvsr_export, sheets):
    manifest = sheets["manifest"]
    for item, s in sheets["by_item"].items():
        root = ET.parse(bvsr_export / s["svg"]).getroot()
        block = root.find(".//s:g[@id='title-block']", NS)
        text = {t.get("class"): t.text for t in block.findall("s:text", NS) if t.get("class")}
        assert text["title-params-sha-256"] == manifest["params_sha256"]
        assert text["title-part"] == item
        if item.startswith("panel"):
            part = next(p for p in manifest["parts"] if p["name"] == item)
            assert (
                text["title-material"].startswith(part["material"] + ":")
                and text["title-process"] == part["process"]
            )


def test_same_geometry_gives_the_same_sheet(bvsr_spec):
    """Two draws of one geometry are byte-identical (the export-wide determinism is
    test_cache's)."""
    from bvsr_cad.exporters.drawings import draw_sheet
    from bvsr_cad.parts.mold import mold_set

    lid = mold_set(bvsr_spec.soa, bvsr_spec.joint.base_diameter_mm, bvsr_spec.casting).parts["lid"]
    views = [["top"], ["front", "right"]]
    first, n = draw_sheet("mold_lid", lid.solid, list(lid.features), views)
    assert draw_sheet("mold_lid", lid.solid, list(lid.features), views) == (first, n)
    assert (
        n == len(lid.features) == 4 + 1 + 4 + 2
    )  # the lid: vents, flange pocket, bolts, pins: one row each


def test_the_title_block_is_the_same_bytes_in_a_fresh_process(bvsr_spec):
    """A build that takes the sheets from the cache never runs build123d's SVG export (which
    registers SVG as ElementTree's default namespace, process-wide): its stamped title block must
    not change."""
    import subprocess
    import sys

    from bvsr_cad.exporters.drawings import _title_block

    code = (
        "import sys; from bvsr_cad.exporters.drawings import _title_block as t; "
        "from bvsr_cad.parameters.load import load_spec\n"
        "class I: material, process, quantity = 'PA12_MJF', 'MJF', 1\n"
        "sys.stdout.buffer.write(t('panel0', I, load_spec(sys.argv[1]), 'f' * 64))"
    )
    params = Path(__file__).resolve().parents[1] / "params" / "bvsr.toml"
    fresh = subprocess.run(
        [sys.executable, "-c", code, str(params)], capture_output=True, check=True
    ).stdout

    class Item:
        material, process, quantity = "PA12_MJF", "MJF", 1

    ET.register_namespace(
        "svg", "http://www.w3.org/2000/svg"
    )  # whatever another module registered before
    assert _title_block("panel0", Item, bvsr_spec, "f" * 64) == fresh
    assert fresh.startswith(b'<g xmlns="http://www.w3.org/2000/svg" id="title-block"')


def test_dimensions_are_the_parts_extents_along_each_views_axes(bvsr_export, sheets):
    """Each view's overall dimensions (its width, and a side view's height) read the part's B-rep
    extent along the view's horizontal and vertical axes, found here from the STEP file's bounding
    box."""
    axes = {"top": ("X", None), "front": ("X", "Z"), "right": ("Y", "Z")}
    for item, s in sheets["by_item"].items():
        folder, name = (
            ("molds/step", item.removeprefix("mold_"))
            if item.startswith("mold_")
            else ("step", item)
        )
        size = (
            bd.import_step(bvsr_export / folder / f"{name}.step")
            .solids()[0]
            .bounding_box(optimal=True)
            .size
        )
        root = ET.parse(bvsr_export / s["svg"]).getroot()
        read = [
            float(t.text)
            for t in root.findall(".//s:g[@id='dimensions']/s:g[@class='dim']/s:text", NS)
        ]
        views = [
            t.text.split(" ")[0]
            for t in root.findall(".//s:g[@id='views']/s:text", NS)
            if " (looking along " in (t.text or "")
        ]
        expected = [getattr(size, a) for v in views for a in axes[v] if a is not None]
        assert views[0] == "top" and len(read) == len(expected) == (
            3 if item.startswith("panel") else 5
        ), item
        assert read == pytest.approx(expected, abs=0.006), item
