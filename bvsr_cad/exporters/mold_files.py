"""Writes the SOA casting mold set into an export (``molds/``).

Layout (paths relative to the export root, as the manifest names them):

* ``molds/soa_cast.stl``: the cast part as it sits in the closed mold
  (the SOA scaled by 1 + shrinkage), in the cast frame;
* ``molds/<part>.stl``: each mold part in print orientation (on z = 0);
* ``molds/assembled/<part>.stl``: the same part in the cast frame;
* ``molds/step/<part>.step``: the part in the cast frame (B-rep);
* ``molds/channels/<name>.stl``: the empty gate and vent channels of the
  closed mold, in the cast frame (the checks subtract them from the void);
* ``molds/exploded.png``: an exploded view of the set.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import build123d as bd
import numpy as np

from ..assembly.assemble import Assembly
from ..colors import rgb
from ..parameters.tables import TailSpec
from ..parts.kernel import mesh_arrays
from ..parts.mold import MoldPart, MoldSet
from .cad import write_step, write_stl
from .render import offscreen_pyvista

#: Mold meshes (relative to each edge's size): fine enough that the cavity (closed mold minus
#: channels) and the cast agree far inside the 0.5 % the cavity check allows.
MOLD_STL_LINEAR_TOLERANCE_MM = 0.005
MOLD_STL_ANGULAR_TOLERANCE_RAD = 0.1

CAST_STL = "molds/soa_cast.stl"
EXPLODED_PNG = "molds/exploded.png"
#: How far each part moves along its pull direction in the exploded view (mm).
EXPLODE_MM = {"half_a": 34.0, "half_b": 34.0, "bottom_plate": 30.0, "lid": 30.0}


def _stl(shape: bd.Shape, path: Path) -> None:
    write_stl(
        shape, path, MOLD_STL_LINEAR_TOLERANCE_MM, MOLD_STL_ANGULAR_TOLERANCE_RAD, relative=True
    )


def _step(part: MoldPart, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    write_step(part.solid, part.name, rgb(part.role), path)


def _render_exploded(molds: MoldSet, path: Path) -> None:
    """Exploded view: every rigid part moved out along its pull direction,
    the core in place with the cast (translucent) around it."""
    pv = offscreen_pyvista()

    def poly(solid: bd.Shape, offset: np.ndarray) -> Any:
        v, tris = mesh_arrays(solid, 0.05, 0.3)
        v = v + offset
        cells = np.hstack([np.full((len(tris), 1), 3), tris]).astype(np.int64).ravel()
        return pv.PolyData(v, cells)

    plotter = pv.Plotter(off_screen=True, window_size=(1300, 1000))
    labels, label_points = [], []
    for part in molds.parts.values():
        pull = np.zeros(3) if part.sacrificial else np.asarray(part.pull_direction)
        offset = pull * EXPLODE_MM.get(part.name, 0.0)
        plotter.add_mesh(
            poly(part.solid, offset),
            color=rgb(part.role),
            smooth_shading=False,
            opacity=0.6 if part.role == "core" else 1.0,
            show_edges=False,
        )
        box = part.solid.bounding_box()
        centre = (
            np.array([(box.min.X + box.max.X) / 2, (box.min.Y + box.max.Y) / 2, box.max.Z]) + offset
        )
        tag = part.name + (" (sacrificial)" if part.sacrificial else "")
        labels.append(tag)
        label_points.append(centre)
    plotter.add_mesh(
        poly(molds.cast, np.zeros(3)), color=rgb("cast"), opacity=0.55, smooth_shading=False
    )
    for ch in molds.channels:
        plotter.add_mesh(poly(ch.solid, np.zeros(3)), color=rgb("channel"))
    plotter.add_point_labels(
        np.array(label_points),
        labels,
        font_size=14,
        point_size=1,
        shape_opacity=0.6,
        always_visible=True,
    )
    plotter.add_text(
        f"SOA mold set: cast x{molds.scale:.4f} (shrinkage), halves split on x = y, "
        "gate (red) from below, vents (red) through the lid",
        font_size=10,
    )
    # Look along the parting plane so both halves, the lid and the plate show.
    d = np.array(molds.parts["half_a"].pull_direction)
    along = np.cross([0.0, 0.0, 1.0], d)
    eye = 170.0 * along + 60.0 * np.array([0.0, 0.0, 1.0]) + 40.0 * d
    centre = np.array([0.0, 0.0, molds.info["cast_height_mm"] / 2.0])
    plotter.camera_position = [tuple(centre + eye), tuple(centre), (0.0, 0.0, 1.0)]
    plotter.reset_camera()  # keep the view direction, fit every exploded part
    plotter.camera.zoom(1.5)
    plotter.add_axes()
    plotter.screenshot(str(path))
    plotter.close()


def write_mold_files(
    molds: MoldSet, root: Path, progress: Callable[[str], None]
) -> tuple[list[dict[str, Any]], list[dict[str, Any]]]:
    """Write the mold set's files under ``root/molds``: what depends on its geometry alone (the
    build caches it). Returns the manifest entries of its parts and of its channels."""
    out = root / "molds"
    out.mkdir(exist_ok=True)
    _stl(molds.cast, root / CAST_STL)
    parts = []
    for name, part in molds.parts.items():
        progress(f"export mold {name} (STL, STEP)")
        files = {
            "stl": f"molds/{name}.stl",
            "assembled_stl": f"molds/assembled/{name}.stl",
            "step": f"molds/step/{name}.step",
        }
        _stl(part.print_solid, root / files["stl"])
        _stl(part.solid, root / files["assembled_stl"])
        _step(part, root / files["step"])
        entry: dict[str, Any] = {
            "name": name,
            "role": part.role,
            "pull_direction": None if part.sacrificial else list(part.pull_direction),
            "volume_mm3": part.solid.volume,
            "print_transform": [list(r) for r in part.print_transform],
            "parting_planes": [
                {"point": list(p), "normal": list(n)} for p, n in part.parting_planes
            ],
            "note": part.note,
            "files": files,
        }
        if part.sacrificial:
            entry["sacrificial"] = True
        parts.append(entry)
    channels = []
    for ch in molds.channels:
        rel = f"molds/channels/{ch.name}.stl"
        _stl(ch.solid, root / rel)
        channels.append(
            {
                "name": ch.name,
                "kind": ch.kind,
                "diameter_mm": ch.diameter_mm,
                "opening_mm": list(ch.opening_mm),
                "volume_mm3": ch.solid.volume,
                "files": {"stl": rel},
            }
        )
    progress("mold exploded view")
    _render_exploded(molds, root / EXPLODED_PNG)
    return parts, channels


def molds_manifest(
    spec: TailSpec, molds: MoldSet, parts: list[dict[str, Any]], channels: list[dict[str, Any]]
) -> dict[str, Any]:
    """The manifest's ``molds`` section: the files' entries (:func:`write_mold_files`) with the
    cast's material, which the files do not depend on."""
    material = spec.material(spec.use.soa)
    return {
        "molds": {
            "cast_part": CAST_STL,
            "cast_frame": "SOA frame (axis +Z, lower flange face z = 0) scaled by 'scale'",
            "scale": molds.scale,
            "shrinkage_percent": spec.casting.shrinkage_percent,
            "cast_volume_mm3": molds.cast.volume,
            "soa_volume_mm3": molds.soa_volume_mm3,
            "material": spec.use.soa,
            "density_g_cm3": material.density_g_cm3,
            "min_print_wall_mm": spec.casting.min_print_wall_mm,
            "parting_margin_mm": molds.parting_margin_mm,
            "parts": parts,
            "channels": channels,
            "exploded_png": EXPLODED_PNG,
            "info": molds.info,
        }
    }


def write_molds(
    asm: Assembly, molds: MoldSet, root: Path, progress: Callable[[str], None]
) -> dict[str, Any]:
    """Write the mold set (built by :func:`bvsr_cad.assembly.products.build_mold_set`) under
    ``root/molds``.

    Returns:
        Keys to merge into the manifest (``{"molds": {...}}``).
    """
    return molds_manifest(asm.spec, molds, *write_mold_files(molds, root, progress))
