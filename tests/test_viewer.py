"""The report's interactive 3D view: scenes computed in memory, written into the export, drawn by a browser.

Expected values come from outside the viewer code: the tail's length from the
parameters, the bending directions of SPEC section 2 (extension dorsal, +Y in
the tail frame; flexion -Y; waggle +X), the mold set's pull directions, and
the rigidity of a panel (a posed panel keeps every distance between its
vertices). The page test opens the written page in headless Chromium
(SwiftShader WebGL) and looks at the pixels of the canvas.
"""

from __future__ import annotations

import base64
import json
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import trimesh

from bvsr_cad.colors import rgb
from .conftest import PARAMS

CALL = "BVSRViewer.addScene("
#: The canvas's clear colour (viewer.js BACKGROUND = 0.93, 0.95, 0.97) as 8-bit RGB.
BACKGROUND_RGB = np.array([237, 242, 247])


@pytest.fixture(scope="module")
def built():
    from bvsr_cad.analysis.poses import limit_poses, viewer_scenes
    from bvsr_cad.assembly.build import build_assembly
    from bvsr_cad.assembly.products import build_mold_set, build_rigid_twin
    from bvsr_cad.parameters.load import load_spec

    asm = build_assembly(load_spec(PARAMS / "bvsr.toml"))
    mold_set = build_mold_set(asm)
    pieces = build_rigid_twin(asm)
    scenes = viewer_scenes(asm, mold_set, pieces)
    return {"asm": asm, "mold_set": mold_set, "pieces": pieces, "scenes": {s.name: s for s in scenes},
            "order": [s.name for s in scenes], "poses": limit_poses(asm)}


@pytest.fixture(scope="module")
def export(built, tmp_path_factory) -> dict:
    """The viewer written into a folder, with a page that holds only the report's viewer section."""
    from bvsr_cad.exporters.report import viewer_section
    from bvsr_cad.exporters.viewer import write_viewer

    root = tmp_path_factory.mktemp("viewer")
    manifest = write_viewer(root, [built["scenes"][n] for n in built["order"]])
    page = root / "report.html"
    page.write_text("<!doctype html><html><head><meta charset='utf-8'><title>viewer</title></head><body>"
                    + viewer_section(manifest) + "</body></html>")
    return {"root": root, "manifest": manifest, "page": page}


def decode(path: Path) -> dict:
    """A scene file back to arrays (independent of the writer: the format of the module docstring)."""
    text = path.read_text()
    assert text.startswith(CALL) and text.rstrip().endswith(");"), path.name
    data = json.loads(text[len(CALL):text.rstrip().rindex(")")])
    bufs = [base64.b64decode(b) for b in data["buffers"]]
    out = []
    for o in data["objects"]:
        m = data["meshes"][o["mesh"]]
        v = np.frombuffer(bufs[m["positions"]], "<f4").reshape(-1, 3).astype(float)
        t = np.frombuffer(bufs[m["triangles"]], "<u4").reshape(-1, 3)
        tf = np.array(o["transform"], float).reshape(4, 4)
        out.append({**o, "vertices": v, "triangles": t, "T": tf, "scene_vertices": v @ tf[:3, :3].T + tf[:3, 3]})
    data["decoded"] = out
    return data


@pytest.fixture(scope="module")
def decoded(export) -> dict[str, dict]:
    return {s["name"]: decode(export["root"] / s["file"]) for s in export["manifest"]["viewer"]["scenes"]}


def _by_label(scene: dict) -> dict[str, dict]:
    return {o["label"]: o for o in scene["decoded"]}


def test_every_scene_written_and_its_data_decode(built, export, decoded):
    from bvsr_cad.analysis.poses import SCENES

    viewer = export["manifest"]["viewer"]
    assert [s["name"] for s in viewer["scenes"]] == list(SCENES)
    assert (export["root"] / viewer["script"]).is_file()
    total = (export["root"] / viewer["script"]).stat().st_size
    for entry in viewer["scenes"]:
        scene, data = built["scenes"][entry["name"]], decoded[entry["name"]]
        total += (export["root"] / entry["file"]).stat().st_size
        assert data["name"] == entry["name"] and data["title"] == entry["title"]
        assert len(data["decoded"]) == entry["objects"] == len(scene.objects) > 0
        assert sum(len(o["triangles"]) for o in data["decoded"]) == entry["triangles"] == scene.triangle_count
        for o, mem in zip(data["decoded"], scene.objects):
            assert o["label"] == mem.label and len(o["triangles"]) > 0
            assert o["triangles"].max() < len(o["vertices"]), (entry["name"], o["label"])
            assert np.isfinite(o["vertices"]).all()
            np.testing.assert_array_equal(o["triangles"], mem.triangles)
            np.testing.assert_allclose(o["vertices"], mem.vertices_mm, atol=1e-4)
    assert total == viewer["bytes"]
    assert total < 8e6, f"viewer data {total / 1e6:.1f} MB"


def test_rest_scene_is_the_assembly(built, decoded):
    asm, spec = built["asm"], built["asm"].spec
    objs = _by_label(decoded["rest"])
    assert sorted(objs) == sorted(i.name for i in asm.instances)
    for inst in asm.instances:
        o = objs[inst.name]
        np.testing.assert_allclose(o["T"], np.asarray(inst.transform), atol=1e-6)
        assert o["rgb"] == pytest.approx(rgb(asm.part_of(inst).kind), abs=1e-4)
    pts = np.vstack([o["scene_vertices"] for o in decoded["rest"]["decoded"]])
    # The tail at rest runs from the root face z = 0 to joints x gap + panels x thickness.
    assert pts[:, 2].min() == pytest.approx(0.0, abs=0.05)
    assert pts[:, 2].max() == pytest.approx(spec.length_mm, abs=0.05)


@pytest.mark.parametrize("motion, axis, sign", [("extension", 1, +1), ("flexion", 1, -1), ("waggle", 0, +1)])
def test_posed_tip_panel_moves_the_way_the_motion_says(built, decoded, motion, axis, sign):
    spec = built["asm"].spec
    tip = f"panel{spec.panels - 1}"
    rest = _by_label(decoded["rest"])
    posed = _by_label(decoded[motion])
    assert sorted(posed) == sorted(rest)
    moved = posed[tip]["scene_vertices"].mean(0) - rest[tip]["scene_vertices"].mean(0)
    # SPEC section 2: extension bends dorsally (+Y), flexion ventrally (-Y), waggle sideways (+X); at the
    # pressure limits each segment bends tens of degrees, so the tip moves a good part of the tail's length.
    assert sign * moved[axis] > 0.3 * spec.length_mm, moved
    assert abs(moved[1 - axis]) < 0.05 * spec.length_mm, moved  # out of the bending plane: gravity's sag only
    assert moved[2] < 0  # a bent tail is shorter along its rest axis
    # The root panel is held by the mount; every panel moves as a rigid body (distances kept).
    np.testing.assert_allclose(posed["panel0"]["scene_vertices"], rest["panel0"]["scene_vertices"], atol=1e-4)
    for k in range(spec.panels):
        a, b = rest[f"panel{k}"]["scene_vertices"], posed[f"panel{k}"]["scene_vertices"]
        idx = np.random.default_rng(k).integers(0, len(a), (200, 2))
        np.testing.assert_allclose(np.linalg.norm(b[idx[:, 0]] - b[idx[:, 1]], axis=1),
                                   np.linalg.norm(a[idx[:, 0]] - a[idx[:, 1]], axis=1), atol=1e-3)
    # The page's description names the pose the statics found.
    pose = built["poses"][motion]
    assert sign * (pose.tip_mm - pose.rest_tip_mm)[axis] > 0
    assert decoded[motion]["note"] == built["scenes"][motion].note


def test_mold_parts_move_out_along_their_pull_directions(built, decoded):
    objs = {o["label"].removesuffix(" (sacrificial)"): o for o in decoded["molds"]["decoded"]}
    for name, part in built["mold_set"].parts.items():
        shift = objs[name]["T"][:3, 3]
        if part.sacrificial:
            np.testing.assert_allclose(shift, 0.0, atol=1e-9)
            continue
        d = np.asarray(part.pull_direction, float)
        assert shift @ d > 10.0, name  # well clear of the closed mold
        np.testing.assert_allclose(shift - (shift @ d) * d, 0.0, atol=1e-6)  # along the pull, nothing else
        assert objs[name]["rgb"] == pytest.approx(rgb(part.role), abs=1e-4)
    assert "cast SOA" in objs and objs["cast SOA"]["alpha"] < 1.0


def test_rigid_twin_has_the_tail_outer_envelope(built, decoded):
    spec = built["asm"].spec
    objs = decoded["rigid_twin"]["decoded"]
    assert [o["label"] for o in objs] == [p.name for p in built["pieces"]]
    pts = np.vstack([o["scene_vertices"] for o in objs])
    rest = np.vstack([o["scene_vertices"] for o in decoded["rest"]["decoded"]])
    assert pts[:, 2].min() == pytest.approx(0.0, abs=0.05)
    assert pts[:, 2].max() == pytest.approx(spec.length_mm, abs=0.05)
    # "Identical geometric parameters": the twin's cross-section spans the BVSR's panels.
    np.testing.assert_allclose(pts[:, :2].min(0), rest[:, :2].min(0), atol=0.5)
    np.testing.assert_allclose(pts[:, :2].max(0), rest[:, :2].max(0), atol=0.5)


def test_build_twin_scene_is_the_rigid_robots_visual_meshes(built, tmp_path):
    """The build's 3D view takes the twin's visual meshes (the rigid robot's, metres, tail frame) instead of
    meshing the pieces a second time: each piece as given, in the tail frame, where the viewer's own
    meshing puts it to within the two tessellations."""
    import dataclasses

    from bvsr_cad import units
    from bvsr_cad.analysis.poses import twin_scene
    from bvsr_cad.exporters.fabrication_files import write_rigid_files
    from bvsr_cad.parts._kernel import fresh_copy

    pieces = [dataclasses.replace(p, solid=fresh_copy(p.solid)) for p in built["pieces"]]  # leave the fixture's be
    visual = write_rigid_files(pieces, tmp_path)
    given = twin_scene(pieces, [(units.m_to_mm(np.asarray(m.vertices)), np.asarray(m.faces)) for m in visual])
    own = built["scenes"]["rigid_twin"]
    assert [o.label for o in given.objects] == [o.label for o in own.objects] == [p.name for p in pieces]
    for a, b, m in zip(own.objects, given.objects, visual):
        assert b.rgb == a.rgb
        np.testing.assert_array_equal(b.transform, np.eye(4))
        # the visual mesh itself: its triangles, on its corners (merged), in millimetres
        assert len(b.triangles) == len(m.faces)
        from scipy.spatial import cKDTree

        corners = units.m_to_mm(np.asarray(m.vertices))
        assert cKDTree(corners).query(b.vertices_mm)[0].max() < 1e-4  # float32 of a few hundred mm
        assert cKDTree(b.vertices_mm).query(corners)[0].max() < 1e-4
        placed = a.vertices_mm @ a.transform[:3, :3].T + a.transform[:3, 3]
        np.testing.assert_allclose(b.vertices_mm.min(0), placed.min(0), atol=0.5)
        np.testing.assert_allclose(b.vertices_mm.max(0), placed.max(0), atol=0.5)
        # the same surface: the given mesh's area within 1 % of the B-rep's faces meshed by the viewer
        assert trimesh.Trimesh(b.vertices_mm, b.triangles).area == pytest.approx(
            trimesh.Trimesh(a.vertices_mm, a.triangles).area, rel=0.01)


def test_nothing_reaches_for_the_network(export):
    root = export["root"]
    files = [export["page"], root / "report" / "viewer.js", *sorted((root / "report").glob("viewer_*.js"))]
    for f in files:
        text = f.read_text()
        # ':' is not a base64 character, so a scheme cannot appear by chance inside the data.
        assert not re.search(r"(?i)\b(https?|ftp|wss?):", text), f.name
        assert "//cdn" not in text and "@import" not in text, f.name
    html = export["page"].read_text()
    for src in re.findall(r'src="([^"]+)"', html):
        assert (root / src).is_file(), src
    for entry in export["manifest"]["viewer"]["scenes"]:
        assert not Path(entry["file"]).is_absolute() and (root / entry["file"]).is_file()


def _screenshot(page: Path, fragment: str, out: Path, profile: Path) -> np.ndarray:
    from PIL import Image

    chromium = shutil.which("chromium")
    cmd = [chromium, "--headless", "--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
           "--hide-scrollbars", f"--user-data-dir={profile}", f"--screenshot={out}", "--window-size=1000,800",
           page.as_uri() + fragment]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
    assert out.is_file(), f"chromium wrote no screenshot (rc {run.returncode}): {run.stderr[-2000:]}"
    return np.asarray(Image.open(out).convert("RGB"), int)


@pytest.mark.parametrize("scene", ["rest", "extension"])
def test_the_page_draws_the_scene_in_headless_chromium(export, scene, tmp_path):
    if shutil.which("chromium") is None:
        pytest.skip("chromium is not installed (Debian: apt-get install chromium); the page is not drawn")
    shot = tmp_path / f"viewer_{scene}.png"
    img = _screenshot(export["page"], f"#viewer={scene}", shot, tmp_path / "profile")
    is_bg = np.all(np.abs(img - BACKGROUND_RGB) <= 2, axis=-1)
    assert is_bg.sum() > 1000, "no canvas background in the screenshot: the page did not lay out a canvas"
    rows, cols = np.nonzero(is_bg)
    y0, y1, x0, x1 = rows.min(), rows.max(), cols.min(), cols.max()
    # The canvas: the whole page width and 560 px high (report.VIEWER_CSS).
    assert x1 - x0 > 900 and 500 < y1 - y0 < 600, (x0, y0, x1, y1)
    box = img[y0:y1 + 1, x0:x1 + 1]
    drawn = np.any(np.abs(box - BACKGROUND_RGB) > 30, axis=-1)
    assert drawn.mean() > 0.03, f"only {drawn.mean():.2%} of the canvas drawn"
    # The SOAs' orange (colors.RGB['soa'], shaded and translucent) is there.
    r, g, b = box[..., 0], box[..., 1], box[..., 2]
    assert np.sum((r > g + 40) & (g > b + 40)) > 2000
    # The script ran: the caption under the canvas names the scene (the page's static text says JavaScript is off).
    dom = subprocess.run([shutil.which("chromium"), "--headless", "--no-sandbox", "--enable-unsafe-swiftshader",
                          "--use-angle=swiftshader", f"--user-data-dir={tmp_path / 'profile'}", "--dump-dom",
                          export["page"].as_uri() + f"#viewer={scene}"], capture_output=True, text=True, timeout=180)
    info = re.search(r'id="bvsr-viewer-info">(.*?)</div>', dom.stdout, re.S)
    title = next(s["title"] for s in export["manifest"]["viewer"]["scenes"] if s["name"] == scene)
    assert info and title in info.group(1) and "triangles" in info.group(1), dom.stdout[-2000:]
    assert re.search(rf'class="active" data-scene="{scene}"|data-scene="{scene}" class="active"', dom.stdout)


def test_tail_scene_meshes_do_not_depend_on_earlier_tessellations(built):
    """OCCT keeps the finest triangulation a solid was given; the tail's scene meshes a copy, so a build
    that took the part files from its cache (no 0.01 mm STL meshing) shows the same scene as a cold one."""
    from bvsr_cad.analysis.poses import _tail_meshes
    from bvsr_cad.parts._kernel import mesh_arrays

    asm = built["asm"]
    before = _tail_meshes(asm)
    for part in asm.parts.values():
        mesh_arrays(part.solid, 0.005, 0.05)
    after = _tail_meshes(asm)
    for name, m in before.items():
        np.testing.assert_array_equal(m.vertices, after[name].vertices)
        np.testing.assert_array_equal(m.faces, after[name].faces)
