"""Standard parts read from data (``data/iso_metric.toml``): ISO metric threads, tap drills and
nuts.

The panel layout (threaded rod sockets), the rigid twin (tie-rod nuts) and the
BOM (fastener designations) all look sizes up here.
"""

from __future__ import annotations

import tomllib
from dataclasses import dataclass
from importlib import resources


@dataclass(frozen=True)
class MetricSize:
    diameter_mm: float
    pitch_mm: float
    tap_drill_mm: float
    nut_af_mm: float
    nut_height_mm: float
    clearance_hole_mm: float

    @property
    def designation(self) -> str:
        return f"M{self.diameter_mm:g}"


def _read_iso_metric() -> dict[float, MetricSize]:
    text = resources.files(__package__).joinpath("data/iso_metric.toml").read_text(encoding="utf-8")
    return {
        float(row["diameter_mm"]): MetricSize(**{k: float(v) for k, v in row.items()})
        for row in tomllib.loads(text).values()
    }


#: Every size in the table, by nominal diameter (mm).
ISO_METRIC: dict[float, MetricSize] = _read_iso_metric()


def metric(diameter_mm: float) -> MetricSize:
    """The ISO metric size of a nominal diameter.

    Raises:
        KeyError: the table has no such size (naming the sizes it has).
    """
    try:
        return ISO_METRIC[float(diameter_mm)]
    except KeyError:
        raise KeyError(
            f"M{diameter_mm:g} is not in data/iso_metric.toml; sizes: "
            + ", ".join(s.designation for s in ISO_METRIC.values())
        ) from None


def size_for_tap_drill(tap_drill_mm: float) -> MetricSize:
    """The size whose tap drill is nearest to ``tap_drill_mm`` (a parameter file's set-screw
    drill)."""
    return min(ISO_METRIC.values(), key=lambda s: abs(s.tap_drill_mm - tap_drill_mm))


def size_for_clearance_hole(hole_mm: float) -> MetricSize:
    """The size whose ISO 273 medium clearance hole is nearest to ``hole_mm`` (a bolt
    through-hole)."""
    return min(ISO_METRIC.values(), key=lambda s: abs(s.clearance_hole_mm - hole_mm))
