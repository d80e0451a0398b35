"""Off-screen pictures of an export (pyvista): the assembly at rest and a sheet of parts."""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..assembly.assemble import Assembly
from ..colors import rgb
from ..parts.kernel import fresh_copy, mesh_arrays


def offscreen_pyvista():
    """pyvista, set to draw off-screen (no display needed). VTK's logger comes from its own module:
    ``import vtk`` loads every VTK module, far more than pyvista's own."""
    import pyvista as pv
    from vtkmodules.vtkCommonCore import vtkLogger

    vtkLogger.SetStderrVerbosity(
        vtkLogger.VERBOSITY_OFF
    )  # no "bad X server" noise without a display
    pv.OFF_SCREEN = True
    return pv


@contextmanager
def composing(plotter) -> Iterator[None]:
    """Set up a scene without drawing it: once a plotter has drawn a frame, pyvista draws another at
    every actor added and every camera move (several frames per picture, each in software OpenGL
    without a display), and its screenshot reads the last frame drawn. The block ends with the
    one frame the picture needs (before a plotter's first frame pyvista draws nothing, and its
    screenshot draws)."""
    plotter.suppress_rendering = True
    try:
        yield
    finally:
        plotter.suppress_rendering = False
    plotter.render()


def _polydata(pv, vertices: np.ndarray, faces: np.ndarray):
    cells = np.hstack([np.full((len(faces), 1), 3), faces]).astype(np.int64).ravel()
    return pv.PolyData(vertices, cells)


def _tessellate(solid, tolerance_mm: float = 0.05):
    """A picture's mesh, from a copy: the part files' writer meshed ``solid`` for print first (0.01
    mm), and OCCT would hand that mesh back, several times the triangles a picture shows."""
    return mesh_arrays(fresh_copy(solid), tolerance_mm, 0.3)


def render_previews(asm: Assembly, root: Path) -> dict[str, str]:
    """Write ``previews/assembly.png`` and ``previews/parts.png``; returns their paths."""
    pv = offscreen_pyvista()
    out = root / "previews"
    out.mkdir(exist_ok=True)
    meshes = {name: _tessellate(p.solid) for name, p in asm.parts.items()}

    plotter = pv.Plotter(off_screen=True, window_size=(1400, 700))
    for inst in asm.instances:
        v, f = meshes[inst.part]
        t = np.asarray(inst.transform)
        placed = v @ t[:3, :3].T + t[:3, 3]
        kind = asm.part_of(inst).kind
        plotter.add_mesh(
            _polydata(pv, placed, f),
            color=rgb(kind),
            smooth_shading=False,
            opacity=0.55 if kind == "soa" else 1.0,
        )
    plotter.add_axes()
    plotter.camera_position = [(-260.0, 170.0, -60.0), (0.0, 0.0, 130.0), (0.0, 1.0, 0.0)]
    plotter.camera.zoom(1.0)
    plotter.add_text(
        f"{asm.spec.name}: {asm.spec.segments} segments, {asm.spec.joints} joints, "
        f"taper {asm.taper_half_angle_deg:.3f} deg",
        font_size=10,
    )
    plotter.screenshot(str(out / "assembly.png"))
    plotter.close()

    names = list(asm.parts)
    cols = min(4, len(names))
    rows = math.ceil(len(names) / cols)
    plotter = pv.Plotter(off_screen=True, shape=(rows, cols), window_size=(300 * cols, 280 * rows))
    for i, name in enumerate(names):
        plotter.subplot(i // cols, i % cols)
        v, f = meshes[name]
        plotter.add_mesh(_polydata(pv, v, f), color=rgb(asm.parts[name].kind), smooth_shading=False)
        plotter.add_text(name, font_size=9)
        plotter.view_isometric()
    plotter.screenshot(str(out / "parts.png"))
    plotter.close()
    return {"assembly": "previews/assembly.png", "parts": "previews/parts.png"}
