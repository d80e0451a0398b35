"""The 3D scenes: computed in memory, written as GLB files (``scenes/``) and drawn by the report's
viewer.

Expected values come from outside the code under test: the GLB files are read back with pygltflib
(an independent glTF reader, not trimesh that wrote them); the instances' names and placements from
the assembly; the bounding box from the B-rep; colours from the colour table through the sRGB
transfer function written out here (IEC 61966-2-1); the tail's length from the parameters, the
bending directions of the paper (extension dorsal, +Y in the tail frame; flexion -Y; waggle
+X), the mold set's pull directions, and the rigidity of a panel (a posed panel keeps every distance
between its vertices). The page test opens the written page in headless Chromium (SwiftShader WebGL)
and looks at the pixels of the canvas.
"""

from __future__ import annotations

import base64
import gzip
import json
import math
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import trimesh

from bvsr_cad.colors import RGB, rgb

from .conftest import PARAMS

CALL = "BVSRViewer.addScene("
#: The canvas's clear colour (bvsr-viewer.mjs: #edf2f7) as 8-bit RGB.
BACKGROUND_RGB = np.array([237, 242, 247])
#: glTF (and so every GLB) is in metres; the scenes are computed in millimetres.
MM_PER_M = 1000.0


def linear(c: float) -> float:
    """The sRGB transfer function undone (IEC 61966-2-1): glTF's baseColorFactor is linear light."""
    return c / 12.92 if c <= 0.04045 else ((c + 0.055) / 1.055) ** 2.4


@pytest.fixture(scope="module")
def built():
    from bvsr_cad.analysis.poses import limit_poses, viewer_scenes
    from bvsr_cad.assembly.assemble import build_assembly
    from bvsr_cad.assembly.products import build_mold_set, build_rigid_twin
    from bvsr_cad.parameters.load import load_spec

    asm = build_assembly(load_spec(PARAMS / "bvsr.toml"))
    mold_set = build_mold_set(asm)
    pieces = build_rigid_twin(asm)
    scenes = viewer_scenes(asm, mold_set, pieces)
    return {
        "asm": asm,
        "mold_set": mold_set,
        "pieces": pieces,
        "scenes": {s.name: s for s in scenes},
        "order": [s.name for s in scenes],
        "poses": limit_poses(asm),
    }


@pytest.fixture(scope="module")
def export(built, tmp_path_factory) -> dict:
    """The scenes and the viewer written into a folder, as the build writes them, with a page that
    holds only the report's viewer section."""
    from bvsr_cad.exporters.gltf import scene_glb, write_scenes
    from bvsr_cad.exporters.report import viewer_section
    from bvsr_cad.exporters.viewer import write_viewer

    root = tmp_path_factory.mktemp("viewer")
    scenes = [built["scenes"][n] for n in built["order"]]
    glb = {s.name: scene_glb(s) for s in scenes}
    manifest = write_scenes(root, scenes, glb)
    manifest.update(write_viewer(root, manifest["scenes"]["files"], glb))
    page = root / "report.html"
    page.write_text(
        "<!doctype html><html><head><meta charset='utf-8'><title>viewer</title></head><body>"
        + viewer_section(manifest)
        + "</body></html>"
    )
    return {"root": root, "manifest": manifest, "page": page}


_COMPONENTS = {5125: "<u4", 5123: "<u2", 5121: "<u1", 5126: "<f4"}
_WIDTH = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}


def read_glb(path: Path) -> dict:
    """A GLB file read with pygltflib, independent of the writer: every mesh-bearing node's name,
    world matrix (metres), vertices in its mesh frame (metres), triangles and material."""
    pygltflib = pytest.importorskip(
        "pygltflib", reason="pygltflib (the viewer extra) reads the GLB files back"
    )
    g = pygltflib.GLTF2().load(str(path))
    blob = g.binary_blob()

    def accessor(i: int) -> np.ndarray:
        a = g.accessors[i]
        view = g.bufferViews[a.bufferView]
        n = a.count * _WIDTH[a.type]
        start = (view.byteOffset or 0) + (a.byteOffset or 0)
        arr = np.frombuffer(blob, _COMPONENTS[a.componentType], n, start)
        return arr.reshape(a.count, _WIDTH[a.type]) if _WIDTH[a.type] > 1 else arr

    nodes = []

    def walk(index: int, parent: np.ndarray) -> None:
        node = g.nodes[index]
        local = (
            np.array(node.matrix, float).reshape(4, 4).T if node.matrix else np.eye(4)
        )  # column-major
        assert not (node.translation or node.rotation or node.scale), (
            "TRS nodes: not written by the exporter"
        )
        world = parent @ local
        if node.mesh is not None:
            (prim,) = g.meshes[node.mesh].primitives
            assert prim.mode in (None, 4)  # triangles
            v = accessor(prim.attributes.POSITION).astype(float)
            nodes.append(
                {
                    "name": node.name,
                    "T": world,
                    "vertices": v,
                    "triangles": accessor(prim.indices).reshape(-1, 3),
                    "material": g.materials[prim.material],
                    "world_vertices": v @ world[:3, :3].T + world[:3, 3],
                }
            )
        for c in node.children or []:
            walk(c, world)

    scene = g.scenes[g.scene or 0]
    for i in scene.nodes:
        walk(i, np.eye(4))
    return {"asset": g.asset, "name": scene.name, "extras": scene.extras, "nodes": nodes}


@pytest.fixture(scope="module")
def decoded(export) -> dict[str, dict]:
    out = {}
    for f in export["manifest"]["scenes"]["files"]:
        data = read_glb(export["root"] / f["file"])
        for o in data["nodes"]:  # in millimetres, as the scenes were computed
            o["T_mm"] = o["T"].copy()
            o["T_mm"][:3, 3] *= MM_PER_M
            o["scene_vertices"] = o["world_vertices"] * MM_PER_M
            c = o["material"].pbrMetallicRoughness.baseColorFactor
            o["rgb_linear"], o["alpha"] = c[:3], c[3]
        out[f["name"]] = data
    return out


def _by_label(scene: dict) -> dict[str, dict]:
    return {o["name"]: o for o in scene["nodes"]}


def test_every_scene_written_as_glb_in_metres(built, export, decoded):
    from bvsr_cad.analysis.poses import SCENES

    entry = export["manifest"]["scenes"]
    assert entry["length_unit"] == "m" and [f["name"] for f in entry["files"]] == list(SCENES)
    for f in entry["files"]:
        scene, data = built["scenes"][f["name"]], decoded[f["name"]]
        assert (export["root"] / f["file"]).stat().st_size == f["bytes"]
        assert data["asset"].version == "2.0" and data["asset"].extras == {"length_unit": "m"}
        assert data["name"] == f["name"] and data["extras"]["title"] == f["title"] == scene.title
        assert data["extras"]["note"] == scene.note
        # One node per object, named as it, in its order; trimesh (a second reader) finds the same
        # nodes and the same extent.
        assert [o["name"] for o in data["nodes"]] == f["nodes"] == [o.label for o in scene.objects]
        back = trimesh.load(export["root"] / f["file"])
        assert sorted(back.graph.nodes_geometry) == sorted(f["nodes"])
        every = np.vstack([o["world_vertices"] for o in data["nodes"]])
        np.testing.assert_allclose(back.bounds, [every.min(0), every.max(0)], atol=1e-9)
        assert (
            sum(len(o["triangles"]) for o in data["nodes"])
            == f["triangles"]
            == scene.triangle_count
        )
        for o, mem in zip(data["nodes"], scene.objects):
            np.testing.assert_array_equal(o["triangles"], mem.triangles)
            # float32 metres of at most a few hundred mm: 1e-7 m
            np.testing.assert_allclose(o["vertices"] * MM_PER_M, mem.vertices_mm, atol=1e-4)
            np.testing.assert_allclose(o["T_mm"], np.asarray(mem.transform, float), atol=1e-9)
            np.testing.assert_allclose(
                o["rgb_linear"], [linear(c) for c in mem.rgb], atol=0.5 / 255
            )
            assert o["alpha"] == pytest.approx(mem.alpha, abs=0.5 / 255)
            assert o["material"].alphaMode == ("OPAQUE" if mem.alpha >= 1 else "BLEND")
            assert o["material"].pbrMetallicRoughness.metallicFactor == 0.0


def test_glb_is_byte_reproducible(built, export):
    from bvsr_cad.exporters.gltf import scene_glb

    for f in export["manifest"]["scenes"]["files"]:
        assert scene_glb(built["scenes"][f["name"]]) == (export["root"] / f["file"]).read_bytes()


def test_rest_scene_is_the_assembly(built, decoded):
    import build123d as bd

    from bvsr_cad.analysis.poses import ANGULAR_TOLERANCE_RAD
    from bvsr_cad.assembly.assemble import instance_solid
    from bvsr_cad.exporters.manifest import manifest_dict

    asm, spec = built["asm"], built["asm"].spec
    objs = _by_label(decoded["rest"])
    listed = manifest_dict(asm, "", {n: {} for n in asm.parts}, "")["assembly"]["instances"]
    assert [o["name"] for o in decoded["rest"]["nodes"]] == [i["name"] for i in listed]
    for inst in asm.instances:
        o = objs[inst.name]
        np.testing.assert_allclose(o["T_mm"], np.asarray(inst.transform), atol=1e-6)
        np.testing.assert_allclose(
            o["rgb_linear"], [linear(c) for c in rgb(asm.part_of(inst).kind)], atol=0.5 / 255
        )
        assert o["material"].name == asm.part_of(inst).kind
    assert objs["j1_soa1"]["alpha"] < 1.0 and objs["j1_soa1"]["material"].alphaMode == "BLEND"
    pts = np.vstack([o["scene_vertices"] for o in decoded["rest"]["nodes"]])
    # The tail at rest runs from the root face z = 0 to joints x gap + panels x thickness.
    assert pts[:, 2].min() == pytest.approx(0.0, abs=0.05)
    assert pts[:, 2].max() == pytest.approx(spec.length_mm, abs=0.05)
    # The B-rep's box: every mesh corner lies on a surface, so inside it (float32 metres: 1e-4 mm),
    # and the box's extremes on the round panels are missed by at most the sagitta of an arc of the
    # viewer's angular tolerance (poses.ANGULAR_TOLERANCE_RAD) on the panels' radius, the box's
    # half-width.
    box = bd.Compound([instance_solid(asm, i) for i in asm.instances]).bounding_box()
    lo, hi = (
        np.array([box.min.X, box.min.Y, box.min.Z]),
        np.array([box.max.X, box.max.Y, box.max.Z]),
    )
    assert np.all(pts.min(0) >= lo - 1e-3) and np.all(pts.max(0) <= hi + 1e-3)
    sagitta_mm = 0.5 * (hi[0] - lo[0]) * (1 - math.cos(ANGULAR_TOLERANCE_RAD / 2))
    np.testing.assert_allclose(pts.min(0), lo, atol=sagitta_mm)
    np.testing.assert_allclose(pts.max(0), hi, atol=sagitta_mm)


@pytest.mark.parametrize(
    "motion, axis, sign", [("extension", 1, +1), ("flexion", 1, -1), ("waggle", 0, +1)]
)
def test_posed_tip_panel_moves_the_way_the_motion_says(built, decoded, motion, axis, sign):
    spec = built["asm"].spec
    tip = f"panel{spec.panels - 1}"
    rest = _by_label(decoded["rest"])
    posed = _by_label(decoded[motion])
    assert list(posed) == list(rest)
    moved = posed[tip]["scene_vertices"].mean(0) - rest[tip]["scene_vertices"].mean(0)
    # Paper's motions: extension bends dorsally (+Y), flexion ventrally (-Y), waggle sideways (+X);
    # at the pressure limits each segment bends tens of degrees, so the tip moves a good part of the
    # tail's length.
    assert sign * moved[axis] > 0.3 * spec.length_mm, moved
    assert abs(moved[1 - axis]) < 0.05 * spec.length_mm, (
        moved
    )  # out of the bending plane: gravity's sag only
    assert moved[2] < 0  # a bent tail is shorter along its rest axis
    # The root panel is held by the mount; every panel moves as a rigid body (distances kept).
    np.testing.assert_allclose(
        posed["panel0"]["scene_vertices"], rest["panel0"]["scene_vertices"], atol=1e-4
    )
    for k in range(spec.panels):
        a, b = rest[f"panel{k}"]["scene_vertices"], posed[f"panel{k}"]["scene_vertices"]
        idx = np.random.default_rng(k).integers(0, len(a), (200, 2))
        np.testing.assert_allclose(
            np.linalg.norm(b[idx[:, 0]] - b[idx[:, 1]], axis=1),
            np.linalg.norm(a[idx[:, 0]] - a[idx[:, 1]], axis=1),
            atol=1e-3,
        )
    # The file's description names the pose the statics found.
    pose = built["poses"][motion]
    assert sign * (pose.tip_mm - pose.rest_tip_mm)[axis] > 0
    assert decoded[motion]["extras"]["note"] == built["scenes"][motion].note


def test_mold_parts_move_out_along_their_pull_directions(built, decoded):
    objs = {o["name"].removesuffix(" (sacrificial)"): o for o in decoded["molds"]["nodes"]}
    for name, part in built["mold_set"].parts.items():
        shift = objs[name]["T_mm"][:3, 3]
        if part.sacrificial:
            np.testing.assert_allclose(shift, 0.0, atol=1e-9)
            continue
        d = np.asarray(part.pull_direction, float)
        assert shift @ d > 10.0, name  # well clear of the closed mold
        np.testing.assert_allclose(
            shift - (shift @ d) * d, 0.0, atol=1e-6
        )  # along the pull, nothing else
        np.testing.assert_allclose(
            objs[name]["rgb_linear"], [linear(c) for c in RGB[part.role]], atol=0.5 / 255
        )
    assert "cast SOA" in objs and objs["cast SOA"]["alpha"] < 1.0


def test_rigid_twin_has_the_tail_outer_envelope(built, decoded):
    spec = built["asm"].spec
    objs = decoded["rigid_twin"]["nodes"]
    assert [o["name"] for o in objs] == [p.name for p in built["pieces"]]
    pts = np.vstack([o["scene_vertices"] for o in objs])
    rest = np.vstack([o["scene_vertices"] for o in decoded["rest"]["nodes"]])
    assert pts[:, 2].min() == pytest.approx(0.0, abs=0.05)
    assert pts[:, 2].max() == pytest.approx(spec.length_mm, abs=0.05)
    # "Identical geometric parameters": the twin's cross-section spans the BVSR's panels.
    np.testing.assert_allclose(pts[:, :2].min(0), rest[:, :2].min(0), atol=0.5)
    np.testing.assert_allclose(pts[:, :2].max(0), rest[:, :2].max(0), atol=0.5)


def test_build_twin_scene_is_the_rigid_robots_visual_meshes(built, tmp_path):
    """The build's 3D view takes the twin's visual meshes (the rigid robot's, metres, tail frame)
    instead of meshing the pieces a second time: each piece as given, in the tail frame, where the
    viewer's own meshing puts it to within the two tessellations."""
    import dataclasses

    from bvsr_cad import units
    from bvsr_cad.analysis.poses import twin_scene
    from bvsr_cad.exporters.fabrication_files import write_rigid_files
    from bvsr_cad.parts.kernel import fresh_copy

    pieces = [
        dataclasses.replace(p, solid=fresh_copy(p.solid)) for p in built["pieces"]
    ]  # leave the fixture's be
    visual = write_rigid_files(pieces, tmp_path)
    given = twin_scene(
        pieces, [(units.m_to_mm(np.asarray(m.vertices)), np.asarray(m.faces)) for m in visual]
    )
    own = built["scenes"]["rigid_twin"]
    assert (
        [o.label for o in given.objects]
        == [o.label for o in own.objects]
        == [p.name for p in pieces]
    )
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
        # the same surface: the given mesh's area within 1 % of the B-rep's faces meshed by the
        # viewer
        assert trimesh.Trimesh(b.vertices_mm, b.triangles).area == pytest.approx(
            trimesh.Trimesh(a.vertices_mm, a.triangles).area, rel=0.01
        )


def test_viewer_files_carry_the_glb_bytes_and_three_js(export):
    """Each scene file is its GLB, gzipped and base64; viewer.js holds three.js's modules as
    published."""
    from bvsr_cad.exporters.viewer import MODULES, THREE

    root, viewer = export["root"], export["manifest"]["viewer"]
    total = sum((root / f).stat().st_size for f in (viewer["script"], "report/three-LICENSE.txt"))
    for entry in viewer["scenes"]:
        text = (root / entry["file"]).read_text()
        m = re.fullmatch(re.escape(CALL) + r'"(\w+)", "([A-Za-z0-9+/=]+)"\);\n', text)
        assert m and m.group(1) == entry["name"], entry["file"]
        assert gzip.decompress(base64.b64decode(m.group(2))) == (root / entry["glb"]).read_bytes()
        total += len(text)
    assert total == viewer["bytes"]
    script = (root / viewer["script"]).read_text()
    imports = json.loads(re.search(r"imports: (\{.*?\n\})", script, re.S).group(1))
    assert set(imports) == set(MODULES) and viewer["library"] == "three 0.185.0"
    for name, url in imports.items():
        code = base64.b64decode(url.removeprefix("data:text/javascript;base64,")).decode()
        # Only the module's relative imports were renamed: the same length of code within their
        # names'.
        original = (THREE / MODULES[name]).read_text()
        assert abs(len(code) - len(original)) < 200 and code.count("import") == original.count(
            "import"
        )
        assert not re.search(r"""from\s*['"]\.{1,2}/""", code), (
            name
        )  # nothing left relative to a data: URL
    assert "MIT License" in (root / "report" / "three-LICENSE.txt").read_text()


def test_nothing_reaches_for_the_network(export):
    root = export["root"]
    files = [
        export["page"],
        root / "report" / "viewer.js",
        *sorted((root / "report").glob("viewer_*.js")),
    ]
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


#: Chromium's headless flags: software WebGL (SwiftShader), and virtual time run on until the page
#: is idle (the scene arrives through promises: decompression and three.js's GLTF parser) or 30 s
#: pass.
CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--enable-unsafe-swiftshader",
    "--use-angle=swiftshader",
    "--disable-background-networking",
    "--virtual-time-budget=30000",
]


def _screenshot(page: Path, fragment: str, out: Path, profile: Path) -> np.ndarray:
    from PIL import Image

    cmd = [
        shutil.which("chromium"),
        *CHROMIUM_FLAGS,
        "--hide-scrollbars",
        f"--user-data-dir={profile}",
        f"--screenshot={out}",
        "--window-size=1000,800",
        page.as_uri() + fragment,
    ]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
    assert out.is_file(), (
        f"chromium wrote no screenshot (rc {run.returncode}): {run.stderr[-2000:]}"
    )
    return np.asarray(Image.open(out).convert("RGB"), int)


#: A colour each scene shows, by its kind in the colour table: (kind, channel that is highest,
#: lowest).
SCENE_COLOUR = {
    "rest": ("soa", 0, 2),
    "extension": ("soa", 0, 2),
    "flexion": ("soa", 0, 2),
    "waggle": ("soa", 0, 2),
    "molds": ("shell", 2, 0),
    "rigid_twin": ("rigid_tail", 0, 2),
}


@pytest.mark.parametrize("scene", list(SCENE_COLOUR))
def test_the_page_draws_the_scene_in_headless_chromium(export, scene, tmp_path):
    if shutil.which("chromium") is None:
        pytest.skip(
            "chromium is not installed (Debian: apt-get install chromium); the page is not drawn"
        )
    shot = tmp_path / f"viewer_{scene}.png"
    img = _screenshot(export["page"], f"#viewer={scene}", shot, tmp_path / "profile")
    is_bg = np.all(np.abs(img - BACKGROUND_RGB) <= 2, axis=-1)
    assert is_bg.sum() > 1000, (
        "no canvas background in the screenshot: the page did not lay out a canvas"
    )
    rows, cols = np.nonzero(is_bg)
    y0, y1, x0, x1 = rows.min(), rows.max(), cols.min(), cols.max()
    # The canvas: the whole page width and 560 px high (report.VIEWER_CSS).
    assert x1 - x0 > 900 and 500 < y1 - y0 < 600, (x0, y0, x1, y1)
    box = img[y0 : y1 + 1, x0 : x1 + 1]
    drawn = np.any(np.abs(box - BACKGROUND_RGB) > 30, axis=-1)
    assert drawn.mean() > 0.03, f"only {drawn.mean():.2%} of the canvas drawn"
    # The scene's colour (shaded, perhaps translucent) is there: its highest channel above its
    # lowest by at least half the table's difference, on thousands of pixels.
    kind, hi, lo = SCENE_COLOUR[scene]
    c = np.array(RGB[kind]) * 255
    assert c[hi] - c[lo] > 15
    assert np.sum(box[..., hi] - box[..., lo] > 0.5 * (c[hi] - c[lo])) > 2000
    # The script ran: the caption under the canvas names the scene (the page's static text says
    # JavaScript is off).
    dom = subprocess.run(
        [
            shutil.which("chromium"),
            *CHROMIUM_FLAGS,
            f"--user-data-dir={tmp_path / 'profile'}",
            "--dump-dom",
            export["page"].as_uri() + f"#viewer={scene}",
        ],
        capture_output=True,
        text=True,
        timeout=180,
    )
    info = re.search(r'id="bvsr-viewer-info">(.*?)</div>', dom.stdout, re.S)
    title = next(s["title"] for s in export["manifest"]["viewer"]["scenes"] if s["name"] == scene)
    assert info and title in info.group(1) and "triangles" in info.group(1), dom.stdout[-2000:]
    count = len(
        next(f for f in export["manifest"]["scenes"]["files"] if f["name"] == scene)["nodes"]
    )
    assert f"{count} objects" in info.group(1)
    assert re.search(
        rf'class="active" data-scene="{scene}"|data-scene="{scene}" class="active"', dom.stdout
    )


def test_tail_scene_meshes_do_not_depend_on_earlier_tessellations(built):
    """OCCT keeps the finest triangulation a solid was given; the tail's scene meshes a copy, so a
    build that took the part files from its cache (no 0.01 mm STL meshing) shows the same scene as a
    cold one."""
    from bvsr_cad.analysis.poses import _tail_meshes
    from bvsr_cad.parts.kernel import mesh_arrays

    asm = built["asm"]
    before = _tail_meshes(asm)
    for part in asm.parts.values():
        mesh_arrays(part.solid, 0.005, 0.05)
    after = _tail_meshes(asm)
    for name, m in before.items():
        np.testing.assert_array_equal(m.vertices, after[name].vertices)
        np.testing.assert_array_equal(m.faces, after[name].faces)
