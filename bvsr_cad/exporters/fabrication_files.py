"""Fabrication package of an export: rigid comparison tail, print files per process, BOM.

Writes, beside what the pipeline already wrote:

* ``step/<piece>.step`` and ``stl/<piece>.stl`` (print orientation; the
  manifest's ``tail_transform`` places it in the tail) for every piece of the
  rigid PLA twin (:mod:`bvsr_cad.parts.rigid_tail`); the pieces join the
  manifest's ``parts`` with kind ``rigid_tail`` and process ``FDM``;
* ``robot/<name>_rigid.urdf`` and ``robot/<name>_rigid.xml``: the twin as one
  rigid body (SI units, inertia from its meshes at solid PLA density);
* ``print/<PROCESS>_<MATERIAL>/``: every printed part's STL lying on z = 0 in
  print orientation, one 3MF per job (named objects, millimetres) and a
  ``quantities.csv``; the manifest's ``print_jobs`` lists them;
* ``bom.csv`` and ``bom.md`` (:mod:`bvsr_cad.exporters.bom`).
"""

from __future__ import annotations

import csv
import shutil
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path
from typing import Any

import build123d as bd
import numpy as np
import trimesh

from .. import units
from ..assembly.assemble import Assembly, rod_span_mm
from ..assembly.fabrication import MadeItem, made_items
from ..assembly.products import RIGID_MATERIAL, RigidRobot, piece_transform_mm
from ..colors import rgb, rgba
from ..memo import Memo, run_now
from ..parameters.tables import TailSpec
from ..parameters.twin import rigid_joining
from ..parts.kernel import location, mesh_arrays
from ..parts.mold import MoldSet
from ..parts.rigid_tail import KEPT_ROLES, RigidPiece
from .bom import bom_rows, write_bom
from .cad import write_step, write_stl
from .reproducible import write_reproducible_3mf
from .urdf import inertial_element, mujoco_compiler
from .xml import num as _f
from .xml import vec as _vec

#: Gap between objects laid out side by side in a job's 3MF (mm).
PLATE_GAP_MM = 5.0
#: Tessellation of the rigid twin's visual mesh in the robot description (mm).
ROBOT_MESH_TOLERANCE_MM = 0.3


def _filled_features(asm: Assembly) -> list[dict[str, Any]]:
    """The BVSR panel features the twin fills (tail frame), excluded from the envelope
    comparison."""
    out = []
    for lay in asm.panel_layouts:
        for c in (*lay.cuts, *lay.passages):
            if c.role in KEPT_ROLES:
                continue
            out.append(
                {
                    "name": f"{lay.name}:{c.name}",
                    "kind": c.role,
                    "diameter_mm": c.diameter_mm,
                    "p0_mm": [c.p0[0], c.p0[1], c.p0[2] + lay.z0_mm],
                    "p1_mm": [c.p1[0], c.p1[1], c.p1[2] + lay.z0_mm],
                }
            )
    spec = asm.spec
    if (
        not spec.vertebra.has_rod
    ):  # no vertebra: the twin's solid rod column stands where the BVSR has none
        for s in range(1, spec.segments + 1):
            z0, z1 = rod_span_mm(spec, s)
            out.append(
                {
                    "name": f"rod_column_s{s}",
                    "kind": "rod column (no vertebra)",
                    "diameter_mm": spec.vertebra.diameter_mm,
                    "p0_mm": [0.0, 0.0, z0],
                    "p1_mm": [0.0, 0.0, z1],
                }
            )
    return out


def write_rigid_files(pieces: list[RigidPiece], root: Path) -> list[trimesh.Trimesh]:
    """Every twin piece's ``step/<piece>.step`` and ``stl/<piece>.stl`` (print frame); returns the
    twin's visual meshes for its robot description (tail frame, metres), tessellated first (see
    :func:`_visual_meshes`). What depends on the twin's geometry alone: the build caches it."""
    visual = _visual_meshes([p.solid.moved(location(piece_transform_mm(p))) for p in pieces])
    (root / "step").mkdir(parents=True, exist_ok=True)
    for p in pieces:
        write_step(p.solid, p.name, rgb("rigid_tail"), root / f"step/{p.name}.step")
        write_stl(p.solid, root / f"stl/{p.name}.stl")
    return visual


def _rigid_parts(asm: Assembly, pieces: list[RigidPiece]) -> list[dict[str, Any]]:
    """The twin's entries of the manifest's parts (its files written by
    :func:`write_rigid_files`)."""
    spec = asm.spec
    mat = spec.material(RIGID_MATERIAL)
    entries = []
    for p in pieces:
        files = {"step": f"step/{p.name}.step", "stl": f"stl/{p.name}.stl"}
        transform = piece_transform_mm(p)
        entries.append(
            {
                "name": p.name,
                "kind": "rigid_tail",
                "material": RIGID_MATERIAL,
                "material_name": mat.name,
                "density_g_cm3": mat.density_g_cm3,
                "process": "FDM",
                "count": 1,
                "volume_mm3": p.volume_mm3,
                "mass_g": units.mass_g(p.volume_mm3, mat.density_g_cm3),
                "instances": [p.name],
                "files": files,
                # The part frame is the print frame; the instance sits at the piece's bed face in
                # the tail.
                "print_transform": np.eye(4).tolist(),
                "tail_transform": transform.tolist(),
                "info": {
                    "size_mm": list(p.size_mm),
                    "z0_mm": p.z0_mm,
                    "joint": p.index if p.name != "rigid_tip" else None,
                    "print_features": [
                        {
                            "name": f.name,
                            "kind": f.kind,
                            "p0_mm": list(f.p0),
                            "p1_mm": list(f.p1),
                            "diameter_mm": f.diameter_mm,
                        }
                        for f in p.features
                    ],
                },
            }
        )
    return entries


def _visual_meshes(solids_mm: list[bd.Shape]) -> list[trimesh.Trimesh]:
    """Coarse meshes of the pieces in the tail frame, in metres.

    Called before the print STLs are written: OCCT keeps the finest triangulation
    a shape has had, so tessellating afterwards would return the print mesh.
    """
    visual = []
    for solid in solids_mm:
        v, tris = mesh_arrays(solid, ROBOT_MESH_TOLERANCE_MM, 0.5)
        visual.append(trimesh.Trimesh(v * units.mm_to_m(1.0), tris, process=False))
    return visual


def _rigid_robot(rigid: RigidRobot, root: Path, visual: list[trimesh.Trimesh]) -> dict[str, Any]:
    """URDF and MJCF of the rigid twin's one-link model: one body fixed to the robot's mount."""
    name = rigid.name
    folder = root / "robot"
    (folder / "meshes").mkdir(parents=True, exist_ok=True)
    mesh_rel = f"meshes/{name}.stl"
    # The visual mesh is coarse (MuJoCo takes at most 200000 faces); the inertia above is from the
    # print STLs.
    trimesh.util.concatenate(visual).export(folder / mesh_rel)
    urdf_rel = f"robot/{name}.urdf"
    robot = _rigid_urdf(rigid, mesh_rel)
    ET.ElementTree(robot).write(root / urdf_rel, encoding="utf-8", xml_declaration=True)
    mjcf_rel = f"robot/{name}.xml"
    mj = _rigid_mjcf(rigid)
    ET.ElementTree(mj).write(root / mjcf_rel, encoding="utf-8", xml_declaration=True)
    return {
        "urdf": urdf_rel,
        "mjcf": mjcf_rel,
        "mesh": f"robot/{mesh_rel}",
        "mass_kg": rigid.inertial.mass_kg,
        "com_m": rigid.inertial.com.tolist(),
        "inertia_kg_m2": rigid.inertial.inertia.tolist(),
        "note": "one rigid body fixed to the mount; solid PLA density (the printed infill lowers "
        "the mass: "
        "weigh the print and scale)",
    }


def _rigid_urdf(rigid: RigidRobot, mesh_rel: str) -> ET.Element:
    """The rigid twin's URDF: the link ``rigid_tail`` (inertia about its centre of mass, tail
    axes; the mesh ``mesh_rel`` as visual and collision) fixed to a massless ``mount``."""
    robot = ET.Element("robot", name=rigid.name)
    # MuJoCo makes a URDF's root link its world: the twin hangs from a massless "mount" by a fixed
    # joint, kept as its own body (fusestatic off) so simulators see the twin's mass and inertia.
    mujoco_compiler(robot)
    ET.SubElement(robot, "link", name="mount")
    m = ET.SubElement(robot, "material", name=rigid.material)
    ET.SubElement(m, "color", rgba=_vec(rgba("rigid_tail")))
    link = ET.SubElement(robot, "link", name="rigid_tail")
    inertial_element(link, rigid.inertial)
    for tag in ("visual", "collision"):
        el = ET.SubElement(link, tag, name=f"rigid_tail_{tag}")
        ET.SubElement(el, "origin", xyz="0 0 0", rpy="0 0 0")
        g = ET.SubElement(el, "geometry")
        ET.SubElement(g, "mesh", filename=mesh_rel)
        if tag == "visual":
            ET.SubElement(el, "material", name=rigid.material)
    fixed = ET.SubElement(robot, "joint", name="mount_to_rigid_tail", type="fixed")
    ET.SubElement(fixed, "origin", xyz="0 0 0", rpy="0 0 0")
    ET.SubElement(fixed, "parent", link="mount")
    ET.SubElement(fixed, "child", link="rigid_tail")
    ET.indent(robot)
    return robot


def _rigid_mjcf(rigid: RigidRobot) -> ET.Element:
    """The rigid twin's MJCF: one body welded to the world, its mesh a visual only."""
    name = rigid.name
    inertia = rigid.inertial.inertia
    mj = ET.Element("mujoco", model=name)
    ET.SubElement(mj, "compiler", angle="radian", meshdir="meshes")
    ET.SubElement(mj, "option", timestep=_f(rigid.timestep_s), gravity="0 -9.81 0")
    asset = ET.SubElement(mj, "asset")
    ET.SubElement(asset, "mesh", name="rigid_tail", file=f"{name}.stl")
    world = ET.SubElement(mj, "worldbody")
    ET.SubElement(world, "light", pos="0 0.5 0.3", dir="0 -1 0")
    # No joint: welded to the mount.
    body = ET.SubElement(world, "body", name="rigid_tail", pos="0 0 0")
    ET.SubElement(
        body,
        "inertial",
        pos=_vec(rigid.inertial.com),
        mass=_f(rigid.inertial.mass_kg),
        fullinertia=_vec(
            (
                inertia[0, 0],
                inertia[1, 1],
                inertia[2, 2],
                inertia[0, 1],
                inertia[0, 2],
                inertia[1, 2],
            )
        ),
    )
    ET.SubElement(
        body,
        "geom",
        type="mesh",
        mesh="rigid_tail",
        rgba=_vec(rgba("rigid_tail")),
        contype="0",
        conaffinity="0",
    )
    ET.indent(mj)
    return mj


def _layout_3mf(items: list[tuple[str, Path]], path: Path) -> list[list[float]]:
    """Each STL once as a named object, side by side in a row of rows (mm); returns each item's size
    (x, y, z) in mm, as its STL is oriented."""
    scene = trimesh.Scene()
    x = y = row_depth = 0.0
    row_limit = 400.0
    sizes = []
    for name, stl in items:
        mesh = trimesh.load(stl, file_type="stl", force="mesh")
        lo, hi = mesh.bounds
        sizes.append((hi - lo).tolist())
        w, d = hi[0] - lo[0], hi[1] - lo[1]
        if x > 0 and x + w > row_limit:
            x, y, row_depth = 0.0, y + row_depth + PLATE_GAP_MM, 0.0
        t = trimesh.transformations.translation_matrix((x - lo[0], y - lo[1], -lo[2]))
        scene.add_geometry(mesh, node_name=name, geom_name=name, transform=t)
        x += w + PLATE_GAP_MM
        row_depth = max(row_depth, d)
    write_reproducible_3mf(scene, path)
    return sizes


def _print_jobs(
    asm: Assembly, root: Path, items: list[MadeItem], stl_of: dict[str, str], memo: Memo = run_now
) -> list[dict]:
    """One job per (process, material) of the printed items (MJF and FDM); ``stl_of`` maps an item's
    label to the STL its writer wrote. A job's 3MF and its items' sizes are a step of ``memo`` read
    by the job's name and its items' names and STL bytes (a rod-material edit changes none)."""
    spec = asm.spec
    fp = spec.fabrication_package
    jobs: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for it in items:
        if it.process in ("MJF", "FDM"):
            jobs.setdefault((it.process, it.material), []).append(
                {
                    "part": it.label,
                    "kind": it.kind,
                    "source": stl_of[it.label],
                    "quantity": it.quantity,
                    "volume_mm3": it.volume_mm3,
                    "mass_g": it.mass_each_g,
                }
            )
    out = []
    volumes = {
        "FDM": (fp.printer_x_mm, fp.printer_y_mm, fp.printer_z_mm),
        "MJF": (fp.mjf_x_mm, fp.mjf_y_mm, fp.mjf_z_mm),
    }
    for (process, material), items in jobs.items():
        job = f"{process}_{material.split('_')[0]}"
        folder = root / "print" / job
        folder.mkdir(parents=True, exist_ok=True)
        for it in items:
            rel = f"print/{job}/{it['part']}.stl"
            shutil.copyfile(root / it["source"], root / rel)
            it["stl"] = rel
        three_mf = f"print/{job}/{job}.3mf"

        def layout(
            dst: Path, items: list[dict[str, Any]] = items, three_mf: str = three_mf
        ) -> list[list[float]]:
            (dst / three_mf).parent.mkdir(parents=True, exist_ok=True)
            return _layout_3mf([(it["part"], root / it["stl"]) for it in items], dst / three_mf)

        sizes, _reused = memo(
            "print_job_layout",
            {"job": job, "items": [(it["part"], it["stl"]) for it in items]},
            layout,
            root,
            files=[root / it["stl"] for it in items],
        )
        for it, size in zip(items, sizes):
            it["size_mm"] = size
        with (root / f"print/{job}/quantities.csv").open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["part", "quantity", "stl", "mass_each_g"])
            for it in items:
                w.writerow(
                    [it["part"], it["quantity"], Path(it["stl"]).name, f"{it['mass_g']:.2f}"]
                )
        out.append(
            {
                "name": job,
                "process": process,
                "material": material,
                "material_name": spec.material(material).name,
                "build_volume_mm": list(volumes[process]),
                "files": {"3mf": three_mf, "quantities": f"print/{job}/quantities.csv"},
                "items": items,
                "total_parts": sum(it["quantity"] for it in items),
                "total_mass_g": sum(it["quantity"] * it["mass_g"] for it in items),
            }
        )
    return out


def write_fabrication(
    asm: Assembly,
    pieces: list[RigidPiece],
    rigid_robot: RigidRobot,
    visual: list[trimesh.Trimesh],
    mold_set: MoldSet | None,
    part_files: dict[str, dict[str, str]],
    mold_files: dict[str, dict[str, str]],
    root: Path,
    progress: Callable[[str], None],
    memo: Memo = run_now,
) -> dict[str, Any]:
    """Write the rigid tail's robot description, print files and the BOM under ``root``, beside the
    twin's pieces (built by :mod:`bvsr_cad.assembly.products`) and their files and ``visual`` meshes
    (:func:`write_rigid_files`). ``part_files`` and ``mold_files`` name the files the part and mold
    writers wrote (by part and mold-part name); ``memo``: the print jobs' layouts
    (:func:`_print_jobs`). Returns keys to merge into the manifest (``rigid_parts``: the twin's
    entries of the manifest's ``parts``)."""
    rigid = _rigid_parts(asm, pieces)
    progress("rigid tail robot description")
    robot_rigid = _rigid_robot(rigid_robot, root, visual)
    progress("print files (STL, 3MF per process and material)")
    items = made_items(asm, pieces, mold_set)
    stl_of = {name: f["stl"] for name, f in part_files.items()}
    stl_of |= {p["name"]: p["files"]["stl"] for p in rigid}
    stl_of |= {f"mold_{name}": f["stl"] for name, f in mold_files.items()}
    jobs = _print_jobs(asm, root, items, stl_of, memo)
    fragment: dict[str, Any] = {
        "rigid_parts": rigid,
        "rigid_tail": _rigid_tail_section(asm, rigid, robot_rigid),
        "print_jobs": jobs,
        "fabrication": _fabrication_limits(asm.spec),
    }
    progress("bill of materials")
    rows = bom_rows(asm, pieces, mold_set)
    fragment["bom"] = write_bom(root, rows)
    return fragment


def _rigid_tail_section(
    asm: Assembly, rigid: list[dict[str, Any]], robot_rigid: dict[str, Any]
) -> dict[str, Any]:
    """The manifest's ``rigid_tail``: the twin's pieces, how it is split, joined and simplified, its
    solid mass and its robot description."""
    fp = asm.spec.fabrication_package
    joining = rigid_joining(asm.spec)
    return {
        "pieces": [p["name"] for p in rigid],
        "printer_volume_mm": [fp.printer_x_mm, fp.printer_y_mm, fp.printer_z_mm],
        "split": "one piece per joint at each panel's lower face (panel on the bed, SOA columns "
        "and rod on it); "
        "the tip panel alone",
        "joining": {
            "pins": {
                "designation": joining.pin_designation,
                "count": joining.pin_count,
                "hole_mm": joining.pin_hole_mm,
            },
            "tie_rod": {
                "designation": joining.tie_rod_designation,
                "cut_length_mm": joining.tie_rod_cut_length_mm,
                "hole_mm": joining.tie_rod_hole_mm,
            },
            "nuts": {
                "designation": joining.nut_designation,
                "count": joining.nut_count,
                "pocket_depth_mm": joining.nut_pocket_depth_mm,
            },
        },
        "simplified": "SOA pockets, air channels, fitting and tube ports, feed passages and the "
        "rod socket are "
        "filled; lightening holes, tube pass-throughs and mount/payload insert bores are kept",
        "envelope_tolerance_mm": fp.envelope_tolerance_mm,
        "filled_features": _filled_features(asm),
        "mass_g_solid": sum(p["mass_g"] for p in rigid),
        "robot": robot_rigid,
    }


def _fabrication_limits(spec: TailSpec) -> dict[str, Any]:
    """The manifest's ``fabrication``: the printability limits the checks hold each print to."""
    fp = spec.fabrication_package
    return {
        "max_overhang_deg": fp.max_overhang_deg,
        "max_bridge_mm": fp.max_bridge_mm,
        "fdm_min_wall_mm": fp.fdm_min_wall_mm,
        "fdm_min_plate_mm": fp.fdm_min_plate_mm,
        "fdm_min_hole_mm": fp.fdm_min_hole_mm,
        "mjf_min_hole_mm": fp.mjf_min_hole_mm,
        # The pocket rim lips are allowed thinner than other webs by the layout rules
        # (fabrication.min_rim_lip_mm): they only locate a flange.
        "mjf_min_wall_mm": min(spec.fabrication.min_wall_mm, spec.fabrication.min_rim_lip_mm),
        "mjf_min_wall_note": "fabrication.min_rim_lip_mm = "
        f"{spec.fabrication.min_rim_lip_mm:g} "
        f"(pocket rim lips); other webs >= {spec.fabrication.min_wall_mm:g} "
        "by the layout validation",
        "mold_min_wall_mm": spec.casting.min_print_wall_mm,
        "slicer_timeout_s": fp.slicer_timeout_s,
    }
