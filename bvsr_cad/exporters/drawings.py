"""Drawings: one SVG sheet (A3 landscape, mm) per panel and per mold part (``drawings/<item>.svg``).

A sheet holds the part's outline views (build123d's hidden-line projection,
``project_to_viewport``, visible and hidden edges), overall dimensions (measured on the
projected geometry, drawn as plain SVG lines, arrowheads and text), the hole table and
the title block. The hole table's rows are the part's declared round features
(:class:`bvsr_cad.parameters.layout.Cyl`: the panel layout's cuts and passages, the
mold set's bolts, pins, sockets, gate, vents and flange pockets), the same objects the
solids were cut from; each bore's length and whether it is through or blind are
measured on the B-rep (its cylindrical faces, and the faces at its ends).

The geometry part of a sheet (views, dimensions, hole table) depends on the
geometry alone and is cached with it (``write_drawing_sheets``); the title
block (material, process, tail name, params SHA-256) is stamped onto the sheets
at every build (``stamp_drawings``), so a material edit never serves a stale
title block and never redraws a view.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import build123d as bd
import numpy as np

from ..assembly.assemble import Assembly
from ..assembly.fabrication import made_items
from ..parameters.layout import Cyl
from ..parameters.standard_parts import size_for_clearance_hole
from ..parts.kernel import bounds
from ..parts.mold import MoldSet

SVG_NS = "http://www.w3.org/2000/svg"
SHEET_MM = (420.0, 297.0)  # A3 landscape
MARGIN_MM = 10.0
TABLE_X_MM = 232.0  # hole table from here to the right border
TITLE_H_MM = 46.0  # title block height, bottom right
ROW_MM = 3.6
FONT_MM = 2.2
SCALES = (5.0, 4.0, 2.5, 2.0, 1.5, 1.0, 0.5, 0.25)
#: Dimensions (sheet mm): the line's distance from the outline, arrowheads, text height and its lift
#: off the line.
DIM_GAP_MM = 8.0
DIM_ARROW_MM = 2.5
DIM_ARROW_WIDTH_MM = 0.9
DIM_FONT_MM = 3.0
DIM_TEXT_LIFT_MM = 0.8
DIM_LINE_MM = 0.18
DIM_DECIMALS = 2
#: What each declared role is, in a workshop's words.
ROLE_TEXT = {
    "pocket": "SOA flange pocket (bonded)",
    "channel": "air channel",
    "port": "push-in fitting port",
    "tube": "tube pass-through",
    "tube_port": "tube port (bonded)",
    "feed": "feed into the pocket",
    "passage": "internal passage",
    "rod": "rod socket",
    "setscrew": "set screw",
    "insert": "heat-set insert bore",
    "lightening": "lightening hole",
    "bolt": "clamping bolt",
    "pin": "registration pin (printed)",
    "pin_socket": "pin socket",
    "gate": "pour gate",
    "vent": "vent",
    "flange_pocket": "flange cavity",
}
#: Views (name, direction towards the viewer, up); the sheet coordinates follow the camera's own
#: axes.
VIEWS = {
    "top": ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    "front": ((0.0, -1.0, 0.0), (0.0, 0.0, 1.0)),
    "right": ((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
}


@dataclass(frozen=True)
class HoleRow:
    """One row of a hole table (mm, part frame)."""

    label: str
    names: tuple[str, ...]  # the declared features (coaxial touching features are one bore)
    role: str
    start_mm: tuple[float, float, float]  # where the bore's B-rep begins on its axis
    axis: tuple[float, float, float]  # unit, into the part
    diameter_mm: float
    length_mm: float  # along the axis, on the B-rep
    through: bool
    thread: str | None  # e.g. "M6x1"
    tap_drill_mm: float | None

    @property
    def is_pin(self) -> bool:
        return self.role == "pin"

    def cells(self) -> list[str]:
        x, y, z = self.start_mm
        ax = "".join(
            f"{'+' if v > 0 else '-'}{n}" for v, n in zip(self.axis, "XYZ") if abs(v) > 0.5
        ) or "({:.2f}, {:.2f}, {:.2f})".format(*self.axis)
        if self.is_pin:
            kind = f"pin, {self.length_mm:.2f} long"
        elif self.role == "passage":
            kind = f"internal, {self.length_mm:.2f}"
        else:
            kind = "through" if self.through else f"blind, {self.length_mm:.2f} deep"
        if self.thread:
            note = f"{self.thread} tap, drill {self.tap_drill_mm:g}"
        elif self.role == "bolt":
            note = f"clearance {size_for_clearance_hole(self.diameter_mm).designation}"
        else:
            note = ROLE_TEXT.get(self.role, self.role)
        return [
            self.label,
            " + ".join(self.names),
            f"{x:.2f}",
            f"{y:.2f}",
            f"{z:.2f}",
            ax,
            f"{self.diameter_mm:.2f}",
            kind,
            note,
        ]


HEADER = ["id", "feature", "x", "y", "z", "axis", "dia", "through / blind", "thread / note"]
COLUMNS_MM = [9.0, 36.0, 13.0, 13.0, 11.0, 11.0, 11.0, 29.0, 45.0]


def _np(v) -> np.ndarray:
    return np.array([v.X, v.Y, v.Z])


def _cyl_faces(solid: bd.Solid) -> list[tuple[bd.Face, np.ndarray, np.ndarray, float]]:
    """(face, axis point, unit axis, radius) of every cylindrical face."""
    out = []
    for f in solid.faces():
        if f.geom_type == bd.GeomType.CYLINDER:
            ax = f.axis_of_rotation
            out.append((f, _np(ax.position), _np(ax.direction), f.radius))
    return out


class _PlaneFace:
    """A plane face of a solid with what :func:`_end_is_closed` asks of it: its point, normal and
    bounding box, and whether points of its plane lie on it, by a 2D classifier in the plane's (u,
    v) made once for the face (build123d's ``Face.is_inside`` builds OCCT's 3D solid classifier at
    every call: a third of the drawings' time). When this replaced it, both answered all 5,921
    queries of the hole tables of ``params/bvsr.toml`` and ``params/bvsr_l.toml`` alike
    (``is_inside`` with the tolerance :data:`ON_FACE_TOLERANCE_MM`), and the sheets stayed
    byte-identical."""

    def __init__(self, face: bd.Face):
        from OCP.BRep import BRep_Tool
        from OCP.BRepTopAdaptor import BRepTopAdaptor_FClass2d

        box = bounds(face)
        self.origin, self.normal = _np(face.center()), _np(face.normal_at())
        self.lo, self.hi = _np(box.min), _np(box.max)
        self._plane = BRep_Tool.Surface_s(face.wrapped).Pln()
        self._classifier = BRepTopAdaptor_FClass2d(face.wrapped, ON_FACE_TOLERANCE_MM)

    def holds(self, point: np.ndarray) -> bool:
        """``point`` (on the face's plane) lies on the face, its boundary included."""
        from OCP.ElSLib import ElSLib
        from OCP.gp import gp_Pnt, gp_Pnt2d
        from OCP.TopAbs import TopAbs_State

        u, v = ElSLib.Parameters_s(self._plane, gp_Pnt(*map(float, point)))
        return self._classifier.Perform(gp_Pnt2d(u, v)) in (
            TopAbs_State.TopAbs_IN,
            TopAbs_State.TopAbs_ON,
        )


#: How near a face a point counts as on it (:class:`_PlaneFace`), mm.
ON_FACE_TOLERANCE_MM = 1e-4


def _end_is_closed(
    solid_planes: list[_PlaneFace], point: np.ndarray, axis: np.ndarray, radius: float
) -> bool:
    """A floor: a plane face across the bore's end (perpendicular to it, through ``point``) that
    holds points of the bore's disc. At an open end the face there surrounds the bore instead. Only
    the faces whose bounding box holds a point of the disc are asked (the classifier is the slow
    part)."""
    helper = np.cross(axis, [1.0, 0.0, 0.0] if abs(axis[0]) < 0.9 else [0.0, 1.0, 0.0])
    helper /= np.linalg.norm(helper)
    other = np.cross(axis, helper)
    ring = [
        point + 0.7 * radius * (math.cos(a) * helper + math.sin(a) * other)
        for a in np.linspace(0, 2 * math.pi, 8, endpoint=False)
    ]
    tol = ON_FACE_TOLERANCE_MM
    for face in solid_planes:
        if (
            abs(abs(float(face.normal @ axis)) - 1.0) > 1e-6
            or abs(float(face.normal @ (point - face.origin))) > tol
        ):
            continue
        if any(
            face.holds(p) for p in ring if np.all(p >= face.lo - tol) and np.all(p <= face.hi + tol)
        ):
            return True
    return False


def hole_table(solid: bd.Solid, features: list[Cyl]) -> list[HoleRow]:
    """The declared round features of ``solid`` as hole-table rows, measured on its B-rep.

    A feature's bore is the set of cylindrical faces of its radius on its axis within its span;
    coaxial features whose faces are the same bore (a rod bore through panel and collar) are one
    row.
    """
    cyls = _cyl_faces(solid)
    planes = [_PlaneFace(f) for f in solid.faces() if f.geom_type == bd.GeomType.PLANE]
    rows: dict[tuple, dict[str, Any]] = {}
    for feat in features:
        p0, p1 = np.array(feat.p0), np.array(feat.p1)
        axis = (p1 - p0) / np.linalg.norm(p1 - p0)
        r = feat.diameter_mm / 2.0
        s_lo, s_hi = 0.0, float(np.linalg.norm(p1 - p0))
        lo, hi, ids = math.inf, -math.inf, []
        for i, (face, pos, d, radius) in enumerate(cyls):
            if abs(radius - r) > 1e-4 or abs(abs(float(d @ axis)) - 1.0) > 1e-6:
                continue
            off = pos - p0
            if np.linalg.norm(off - (off @ axis) * axis) > 1e-3:
                continue
            s = [float((_np(v) - p0) @ axis) for v in face.vertices()]
            if min(s) > s_hi + 1e-3 or max(s) < s_lo - 1e-3:
                continue
            lo, hi = min(lo, min(s)), max(hi, max(s))
            ids.append(i)
        if not ids:
            raise ValueError(
                f"{feat.name}: declared but not in the solid (no cylindrical face of "
                f"diameter {feat.diameter_mm:g} mm on its axis)"
            )
        key = tuple(sorted(ids))
        if key in rows:
            rows[key]["names"].append(feat.name)
            continue
        start, end = p0 + lo * axis, p0 + hi * axis
        start_closed = feat.role != "pin" and _end_is_closed(planes, start, axis, r)
        through = feat.role != "pin" and not (start_closed or _end_is_closed(planes, end, axis, r))
        if start_closed:
            start, end, axis = end, start, -axis  # the table gives a blind bore from its opening
        rows[key] = {
            "names": [feat.name],
            "feat": feat,
            "start": start,
            "axis": axis,
            "length": hi - lo,
            "through": through,
        }
    out = []
    for n, row in enumerate(rows.values(), start=1):
        feat = row["feat"]
        out.append(
            HoleRow(
                f"{'P' if feat.role == 'pin' else 'H'}{n}",
                tuple(row["names"]),
                feat.role,
                tuple(round(float(v), 6) + 0.0 for v in row["start"]),
                tuple(round(float(v), 9) + 0.0 for v in row["axis"]),
                feat.diameter_mm,
                float(row["length"]),
                bool(row["through"]),
                feat.thread.designation if feat.thread else None,
                feat.thread.drill_mm if feat.thread else None,
            )
        )
    return out


def _project(solid: bd.Solid, view: str) -> tuple[list[bd.Edge], list[bd.Edge]]:
    toward, up = VIEWS[view]
    return solid.project_to_viewport(tuple(1000.0 * v for v in toward), up, look_at=(0.0, 0.0, 0.0))


def _uv(view: str, p: np.ndarray) -> tuple[float, float]:
    """A model point in the view's 2D coordinates (the projector's X = up x toward, Y = up)."""
    toward, up = (np.array(v) for v in VIEWS[view])
    return float(p @ np.cross(up, toward)), float(p @ up)


def _view_box(edges: list[bd.Edge]) -> tuple[float, float, float, float]:
    box = bd.Compound(edges).bounding_box()
    return box.min.X, box.min.Y, box.max.X, box.max.Y


def _layout(
    boxes: dict[str, tuple[float, float, float, float]],
    views: list[list[str]],
    region: tuple[float, float, float, float],
    gap_mm: float,
) -> tuple[float, dict[str, tuple[float, float]]]:
    """Largest listed scale at which the rows of views fit the region; each view's sheet offset."""
    x0, y0, x1, y1 = region
    for scale in SCALES:
        widths = [
            sum((boxes[v][2] - boxes[v][0]) * scale for v in row) + gap_mm * (len(row) - 1)
            for row in views
        ]
        heights = [max((boxes[v][3] - boxes[v][1]) * scale for v in row) for row in views]
        if max(widths) <= x1 - x0 and sum(heights) + gap_mm * (len(views) - 1) <= y1 - y0:
            break
    offsets = {}
    y = y1
    for row, h in zip(views, heights):
        x = x0
        for v in row:
            bx0, by0, bx1, by1 = boxes[v]
            offsets[v] = (x - bx0 * scale, y - h - by0 * scale)
            x += (bx1 - bx0) * scale + gap_mm
        y -= h + gap_mm
    return scale, offsets


def _placed(edges: list[bd.Edge], scale: float, offset: tuple[float, float]) -> list[bd.Edge]:
    """View edges (model mm) on the sheet: scaled about the view's origin, then moved by ``offset``;
    one OCCT transform per edge (build123d's ``scale`` and ``Pos *`` each deep-copy the edge in
    Python first)."""
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.gp import gp_Pnt, gp_Trsf, gp_Vec

    grow, move = gp_Trsf(), gp_Trsf()
    grow.SetScale(gp_Pnt(0.0, 0.0, 0.0), scale)
    move.SetTranslation(gp_Vec(offset[0], offset[1], 0.0))
    trsf = move.Multiplied(grow)
    return [bd.Edge(BRepBuilderAPI_Transform(e.wrapped, trsf, True).Shape()) for e in edges]


def _sheet(
    p: tuple[float, float], scale: float, offset: tuple[float, float]
) -> tuple[float, float]:
    """A view point (model mm) on the sheet (mm, y up)."""
    return offset[0] + scale * p[0], offset[1] + scale * p[1]


@dataclass(frozen=True)
class Dimension:
    """A linear dimension on the sheet: its line from ``a`` to ``b`` (sheet mm, y up), arrows at
    both ends pointing out to the extension lines, and the measured model length written above the
    line."""

    a: tuple[float, float]
    b: tuple[float, float]
    length_mm: float

    def text(self) -> str:
        return f"{self.length_mm:.{DIM_DECIMALS}f}"


def _dimensions(parent: ET.Element, dims: list[Dimension]) -> None:
    """Each dimension as plain SVG (a line, two filled arrowheads, a text): a reader can pick the
    value out of the ``dim`` group's text, and nothing is a glyph outline."""
    g = ET.SubElement(
        parent,
        f"{{{SVG_NS}}}g",
        {
            "id": "dimensions",
            "font-family": "DejaVu Sans",
            "stroke": "black",
            "stroke-width": f"{DIM_LINE_MM:g}",
        },
    )
    for d in dims:
        a, b = np.array(d.a), np.array(d.b)
        u = (b - a) / max(float(np.linalg.norm(b - a)), 1e-12)
        n = np.array([-u[1], u[0]])
        el = ET.SubElement(g, f"{{{SVG_NS}}}g", {"class": "dim"})
        ET.SubElement(
            el,
            f"{{{SVG_NS}}}line",
            {"x1": f"{a[0]:.3f}", "y1": f"{-a[1]:.3f}", "x2": f"{b[0]:.3f}", "y2": f"{-b[1]:.3f}"},
        )
        for tip, inward in ((a, u), (b, -u)):
            base = tip + DIM_ARROW_MM * inward
            pts = [tip, base + 0.5 * DIM_ARROW_WIDTH_MM * n, base - 0.5 * DIM_ARROW_WIDTH_MM * n]
            ET.SubElement(
                el,
                f"{{{SVG_NS}}}polygon",
                {
                    "points": " ".join(f"{x:.3f},{-y:.3f}" for x, y in pts),
                    "fill": "black",
                    "stroke": "none",
                },
            )
        # Read from below or from the right (ISO 129): left to right, or bottom to top; the text
        # stands on the line's side its letters point to.
        read = u if u[0] > 1e-9 or (abs(u[0]) <= 1e-9 and u[1] > 0) else -u
        up = np.array([-read[1], read[0]])
        mid = (a + b) / 2 + DIM_TEXT_LIFT_MM * up
        angle = (
            -math.degrees(math.atan2(read[1], read[0])) + 0.0
        )  # SVG turns clockwise (its y runs down)
        t = _text(el, float(mid[0]), float(mid[1]), d.text(), DIM_FONT_MM, "middle", stroke="none")
        if abs(angle) > 1e-9:
            t.set("transform", f"rotate({angle:.3f} {mid[0]:.3f} {-mid[1]:.3f})")


def _text(
    parent: ET.Element,
    x: float,
    y: float,
    text: str,
    size: float = FONT_MM,
    anchor: str = "start",
    **attrs: str,
) -> ET.Element:
    """Text at sheet point (x, y) mm (y up); the SVG root runs y down."""
    el = ET.SubElement(
        parent,
        f"{{{SVG_NS}}}text",
        {
            "x": f"{x:.3f}",
            "y": f"{-y:.3f}",
            "font-size": f"{size:g}",
            "text-anchor": anchor,
            **attrs,
        },
    )
    el.text = text
    return el


def _rect(x0: float, y0: float, x1: float, y1: float) -> list[bd.Edge]:
    pts = [(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)]
    return [bd.Edge.make_line(a, b) for a, b in zip(pts, pts[1:])]


class _SheetSVG(bd.ExportSVG):
    """build123d's SVG export with one change: a Bezier arc's poles are read by index. Iterating
    OCCT's pole array from Python (what build123d 0.12 does) ends in an exception pybind11
    translates, about a millisecond per arc and most of a cold build's drawing time; the points, and
    the sheet's bytes, are the same."""

    def _bspline_segments(self, edge: bd.Edge, reverse: bool) -> list:
        import svgpathtools as PT
        from OCP.GeomConvert import GeomConvert_BSplineCurveToBezierCurve

        edge = edge.to_splines()  # from here on build123d's own method, but for the poles
        adaptor = edge.geom_adaptor()
        spline = adaptor.Curve().Curve().Copy()
        u1, u2 = adaptor.FirstParameter(), adaptor.LastParameter()
        if not edge or edge.location is None:
            raise ValueError(f"Edge is empty {edge}.")
        spline.Transform(edge.location.wrapped.Transformation())
        converter = GeomConvert_BSplineCurveToBezierCurve(
            spline, u1, u2, bd.Export2D.PARAMETRIC_TOLERANCE
        )
        kinds = {2: PT.Line, 3: PT.QuadraticBezier, 4: PT.CubicBezier}
        result = []
        for i in range(1, converter.NbArcs() + 1):
            bezier = converter.Arc(i)
            p = [self._path_point(bezier.Pole(j)) for j in range(1, bezier.NbPoles() + 1)]
            if reverse:
                p.reverse()
            if len(p) not in kinds:
                raise ValueError(f"Surprising Bézier of degree {bezier.Degree()}!")
            result.append(kinds[len(p)](*p))
        if reverse:
            result.reverse()
        return result


def draw_sheet(
    name: str, solid: bd.Solid, features: list[Cyl], views: list[list[str]]
) -> tuple[bytes, int]:
    """The sheet without its title block (SVG bytes) and its number of hole-table rows."""
    rows = hole_table(solid, features)
    projected = {v: _project(solid, v) for row in views for v in row}
    boxes = {v: _view_box(vis + hid) for v, (vis, hid) in projected.items()}
    w, h = SHEET_MM
    # Room left of the views for a side view's height dimension and its text (it stood on the frame
    # once).
    region = (
        MARGIN_MM + DIM_GAP_MM + DIM_FONT_MM + 2.0 * DIM_TEXT_LIFT_MM + 1.0,
        MARGIN_MM + 14.0,
        TABLE_X_MM - 8.0,
        h - MARGIN_MM - 12.0,
    )
    scale, offsets = _layout(boxes, views, region, 22.0)
    top = h - MARGIN_MM - 10.0  # the hole table's top edge
    x_cols = np.cumsum([TABLE_X_MM, *COLUMNS_MM])
    svg = _sheet_svg()
    dims = _draw_views(svg, projected, boxes, scale, offsets)
    _draw_table_grid(svg, len(rows), top, x_cols)
    buf = io.BytesIO()
    svg.write(buf)
    ET.register_namespace("", SVG_NS)
    root = ET.fromstring(buf.getvalue())
    root.set("id", f"drawing-{name}")
    _label_views(root, boxes, scale, offsets, rows)
    _dimensions(root, dims)
    _hole_table_text(root, rows, top, x_cols)
    ET.indent(root, "  ")
    return ET.tostring(root, encoding="unicode").encode() + b"\n", len(rows)


def _sheet_svg() -> _SheetSVG:
    """An empty sheet: its layers (frame, grid, visible, hidden) and its edge and frame lines."""
    w, h = SHEET_MM
    svg = _SheetSVG(unit=bd.Unit.MM, margin=0.0, fit_to_stroke=False)
    svg.add_layer("frame", line_weight=0.5)
    svg.add_layer("grid", line_weight=0.18)
    svg.add_layer("visible", line_weight=0.35)
    svg.add_layer(
        "hidden", line_color=(0.43, 0.43, 0.43), line_weight=0.18, line_type=bd.LineType.ISO_DASH
    )
    svg.add_shape(_rect(0.0, 0.0, w, h), "grid")
    svg.add_shape(_rect(MARGIN_MM, MARGIN_MM, w - MARGIN_MM, h - MARGIN_MM), "frame")
    return svg


def _draw_views(
    svg: _SheetSVG,
    projected: dict[str, tuple[list[bd.Edge], list[bd.Edge]]],
    boxes: dict[str, tuple[float, float, float, float]],
    scale: float,
    offsets: dict[str, tuple[float, float]],
) -> list[Dimension]:
    """Draw each view's visible and hidden edges and its dimensions' extension lines; returns the
    dimensions (drawn as text later)."""
    dims: list[Dimension] = []
    for view, (vis, hid) in projected.items():
        off = offsets[view]
        svg.add_shape(_placed(vis, scale, off), "visible")
        if hid:
            svg.add_shape(_placed(hid, scale, off), "hidden")
        bx0, by0, bx1, by1 = boxes[view]
        # Overall width below the view, and height left of the side views, measured on the projected
        # outline; their extension lines from the outline's corners to just past the dimension line.
        gap = DIM_GAP_MM / scale
        spans = [((bx0, by0), (bx1, by0), (0.0, -gap))]
        if view != "top":
            spans.append(((bx0, by1), (bx0, by0), (-gap, 0.0)))
        for a, b, (dx, dy) in spans:
            a2, b2 = (a[0] + dx, a[1] + dy), (b[0] + dx, b[1] + dy)
            dims.append(Dimension(_sheet(a2, scale, off), _sheet(b2, scale, off), math.dist(a, b)))
            ext = [bd.Edge.make_line(p, (p[0] + 1.15 * dx, p[1] + 1.15 * dy)) for p in (a, b)]
            svg.add_shape(_placed(ext, scale, off), "grid")
    return dims


def _draw_table_grid(svg: _SheetSVG, n_rows: int, top: float, x_cols: np.ndarray) -> None:
    """The hole table's ruling: its outline, a line under each row and between the columns."""
    bottom = top - ROW_MM * (n_rows + 1)
    grid = _rect(TABLE_X_MM, bottom, x_cols[-1], top)
    grid += [
        bd.Edge.make_line((TABLE_X_MM, top - ROW_MM * i), (x_cols[-1], top - ROW_MM * i))
        for i in range(1, n_rows + 1)
    ]
    grid += [bd.Edge.make_line((x, bottom), (x, top)) for x in x_cols[1:-1]]
    svg.add_shape(grid, "grid")


def _label_views(
    root: ET.Element,
    boxes: dict[str, tuple[float, float, float, float]],
    scale: float,
    offsets: dict[str, tuple[float, float]],
    rows: list[HoleRow],
) -> None:
    """Each view's caption (direction and scale) and, on the top view, each hole row's id where
    its bore begins."""
    labels = ET.SubElement(root, f"{{{SVG_NS}}}g", {"id": "views", "font-family": "DejaVu Sans"})
    for view, (bx0, _, bx1, by1) in boxes.items():
        off = offsets[view]
        _text(
            labels,
            off[0] + scale * (bx0 + bx1) / 2,
            off[1] + scale * by1 + 4.0,
            f"{view} ({'looking along ' + _towards(view)}), scale {_scale_text(scale)}",
            2.5,
            "middle",
        )
        if view == "top":  # each row's id where its bore begins
            for row in rows:
                u, v = _uv(view, np.array(row.start_mm))
                _text(
                    labels,
                    off[0] + scale * u + 0.8,
                    off[1] + scale * v + 0.8,
                    row.label,
                    1.8,
                    fill="#0645ad",
                )


def _hole_table_text(root: ET.Element, rows: list[HoleRow], top: float, x_cols: np.ndarray) -> None:
    """The hole table's caption, header and rows."""
    table = ET.SubElement(
        root, f"{{{SVG_NS}}}g", {"id": "hole-table", "font-family": "DejaVu Sans"}
    )
    _text(
        table,
        TABLE_X_MM,
        top + 3.0,
        f"Hole table: {len(rows)} features, mm, part frame "
        "(positions where each bore begins; B-rep lengths)",
        2.5,
    )
    for i, cells in enumerate([HEADER] + [r.cells() for r in rows]):
        g = ET.SubElement(table, f"{{{SVG_NS}}}g", {"class": "hole-head" if i == 0 else "hole-row"})
        for x, cell in zip(x_cols, cells):
            _text(
                g,
                x + 0.8,
                top - ROW_MM * (i + 1) + 1.0,
                cell,
                FONT_MM,
                **({"font-weight": "bold"} if i == 0 else {}),
            )


def _towards(view: str) -> str:
    toward = np.array(VIEWS[view][0])
    axis = "XYZ"[int(np.argmax(np.abs(toward)))]
    return ("-" if toward.max() > 0.5 else "+") + axis


def _scale_text(scale: float) -> str:
    return f"{scale:g}:1" if scale >= 1 else f"1:{1 / scale:g}"


def _sheets(
    asm: Assembly, molds: MoldSet
) -> list[tuple[str, bd.Solid, list[Cyl], list[list[str]]]]:
    """(item name, solid, declared features, rows of views) of every sheet: panels, then the mold
    set."""
    out = []
    layouts = {lay.name: lay for lay in asm.panel_layouts}
    for name, part in asm.parts.items():
        if part.kind == "panel":
            lay = layouts[name]
            out.append((name, part.solid, [*lay.cuts, *lay.passages], [["top"], ["front"]]))
    for name, mp in molds.parts.items():
        out.append((f"mold_{name}", mp.solid, list(mp.features), [["top"], ["front", "right"]]))
    return out


def write_drawing_sheets(asm: Assembly, molds: MoldSet, root: Path) -> None:
    """The sheets' geometry (``drawings/<item>.svg``) and their hole counts
    (``drawings/holes.json``): what depends on the geometry alone (the cached part of the
    drawings)."""
    out = root / "drawings"
    out.mkdir(parents=True, exist_ok=True)
    holes = {}
    for name, solid, features, views in _sheets(asm, molds):
        data, holes[name] = draw_sheet(name, solid, features, views)
        (out / f"{name}.svg").write_bytes(data)
    (out / "holes.json").write_text(json.dumps(holes, indent=1) + "\n")


def _title_block(name: str, item, spec, params_sha256: str) -> bytes:
    # ElementTree's namespace prefixes are process-wide: build123d's SVG export registers SVG as the
    # default namespace, and a build that takes the sheets from the cache never runs it. Register it
    # here too, so the stamped block is the same bytes either way.
    ET.register_namespace("", SVG_NS)
    w, _ = SHEET_MM
    x0, y0 = w - MARGIN_MM - 178.0, MARGIN_MM
    g = ET.Element(f"{{{SVG_NS}}}g", {"id": "title-block", "font-family": "DejaVu Sans"})
    ET.SubElement(
        g,
        f"{{{SVG_NS}}}rect",
        {
            "x": f"{x0:g}",
            "y": f"{-(y0 + TITLE_H_MM):g}",
            "width": "178",
            "height": f"{TITLE_H_MM:g}",
            "fill": "white",
            "stroke": "black",
            "stroke-width": "0.5",
        },
    )
    mat = spec.material(item.material)
    lines = [
        ("part", name, 4.0),
        ("tail", spec.name, 2.6),
        ("material", f"{item.material}: {mat.name}", 2.6),
        ("process", item.process, 2.6),
        ("quantity", str(item.quantity), 2.6),
        ("units", "mm; each view named by its direction", 2.6),
        ("params SHA-256", params_sha256, 2.3),
    ]
    y = y0 + TITLE_H_MM - 6.0
    for key, value, size in lines:
        _text(g, x0 + 3.0, y, key, 2.0, fill="#555")
        _text(g, x0 + 30.0, y, value, size, **{"class": f"title-{key.replace(' ', '-').lower()}"})
        y -= 5.6
    return ET.tostring(g, encoding="unicode").encode()


def stamp_drawings(root: Path, asm: Assembly, molds: MoldSet, params_sha256: str) -> dict[str, Any]:
    """Add the title block to every sheet in ``root/drawings`` and list the sheets for the
    manifest."""
    items = {i.label: i for i in made_items(asm, (), molds)}
    holes = json.loads((root / "drawings" / "holes.json").read_text())
    (root / "drawings" / "holes.json").unlink()
    sheets = []
    for name, count in holes.items():
        path = root / "drawings" / f"{name}.svg"
        data = path.read_bytes()
        i = data.rindex(b"</svg>")
        data = (
            data[:i] + _title_block(name, items[name], asm.spec, params_sha256) + b"\n" + data[i:]
        )
        path.write_bytes(data)
        sheets.append(
            {
                "item": name,
                "kind": items[name].kind,
                "svg": f"drawings/{name}.svg",
                "holes": count,
                "sha256": hashlib.sha256(data).hexdigest(),
            }
        )
    return {"drawings": {"format": "SVG, A3 landscape, mm", "sheets": sheets}}


__all__ = ["HoleRow", "hole_table", "write_drawing_sheets", "stamp_drawings", "draw_sheet"]
