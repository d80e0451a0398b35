"""The export's report: ``report.html`` with its pictures in ``report/``.

Written last, after the checks, so it shows their results. It reads only
the export folder (the manifest and the files it names) and renders
off-screen with pyvista (VTK's OSMesa/EGL build needs no display); if
rendering fails the report says so in place of the pictures instead of
failing the build.

Sections: summary, the interactive 3D view (when the manifest has a
``viewer``: :mod:`bvsr_cad.exporters.viewer`), the assembly and every part
(print orientation), the rigid comparison tail, the mold set, the analysis
plots the manifest lists, the paper comparison (computed
beside reported, with the difference; figures the build does not model are
marked so), the mass budget, print jobs and BOM totals, and the table of
checks.
"""

from __future__ import annotations

import html
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import trimesh

from ..colors import rgb
from ..memo import Memo, run_now
from ..parameters import paper
from .render import composing, offscreen_pyvista

_MODEL = (
    "the Eq 6-12 model predicts it: see Model against measurements (and `bvsr simulate` in MuJoCo)"
)
_CART = "the Eq 20-22 cart model predicts it: see Model against measurements"
#: Paper comparison: quantity, the paper's figure (parameters/paper.py), the check that computes it
#: (or None), a note.
PAPER_ROWS: tuple[tuple[str, paper.PaperFigure, str | None, str], ...] = (
    ("mass", paper.SEGMENT_STANDALONE_MASS, "paper:segment_standalone_mass", ""),
    ("mass", paper.TAIL_MASS, "paper:tail_mass", ""),
    ("length", paper.TAIL_LENGTH_BVSR, "paper:tail_length", ""),
    (
        "taper half-angle (alpha_2 - 90)",
        paper.PaperFigure(
            round(paper.TILT_ANGLE_SEGMENT_1.value - 90.0, 6),
            "deg",
            "Table I",
            paper.TILT_ANGLE_SEGMENT_1.where,
        ),
        "paper:taper_half_angle",
        "",
    ),
    *(
        (f"quasi-static max angle, {m}", f, f"paper:qs_max_angle:{m}", "")
        for m, f in paper.QS_MAX_ANGLE_DEG.items()
    ),
    *(
        (f"blocked force, {m}", f, f"paper:qs_blocked_force:{m}", "")
        for m, f in paper.QS_BLOCKED_FORCE_N.items()
    ),
    (
        "peak angular velocity at 6 bar, extension",
        paper.SEGMENT_PEAK_VELOCITY_EXTENSION,
        None,
        _MODEL,
    ),
    ("peak angular velocity at 6 bar, flexion", paper.SEGMENT_PEAK_VELOCITY_FLEXION, None, _MODEL),
    ("peak angular velocity at 6 bar, waggle", paper.SEGMENT_PEAK_VELOCITY_WAGGLE, None, _MODEL),
    ("motion time exponent T ~ P^n", paper.MOTION_TIME_EXPONENT, None, _MODEL),
    ("velocity exponent V ~ P^n", paper.VELOCITY_EXPONENT, None, _MODEL),
    ("peak inertial torque, 6 bar, no payload", paper.TAIL_PEAK_TORQUE_NO_PAYLOAD, None, _MODEL),
    ("peak inertial torque, 6 bar, 100 g tip", paper.TAIL_PEAK_TORQUE_100G, None, _MODEL),
    (
        "peak root force, 500 g tip",
        paper.TAIL_PEAK_500G[0],
        None,
        "not in the data file: Table IV gives it without a pressure",
    ),
    ("peak root torque, 500 g tip", paper.TAIL_PEAK_500G[1], None, _MODEL),
    ("workspace half-width", paper.WORKSPACE_HALF_WIDTH_BVSR, "paper:workspace_half_width", ""),
    ("cart lift over a 9 mm obstacle (700 g cart)", paper.CART_LIFT_9MM, None, _CART),
)

CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;margin:2em auto;\
max-width:1200px;color:#222;
line-height:1.4;padding:0 1em}
h1{margin-bottom:0.2em} h2{border-bottom:2px solid #ddd;padding-bottom:0.2em;margin-top:2em}
table{border-collapse:collapse;margin:0.5em 0;font-size:0.9em} td,th{border:1px solid #ccc;\
padding:3px 7px;
vertical-align:top} th{background:#f3f3f3;text-align:left} td.num{text-align:right;\
font-variant-numeric:tabular-nums}
.pass{color:#1a7f37;font-weight:600}.fail{color:#cf222e;font-weight:700}.info{color:#6e7781}
.grid{display:flex;flex-wrap:wrap;gap:10px}.grid figure{margin:0;border:1px solid #ddd;padding:4px;\
background:#fafafa}
figcaption{font-size:0.85em;text-align:center} img{max-width:100%} .muted{color:#6e7781}
.badge{display:inline-block;padding:2px 10px;border-radius:10px;color:#fff;font-weight:600}
"""


def _e(v: Any) -> str:
    return html.escape(str(v))


def _num(v: Any, digits: int = 4) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, (int, float)):
        return f"{v:.{digits}g}"
    if isinstance(v, list):
        return "[" + ", ".join(_num(x, digits) for x in v) + "]"
    return _e(v)


def _poly(pv, mesh: trimesh.Trimesh):
    cells = np.hstack([np.full((len(mesh.faces), 1), 3), mesh.faces]).astype(np.int64).ravel()
    return pv.PolyData(np.asarray(mesh.vertices, float), cells)


#: Where the report's pictures go, in the export.
PART_PICTURES = "report/parts"
RIGID_PICTURE = "report/rigid_tail.png"


def _render_parts(root: Path, items: list[tuple[str, str, str]], dst: Path) -> dict[str, str]:
    """One small picture per STL of ``root`` (print orientation, the bed drawn as a grid), written
    under ``dst`` (the export, or a cache entry); returns name -> path in the export."""
    pv = offscreen_pyvista()
    out = dst / PART_PICTURES
    out.mkdir(parents=True, exist_ok=True)
    pics: dict[str, str] = {}
    plotter = pv.Plotter(off_screen=True, window_size=(360, 300))
    for name, rel, kind in items:
        # As read (process=False): merging the STL's repeated corners changes no pixel of a
        # flat-shaded picture (every PNG of the default build compared byte for byte), so it is
        # work for nothing.
        mesh = trimesh.load(root / rel, file_type="stl", force="mesh", process=False)
        with composing(plotter):
            plotter.clear()
            plotter.add_mesh(_poly(pv, mesh), color=rgb(kind), smooth_shading=False)
            lo, hi = mesh.bounds
            size = float(max(hi[0] - lo[0], hi[1] - lo[1])) * 1.3
            bed = pv.Plane(
                center=((lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, 0.0),
                direction=(0, 0, 1),
                i_size=size,
                j_size=size,
                i_resolution=8,
                j_resolution=8,
            )
            plotter.add_mesh(bed, color=(0.85, 0.85, 0.85), style="wireframe", line_width=1)
            plotter.view_isometric()
            plotter.reset_camera()
            plotter.add_text(
                f"{name}  {hi[0] - lo[0]:.0f} x {hi[1] - lo[1]:.0f} x {hi[2] - lo[2]:.0f} mm",
                font_size=8,
            )
        plotter.screenshot(str(out / f"{name}.png"))
        pics[name] = f"{PART_PICTURES}/{name}.png"
    plotter.close()
    return pics


def _rigid_pieces(manifest: dict[str, Any]) -> list[dict[str, Any]]:
    return [p for p in manifest["parts"] if p["kind"] == "rigid_tail"]


def _render_rigid(root: Path, manifest: dict[str, Any], dst: Path) -> str:
    """The rigid twin assembled beside an exploded stack of its pieces (written under ``dst``)."""
    pv = offscreen_pyvista()
    plotter = pv.Plotter(off_screen=True, window_size=(1200, 560), shape=(1, 2))
    pieces = _rigid_pieces(manifest)
    meshes = [
        trimesh.load(
            root / p["files"]["stl"], file_type="stl", force="mesh", process=False
        )  # read once, as
        for p in pieces
    ]  # in _render_parts
    for col, gap in ((0, 0.0), (1, 18.0)):
        plotter.subplot(0, col)
        for i, (p, piece) in enumerate(zip(pieces, meshes)):
            mesh = piece.copy()
            t = np.asarray(p["tail_transform"], float).copy()
            t[2, 3] += gap * i
            mesh.apply_transform(t)
            shade = 0.72 + 0.1 * (i % 2)
            plotter.add_mesh(
                _poly(pv, mesh), color=(shade, shade, shade * 0.92), smooth_shading=False
            )
        plotter.camera_position = [
            (-300.0, 200.0, -40.0 + 60 * col),
            (0.0, 0.0, 130.0 + 50 * col),
            (0.0, 1.0, 0.0),
        ]
        plotter.reset_camera()
        plotter.add_text(
            "rigid PLA twin, assembled"
            if col == 0
            else "pieces as printed, exploded along the tail",
            font_size=10,
        )
    (dst / RIGID_PICTURE).parent.mkdir(parents=True, exist_ok=True)
    plotter.screenshot(str(dst / RIGID_PICTURE))
    plotter.close()
    return RIGID_PICTURE


def _pngs(section: Any) -> list[str]:
    out: list[str] = []
    if isinstance(section, dict):
        for v in section.values():
            out += _pngs(v)
    elif isinstance(section, list):
        for v in section:
            out += _pngs(v)
    elif isinstance(section, str) and section.lower().endswith(".png"):
        out.append(section)
    return out


def _fig(src: str, caption: str, width: int | None = None) -> str:
    w = f' style="width:{width}px"' if width else ""
    return (
        f'<figure{w}><img src="{_e(src)}" '
        f'alt="{_e(caption)}"><figcaption>{_e(caption)}</figcaption></figure>'
    )


def _status(passed: Any) -> str:
    return {
        True: '<span class="pass">PASS</span>',
        False: '<span class="fail">FAIL</span>',
        None: '<span class="info">INFO</span>',
    }[passed]


def _paper_table(manifest: dict[str, Any]) -> str:
    checks = {c["name"]: c for c in manifest.get("checks", [])}
    rows = [
        "<table><tr><th>quantity</th><th>measured "
        "on</th><th>paper</th><th>computed</th><th>difference</th>"
        "<th>unit</th><th>note</th></tr>"
    ]
    segments = int(manifest.get("segments", 2))
    for qty, fig, check, why in PAPER_ROWS:
        value, unit, on = fig.value, fig.unit, fig.measured_on
        c = checks.get(check) if check else None
        if check == "paper:tail_mass" and segments != 2:
            c, why = None, "the paper weighs only the 2-segment tail"
        if c is not None and isinstance(c.get("value"), (int, float)):
            ref = c["limit"] if isinstance(c.get("limit"), (int, float)) else value
            diff = c["value"] - ref
            pct = f" ({100 * diff / ref:+.1f} %)" if ref else ""
            rows.append(
                f"<tr><td>{_e(qty)}</td><td>{_e(on)}</td><td class=num>{_num(ref)}</td>"
                f"<td class=num>{_num(c['value'])}</td><td "
                f"class=num>{diff:+.4g}{pct}</td><td>{_e(unit)}</td>"
                f"<td>{_e(c.get('note', ''))}</td></tr>"
            )
        else:
            rows.append(
                f"<tr><td>{_e(qty)}</td><td>{_e(on)}</td><td class=num>{_num(value)}</td>"
                f"<td class=info>not computed here</td><td></td><td>{_e(unit)}</td>"
                f"<td>{_e(why or 'not computed by this build')}</td></tr>"
            )
    rows.append("</table>")
    return "\n".join(rows)


def _measurements_section(root: Path, manifest: dict[str, Any]) -> str:
    """Reported, uncalibrated and calibrated per data row, fit or holdout, and the plot."""
    ana = manifest.get("analysis", {})
    if "measurements" not in ana:
        return (
            "<p class=muted>This parameter file carries no calibration: the model uses the tables' "
            "values. "
            "<code>bvsr calibrate PARAMS DATA -o OUT.toml</code> fits it to measurements.</p>"
        )
    try:
        meas = json.loads((root / ana["measurements"]).read_text())
    except (OSError, ValueError):
        return "<p class=fail>analysis/measurements.json is unreadable.</p>"
    h = [
        "<p>Fitted values (they replace the tables' values in their one home): "
        + ", ".join(f"<code>{_e(k)}</code> = {_num(v)}" for k, v in meas["fitted"].items())
        + ".</p>",
        f"<p class=muted>{_e(meas['note'])}.</p>",
    ]
    if not meas["rows"]:
        return "\n".join(h)
    band = 100 * meas["lands_within_rel"]
    rms = "; ".join(
        f"{role} rows {meas[f'rms_rel_{role}_uncalibrated']:.3f} uncalibrated, "
        f"{meas[f'rms_rel_{role}']:.3f} calibrated"
        for role in ("fit", "holdout")
        if f"rms_rel_{role}" in meas
    )
    landed = (
        f" {meas['holdout_landed'][0]} of {meas['holdout_landed'][1]} holdout rows land within "
        f"+/-{band:.0f} %."
        if "holdout_landed" in meas
        else ""
    )
    h.append(f"<p>RMS relative error: {rms}.{landed}</p>")
    h.append(
        "<table><tr><th>row</th><th>role</th><th>quantity "
        "(conditions)</th><th>unit</th><th>reported</th>"
        "<th>uncalibrated</th><th>calibrated</th><th>error</th><th>source</th></tr>"
    )
    for r in meas["rows"]:
        err = r["rel_calibrated"]
        cls = "pass" if abs(err) <= meas["lands_within_rel"] else "fail"
        h.append(
            f"<tr><td class=num>{r['row']}</td><td>{_e(r['role'])}</td><td>{_e(r['label'])}</td>"
            f"<td>{_e(r['unit'])}</td><td class=num>{_num(r['reported'])}</td>"
            f"<td class=num>{_num(r['uncalibrated'])}</td><td "
            f"class=num>{_num(r['calibrated'])}</td>"
            f"<td class='num {cls}'>{100 * err:+.0f} %</td><td "
            f"class=muted>{_e(r['source'])}</td></tr>"
        )
    h.append("</table>")
    if "measurements_png" in ana:
        h.append(
            "<div class=grid>"
            + _fig(ana["measurements_png"], "predicted against reported", 640)
            + "</div>"
        )
    return "\n".join(h)


def _mass_table(manifest: dict[str, Any]) -> str:
    rows = [
        "<table><tr><th>part</th><th>kind</th><th>material</th><th>process</th><th>count</th>"
        "<th>mass each (g)</th><th>mass total (g)</th></tr>"
    ]
    for p in manifest["parts"]:
        if p["kind"] == "rigid_tail":
            continue
        rows.append(
            f"<tr><td>{_e(p['name'])}</td><td>{_e(p['kind'])}</td><td>{_e(p['material'])}</td>"
            f"<td>{_e(p['process'])}</td><td class=num>{p['count']}</td><td "
            f"class=num>{p['mass_g']:.2f}</td>"
            f"<td class=num>{p['count'] * p['mass_g']:.2f}</td></tr>"
        )
    m = manifest["mass_g"]
    rows.append(
        "<tr><th colspan=6>BVSR tail (modelled: panels, SOAs, rods)</th><th "
        f"class=num>{m['tail']:.2f}</th></tr>"
    )
    for i, (a, b) in enumerate(
        zip(m.get("segments", []), m.get("segments_standalone", [])), start=1
    ):
        rows.append(
            f"<tr><td colspan=6>segment s{i}: in the tail (shared panels halved) / standalone</td>"
            f"<td class=num>{a:.2f} / {b:.2f}</td></tr>"
        )
    rt = manifest.get("rigid_tail")
    if rt:
        rows.append(
            f"<tr><th colspan=6>rigid PLA twin (solid density; infill lowers it)</th>"
            f"<th class=num>{rt['mass_g_solid']:.2f}</th></tr>"
        )
    rows.append("</table>")
    return "\n".join(rows)


def _analysis_table(root: Path, manifest: dict[str, Any]) -> str:
    """Workspace extents, the certified minimum clearance and every joint's limit, from the analysis
    files."""
    ana = manifest.get("analysis", {})
    try:
        ws = json.loads((root / ana["workspace"]).read_text())
        cl = json.loads((root / ana["clearance"]).read_text())
        lim = json.loads((root / ana["limits"]).read_text())
    except (KeyError, OSError, ValueError):
        return "<p class=muted>No analysis results in this export.</p>"
    ext = ws["tip_extent_mm"]
    rows = [
        "<table><tr><th>analysis</th><th>result</th></tr>",
        f"<tr><td>tip workspace ({ws['samples']} samples of the paper's protocol)</td><td>x "
        f"{_num(ext['x'])} mm, "
        f"y {_num(ext['y'])} mm; largest joint bend {math.degrees(ws['max_theta_rad']):.2f} "
        "deg</td></tr>",
        f"<tr><td>minimum clearance over {cl['poses']} workspace poses (required "
        f"{_num(cl['required_mm'])} mm)</td><td>{cl['min_clearance_mm']:.3f} mm between "
        f"{_e(cl['pair'][0])} and "
        f"{_e(cl['pair'][1])}; {'certified' if cl['certified'] else 'not certified'} (no pose and "
        "pair has a "
        f"lower bound below it), {cl['exact_evaluations']} exact distance(s)</td></tr>",
    ]
    for j in lim["joints"]:
        th = np.degrees(j["theta_max_rad"])
        why = ", ".join(
            f"{'the clearance bound' if w == 'clearance' else 'the ' + w} on "
            f"{j['limited_by'].count(w)}"
            for w in sorted(set(j["limited_by"]))
        )
        pairs = sorted({" / ".join(p) for p in j["limiting_pair"] if p})
        rows.append(
            f"<tr><td>joint {_e(j['joint'])}: bending limit theta_max over {len(th)} planes</td>"
            f"<td>{th.min():.1f} to {th.max():.1f} deg (set by {why}"
            f"{'; pair ' + _e(', '.join(pairs[:2])) if pairs else ''})</td></tr>"
        )
    rows.append("</table>")
    return "\n".join(rows)


def _checks_table(checks: list[dict[str, Any]]) -> str:
    order = sorted(checks, key=lambda c: {False: 0, None: 1, True: 2}[c["passed"]])
    rows = [
        "<table><tr><th></th><th>check</th><th>value</th><th>limit</th><th>unit</th><th>where</th><th>note</th></tr>"
    ]
    for c in order:
        rows.append(
            f"<tr><td>{_status(c['passed'])}</td><td>{_e(c['name'])}</td><td "
            f"class=num>{_num(c['value'])}</td>"
            f"<td class=num>{_num(c['limit'])}</td><td>{_e(c['unit'])}</td>"
            f"<td>{_e(c['where'])}</td>"
            f"<td>{_e(c.get('note', ''))}</td></tr>"
        )
    rows.append("</table>")
    return "\n".join(rows)


#: The viewer section's style (self-contained: a page holding only the section looks the same).
VIEWER_CSS = """
.viewer-buttons button{font:inherit;margin:0 6px 6px 0;padding:4px 12px;border:1px solid #bbb;\
border-radius:6px;
background:#f6f8fa;cursor:pointer}.viewer-buttons button.active{background:#0969da;color:#fff;\
border-color:#0969da}
canvas.viewer{width:100%;height:560px;display:block;box-sizing:border-box;border:1px solid #ccc;\
border-radius:4px;
touch-action:none;background:rgb(237,242,247)}.viewer-info{font-size:0.85em;margin:4px 0 0;\
min-height:2.6em}
.viewer-info .swatch{display:inline-block;width:0.9em;height:0.9em;border:1px solid #999;\
margin:0 3px 0 8px;
vertical-align:middle}
"""


def viewer_section(manifest: dict[str, Any]) -> str:
    """The interactive 3D view (``manifest["viewer"]``, written by
    :mod:`bvsr_cad.exporters.viewer`): scene buttons, a canvas and the viewer's script, all from the
    export folder; empty without a viewer."""
    viewer = manifest.get("viewer")
    if not viewer or not viewer.get("scenes"):
        return ""
    scenes = [{"name": s["name"], "title": s["title"], "file": s["file"]} for s in viewer["scenes"]]
    config = {
        "canvas": "bvsr-viewer",
        "info": "bvsr-viewer-info",
        "buttons": "bvsr-viewer-buttons",
        "scenes": scenes,
        "initial": scenes[0]["name"],
    }
    mb = viewer.get("bytes", 0) / 1e6
    buttons = "".join(
        f'<button type=button data-scene="{_e(s["name"])}">{_e(s["title"])}</button>'
        for s in scenes
    )
    return "\n".join(
        [
            f"<style>{VIEWER_CSS}</style>",
            "<h2>Interactive 3D view</h2>",
            "<p class=muted>Drag to orbit, wheel to zoom, shift-drag or right-drag to pan, "
            "double-click to reset. "
            f"Runs offline: the viewer ({_e(viewer.get('library', ''))}, "
            f"<code>{_e(viewer['script'])}</code>) and "
            "its scenes (the GLB files of <code>scenes/</code>, gzipped into "
            "<code>report/viewer_*.js</code>: "
            f"{mb:.1f} MB in all) are part of this export.</p>",
            f"<div class=viewer-buttons id=bvsr-viewer-buttons>{buttons}</div>",
            "<canvas class=viewer id=bvsr-viewer></canvas><div class=viewer-info "
            "id=bvsr-viewer-info>"
            "The 3D view needs JavaScript and WebGL.</div>",
            f'<script src="{_e(viewer["script"])}"></script>',
            "<script>BVSRViewer.start(" + json.dumps(config).replace("</", "<\\/") + ");</script>",
        ]
    )


def drawings_section(manifest: dict[str, Any]) -> str:
    """Links to the drawing sheets (one per panel and mold part), or nothing for an export without
    them."""
    sheets = manifest.get("drawings", {}).get("sheets", [])
    if not sheets:
        return ""
    rows = "".join(
        f"<tr><td><a href='{_e(s['svg'])}'>{_e(s['item'])}</a></td><td>{_e(s['kind'])}</td>"
        f"<td class=num>{s['holes']}</td><td><code>{_e(s['sha256'][:12])}</code></td></tr>"
        for s in sheets
    )
    return (
        "<h2>Drawings</h2><p class=muted>One A3 sheet per panel and mold part: outline views, "
        "overall "
        "dimensions, the hole table (position, diameter, through or blind, thread and tap drill) "
        "and the title "
        "block with the params SHA-256.</p><table><tr><th>sheet</th><th>kind</th><th>hole-table "
        "rows</th>"
        f"<th>sha256</th></tr>{rows}</table>"
    )


@dataclass(frozen=True)
class ReportPictures:
    """The report's pictures, written under ``report/`` (:func:`report_pictures`)."""

    parts: dict[str, str]  # part name -> picture
    rigid: str | None
    problems: list[str]  # what failed to render


def report_pictures(root: Path, manifest: dict[str, Any], memo: Memo = run_now) -> ReportPictures:
    """Draw the report's pictures of the print files and the rigid twin under ``root``: they read
    the manifest's parts, print jobs and twin and the STLs, so a build draws them before its
    analyses are in.

    The pictures are steps of ``memo`` (:class:`bvsr_cad.memo.Memo`) read by what they draw: the
    STLs' bytes, the names and kinds (the parts sheet), the pieces' placements (the twin)."""
    (root / "report").mkdir(exist_ok=True)
    problems: list[str] = []
    items = [
        (it["part"], it["stl"], it["kind"])
        for job in manifest.get("print_jobs", [])
        for it in job["items"]
    ]
    items += [
        (p["name"], p["files"]["stl"], p["kind"])
        for p in manifest["parts"]
        if p["process"] not in ("MJF", "FDM")
    ]
    try:
        part_pics, _reused = memo(
            "report_part_pictures",
            {"items": items},
            lambda dst: _render_parts(root, items, dst),
            root,
            files=[root / i[1] for i in items],
        )
    except (
        Exception
    ) as exc:  # a missing GL library must not lose the export; the report says what failed
        part_pics, problems = {}, problems + [f"part renders failed: {exc}"]
    rigid_pic = None
    if manifest.get("rigid_tail"):
        pieces = [(p["files"]["stl"], p["tail_transform"]) for p in _rigid_pieces(manifest)]
        try:
            rigid_pic, _reused = memo(
                "report_rigid_picture",
                {"pieces": pieces},
                lambda dst: _render_rigid(root, manifest, dst),
                root,
                files=[root / stl for stl, _t in pieces],
            )
        except Exception as exc:
            problems.append(f"rigid tail render failed: {exc}")
    return ReportPictures(part_pics, rigid_pic, problems)


def write_report(
    root: Path,
    manifest: dict[str, Any],
    memo: Memo = run_now,
    pictures: ReportPictures | None = None,
) -> dict[str, Any]:
    """Write ``report.html`` and its pictures (``report/``; ``pictures``: drawn already by
    :func:`report_pictures`) under ``root``; returns the manifest's ``report``."""
    if pictures is None:
        pictures = report_pictures(root, manifest, memo)
    part_pics, rigid_pic, problems = pictures.parts, pictures.rigid, list(pictures.problems)
    checks = manifest.get("checks", [])
    h = _report_head(manifest, checks, problems)
    h.append(viewer_section(manifest))
    h += _report_views(manifest, part_pics)
    h += _report_rigid_tail(manifest, checks, rigid_pic)
    h += _report_molds(manifest)
    h.append(drawings_section(manifest))
    h += _report_analyses(root, manifest)
    h += _report_quadruped(manifest)
    h += _report_fabrication(manifest)
    h.append("<h2>Checks</h2><p class=muted>Failures first, then comparisons, then passes.</p>")
    h.append(_checks_table(checks))
    h.append("</body></html>")
    (root / "report.html").write_text("\n".join(h))
    return {
        "report": {
            "html": "report.html",
            "pictures": sorted(set(part_pics.values()) | ({rigid_pic} - {None})),
            "problems": problems,
        }
    }


def _report_head(manifest: dict[str, Any], checks: list[dict], problems: list[str]) -> list[str]:
    """The page's head, title and summary line (the checks' counts, the tail's size and taper), and
    what failed to render."""
    n_fail = sum(1 for c in checks if c["passed"] is False)
    n_pass = sum(1 for c in checks if c["passed"] is True)
    n_info = sum(1 for c in checks if c["passed"] is None)
    badge = (
        '<span class="badge" style="background:#cf222e">checks FAILED</span>'
        if n_fail
        else '<span class="badge" style="background:#1a7f37">all checks pass</span>'
    )
    h = [
        f"<!doctype html><html><head><meta charset='utf-8'><title>{_e(manifest['name'])} "
        "report</title>"
        f"<style>{CSS}</style></head><body>"
    ]
    h.append(f"<h1>{_e(manifest['name'])}: build report</h1>")
    h.append(
        f"<p>{badge} {n_pass} passed, {n_fail} failed, {n_info} informational. "
        f"{manifest['segments']} segments, {manifest['joints']} joints, {manifest['panels']} "
        "panels; "
        f"length {manifest['length_mm']:.2f} mm; taper {manifest['taper']['half_angle_deg']:.3f} "
        "deg "
        f"(paper's alpha_2 - 90 = 1.23 deg: {_e(manifest['taper']['limited_by'])}); "
        f"params sha256 <code>{_e(manifest['params_sha256'][:12])}</code>.</p>"
    )
    for p in problems:
        h.append(
            f"<p class=fail>{_e(p)} (install the system GL libraries VTK needs, e.g. libgl1 / "
            "libosmesa6)</p>"
        )
    return h


def _report_views(manifest: dict[str, Any], part_pics: dict[str, str]) -> list[str]:
    """The assembly at rest and every part in print orientation."""
    h: list[str] = []
    h.append("<h2>Assembly at rest</h2><div class=grid>")
    prev = manifest.get("previews", {})
    if prev.get("assembly"):
        h.append(_fig(prev["assembly"], "BVSR at rest (SOAs translucent)"))
    if prev.get("parts"):
        h.append(_fig(prev["parts"], "unique parts in their part frames"))
    h.append("</div>")

    h.append(
        "<h2>Every part in print orientation</h2><p class=muted>As exported in "
        "<code>print/</code>: lying on "
        "z = 0 on the bed grid; SOAs and rods are cast and cut, shown in their part frame.</p><div "
        "class=grid>"
    )
    for name, pic in part_pics.items():
        h.append(_fig(pic, name, 260))
    h.append("</div>")
    return h


def _report_rigid_tail(
    manifest: dict[str, Any], checks: list[dict], rigid_pic: str | None
) -> list[str]:
    """The rigid PLA comparison tail: its picture, pieces, joining, envelope and robot
    description."""
    h: list[str] = []
    rt = manifest.get("rigid_tail")
    if rt:
        j = rt["joining"]
        h.append("<h2>Rigid PLA comparison tail</h2>")
        if rigid_pic:
            h.append(
                f"<div class=grid>{_fig(rigid_pic, 'rigid twin: assembled and exploded')}</div>"
            )
        env = {c["name"]: c for c in checks if c["name"].startswith("rigid_tail_envelope")}
        env_txt = ", ".join(
            f"{k.removeprefix('rigid_tail_envelope_')}: {_num(v['value'], 3)} mm (limit "
            f"{_num(v['limit'])})"
            for k, v in env.items()
        )
        h.append(
            f"<p>{len(rt['pieces'])} pieces for a "
            f"{' x '.join(f'{v:g}' for v in rt['printer_volume_mm'])} mm "
            f"printer: {_e(rt['split'])}. Joined by {j['pins']['count']} dowel pins "
            f"({_e(j['pins']['designation'])}) and a {_e(j['tie_rod']['designation'])} tie rod cut "
            "to "
            f"{j['tie_rod']['cut_length_mm']:.1f} mm with two {_e(j['nuts']['designation'])} nuts. "
            f"Simplified: {_e(rt['simplified'])}. Envelope against the BVSR at rest: "
            f"{_e(env_txt)}. "
            f"Robot description: <code>{_e(rt['robot']['urdf'])}</code>, "
            f"<code>{_e(rt['robot']['mjcf'])}</code> "
            f"(one rigid body, {rt['robot']['mass_kg'] * 1000:.1f} g solid).</p>"
        )
    return h


def _report_molds(manifest: dict[str, Any]) -> list[str]:
    """The SOA mold set, exploded."""
    h: list[str] = []
    molds = manifest.get("molds", {})
    if molds.get("exploded_png"):
        h.append("<h2>SOA mold set</h2><div class=grid>")
        h.append(_fig(molds["exploded_png"], "mold set, exploded along the pull directions"))
        h.append("</div>")
    return h


def _report_analyses(root: Path, manifest: dict[str, Any]) -> list[str]:
    """The analyses' table and plots, the paper's figures, the measurements and the mass budget."""
    h: list[str] = []
    pngs = [
        p
        for p in _pngs(manifest.get("analysis", {}))
        if p != manifest.get("analysis", {}).get("measurements_png")
    ]
    h.append("<h2>Analyses</h2>")
    h.append(_analysis_table(root, manifest))
    if pngs:
        h.append(
            "<div class=grid>"
            + "".join(_fig(p, Path(p).stem.replace("_", " ")) for p in pngs)
            + "</div>"
        )
    else:
        h.append("<p class=muted>No analysis plots in this export.</p>")

    h.append("<h2>Against the paper</h2>")
    h.append(_paper_table(manifest))
    h.append("<h2>Model against measurements</h2>")
    h.append(_measurements_section(root, manifest))
    h.append("<h2>Mass budget</h2>")
    h.append(_mass_table(manifest))
    return h


def _report_quadruped(manifest: dict[str, Any]) -> list[str]:
    """The tail on a quadruped: the host's scene and licence, and the paper's Figs. 17 and 18 as
    simulated (when the build ran them), each beside the paper's finding; else how to run them."""
    q = manifest.get("quadruped")
    if not q:
        return []
    h = ["<h2>On a quadruped (the paper's Figs. 17 and 18)</h2>"]
    if not q.get("installed"):
        return h + [f"<p class=muted>Not in this export: {_e(q.get('how', ''))}.</p>"]
    h.append(
        f"<p>Host: {_e(q['host'])} from {_e(q['host_package'])}, {_num(q['host_mass_kg'])} kg; "
        f"the tail on it: <code>{_e(q['scene'])}</code>; the host model's licence "
        f"({_e(q['licence'])}): <code>{_e(q['licence_file'])}</code>.</p>"
    )
    summary = q.get("summary")
    if not summary:
        return h + [
            f"<p class=muted>Experiments not run in this build: {_e(q.get('how', ''))}.</p>"
        ]
    h += _quadruped_stand(summary) + _quadruped_fig17(q, summary) + _quadruped_fig18(q, summary)
    return h


def _quadruped_stand(summary: dict[str, Any]) -> list[str]:
    rows = "".join(
        f"<tr><td>{_e(r['tail'])}</td><td>{r['seconds']:g}</td>"
        f"<td>{r['height_min_m']:.4f}-{r['height_max_m']:.4f}</td>"
        f"<td>{r['max_roll_pitch_deg']:.2f}</td><td>{r['yaw_range_deg']:.2f}</td>"
        f"<td>{_status(bool(r['finite']) and r['warnings'] == 0)}</td></tr>"
        for r in summary["stand"]
    )
    host = summary["host"]
    return [
        f"<p>PD stance (kp {host['stance_kp_nm_per_rad']:g} N m/rad, kd "
        f"{host['stance_kd_nm_s_per_rad']:g} N m s/rad) at the {_e(host['stance'])} pose, step "
        f"{host['timestep_s']:g} s; the tail at {_e(str(host['mount_pos_m']))} m on "
        f"{_e(host['body'])}, pointing backward.</p>",
        "<table><tr><th>tail</th><th>s</th><th>trunk height (m)</th><th>max roll, pitch "
        f"(deg)</th><th>yaw range (deg)</th><th>no NaN, no warning</th></tr>{rows}</table>",
    ]


def _quadruped_fig17(q: dict[str, Any], summary: dict[str, Any]) -> list[str]:
    f17 = summary["fig17"]
    rows = "".join(
        f"<tr><td>{_e(r['ball'])}</td><td>{_e(r['tail'])}</td>"
        f"<td>{1000 * r.get('tail_mass_kg', 0.0):.0f}</td>"
        f"<td>{r['peak_torso_speed_m_s']:.3f}</td><td>{r['peak_torso_rate_deg_s']:.1f}</td>"
        f"<td>{r['peak_root_force_n']:.1f}</td><td>{r['peak_root_torque_nm']:.2f}</td></tr>"
        for r in f17["rows"]
    )
    ratios = "; ".join(
        f"{_e(b)}: {v['torso_speed']:.2f}" for b, v in f17["soft_over_rigid"].items()
    )
    verdict = "agrees" if f17["agrees"] else "does not agree"
    h = [
        "<h3>Fig. 17: ball impacts, soft tail against the rigid twin</h3>",
        "<table><tr><th>ball</th><th>tail</th><th>tail mass (g)</th><th>peak torso speed "
        "(m/s)</th><th>peak torso "
        "rate (deg/s)</th><th>peak root force (N)</th><th>peak root torque (N m)</th></tr>"
        f"{rows}</table>",
        f"<p>Paper: {_e(f17['paper'])}. Model: peak torso speed soft over rigid {ratios}: it "
        f"{verdict}.</p>",
    ]
    fig = q.get("results", {}).get("fig17")
    return h + ([_fig(fig, "Fig. 17 as simulated")] if fig else [])


def _quadruped_fig18(q: dict[str, Any], summary: dict[str, Any]) -> list[str]:
    f18 = summary["fig18"]
    rows = "".join(
        f"<tr><td>{r['payload_g']:g}</td><td>{r['excursion_deg']['roll']:.2f}</td>"
        f"<td>{r['excursion_deg']['pitch']:.2f}</td><td>{r['excursion_deg']['yaw']:.2f}</td>"
        f"<td>{r['peak_root_force_n']:.2f}</td><td>{r['peak_root_torque_nm']:.2f}</td></tr>"
        for r in f18["rows"]
    )
    h = [
        f"<h3>Fig. 18: waggle, extension, flexion to {f18['tip_distance_mm']:g} mm of tip travel "
        "with tip payloads</h3>",
        "<table><tr><th>payload (g)</th><th>roll</th><th>pitch</th><th>yaw (deg)</th>"
        f"<th>peak root force (N)</th><th>peak root torque (N m)</th></tr>{rows}</table>",
        f"<p>Paper: {_e(f18['paper'])}; at 500 g a root force of {f18['paper_force_n_500g']:g} N "
        f"and torque of {f18['paper_torque_nm_500g']:g} N m.</p>",
    ]
    if "force_minus_paper_n" in f18:
        h.append(
            f"<p>Model minus paper at 500 g: {f18['force_minus_paper_n']:+.2f} N, "
            f"{f18['torque_minus_paper_nm']:+.2f} N m.</p>"
        )
    fig = q.get("results", {}).get("fig18")
    return h + ([_fig(fig, "Fig. 18 as simulated")] if fig else [])


def _report_fabrication(manifest: dict[str, Any]) -> list[str]:
    """The print jobs and the bill of materials."""
    h: list[str] = []
    jobs = manifest.get("print_jobs", [])
    if jobs:
        h.append(
            "<h2>Print jobs</h2><table><tr><th>job</th><th>material</th><th>build volume "
            "(mm)</th><th>parts</th>"
            "<th>mass (g)</th><th>3MF</th></tr>"
        )
        for job in jobs:
            h.append(
                f"<tr><td>{_e(job['name'])}</td><td>{_e(job['material_name'])}</td>"
                f"<td>{_num(job['build_volume_mm'])}</td><td class=num>{job['total_parts']}</td>"
                f"<td class=num>{job['total_mass_g']:.1f}</td><td><a "
                f"href='{_e(job['files']['3mf'])}'>"
                f"{_e(job['files']['3mf'])}</a></td></tr>"
            )
        h.append("</table>")
    bom = manifest.get("bom")
    if bom:
        h.append(
            f"<p>Bill of materials: <a href='{_e(bom['md'])}'>{_e(bom['md'])}</a>, "
            f"<a href='{_e(bom['csv'])}'>{_e(bom['csv'])}</a> ({bom['rows']} rows; "
            + ", ".join(f"{_e(k.replace('_', ' '))} {_num(v)}" for k, v in bom["counts"].items())
            + ").</p>"
        )
    return h
