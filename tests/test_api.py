"""The Python API for CAD users (bvsr_cad.api) and the assembly STEP read back by CadQuery and
FreeCAD.

One assembly is built for the module; the STEP is written by the writer itself into tmp_path
(no full `bvsr build`). Expected values come from outside the API: the manifest's part volumes,
the instance transforms, the colour table, and the constant-curvature forward kinematics written
out below in closed form.
"""

from __future__ import annotations

import json
import math
import os
import re
import shutil
import subprocess
import textwrap

import numpy as np
import pytest

import bvsr_cad
from bvsr_cad import api
from bvsr_cad.assembly.assemble import build_assembly
from bvsr_cad.colors import rgb
from bvsr_cad.exporters.cad import write_assembly_step
from bvsr_cad.exporters.manifest import manifest_dict
from bvsr_cad.exporters.reproducible import fix_step
from bvsr_cad.parameters.load import ParamError, load_spec

from .conftest import PARAMS

#: The README's "Python API" examples, verbatim (README.md, section "Python API for CAD users").
README_API = """
import bvsr_cad

tail = bvsr_cad.load("params/bvsr.toml")      # ParamError if the file is invalid
print(tail.instance_names[:3])                # ['panel0', 'panel1', 'panel2']
soa = tail.parts["soa"]                       # build123d Solid in its part frame, mm
print(f"SOA: {soa.volume:.0f} mm^3")

rest = tail.assembly()                        # Compound: one labelled, coloured child per instance
print(len(rest.children), rest.children[7].label)   # 39 j1_soa1
bent = tail.posed(theta_deg=10, phi_deg=90)   # every joint bent 10 deg towards +Y (dorsal)
tail.write_step("bent.step", posed=bent)      # named, coloured STEP for any CAD system
"""

README_CADQUERY = """
import cadquery as cq
import bvsr_cad

tail = bvsr_cad.load("params/bvsr.toml")
assy = tail.cadquery_assembly(posed=tail.posed(theta_deg=[0, 0, 0, 15, 15, 15]))
print([child.name for child in assy.children][:2])   # ['panel0', 'panel1']

tail.write_step("tail.step")                  # the tail at rest, as in step/assembly.step
back = cq.Assembly.importStep("tail.step")
print(len(back.children), back.children[0].name)    # 39 panel0
"""

#: Link groups off: FreeCAD 0.20's console importer crashes on them; every product then becomes one
#: Part::Feature labelled with the product's name. In console mode Import.insert returns the
#: colours.
FREECAD_SCRIPT = """
import json, os
import FreeCAD as App
import Import

doc = App.newDocument("check")
colours = Import.insert(os.environ["STEP_PATH"], doc.Name, useLinkGroup=False) or []
doc.recompute()
colour_of = {f.Name: [list(c)[:3] for c in cols] for f, cols in colours}
rows = [dict(label=o.Label, solids=len(o.Shape.Solids), volume_mm3=o.Shape.Volume,
             base_mm=list(o.getGlobalPlacement().Base), colours=colour_of.get(o.Name, []))
        for o in doc.Objects if o.TypeId == "Part::Feature"]
with open(os.environ["OUT_JSON"], "w") as f:
    json.dump(rows, f)
"""

VOLUME_REL = 1e-4  # 0.01 %
COLOUR_ABS = 2e-3  # STEP and FreeCAD keep colours in single precision


@pytest.fixture(scope="module")
def asm():
    return build_assembly(load_spec(PARAMS / "bvsr.toml"))


@pytest.fixture(scope="module")
def tail(asm):
    return api.Tail(asm.spec, asm)


@pytest.fixture(scope="module")
def manifest_volumes(asm) -> dict[str, float]:
    """Part volumes as the manifest states them, by instance."""
    m = manifest_dict(asm, "", {name: {} for name in asm.parts}, "step/assembly.step")
    return {inst: p["volume_mm3"] for p in m["parts"] for inst in p["instances"]}


@pytest.fixture(scope="module")
def assembly_step(asm, tmp_path_factory):
    """The tail's STEP as the export writes it: OCCT's file made reproducible (the reimport tests
    read the colours of its canonically ordered presentation section)."""
    path = tmp_path_factory.mktemp("step") / "assembly.step"
    write_assembly_step(asm, path)
    fix_step(path)
    return path


@pytest.fixture()
def in_tmp_with_params(tmp_path, monkeypatch, tail):
    """cwd = tmp_path with params/ beside it, so the README's relative paths work; the examples'
    bvsr_cad.load returns the module's tail for params/bvsr.toml (one build for the module)."""
    (tmp_path / "params").symlink_to(PARAMS, target_is_directory=True)
    monkeypatch.chdir(tmp_path)
    real = api.load
    monkeypatch.setattr(api, "load", lambda p: tail if str(p) == "params/bvsr.toml" else real(p))
    return tmp_path


def _matrix(location) -> np.ndarray:
    """4x4 of a build123d/CadQuery location (TopLoc_Location or an object wrapping one)."""
    loc = getattr(location, "wrapped", location)
    trsf = loc.Transformation()
    return np.array([[trsf.Value(r, c) for c in range(1, 5)] for r in range(1, 4)] + [[0, 0, 0, 1]])


# ---------------------------------------------------------------------------- README examples


def test_readme_api_example_runs(in_tmp_with_params, capsys):
    exec(compile(textwrap.dedent(README_API), "README.md", "exec"), {})
    out = capsys.readouterr().out.splitlines()
    assert out[0] == "['panel0', 'panel1', 'panel2']"
    assert out[2] == "39 j1_soa1"
    assert (in_tmp_with_params / "bent.step").stat().st_size > 0


def test_readme_cadquery_example_runs(in_tmp_with_params, capsys):
    exec(compile(textwrap.dedent(README_CADQUERY), "README.md", "exec"), {})
    out = capsys.readouterr().out.splitlines()
    assert out == ["['panel0', 'panel1']", "39 panel0"]


# ---------------------------------------------------------------------------- load, parts, assembly


def test_package_reexports_the_api():
    assert (
        bvsr_cad.load is api.load
        and bvsr_cad.Tail is api.Tail
        and bvsr_cad.ParamError is ParamError
    )
    assert bvsr_cad.__version__ == "0.1.0"
    assert {"load", "Tail", "ParamError"} <= set(bvsr_cad.__all__)


def test_load_reads_and_validates_the_parameter_file(tmp_path):
    tail = bvsr_cad.load(PARAMS / "bvsr.toml")  # the geometry is built on first use, not here
    assert tail.spec == load_spec(PARAMS / "bvsr.toml")
    assert tail.name == "bvsr" and "_assembly" not in tail.__dict__
    broken = tmp_path / "broken.toml"
    broken.write_text("name = ")
    with pytest.raises(ParamError, match="not valid TOML"):
        bvsr_cad.load(broken)
    with pytest.raises(ParamError, match="file not found"):
        bvsr_cad.load(tmp_path / "missing.toml")


def test_parts_are_the_assembly_parts(tail, asm):
    parts = tail.parts
    assert list(parts) == list(asm.parts)
    for name, solid in parts.items():
        assert solid.volume == asm.parts[name].solid.volume, name
        assert solid.wrapped.IsSame(asm.parts[name].solid.wrapped), (
            name
        )  # the same geometry, not a rebuild


def test_assembly_children_are_the_labelled_placed_instances(tail, asm, manifest_volumes):
    rest = tail.assembly()
    assert rest.label == "bvsr"
    assert [c.label for c in rest.children] == [i.name for i in asm.instances]
    assert len(rest.children) == 39
    for child, inst in zip(rest.children, asm.instances):
        part = asm.part_of(inst)
        assert tuple(child.color)[:3] == pytest.approx(rgb(part.kind), abs=1e-6), inst.name
        np.testing.assert_allclose(_matrix(child.location), np.asarray(inst.transform), atol=1e-12)
        assert child.volume == pytest.approx(manifest_volumes[inst.name], rel=1e-9), inst.name
        assert child.wrapped.IsPartner(part.solid.wrapped), inst.name  # placed, not copied


# ---------------------------------------------------------------------------- posed


def _expected_panel_frames(spec, theta_rad: float, phi_rad: float) -> list[np.ndarray]:
    """Lower-face frame of every panel: rigid panels of thickness t, then per joint a circular arc
    of length L bending about the axis (-sin phi, cos phi, 0): rotation R_phi Ry(theta) R_phi^T and
    chord end L/theta (1 - cos theta) (cos phi, sin phi, 0) + L/theta sin theta z (closed form,
    written here)."""
    t = spec.joint.panel_thickness_mm
    L = spec.joint.joint_height_mm - t
    c, s = math.cos(theta_rad), math.sin(theta_rad)
    rz = np.array(
        [
            [math.cos(phi_rad), -math.sin(phi_rad), 0],
            [math.sin(phi_rad), math.cos(phi_rad), 0],
            [0, 0, 1],
        ]
    )
    arc = np.eye(4)
    arc[:3, :3] = rz @ np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]) @ rz.T
    arc[:3, 3] = rz @ np.array([L / theta_rad * (1 - c), 0.0, L / theta_rad * s])
    slab = np.eye(4)
    slab[2, 3] = t
    frames = [np.eye(4)]
    for _ in range(spec.joints):
        frames.append(frames[-1] @ slab @ arc)
    return frames


@pytest.mark.parametrize("phi_deg", [0.0, 90.0, -30.0])
def test_posed_moves_the_tip_panel_where_the_kinematics_put_it(tail, asm, phi_deg):
    bent = tail.posed(theta_deg=10, phi_deg=phi_deg)
    assert [c.label for c in bent.children] == [i.name for i in asm.instances]
    tip = asm.panel(asm.spec.joints)
    frame = _expected_panel_frames(asm.spec, math.radians(10), math.radians(phi_deg))[-1]
    shift = np.eye(4)
    shift[2, 3] = (
        -asm.spec.joints * asm.spec.joint.joint_height_mm
    )  # rest lower face of the tip panel
    expected = frame @ shift @ np.asarray(tip.transform)
    child = next(c for c in bent.children if c.label == tip.name)
    np.testing.assert_allclose(_matrix(child.location), expected, atol=1e-9)
    rest_centre = np.array(tuple(asm.part_of(tip).solid.center()))  # part frame
    placed_centre = np.array(tuple(child.center()))
    np.testing.assert_allclose(
        placed_centre, (expected @ np.append(rest_centre, 1.0))[:3], atol=1e-6
    )
    # Bent towards phi: the tip leaves the axis in that direction.
    direction = np.array([math.cos(math.radians(phi_deg)), math.sin(math.radians(phi_deg))])
    assert placed_centre[:2] @ direction > 20.0


def test_posed_keeps_every_volume_and_bends_the_soas_and_rods(tail, asm, manifest_volumes):
    bent = tail.posed(theta_deg=[5, 5, 5, 15, 15, 15], phi_deg=45)
    for child, inst in zip(bent.children, asm.instances):
        assert child.label == inst.name
        assert tuple(child.color)[:3] == pytest.approx(rgb(asm.part_of(inst).kind), abs=1e-6)
        # Slices are placed rigidly: their volumes add up to the part's.
        assert child.volume == pytest.approx(manifest_volumes[inst.name], rel=1e-6), inst.name
        if inst.role != "panel":
            assert len(child.children) > api.SLICES_PER_GAP, inst.name
            assert all(p.label.startswith(f"{inst.name}_slice") for p in child.children)
    # Straight: every instance stays where it is at rest.
    straight = tail.posed(theta_deg=0)
    for child, inst in zip(straight.children, asm.instances):
        ref = (
            asm.part_of(inst).solid.moved(api._location(np.asarray(inst.transform))).bounding_box()
        )
        box = child.bounding_box()
        np.testing.assert_allclose(tuple(box.min), tuple(ref.min), atol=1e-6, err_msg=inst.name)
        np.testing.assert_allclose(tuple(box.max), tuple(ref.max), atol=1e-6, err_msg=inst.name)


def test_posed_rejects_a_wrong_pose(tail):
    with pytest.raises(ValueError, match="theta_deg.*6 \\(one per joint\\)"):
        tail.posed(theta_deg=[10, 10])
    with pytest.raises(ValueError, match="slices_per_gap"):
        tail.posed(theta_deg=10, slices_per_gap=0)


# ---------------------------------------------------------------------------- CadQuery


def test_cadquery_assembly_has_the_same_names_colours_and_places(tail, asm, manifest_volumes):
    import cadquery as cq  # the `test` extra installs it

    assy = tail.cadquery_assembly()
    assert isinstance(assy, cq.Assembly) and assy.name == "bvsr"
    assert [c.name for c in assy.children] == [i.name for i in asm.instances]
    for child, inst in zip(assy.children, asm.instances):
        part = asm.part_of(inst)
        assert child.color.toTuple() == pytest.approx((*rgb(part.kind), 1.0), abs=1e-6), inst.name
        np.testing.assert_allclose(_matrix(child.loc), np.asarray(inst.transform), atol=1e-12)
        shape = child.obj
        assert shape.wrapped.IsSame(part.solid.wrapped), inst.name  # wrapped, not converted
        assert shape.Volume() == pytest.approx(manifest_volumes[inst.name], rel=1e-9)
    bent = tail.posed(theta_deg=10)
    posed = tail.cadquery_assembly(posed=bent)
    assert [c.name for c in posed.children] == [c.label for c in bent.children]
    tip = posed.children[asm.spec.joints]
    np.testing.assert_allclose(
        _matrix(tip.loc), _matrix(bent.children[asm.spec.joints].location), atol=1e-12
    )


def _reordered_presentation(data: bytes) -> bytes:
    """The STEP file with its colour blocks (one per
    MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION) written in the reverse order and
    renumbered, each shared colour defined in the first block that now uses it: what OCCT writes
    when its in-memory map comes out in another order."""
    start = (
        data.rfind(b"\n", 0, data.index(b"MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION"))
        + 1
    )
    end = data.index(b"\nENDSEC;", start) + 1
    bodies = {
        int(m.group(1)): m.group(2)
        for m in re.finditer(rb"^#(\d+) = (.*?;)\s*$(?=\n#|\Z)", data[start:end], re.M | re.S)
    }
    inner = {
        n: [int(r) for r in re.findall(rb"#(\d+)", b) if int(r) in bodies]
        for n, b in bodies.items()
    }
    roots = [n for n in sorted(bodies) if not any(n in refs for refs in inner.values())]
    assert len(roots) == 39  # one block per coloured instance
    first, new = min(bodies), {}

    def walk(n: int) -> None:
        if n not in new:
            new[n] = first + len(new)
            for r in inner[n]:
                walk(r)

    for root in reversed(roots):
        walk(root)
    assert len(new) == len(bodies)
    text = {
        new[n]: re.sub(rb"#(\d+)", lambda m: b"#%d" % new.get(int(m.group(1)), int(m.group(1))), b)
        for n, b in bodies.items()
    }
    return data[:start] + b"".join(b"#%d = %s\n" % (n, text[n]) for n in sorted(text)) + data[end:]


def test_assembly_step_colours_are_in_one_order(assembly_step, tmp_path):
    """OCCT writes the colour blocks in the order of an in-memory map, which changes from run to
    run; the published file puts them in one order that follows the content: the blocks in another
    order give the same bytes."""
    data = assembly_step.read_bytes()
    other = _reordered_presentation(data)
    assert other != data
    path = tmp_path / "other.step"
    path.write_bytes(other)
    assert fix_step(path)
    assert path.read_bytes() == data
    assert not fix_step(path)  # a fixed file stays as it is


def test_presentation_sections_that_cannot_be_renumbered_are_left_as_they_are():
    """Renumbering the colour section is safe only when nothing before it refers into it and its
    references form no cycle; otherwise the file keeps OCCT's order. A well-formed one is
    reordered."""
    from bvsr_cad.exporters.reproducible import _canonical_presentation

    head = b"ISO-10303-21;\nHEADER;\nENDSEC;\nDATA;\n#1 = CARTESIAN_POINT('',(0.,0.,0.));\n"
    blocks = (
        b"#2 = MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION('',(#4),#1);\n"
        b"#3 = MECHANICAL_DESIGN_GEOMETRIC_PRESENTATION_REPRESENTATION('',(#5),#1);\n"
        b"#4 = STYLED_ITEM('color',(),#1);\n#5 = STYLED_ITEM('colour',(),#1);\n"
    )
    tail = b"ENDSEC;\nEND-ISO-10303-21;\n"
    good = head + blocks + tail
    fixed = _canonical_presentation(good)
    assert sorted(fixed.splitlines()) != sorted(
        good.splitlines()
    )  # the walk numbers each block's item next to it
    assert _canonical_presentation(fixed) == fixed
    assert sorted(re.sub(rb"#\d+", b"#", fixed).splitlines()) == sorted(
        re.sub(rb"#\d+", b"#", good).splitlines()
    )
    into = good.replace(
        b"#1 = CARTESIAN_POINT('',(0.,0.,0.));", b"#1 = CARTESIAN_POINT('',(0.,0.,0.),#4);"
    )
    assert _canonical_presentation(into) == into
    cycle = good.replace(b"STYLED_ITEM('color',(),#1)", b"STYLED_ITEM('color',(#2),#1)")
    assert _canonical_presentation(cycle) == cycle


def test_assembly_step_is_the_same_after_other_writes(assembly_step, asm, tmp_path):
    """OCCT numbers assembly usages with a counter that runs on across a process's writes (three
    writes of the 39 usages take it past 100, and OCCT then wraps those lines elsewhere): each later
    write of the tail gives other raw bytes and, made reproducible, the fixture's."""
    raw = []
    for i in range(3):
        path = tmp_path / f"again{i}.step"
        write_assembly_step(asm, path)
        raw.append(path.read_bytes())
        fix_step(path)
        assert path.read_bytes() == assembly_step.read_bytes(), i
    assert raw[0] != raw[2]


def test_assembly_step_reimports_in_cadquery(assembly_step, asm, manifest_volumes):
    import cadquery as cq  # the `test` extra installs it

    back = cq.Assembly.importStep(str(assembly_step))
    assert [c.name for c in back.children] == [i.name for i in asm.instances]
    total = 0.0
    for child, inst in zip(back.children, asm.instances):
        solids = child.obj.Solids()
        assert len(solids) == 1, inst.name
        volume = solids[0].Volume()
        total += volume
        assert volume == pytest.approx(manifest_volumes[inst.name], rel=VOLUME_REL), inst.name
        assert child.color.toTuple()[:3] == pytest.approx(
            rgb(asm.part_of(inst).kind), abs=COLOUR_ABS
        )
        np.testing.assert_allclose(_matrix(child.loc), np.asarray(inst.transform), atol=1e-6)
    assert total == pytest.approx(sum(manifest_volumes.values()), rel=VOLUME_REL)


# ---------------------------------------------------------------------------- FreeCAD


def test_assembly_step_reimports_in_freecad(assembly_step, asm, manifest_volumes, tmp_path):
    freecadcmd = shutil.which("freecadcmd")
    if freecadcmd is None:
        pytest.skip(
            "freecadcmd not found: FreeCAD is not installed (Debian: apt-get install freecad)"
        )
    script, out = tmp_path / "read_step.py", tmp_path / "objects.json"
    script.write_text(FREECAD_SCRIPT)
    env = dict(os.environ, STEP_PATH=str(assembly_step), OUT_JSON=str(out))
    run = subprocess.run(
        [freecadcmd, str(script)], env=env, capture_output=True, text=True, timeout=600
    )
    assert out.exists(), (
        f"freecadcmd failed ({run.returncode}): {run.stdout[-2000:]} {run.stderr[-2000:]}"
    )
    rows = json.loads(out.read_text())
    assert [r["label"] for r in rows] == [i.name for i in asm.instances]  # 39 named objects
    for row, inst in zip(rows, asm.instances):
        assert row["solids"] == 1, inst.name
        assert row["volume_mm3"] == pytest.approx(manifest_volumes[inst.name], rel=VOLUME_REL), (
            inst.name
        )
        assert row["colours"] and all(
            c == pytest.approx(rgb(asm.part_of(inst).kind), abs=COLOUR_ABS) for c in row["colours"]
        ), inst.name
        np.testing.assert_allclose(row["base_mm"], np.asarray(inst.transform)[:3, 3], atol=1e-6)
    assert sum(r["volume_mm3"] for r in rows) == pytest.approx(
        sum(manifest_volumes.values()), rel=VOLUME_REL
    )
