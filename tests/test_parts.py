"""Part generators against closed forms and independent computations."""

from __future__ import annotations

import dataclasses
import math

import pytest

from bvsr_cad.assembly.assemble import build_assembly
from bvsr_cad.parameters import layout
from bvsr_cad.parameters.load import load_spec, spec_from_dict
from bvsr_cad.parts.panel import panel
from bvsr_cad.parts.soa import bellows_profile, soa_body
from bvsr_cad.parts.vertebra import rod

from .conftest import PARAMS


def test_featureless_panel_is_a_frustum(bvsr_spec):
    lay = dataclasses.replace(layout.panel_layout(bvsr_spec, 2), cuts=(), bosses=(), passages=())
    solid = panel(lay)
    r1, r2, h = lay.rim_radius_lower_mm, lay.rim_radius_upper_mm, lay.thickness_mm
    assert r1 > r2  # the taper narrows towards the tip
    assert solid.volume == pytest.approx(math.pi * h * (r1 * r1 + r1 * r2 + r2 * r2) / 3, rel=1e-9)
    # With no taper it is pi r^2 h.
    flat = dataclasses.replace(lay, rim_radius_upper_mm=r1)
    assert panel(flat).volume == pytest.approx(math.pi * r1 * r1 * h, rel=1e-9)


def _bellows_volume_closed_form(soa, flange_d):
    """Independent of the CAD kernel: rounded-square frustums and flat flanges.

    A ruled loft between two squares rounded at the same R has rounded-square
    sections all along, so each facet row holds integral (s(z)^2 - (4 - pi) R^2) dz
    with s linear in z; the inside is a sharp square offset by t / cos(facet slope).
    """
    R = soa.fillet_radius_mm
    rise = soa.row_rise_mm
    depth = (soa.long_side_mm - soa.short_side_mm) / 2
    off = soa.facet_thickness_mm / math.cos(math.atan(depth / rise))
    vol = 0.0
    for m in range(2 * soa.pleats):
        s0, s1 = (
            (soa.long_side_mm, soa.short_side_mm)
            if m % 2 == 0
            else (soa.short_side_mm, soa.long_side_mm)
        )
        outer = rise * (s0 * s0 + s0 * s1 + s1 * s1) / 3 - (4 - math.pi) * R * R * rise
        i0, i1 = s0 - 2 * off, s1 - 2 * off
        inner = rise * (i0 * i0 + i0 * i1 + i1 * i1) / 3
        vol += outer - inner
    f = (soa.height_mm - soa.origami_height_mm) / 2
    end_inner = soa.long_side_mm - 2 * off
    vol += 2 * f * (math.pi * flange_d**2 / 4 - end_inner**2)
    return vol


@pytest.mark.parametrize("pleats,t", [(2, 1.0), (3, 0.8)])
def test_soa_volume_matches_closed_form(bvsr_spec, pleats, t):
    soa = dataclasses.replace(bvsr_spec.soa, pleats=pleats, facet_thickness_mm=t)
    solid = soa_body(soa, bvsr_spec.joint.base_diameter_mm)
    assert solid.is_valid
    assert solid.volume == pytest.approx(
        _bellows_volume_closed_form(soa, bvsr_spec.joint.base_diameter_mm), rel=1e-6
    )
    box = solid.bounding_box()
    assert box.max.Z - box.min.Z == pytest.approx(soa.built_height_mm, abs=1e-6)


def test_soa_profile_has_mountains_at_the_ends(bvsr_spec):
    p = bellows_profile(bvsr_spec.soa, bvsr_spec.joint.base_diameter_mm)
    assert p.outer_side_mm[0] == p.outer_side_mm[-1] == bvsr_spec.soa.long_side_mm
    assert min(p.outer_side_mm) == bvsr_spec.soa.short_side_mm
    assert p.z_mm[-1] - p.z_mm[0] == pytest.approx(bvsr_spec.soa.origami_height_mm)


def test_rod_volume():
    assert rod(6.0, 130.53).volume == pytest.approx(math.pi * 9.0 * 130.53, rel=1e-9)
    with pytest.raises(ValueError, match="diameter_mm"):
        rod(0.0, 10.0)


@pytest.mark.parametrize("name,n_soa,n_panels,n_rods", [("bvsr", 30, 7, 2), ("bvsr_l", 45, 10, 3)])
def test_assemblies_are_valid_solids_with_spec_names(name, n_soa, n_panels, n_rods):
    spec = load_spec(PARAMS / f"{name}.toml")
    asm = build_assembly(spec)
    for part in asm.parts.values():
        assert part.solid.is_valid and len(part.solid.solids()) == 1, part.name
    names = [i.name for i in asm.instances]
    assert len(names) == len(set(names))
    assert sum(n.startswith("j") and "_soa" in n for n in names) == n_soa
    assert [n for n in names if n.startswith("panel")] == [f"panel{k}" for k in range(n_panels)]
    assert [n for n in names if n.startswith("rod_")] == [f"rod_s{s}" for s in range(1, n_rods + 1)]
    assert f"j{n_panels - 1}_soa5" in names
    assert asm.instances_of("soa") and len(asm.instances_of("soa")) == n_soa


def _panel_kinds(spec):
    return {layout.panel_kind(spec, k): k for k in range(spec.panels)}


@pytest.mark.parametrize("socket", ["threaded", "set_screw"])
@pytest.mark.parametrize("diameter", [4.0, 5.0, 6.0])
def test_every_rod_diameter_and_socket_gives_valid_panels(bvsr_spec, diameter, socket):
    spec = dataclasses.replace(
        bvsr_spec,
        vertebra=dataclasses.replace(bvsr_spec.vertebra, diameter_mm=diameter, socket=socket),
    )
    if (
        diameter == 4.0
    ):  # the twin's M3 tie-rod hole would leave 0.3 mm of a 4 mm rod column: M2 fits
        spec = dataclasses.replace(
            spec,
            fabrication_package=dataclasses.replace(spec.fabrication_package, tie_rod_thread=2.0),
        )
    spec = spec_from_dict(dataclasses.asdict(spec))  # goes through validation
    for kind, k in _panel_kinds(spec).items():
        lay = layout.panel_layout(spec, k)
        solid = panel(lay)
        assert solid.is_valid, (kind, diameter, socket)
        # The bore is a through hole inside solid material: removing it adds
        # exactly its cylinder back (over the panel and any collar).
        plain = dataclasses.replace(lay, cuts=tuple(c for c in lay.cuts if c.role != "rod"))
        z_lo = min([0.0] + [b.z_range[0] for b in lay.bosses])
        z_hi = max([lay.thickness_mm] + [b.z_range[1] for b in lay.bosses])
        # ISO 2306 tap drill of M4/M5/M6 (3.3, 4.2, 5.0) plus the printed-hole compensation; not
        # rod_bore_mm().
        bore = {4.0: 3.3, 5.0: 4.2, 6.0: 5.0}[diameter] + spec.fabrication.hole_compensation_mm
        expected = math.pi * bore**2 / 4 * (z_hi - z_lo)
        if socket == "set_screw":
            continue  # the set screw crosses the bore: checked by validity above
        assert panel(plain).volume - solid.volume == pytest.approx(expected, rel=1e-6), kind


def test_rod_material_changes_mass_not_geometry(bvsr_spec):
    pvc = dataclasses.replace(
        bvsr_spec, vertebra=dataclasses.replace(bvsr_spec.vertebra, material="PVC")
    )
    a = layout.panel_layout(bvsr_spec, 1)
    b = layout.panel_layout(pvc, 1)
    assert a == b


def test_remembered_solids_are_made_once_copied_per_call_and_bounded():
    """parts.kernel.remembered: a repeated call does not make the solid again and gets its own copy
    (a triangulation or label on one leaves the others as they were); past REMEMBERED_MAX arguments
    the least recently used is made again, the others are not."""
    import build123d as bd

    from bvsr_cad.parts import kernel

    made: list[float] = []

    @kernel.remembered
    def box(size_mm: float) -> bd.Solid:
        made.append(size_mm)
        return bd.Solid.make_box(size_mm, 1.0, 1.0)

    first = box(1.0)
    again = box(1.0)
    assert made == [1.0]
    assert first.wrapped is not again.wrapped and not first.wrapped.IsSame(again.wrapped)
    first.label = "mine"
    first.mesh(0.1)
    assert box(1.0).label != "mine"
    assert math.isclose(again.volume, 1.0, rel_tol=1e-12)
    sizes = [1.0 + k for k in range(1, kernel.REMEMBERED_MAX)]  # REMEMBERED_MAX arguments in all
    for s in sizes:
        box(s)
    box(1.0)  # used last: kept, and 2.0 is now the least recently used
    assert made == [1.0, *sizes]
    box(100.0)  # one more than the bound: 2.0 goes
    box(1.0)
    box(3.0)
    assert made == [1.0, *sizes, 100.0]
    box(2.0)
    assert made == [1.0, *sizes, 100.0, 2.0]
    assert math.isclose(box(2.0).volume, 2.0, rel_tol=1e-12)


def test_kernel_threads_run_the_kernel_on_one_thread_for_the_same_solids(bvsr_spec, tmp_path):
    """process.kernel_threads: OCCT's pool on the threads asked for, the number before
    returned (to give back); a panel's booleans and its print STL on one thread are the parallel
    ones, byte for byte."""
    from OCP.OSD import OSD_ThreadPool

    from bvsr_cad.exporters.cad import write_stl
    from bvsr_cad.process import kernel_threads

    pool = OSD_ThreadPool.DefaultPool_s()
    before = kernel_threads(2)
    try:
        assert pool.NbThreads() == 2
        lay = layout.panel_layout(bvsr_spec, 1)
        write_stl(panel(lay), tmp_path / "parallel.stl")
        assert kernel_threads(1) == 2 and pool.NbThreads() == 1
        write_stl(panel(lay), tmp_path / "one.stl")
        assert (tmp_path / "one.stl").read_bytes() == (tmp_path / "parallel.stl").read_bytes()
        assert kernel_threads(0) == 1 and pool.NbThreads() == 1  # at least the calling thread
    finally:
        kernel_threads(before)


def test_ruled_loft_gives_its_flat_bands_planes_for_the_same_solid(bvsr_spec):
    """A ruled loft of squares is a stack of square frusta, V = h (a^2 + a b + b^2) / 3 each, every
    band flat: all of them planes. Of the rounded squares only the corners' bands are curved: every
    face left a B-spline is one (not flat), and the outer surface is the loft's own (volume to
    1e-9)."""
    import build123d as bd
    from OCP.BRep import BRep_Tool
    from OCP.GeomLib import GeomLib_IsPlanarSurface

    from bvsr_cad.parts.kernel import ruled_loft
    from bvsr_cad.parts.soa import rounded_square

    sides, zs = (20.0, 8.0, 14.0), (0.0, 5.0, 12.0)
    solid = ruled_loft([rounded_square(s, 0.0, z) for s, z in zip(sides, zs)], "test loft")
    frusta = sum(
        (z1 - z0) * (a * a + a * b + b * b) / 3
        for a, b, z0, z1 in zip(sides, sides[1:], zs, zs[1:])
    )
    assert solid.is_valid and solid.volume == pytest.approx(frusta, rel=1e-9)
    assert {f.geom_type for f in solid.faces()} == {bd.GeomType.PLANE} and len(
        solid.faces()
    ) == 2 + 4 * 2
    p = bellows_profile(bvsr_spec.soa, bvsr_spec.joint.base_diameter_mm)
    sections = [rounded_square(s, p.corner_radius_mm, z) for s, z in zip(p.outer_side_mm, p.z_mm)]
    made, plain = ruled_loft(sections, "outer"), bd.loft(sections, ruled=True)
    assert made.is_valid and made.volume == pytest.approx(plain.volume, rel=1e-9)
    bands = [f for f in made.faces() if f.geom_type == bd.GeomType.BSPLINE]
    assert not any(
        GeomLib_IsPlanarSurface(BRep_Tool.Surface_s(f.wrapped), 1e-7).IsPlanar() for f in bands
    )
    assert len(bands) == 4 * (len(sections) - 1)  # the four corners of each band


def test_solid_properties_are_build123d_s_three_properties_to_the_bit(bvsr_spec):
    """SolidProperties.of integrates each B-rep once: its volume, centre of mass and inertia equal
    build123d's ``volume``, ``center(CenterOf.MASS)`` and ``matrix_of_inertia`` (three integrations)
    exactly, for every part of the tail and a rigid twin's piece."""
    import build123d as bd
    import numpy as np

    from bvsr_cad.assembly.inertia import SolidProperties
    from bvsr_cad.assembly.products import build_rigid_twin

    asm = build_assembly(bvsr_spec)
    solids = [p.solid for p in asm.parts.values()] + [build_rigid_twin(asm)[0].solid]
    for solid in solids:
        props = SolidProperties.of(solid)
        assert props.volume_mm3 == solid.volume
        assert np.array_equal(props.com_mm, np.array(tuple(solid.center(bd.CenterOf.MASS))))
        assert np.array_equal(props.inertia_mm5, np.asarray(solid.matrix_of_inertia, float))


def test_bounds_is_bounding_box_and_keeps_the_triangulation(bvsr_spec):
    """parts.kernel.bounds gives build123d's ``bounding_box`` to the bit on every part, every face
    of a part and the placed tail, and leaves a meshed shape's triangulation in place
    (``bounding_box`` clears it: a robot mesh or a fit after it meshed again)."""
    import build123d as bd
    from OCP.BRepTools import BRepTools

    from bvsr_cad.assembly.assemble import instance_solid
    from bvsr_cad.parts.kernel import bounds, mesh_absolute

    asm = build_assembly(bvsr_spec)
    shapes = [bd.Compound([instance_solid(asm, i) for i in asm.instances])]
    for p in asm.parts.values():
        shapes += [p.solid, *p.solid.faces()]
    for s in shapes:
        mesh_absolute(s, 0.01, 0.1)
        box = bounds(s)
        assert BRepTools.Triangulation_s(s.wrapped, 0.01), type(s).__name__
        ref = s.bounding_box()
        assert not BRepTools.Triangulation_s(s.wrapped, 0.01)  # what bounds avoids
        assert (tuple(box.min), tuple(box.max)) == (tuple(ref.min), tuple(ref.max)), type(
            s
        ).__name__
