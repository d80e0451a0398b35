"""Mesh soundness of every exported STL."""

from __future__ import annotations

import numpy as np

from .export import Export
from .result import CheckResult

VOLUME_TOLERANCE = 0.002  # 0.2 % of the B-rep volume
FLAT_NORMAL_DOT = 0.9999


def part_mesh_reads(part: dict) -> tuple[list[str], dict]:
    """What :func:`check_part_mesh` reads: the part's STL, its name and its B-rep volume."""
    return [part["files"]["stl"]], {
        "name": part["name"],
        "stl": part["files"]["stl"],
        "volume_mm3": part["volume_mm3"],
    }


def check_part_mesh(exp: Export, part: dict) -> list[CheckResult]:
    name, rel = part["name"], part["files"]["stl"]
    mesh = exp.mesh(rel)
    out = [
        CheckResult(
            f"stl_watertight:{name}", bool(mesh.is_watertight), int(mesh.is_watertight), 1, "", rel
        ),
        CheckResult(
            f"stl_winding:{name}",
            bool(mesh.is_winding_consistent),
            int(mesh.is_winding_consistent),
            1,
            "",
            rel,
        ),
    ]
    bodies = int(mesh.body_count)
    out.append(CheckResult(f"stl_one_body:{name}", bodies == 1, bodies, 1, "bodies", rel))
    brep = float(part["volume_mm3"])
    rel_err = abs(float(mesh.volume) - brep) / brep if brep > 0 else float("inf")
    out.append(
        CheckResult(
            f"stl_volume:{name}",
            rel_err <= VOLUME_TOLERANCE,
            100.0 * rel_err,
            100.0 * VOLUME_TOLERANCE,
            "% of B-rep volume",
            rel,
            f"mesh {mesh.volume:.1f} mm3, B-rep {brep:.1f} mm3",
        )
    )
    # Print orientation: resting on z = 0 with a flat face on the bed.
    zmin = float(mesh.bounds[0][2])
    down = (mesh.face_normals[:, 2] < -FLAT_NORMAL_DOT) & (
        np.abs(mesh.triangles[:, :, 2] - zmin).max(axis=1) < 1e-6
    )
    bed_area = float(mesh.area_faces[down].sum())
    out.append(
        CheckResult(
            f"stl_on_bed:{name}",
            abs(zmin) < 1e-6 and bed_area > 0,
            bed_area,
            "> 0 at z = 0",
            "mm2",
            rel,
            f"lowest z {zmin:.6f} mm",
        )
    )
    return out
