"""Panels: root mount, intermediate, segment boundary and tip.

Every feature comes from :func:`bvsr_cad.parameters.layout.panel_layout`, so the
validated layout and the built solid cannot disagree. Frame: the panel's lower
face at z = 0, Y dorsal; the rim is a frustum following the tail's taper.
"""

from __future__ import annotations

import build123d as bd

from ..parameters.layout import PanelLayout
from .kernel import cut_all, cylinder_between, fuse_all, single_solid


def panel(lay: PanelLayout) -> bd.Solid:
    """The panel described by ``lay`` as one solid (mm).

    Raises:
        GeometryError: a feature split the panel or the kernel failed.
    """
    if (
        abs(lay.rim_radius_lower_mm - lay.rim_radius_upper_mm) < 1e-9
    ):  # no taper: OCC refuses a flat cone
        disc = bd.Solid.make_cylinder(lay.rim_radius_lower_mm, lay.thickness_mm)
    else:
        disc = bd.Solid.make_cone(
            lay.rim_radius_lower_mm, lay.rim_radius_upper_mm, lay.thickness_mm
        )
    body = fuse_all(disc, (cylinder_between(b.p0, b.p1, b.diameter_mm) for b in lay.bosses))
    tools = [cylinder_between(c.p0, c.p1, c.diameter_mm) for c in (*lay.cuts, *lay.passages)]
    return single_solid(cut_all(body, tools), lay.name)
