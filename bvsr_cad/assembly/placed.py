"""Named, coloured shapes placed in the tail frame: where a part's solid meets its instance
transform.

The STEP writer (:func:`bvsr_cad.exporters.cad.write_assembly_step`) and the
Python API (:mod:`bvsr_cad.api`) both place the instances through this module,
so a STEP file and a compound built in Python hold the same children, names,
colours and placements.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import build123d as bd
import numpy as np

from ..colors import rgb
from ..parts.kernel import location
from .assemble import Assembly

IDENTITY = tuple(tuple(float(v) for v in row) for row in np.eye(4))


@dataclass(frozen=True)
class PlacedShape:
    """One instance: its shape in its own frame and the rigid transform into the tail frame.

    A rigid instance keeps its part's solid (shared with every other instance
    of that part) and carries the instance transform; a posed bending
    instance is a compound whose children are its labelled pieces, already in
    the tail frame, with the identity as its transform.
    """

    name: str  # the instance's name (panel0, j1_soa1, rod_s1, ...)
    kind: str  # panel, soa, rod: the key into colors.RGB
    shape: bd.Shape  # in the part frame (mm)
    transform: tuple[tuple[float, ...], ...] = IDENTITY  # 4x4, part frame -> tail frame (mm)

    @property
    def rgb(self) -> tuple[float, float, float]:
        return rgb(self.kind)

    def placed(self) -> bd.Shape:
        """The shape moved into the tail frame, labelled with the instance name and coloured.

        Its geometry stays shared with the part (only the location differs).
        A compound with children (a posed bending instance: its labelled
        slices, already in the tail frame) keeps them as its children.
        """
        if self.shape.children:
            if not np.allclose(self.transform, IDENTITY):
                raise ValueError(
                    f"{self.name}: a compound of pieces must already be in the tail frame"
                )
            out = bd.Compound(
                children=[_wrapper(c, c.label, self.rgb) for c in self.shape.children]
            )
        else:
            out = bd.Shape.cast(self.shape.wrapped).moved(location(self.transform))
        out.label = self.name
        out.color = bd.Color(*self.rgb)
        return out


def _wrapper(shape: bd.Shape, label: str, colour: tuple[float, float, float]) -> bd.Shape:
    """A new wrapper of the same geometry, labelled and coloured (the original stays as it was)."""
    out = bd.Shape.cast(shape.wrapped)
    out.label = label
    out.color = bd.Color(*colour)
    return out


def placed_instances(asm: Assembly) -> list[PlacedShape]:
    """Every instance of the tail at rest, in the assembly's order, each with its part's solid."""
    out = []
    for inst in asm.instances:
        part = asm.part_of(inst)
        out.append(PlacedShape(inst.name, part.kind, part.solid, inst.transform))
    return out


def labelled_compound(placed: Sequence[PlacedShape], label: str) -> bd.Compound:
    """A compound whose children are the placed instances, labelled and coloured.

    Args:
        placed: the instances.
        label: the compound's own label (the tail's name).
    """
    return bd.Compound(children=[p.placed() for p in placed], label=label)
