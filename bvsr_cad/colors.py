"""The one colour table: every part kind and mold role, as RGB in 0..1.

STEP files, renders, the report and the robot descriptions all take their
colours from here (the robot descriptions add :data:`ALPHA`).
"""

from __future__ import annotations

RGB: dict[str, tuple[float, float, float]] = {
    "panel": (0.55, 0.60, 0.68),
    "soa": (0.95, 0.55, 0.15),
    "rod": (0.92, 0.92, 0.88),
    "rigid_tail": (0.80, 0.80, 0.74),
    "shell": (0.45, 0.62, 0.85),  # mold halves
    "bottom_plate": (0.55, 0.60, 0.68),
    "lid": (0.55, 0.60, 0.68),
    "core": (0.35, 0.75, 0.45),  # sacrificial mold core
    "cast": (0.95, 0.55, 0.15),  # the cast SOA inside its mold
    "channel": (0.85, 0.15, 0.15),  # gate and vents
}
RGB["mold"] = RGB["shell"]  # print jobs: rigid mold parts
RGB["mold_core"] = RGB["core"]
#: Opacity in the robot descriptions (the SOAs translucent so the rod shows).
ALPHA = {"soa": 0.8}
FALLBACK = (0.7, 0.7, 0.7)


def rgb(kind: str) -> tuple[float, float, float]:
    return RGB.get(kind, FALLBACK)


def rgba(kind: str) -> tuple[float, float, float, float]:
    return (*rgb(kind), ALPHA.get(kind, 1.0))
