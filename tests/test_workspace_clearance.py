"""Workspace protocol, the clearance bound (never above the exact distance), CLI exit codes."""

from __future__ import annotations

import numpy as np
import pytest

from bvsr_cad.cli import main

from .conftest import PARAMS


@pytest.fixture(scope="module")
def asm(bvsr_spec):
    from bvsr_cad.assembly.assemble import build_assembly

    return build_assembly(bvsr_spec)


def test_protocol_pressures_in_range(bvsr_spec):
    from bvsr_cad.analysis.workspace import sample_line_pressures_kpa

    p = sample_line_pressures_kpa(bvsr_spec, 3000, np.random.default_rng(0))
    assert p.min() >= 50 - 101 and p.max() <= 150 - 101
    frac = [(p > 0).mean(), (p < 0).mean(), (p == 0).mean()]
    assert frac == pytest.approx([1 / 3] * 3, abs=0.03)


def test_bound_is_conservative_and_exact_at_rest(asm):
    from bvsr_cad.analysis.clearance import TIE_MM, posed_tail

    pt = posed_tail(asm)
    n = pt.kin.n_joints
    everything = np.arange(len(pt.pairs))
    np.testing.assert_allclose(pt.exact(np.zeros((n, 2)), everything), pt.rest_mm, atol=1e-9)
    rng = np.random.default_rng(5)
    w = rng.normal(size=(2, n, 2)) * 0.3
    lam = pt.stretch(w)
    lb = lam * pt.rest_mm
    for k in range(len(w)):
        exact = pt.exact(w[k], everything)
        refined = pt.refine(lam[k], everything)
        assert (refined >= lb[k] - 1e-12).all()
        # The posed meshes follow the arcs by chords: their distances are good to TIE_MM.
        assert (exact >= refined - TIE_MM).all()
        # The bounds bite: stage 1b is within 20 % of the exact clearance for most pairs at 0.3 rad.
        assert np.median(refined / exact) > 0.8
    # Panels are posed as their rest BVH under a rigid transform: the same as deforming the mesh.
    import trimesh

    from bvsr_cad.analysis.clearance import _fcl_distance

    a, b = pt.names.index("panel0"), pt.names.index("panel1")
    pair = int(np.flatnonzero((pt.pairs[:, 0] == a) & (pt.pairs[:, 1] == b))[0])
    posed = [
        trimesh.Trimesh(pt.deform_points(pt.meshes[i].vertices, w[1]), pt.meshes[i].faces)
        for i in (a, b)
    ]
    assert pt.exact(w[1], np.array([pair]))[0] == pytest.approx(_fcl_distance(*posed), abs=1e-9)
    # Flanges seated in one panel move rigidly: their clearance does not change with the pose,
    # and the refined bound (a horizontal gap) keeps it.
    i = int(np.argmin(pt.rest_mm))
    assert pt.exact(w[0], np.array([i]))[0] == pytest.approx(pt.rest_mm[i], abs=1e-3)
    assert pt.refine(lam[0, [i]], np.array([i]))[0] == pytest.approx(pt.rest_mm[i], abs=1e-3)


def test_clearance_over_is_certified_and_limits_are_conservative(asm):
    from bvsr_cad.analysis.clearance import TIE_MM, clearance_over, posed_tail
    from bvsr_cad.analysis.limits import fold_stack, joint_limits, stack_limit_rad

    pt = posed_tail(asm)
    rng = np.random.default_rng(2)
    w = rng.normal(size=(500, pt.kin.n_joints, 2)) * 0.05
    res = clearance_over(pt, w)
    assert res.certified and res.lower_bound_mm == res.min_clearance_mm
    # Brute force over the poses the reported minimum and its neighbours came from.
    worst = np.argsort(pt.lower_bounds(w).min(axis=1))[:3]
    everything = np.arange(len(pt.pairs))
    assert min(pt.exact(w[p], everything).min() for p in worst) >= res.min_clearance_mm - TIE_MM
    need = asm.spec.analysis.min_clearance_mm
    stack = fold_stack(asm.spec)
    bound = joint_limits(pt, need, n_phi=4, exact=False, stack=stack)
    lims = joint_limits(pt, need, n_phi=4, exact=True, stack=stack)
    for b, lim in zip(bound, lims):
        assert b.theta_max_rad == b.theta_bound_rad == lim.theta_bound_rad
        assert all(x >= y for x, y in zip(lim.theta_max_rad, lim.theta_bound_rad))
    for lim in (bound[-1], lims[-1]):
        k = int(lim.joint[1:]) - 1
        for phi, th, why in zip(lim.phi_rad, lim.theta_max_rad, lim.limited_by):
            pose = np.zeros((pt.kin.n_joints, 2))
            pose[k] = (th * np.cos(phi), th * np.sin(phi))
            assert pt.exact(pose, np.flatnonzero(pt.span[:, k])).min() >= need
            if why == "fold stack":  # then theta_max is where the most compressed SOA folds flat
                assert th == pytest.approx(stack_limit_rad(pt, k, np.array([phi]), *stack)[0])


def test_a_posed_tail_read_back_from_its_pickle_gives_the_same_clearances(asm):
    """The build keeps a geometry's posed tail in its cache (pickled without FCL's objects and the
    caches it fills as it goes): read back, before or after its caches filled, it gives the same
    clearances to the bit, so an edit built from the cache equals one built without it."""
    import dataclasses
    import pickle

    from bvsr_cad.analysis.clearance import clearance_over, posed_tail

    pt = posed_tail(asm)
    before = pickle.loads(pickle.dumps(pt))
    w = np.random.default_rng(3).normal(size=(200, pt.kin.n_joints, 2)) * 0.08
    res = clearance_over(pt, w)
    assert pt.rest_bvh and pt._aniso  # filled as it went
    after = pickle.loads(pickle.dumps(pt))
    assert after.rest_bvh == {} and after._aniso == {} and after._scaled == {}
    fields = lambda r: {k: v for k, v in dataclasses.asdict(r).items() if k != "seconds"}  # noqa: E731
    for copy in (before, after):
        assert fields(clearance_over(copy, w)) == fields(res)
        assert np.array_equal(copy.rest_mm, pt.rest_mm) and np.array_equal(copy.pairs, pt.pairs)
        everything = np.arange(len(pt.pairs))
        assert np.array_equal(copy.exact(w[0], everything), pt.exact(w[0], everything))


def test_cli_bad_input_exit_2(capsys):
    assert main(["clearance", str(PARAMS / "bvsr.toml"), "--poses", "0"]) == 2
    assert main(["workspace", str(PARAMS / "nope.toml")]) == 2


def test_the_limit_searchs_shortcuts_give_the_same_numbers(asm):
    """The one-joint screen is PosedTail.stretch to the last bit, and the lowest limit per joint
    found with planes skipped is the minimum of the full search's."""
    from bvsr_cad.analysis.clearance import posed_tail
    from bvsr_cad.analysis.limits import (
        _pose,
        _Tester,
        fold_stack,
        joint_limits,
        lowest_limits_rad,
        per_joint_rad,
    )

    pt = posed_tail(asm)
    need = asm.spec.analysis.min_clearance_mm
    rng = np.random.default_rng(11)
    for k in range(pt.kin.n_joints):
        test = _Tester(pt, k, need)
        for theta, phi in [
            (0.0, 0.0),
            (1.0, np.pi),
            *zip(rng.uniform(0, 1.2, 20), rng.uniform(-np.pi, np.pi, 20)),
        ]:
            w = _pose(pt, k, float(theta), float(phi))
            np.testing.assert_array_equal(test._stretch(w), pt.stretch(w[None])[0, test.ids])
    stack = fold_stack(asm.spec)
    full = joint_limits(pt, need, n_phi=12, stack=stack)
    assert lowest_limits_rad(pt, need, n_phi=12, stack=stack) == per_joint_rad(full)


def test_plane_sections_is_the_posed_tails_map_without_its_meshes(asm):
    """The 3D view and the API pose with the plane-section map alone: the same map, value for value,
    as the clearance analysis's PosedTail (which meshes every instance and finds its pairs
    first)."""
    from bvsr_cad.analysis.clearance import plane_sections, posed_tail

    full, bare = posed_tail(asm, cutoff_mm=-1.0), plane_sections(asm)
    assert bare.meshes == [] and len(bare.pairs) == 0 and len(full.meshes) == len(asm.instances)
    rng = np.random.default_rng(7)
    pts = np.c_[rng.uniform(-40, 40, (4000, 2)), rng.uniform(-5.0, asm.spec.length_mm + 5.0, 4000)]
    for _ in range(4):
        w = rng.uniform(-0.6, 0.6, (asm.spec.joints, 2))
        np.testing.assert_array_equal(bare.deform_points(pts, w), full.deform_points(pts, w))


def test_stage_1b_shares_a_shortened_mesh_between_spans_that_differ_only_above_it(asm):
    """A gap that starts above a mesh moves none of its vertices, and an SOA is a turned copy of its
    joint's first: d_lambda from the shared (turned) BVHs, or the pair's turned copy's, equals the
    distance of both meshes shortened by the pair's whole span (to 1e-12 mm: the placements are
    turns of each other to 4e-15), and fewer meshes are built than (instance, grid value, span)
    combinations asked for, the SOAs' shortened meshes only for each joint's first."""
    import trimesh

    from bvsr_cad.analysis.clearance import LAMBDA_GRID, _fcl_distance, attained_gap_mm, posed_tail

    pt = posed_tail(asm)
    asked = set()
    spanned = [p for p in range(len(pt.pairs)) if pt.span[p].any()]
    rng = np.random.default_rng(2)
    picks = [
        (int(p), int(k))
        for p, k in zip(rng.choice(spanned, 40), rng.integers(0, len(LAMBDA_GRID) - 1, 40))
    ]
    for p, k in picks:
        shortened = []
        for i in pt.pairs[p]:
            asked.add((int(i), k, pt.span[p].tobytes()))
            v = pt.cut[int(i)].vertices.copy()
            v[:, 2] = pt.shorten_z(v[:, 2], float(LAMBDA_GRID[k]), pt.span[p])
            shortened.append(trimesh.Trimesh(v, pt.cut[int(i)].faces, process=False))
        gap, fcl_mm = attained_gap_mm(*shortened), _fcl_distance(*shortened)
        assert pt.aniso_rest(p, k) == pytest.approx(fcl_mm if gap is None else gap, abs=1e-12)
        assert gap is None or abs(fcl_mm - gap) < 1e-12
    assert len(pt._scaled) < len(asked)
    soas = {pt.names[i] for i, _k, _s in pt._scaled if pt.instances[i].role == "soa"}
    assert soas and all(name.endswith("_soa1") for name in soas)


def test_the_soas_of_a_joint_are_turned_copies_and_turned_pairs_share_d_lambda(asm):
    """Each joint's SOAs 2-5 are its SOA 1 turned about the tail's axis by a multiple of 72 deg (and
    no other instance is a turned copy of another); pairs that are turned copies of an earlier pair
    (two neighbouring SOAs of a joint: one orbit of five) take its d_lambda, which equals their own
    direct distance to 1e-12 mm, for every such pair."""
    import math

    import trimesh

    from bvsr_cad.analysis.clearance import LAMBDA_GRID, _fcl_distance, posed_tail

    pt = posed_tail(asm)
    for i, (ref, rot) in enumerate(pt._turn):
        inst = pt.instances[i]
        if inst.role == "soa":
            assert pt.names[ref] == f"j{inst.joint}_soa1"
            turn = math.degrees(math.atan2(rot[1, 0], rot[0, 0])) % 72.0
            assert min(turn, 72.0 - turn) < 1e-9
        else:
            assert ref == i and np.array_equal(rot, np.eye(3))
    orbits: dict[int, list[int]] = {}
    for p, rep in enumerate(pt._orbit):
        orbits.setdefault(rep, []).append(p)
    neighbours = [
        ps
        for ps in orbits.values()
        if {pt.names[i].split("_")[0] for p in ps for i in pt.pairs[p]} == {"j2"} and len(ps) == 5
    ]
    assert neighbours, "the five neighbouring SOA pairs of joint 2 form one orbit"
    k = int(np.searchsorted(LAMBDA_GRID, 0.6))
    shared = [p for ps in orbits.values() if len(ps) > 1 for p in ps if pt.span[p].any()]
    assert set(neighbours[0]) <= set(shared)
    for p in shared:
        span = pt.span[p]
        shortened = []
        for i in pt.pairs[p]:
            v = pt.cut[int(i)].vertices.copy()
            v[:, 2] = pt.shorten_z(v[:, 2], float(LAMBDA_GRID[k]), span & pt._gaps_under[int(i)])
            shortened.append(trimesh.Trimesh(v, pt.cut[int(i)].faces, process=False))
        assert pt.aniso_rest(p, k) == pytest.approx(_fcl_distance(*shortened), abs=1e-12)


def test_a_gap_between_parallel_faces_is_taken_from_the_boxes_where_attained(asm):
    """Meshes apart along one axis: the boxes' gap is their distance when a point of one face of the
    gap lies over a triangle of the other (exactly: one subtraction), None where it does not (an L
    whose notch faces the other mesh, boxes apart along two axes, overlapping boxes); on the default
    tail every rest distance equals FCL's to 1e-12 mm (the gap's, and those of turned copies of an
    earlier pair), and it gives the panels' (parallel faces: FCL's slowest queries) and no others
    than those FCL puts at the boxes' gap."""
    import trimesh

    from bvsr_cad.analysis.clearance import _fcl_distance, attained_gap_mm, posed_tail

    lower = trimesh.creation.box((10.0, 10.0, 2.0))  # top face at z = 1
    upper = trimesh.creation.box((4.0, 4.0, 2.0))
    upper.apply_translation((2.0, 1.0, 1.0 + 2.75 + 1.0))  # bottom face at z = 3.75
    assert attained_gap_mm(lower, upper) == attained_gap_mm(upper, lower) == 2.75
    assert _fcl_distance(lower, upper) == pytest.approx(2.75, abs=1e-12)
    # An L: its top face covers x < 0 only at z = 1 (the x > 0 half is lower); the upper box sits
    # over the notch.
    ell = trimesh.util.concatenate(
        [
            trimesh.creation.box((5.0, 10.0, 2.0)).apply_translation((-2.5, 0, 0)),
            trimesh.creation.box((5.0, 10.0, 1.0)).apply_translation((2.5, 0, -0.5)),
        ]
    )
    over_notch = trimesh.creation.box((2.0, 2.0, 2.0)).apply_translation(
        (3.0, 0.0, 3.0)
    )  # bottom at z = 2
    assert attained_gap_mm(ell, over_notch) is None
    assert _fcl_distance(ell, over_notch) > 1.0 + 1e-9
    diagonal = trimesh.creation.box((4.0, 4.0, 2.0)).apply_translation((20.0, 0.0, 10.0))
    touching = trimesh.creation.box((4.0, 4.0, 2.0)).apply_translation((0.0, 0.0, 1.5))
    assert attained_gap_mm(lower, diagonal) is None and attained_gap_mm(lower, touching) is None
    pt = posed_tail(asm)
    given = 0
    for (a, b), rest in zip(pt.pairs, pt.rest_mm):
        gap, fcl_mm = (
            attained_gap_mm(pt.coarse[a], pt.coarse[b]),
            _fcl_distance(pt.coarse[a], pt.coarse[b]),
        )
        boxes = np.maximum(
            np.maximum(pt.coarse[a].bounds[0], pt.coarse[b].bounds[0])
            - np.minimum(pt.coarse[a].bounds[1], pt.coarse[b].bounds[1]),
            0.0,
        )
        at_boxes = abs(fcl_mm - np.linalg.norm(boxes)) < 1e-9
        assert (gap is not None) == at_boxes, (pt.names[a], pt.names[b])
        # A pair that is a turned copy of an earlier one is at that one's distance (to 1e-14 its
        # own).
        assert rest == pytest.approx(fcl_mm if gap is None else gap, abs=1e-12) and (
            gap is None or abs(gap - fcl_mm) < 1e-12
        )
        given += gap is not None
    panels = {(f"panel{k}", f"panel{k + 1}") for k in range(asm.spec.joints)}
    assert panels <= {
        (pt.names[a], pt.names[b])
        for (a, b), r in zip(pt.pairs, pt.rest_mm)
        if attained_gap_mm(pt.coarse[a], pt.coarse[b]) is not None
    }
    assert given >= len(panels)


def test_analyses_given_the_rest_geometry_make_no_solid_and_give_the_same_results(
    bvsr_spec, monkeypatch
):
    """An edit that moves no solid (a material): the analyses' process gets the cached geometry
    analyses and rest geometry (the posed tail, every part's mass properties), read back from their
    pickles, on an assembly whose solids are made only when read. It makes none, and its workspace,
    quasi-static table and clearance equal those of analyses that made everything, to the bit."""
    import dataclasses
    import pickle

    from bvsr_cad.analysis import run
    from bvsr_cad.assembly.assemble import build_assembly

    monkeypatch.setattr(
        run, "compare_measurements", lambda *_a, **_k: None
    )  # rows need robot models
    kept = []
    full = run.run_analyses(build_assembly(bvsr_spec), on_rest=kept.append)
    assert len(kept) == 1 and sorted(kept[0].properties) == sorted(
        build_assembly(bvsr_spec, solids=False).parts
    )
    lazy = build_assembly(bvsr_spec, solids=False)
    again = run.run_analyses(
        lazy,
        geometry=pickle.loads(pickle.dumps(full.geometry)),
        rest=pickle.loads(pickle.dumps(kept[0])),
        on_rest=kept.append,
    )
    assert not any(p.solid_made for p in lazy.parts.values()) and len(kept) == 1
    for name in ("tip_mm", "w", "line_kpa"):
        assert np.array_equal(getattr(again.workspace, name), getattr(full.workspace, name))
    assert again.quasi_static == full.quasi_static
    fields = lambda r: {k: v for k, v in dataclasses.asdict(r).items() if k != "seconds"}  # noqa: E731
    assert fields(again.clearance) == fields(full.clearance)
    # Read, a solid is made then: the same one an eager assembly has.
    assert (
        lazy.parts["panel1"].solid.volume == build_assembly(bvsr_spec).parts["panel1"].solid.volume
    )
    assert lazy.parts["panel1"].solid_made
