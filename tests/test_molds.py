"""The SOA casting mold set: built, exported and proven castable from its meshes."""

from __future__ import annotations

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
import trimesh

from bvsr_cad.checks.export import Export
from bvsr_cad.checks.molds import (
    MoldMesh,
    cast_samples,
    check_demolding,
    check_molds,
    mold_meshes,
    subdivided_triangles,
)
from bvsr_cad.checks.queries import contains
from bvsr_cad.exporters.mold_files import write_molds
from bvsr_cad.parameters.load import ParamError, spec_from_dict
from bvsr_cad.parts.mold import mold_set

MOLD_PARTS = {"half_a", "half_b", "bottom_plate", "lid", "core"}


def _export_molds(spec, root: Path) -> Export:
    """Write only the mold set of ``spec`` and open it as an export."""
    root.mkdir(parents=True, exist_ok=True)
    fragment = write_molds(
        SimpleNamespace(spec=spec),
        mold_set(spec.soa, spec.joint.base_diameter_mm, spec.casting),
        root,
        lambda _m: None,
    )
    (root / "molds.json").write_text(json.dumps(fragment))
    return Export(root, fragment)


@pytest.fixture(scope="module")
def default_molds(tmp_path_factory, bvsr_spec):
    exp = _export_molds(bvsr_spec, tmp_path_factory.mktemp("molds"))
    return exp, check_molds(exp)


def _by_name(results):
    return {r.name: r for r in results}


def test_manifest_follows_spec_section_7(default_molds):
    exp, _ = default_molds
    molds = exp.manifest["molds"]
    assert (exp.root / molds["cast_part"]).is_file()
    assert (exp.root / molds["exploded_png"]).stat().st_size > 10_000
    parts = {p["name"]: p for p in molds["parts"]}
    assert set(parts) == MOLD_PARTS
    for name, p in parts.items():
        for key in ("stl", "assembled_stl", "step"):
            assert (exp.root / p["files"][key]).is_file(), (name, key)
        if name == "core":
            assert p["pull_direction"] is None and p["sacrificial"] is True
        else:
            assert np.linalg.norm(p["pull_direction"]) == pytest.approx(1.0, abs=1e-12)
    # The split's example: half_a leaves along (1, -1, 0)/sqrt(2), half_b the other way.
    assert parts["half_a"]["pull_direction"] == pytest.approx(
        [math.sqrt(0.5), -math.sqrt(0.5), 0.0]
    )
    assert parts["half_b"]["pull_direction"] == pytest.approx(
        [-math.sqrt(0.5), math.sqrt(0.5), 0.0]
    )
    assert parts["lid"]["pull_direction"] == pytest.approx([0, 0, 1])
    assert parts["bottom_plate"]["pull_direction"] == pytest.approx([0, 0, -1])


def test_cast_is_the_soa_scaled_by_the_shrinkage(bvsr_spec):
    molds = mold_set(bvsr_spec.soa, bvsr_spec.joint.base_diameter_mm, bvsr_spec.casting)
    k = 1.0 + bvsr_spec.casting.shrinkage_percent / 100.0
    assert molds.scale == k
    assert molds.cast.volume == pytest.approx(k**3 * molds.soa_volume_mm3, rel=1e-9)
    box = molds.cast.bounding_box()
    assert box.min.Z == pytest.approx(0.0, abs=1e-5)  # bounding boxes carry a 1e-7 gap
    # fold_height_from = "origami_height": the SOA is Table II's H = 37.60 mm tall.
    assert box.max.Z == pytest.approx(k * 37.60, abs=1e-5)
    for part in molds.parts.values():
        assert part.solid.is_valid and len(part.solid.solids()) == 1


def test_default_mold_set_passes_every_check(default_molds):
    _, results = default_molds
    failed = [r.line() for r in results if r.passed is False]
    assert not failed, failed
    by = _by_name(results)
    assert abs(by["mold_cavity_volume"].value) <= 0.5
    for half in ("half_a", "half_b"):
        # The diagonal split leaves about 34 deg on every facet.
        assert 30.0 <= by[f"mold_draft:{half}"].value <= 40.0
        assert by[f"mold_demold:{half}"].value == 0.0
    for name in MOLD_PARTS:
        assert by[f"mold_min_wall:{name}"].value >= 1.2
        assert by[f"mold_one_body:{name}"].value == 1
    # The core breaks at its valley neck (about 2.8 mm): the check must see it.
    neck_mm = default_molds[0].manifest["molds"]["info"]["valley_core_width_mm"]
    assert by["mold_min_wall:core"].value == pytest.approx(neck_mm, abs=0.05)
    assert by["mold_channel:gate"].passed
    assert sum(1 for r in results if r.name.startswith("mold_channel:vent")) >= 1
    assert by["mold_pu_part"].value == pytest.approx(exp_volume(default_molds[0]), rel=1e-3)


def exp_volume(exp: Export) -> float:
    return float(exp.manifest["molds"]["cast_volume_mm3"])


def test_half_pulled_along_the_axis_is_not_demoldable(default_molds):
    exp, _ = default_molds
    cast, parts, channels = mold_meshes(exp)
    wrong = [
        MoldMesh(
            p.name,
            p.assembled,
            np.array([0.0, 0.0, 1.0]) if p.name == "half_a" else p.pull_direction,
            p.parting_planes,
            p.printed,
            p.where,
        )
        for p in parts
    ]
    samples = cast_samples(cast, wrong, [m for _, _, m in channels])
    by = _by_name(check_demolding(cast, wrong, samples, exp.manifest["molds"]["parting_margin_mm"]))
    bad = by["mold_demold:half_a"]
    assert bad.passed is False and "half_a" in bad.name
    assert bad.value > 10.0  # percent of the surface half_a forms: the downward-facing facets
    assert "NOT demoldable" in bad.note
    assert by["mold_demold:half_b"].passed is True


def test_variant_with_three_pleats_and_thinner_wall_passes(tmp_path, data):
    data["soa"]["pleats"] = 3
    data["soa"]["facet_thickness_mm"] = 0.8
    spec = spec_from_dict(data)
    exp = _export_molds(spec, tmp_path / "variant")
    results = check_molds(exp)
    failed = [r.line() for r in results if r.passed is False]
    assert not failed, failed
    by = _by_name(results)
    # Steeper facets with three pleats: less draft than the default, still positive.
    assert 20.0 <= by["mold_draft:half_a"].value < 34.0
    assert by["mold_pu_part"].value < exp_volume(exp) * 1.001


def test_bad_casting_parameters_are_named(data, bvsr_spec):
    data["casting"]["shrinkage_percent"] = 12.0
    with pytest.raises(ParamError, match="casting.shrinkage_percent"):
        spec_from_dict(data)
    del data["casting"]
    with pytest.raises(ParamError, match="casting"):
        spec_from_dict(data)
    thin = SimpleNamespace(**{**bvsr_spec.casting.__dict__, "cavity_wall_mm": 3.0})
    with pytest.raises(ValueError, match="casting.cavity_wall_mm"):
        mold_set(bvsr_spec.soa, bvsr_spec.joint.base_diameter_mm, thin)


def test_subdivision_is_trimeshs_subdivide_to_size():
    # A box with long and short edges and a cylinder (thin fan triangles): every case of the split.
    for mesh in (
        trimesh.creation.box((7.3, 2.2, 0.6)),
        trimesh.creation.cylinder(4.0, 9.0, sections=24),
    ):
        v, f = trimesh.remesh.subdivide_to_size(mesh.vertices, mesh.faces, max_edge=1.0)
        got = subdivided_triangles(mesh, 1.0)
        assert got.shape == (len(f), 3, 3)

        def rows(tri):
            r = np.round(tri, 12).reshape(len(tri), -1)
            return r[np.lexsort(r.T[::-1])]

        assert np.array_equal(rows(got), rows(v[f]))


def test_contains_is_trimeshs():
    mesh = trimesh.creation.annulus(2.0, 5.0, 4.0, sections=32)
    rng = np.random.default_rng(2)
    on, faces = trimesh.sample.sample_surface(mesh, 2000, seed=3)
    side = rng.choice([-1.0, 1.0], len(on))[:, None]
    pts = np.vstack([rng.uniform(-6, 6, (4000, 3)), on + 0.02 * side * mesh.face_normals[faces]])
    assert np.array_equal(contains(mesh, pts), mesh.contains(pts))
