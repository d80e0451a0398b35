"""The vertebra: one elastic rod per segment, cut from stock."""

from __future__ import annotations

import build123d as bd

from .kernel import single_solid


def rod(diameter_mm: float, length_mm: float) -> bd.Solid:
    """A rod along +Z from z = 0 (mm)."""
    if diameter_mm <= 0 or length_mm <= 0:
        raise ValueError(
            f"rod: diameter_mm = {diameter_mm}, length_mm = {length_mm}; both must be > 0"
        )
    return single_solid(bd.Solid.make_cylinder(diameter_mm / 2.0, length_mm), "rod")
