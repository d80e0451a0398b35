"""The designer's figure: the paper's Table I and II symbols dimensioned on a joint and an SOA.

One SVG (mm) drawn with the drawing sheets' own code (:mod:`bvsr_cad.exporters.drawings`: the
hidden-line projection, the dimension lines and their text), from a tail's parameters:

- the first joint seen from the front (the root panel, the next panel and the joint's five SOAs):
  H_j, H_a and D_p;
- the root panel seen from above with the SOAs' pitch circle: D_a;
- one SOA seen from the front, its square's sides parallel to the view: H, D_b, a and b.

Every length is measured on the geometry the build makes (the placed solids' extents, the SOA's
fold edges), except D_a, the pitch circle at the root face, which no edge draws: it is the panel
layout's. A legend names each symbol's key in the parameter file. The documentation's hook calls
:func:`parameter_figure` at every docs build, so the figure cannot fall behind the code.
"""

from __future__ import annotations

import io
import xml.etree.ElementTree as ET

import build123d as bd

from ..assembly.assemble import Assembly, instance_solid
from ..parts.soa import bellows_profile, soa_envelope
from .drawings import SVG_NS, Dimension, _dimensions, _placed, _project, _SheetSVG, _text

#: The symbols drawn (the paper's Table I and II): symbol -> (parameter-file key, what it is).
PAPER_SYMBOLS: dict[str, tuple[str, str]] = {
    "H_j": ("joint.joint_height_mm", "one joint"),
    "H_a": ("joint.gap_mm", "between two panels"),
    "D_a": ("joint.pitch_diameter_mm", "actuator circle (root)"),
    "D_p": ("joint.panel_diameter_mm", "end panel (root)"),
    "D_b": ("joint.base_diameter_mm", "actuator base"),
    "H": ("soa.height_mm", "SOA height"),
    "a": ("soa.short_side_mm", "facet short side"),
    "b": ("soa.long_side_mm", "facet long side"),
}
FIGURE_MM = (230.0, 118.0)
#: Each view's scale and the sheet point (mm, y up) of its model origin.
JOINT_VIEW = (1.0, (57.0, 52.0))
TOP_VIEW = (0.75, (138.0, 78.0))
SOA_VIEW = (1.5, (205.0, 44.0))
EXT_MM = 1.5  # how far an extension line runs past its dimension line
_EXT_STYLE = {"stroke": "#555", "stroke-width": "0.13", "fill": "none"}


def measured_symbols(asm: Assembly) -> dict[str, float]:
    """Each symbol's length (mm) measured on the tail ``asm`` builds; D_a from the root panel's
    layout (the pitch circle at its lower face)."""
    p0 = instance_solid(asm, asm.panel(0)).bounding_box()
    p1 = instance_solid(asm, asm.panel(1)).bounding_box()
    soa = asm.parts["soa"].solid.bounding_box()
    return {
        "H_j": p1.min.Z - p0.min.Z,
        "H_a": p1.min.Z - p0.max.Z,
        "D_a": 2.0 * asm.panel_layouts[0].pitch_radius_lower_mm,
        "D_p": p0.max.X - p0.min.X,
        "D_b": soa.max.X - soa.min.X,
        "H": soa.max.Z - soa.min.Z,
        "a": _fold_width_mm(asm, 1),
        "b": _fold_width_mm(asm, 2),
    }


def _fold_z_mm(asm: Assembly, fold: int) -> float:
    return bellows_profile(asm.spec.soa, asm.spec.joint.base_diameter_mm).z_mm[fold]


def _fold_width_mm(asm: Assembly, fold: int) -> float:
    """The SOA's outer width along X at a fold (odd: a valley fold, even: a mountain fold),
    measured on the envelope's edges that lie in the fold's plane."""
    z = _fold_z_mm(asm, fold)
    env = soa_envelope(asm.spec.soa, asm.spec.joint.base_diameter_mm)
    flat = [e for e in env.edges() if abs(e.bounding_box().min.Z - z) < 1e-6]
    flat = [e for e in flat if abs(e.bounding_box().max.Z - z) < 1e-6]
    box = bd.Compound(flat).bounding_box()
    return box.max.X - box.min.X


def _view(
    svg: _SheetSVG, solid: bd.Shape, view: str, where: tuple[float, tuple[float, float]]
) -> None:
    visible, _hidden = _project(solid, view)
    scale, origin = where
    svg.add_shape(_placed(visible, scale, origin), "visible")


def _at(where: tuple[float, tuple[float, float]], u: float, v: float) -> tuple[float, float]:
    scale, (x0, y0) = where
    return x0 + scale * u, y0 + scale * v


def parameter_figure(asm: Assembly) -> bytes:
    """The figure as SVG bytes (mm): views, dimensions (``<g class="dim" data-symbol=...>``, their
    text "symbol = value"), view captions and the legend of symbols and keys."""
    m = measured_symbols(asm)
    w, h = FIGURE_MM
    svg = _SheetSVG(unit=bd.Unit.MM, margin=0.0, fit_to_stroke=False)
    svg.add_layer("frame", line_weight=0.0, line_color=(1.0, 1.0, 1.0))
    svg.add_layer("visible", line_weight=0.25)
    svg.add_layer("centre", line_weight=0.13, line_type=bd.LineType.ISO_DASH_DOT)
    pts = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h), (0.0, 0.0)]
    svg.add_shape([bd.Edge.make_line(a, b) for a, b in zip(pts, pts[1:])], "frame")
    joint = [asm.panel(0), asm.panel(1), *asm.soas_of_joint(1)]
    _view(svg, bd.Compound([instance_solid(asm, i) for i in joint]), "front", JOINT_VIEW)
    _view(svg, instance_solid(asm, asm.panel(0)), "top", TOP_VIEW)
    _view(svg, asm.parts["soa"].solid, "front", SOA_VIEW)
    pitch = bd.Edge.make_circle(m["D_a"] / 2.0)
    svg.add_shape(_placed([pitch], TOP_VIEW[0], TOP_VIEW[1]), "centre")
    buf = io.BytesIO()
    svg.write(buf)
    ET.register_namespace("", SVG_NS)
    root = ET.fromstring(buf.getvalue())
    root.set("id", "parameter-figure")
    dims, lines = _symbol_dimensions(asm, m)
    ext = ET.SubElement(root, f"{{{SVG_NS}}}g", {"id": "extension-lines", **_EXT_STYLE})
    for (x1, y1), (x2, y2) in lines:
        ET.SubElement(
            ext,
            f"{{{SVG_NS}}}line",
            {"x1": f"{x1:.3f}", "y1": f"{-y1:.3f}", "x2": f"{x2:.3f}", "y2": f"{-y2:.3f}"},
        )
    _dimensions(root, [d for _s, d in dims])
    for (symbol, _d), g in zip(dims, root.find(f"{{{SVG_NS}}}g[@id='dimensions']")):
        g.set("data-symbol", symbol)
        _symbol_text(g.find(f"{{{SVG_NS}}}text"), symbol, f" = {_d.text()}")
    _captions(root)
    _legend(root, m)
    ET.indent(root, "  ")
    return ET.tostring(root, encoding="unicode").encode() + b"\n"


def _symbol_dimensions(asm: Assembly, m: dict[str, float]) -> tuple[list, list]:
    """(symbol, Dimension) of each symbol, and the extension lines (sheet point pairs)."""
    lay0 = asm.panel_layouts[0]
    r_p, t0 = m["D_p"] / 2.0, lay0.thickness_mm
    dims, lines = [], []

    def horizontal(symbol, where, u0, u1, v_from, v_line):
        a, b = _at(where, u0, v_line), _at(where, u1, v_line)
        dims.append((symbol, Dimension(a, b, m[symbol])))
        sign = 1.0 if v_line > v_from else -1.0
        for u in (u0, u1):
            lines.append((_at(where, u, v_from), (_at(where, u, v_line)[0], a[1] + sign * EXT_MM)))

    def vertical(symbol, where, v0, v1, u_from, u_line):
        a, b = _at(where, u_line, v0), _at(where, u_line, v1)
        dims.append((symbol, Dimension(a, b, m[symbol])))
        sign = 1.0 if u_line > u_from else -1.0
        for v in (v0, v1):
            lines.append((_at(where, u_from, v), (a[0] + sign * EXT_MM, _at(where, u_line, v)[1])))

    vertical("H_j", JOINT_VIEW, 0.0, m["H_j"], -r_p, -r_p - 9.0)
    vertical("H_a", JOINT_VIEW, t0, t0 + m["H_a"], r_p, r_p + 9.0)
    horizontal("D_p", JOINT_VIEW, -r_p, r_p, 0.0, -9.0)
    r_a = m["D_a"] / 2.0
    horizontal("D_a", TOP_VIEW, -r_a, r_a, 0.0, -r_p - 8.0)
    r_b, height = m["D_b"] / 2.0, m["H"]
    vertical("H", SOA_VIEW, 0.0, height, -r_b, -r_b - 7.0)
    horizontal("D_b", SOA_VIEW, -r_b, r_b, 0.0, -6.0)
    horizontal("a", SOA_VIEW, -m["a"] / 2, m["a"] / 2, _fold_z_mm(asm, 1), _fold_z_mm(asm, 1))
    horizontal("b", SOA_VIEW, -m["b"] / 2, m["b"] / 2, _fold_z_mm(asm, 2), _fold_z_mm(asm, 2))
    return dims, lines


def _captions(root: ET.Element) -> None:
    g = ET.SubElement(root, f"{{{SVG_NS}}}g", {"id": "captions", "font-family": "DejaVu Sans"})
    for text, (x, y) in (
        ("joint 1, front (-Y), 1:1", (JOINT_VIEW[1][0], 110.0)),
        ("root panel, top (+Z), 1:1.33", (TOP_VIEW[1][0], 110.0)),
        ("SOA, front, 1.5:1", (SOA_VIEW[1][0], 110.0)),
    ):
        _text(g, x, y, text, 3.4, "middle", fill="#333")


def _legend(root: ET.Element, m: dict[str, float]) -> None:
    """Two columns of rows "symbol  key  value mm  what it is" under the views."""
    g = ET.SubElement(root, f"{{{SVG_NS}}}g", {"id": "legend", "font-family": "DejaVu Sans"})
    for i, (symbol, (key, what)) in enumerate(PAPER_SYMBOLS.items()):
        x, y = 4.0 + 115.0 * (i // 4), 31.0 - 6.5 * (i % 4)
        row = ET.SubElement(g, f"{{{SVG_NS}}}g", {"class": "legend-row", "data-symbol": symbol})
        _symbol_text(_text(row, x, y, "", 3.4, **{"font-weight": "bold"}), symbol, "")
        _text(row, x + 8.0, y, key, 3.4, **{"font-family": "DejaVu Sans Mono"})
        _text(row, x + 58.0, y, f"{m[symbol]:.2f} mm", 3.4, **{"class": "value"})
        _text(row, x + 78.0, y, what, 2.8, fill="#555")


def _symbol_text(el: ET.Element, symbol: str, rest: str) -> None:
    """``el``'s text as the symbol with its subscript lowered (H_j: H, then j as a subscript), then
    ``rest``."""
    main, _, sub = symbol.partition("_")
    el.text = main
    if sub:
        low = ET.SubElement(
            el,
            f"{{{SVG_NS}}}tspan",
            {"baseline-shift": "sub", "font-size": f"{0.75 * float(el.get('font-size')):g}"},
        )
        low.text = sub
        low.tail = rest
    else:
        el.text = main + rest
