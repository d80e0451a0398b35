"""The pentagon actuator layout, measured on the exported panel meshes.

Each panel mesh is sliced half-way down every face's flange pockets; the
pockets are the holes of that section whose area matches a pocket. Their
centres must lie on the pitch circle, 72 deg apart, mirror-symmetric about
the sagittal YZ plane, with soa1 on +Y.
"""

from __future__ import annotations

import math

import numpy as np
from shapely.geometry import Polygon

from .export import Export
from .result import CheckResult

RADIUS_TOL_MM = 0.05
ANGLE_TOL_DEG = 0.1
MIRROR_TOL_MM = 0.05


def pocket_centres(mesh, z_mm: float, pocket_diameter_mm: float) -> np.ndarray:
    """Centres (x, y) of the section holes at height z whose area is a pocket's."""
    section = mesh.section(plane_origin=(0.0, 0.0, z_mm), plane_normal=(0.0, 0.0, 1.0))
    if section is None:
        return np.zeros((0, 2))
    to_2d = np.eye(4)
    to_2d[2, 3] = -z_mm
    planar, _ = section.to_2D(to_2D=to_2d, check=False)
    target = math.pi * pocket_diameter_mm**2 / 4
    centres = []
    for poly in planar.polygons_full:
        for ring in poly.interiors:
            hole = Polygon(ring)
            if abs(hole.area - target) <= 0.03 * target:
                c = hole.centroid
                centres.append((c.x, c.y))
    return np.array(centres).reshape(-1, 2)


def _sorted_from_dorsal(centres: np.ndarray) -> np.ndarray:
    ang = np.degrees(np.arctan2(centres[:, 1], centres[:, 0]))
    return centres[np.argsort((ang - 90.0 + 36.0) % 360.0)]  # soa1 first, robust to 89.999 deg


def check_layout(exp: Export) -> list[CheckResult]:
    out: list[CheckResult] = []
    for part in exp.parts:
        if part["kind"] != "panel":
            continue
        info = part["info"]
        mesh = exp.part_frame_mesh(part)
        depth, t = info["pocket_depth_mm"], info["thickness_mm"]
        for face in info["pocket_faces"]:
            z = depth / 2 if face == "lower" else t - depth / 2
            expected_r = info[f"pitch_radius_{face}_mm"]
            where = f"{part['files']['stl']} z={z:.3f}"
            c = pocket_centres(mesh, z, info["pocket_diameter_mm"])
            tag = f"{part['name']}:{face}"
            out.append(
                CheckResult(f"pentagon_pockets:{tag}", len(c) == 5, len(c), 5, "pockets", where)
            )
            if len(c) != 5:
                continue
            c = _sorted_from_dorsal(c)
            r = np.hypot(c[:, 0], c[:, 1])
            ang = np.degrees(np.arctan2(c[:, 1], c[:, 0]))
            r_err = float(np.max(np.abs(r - expected_r)))
            out.append(
                CheckResult(
                    f"pentagon_pitch_circle:{tag}",
                    r_err <= RADIUS_TOL_MM,
                    r_err,
                    RADIUS_TOL_MM,
                    "mm",
                    where,
                    f"measured radii {np.round(r, 3).tolist()}, pitch {expected_r:.3f}",
                )
            )
            spacing = np.diff(np.append(ang, ang[0] + 360.0)) % 360.0
            s_err = float(np.max(np.abs(spacing - 72.0)))
            out.append(
                CheckResult(
                    f"pentagon_spacing:{tag}",
                    s_err <= ANGLE_TOL_DEG,
                    s_err,
                    ANGLE_TOL_DEG,
                    "deg",
                    where,
                    f"spacings {np.round(spacing, 3).tolist()}",
                )
            )
            mirrored = c * np.array([-1.0, 1.0])
            d = np.linalg.norm(mirrored[:, None, :] - c[None, :, :], axis=2).min(axis=1)
            m_err = float(d.max())
            out.append(
                CheckResult(
                    f"pentagon_mirror_yz:{tag}",
                    m_err <= MIRROR_TOL_MM,
                    m_err,
                    MIRROR_TOL_MM,
                    "mm",
                    where,
                    "largest distance from a mirrored pocket to its twin",
                )
            )
            dorsal = float(abs(((ang[0] - 90.0 + 180.0) % 360.0) - 180.0))
            out.append(
                CheckResult(
                    f"pentagon_soa1_dorsal:{tag}",
                    dorsal <= ANGLE_TOL_DEG,
                    dorsal,
                    ANGLE_TOL_DEG,
                    "deg",
                    where,
                    "angle of the pocket nearest +Y from +Y",
                )
            )
    return out
