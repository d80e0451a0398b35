"""The pressure lines as built: tube routes and lengths, the SOAs' air space, and the supply model
of a pulse.

The BOM cuts its tubes from :func:`line_tube_lengths_mm`; the dynamics
(:mod:`bvsr_cad.models.pneumatics`) fill the same tubes and the SOA cavity of
the B-rep (:func:`bvsr_cad.parts.soa.soa_interior`).
"""

from __future__ import annotations

import math

import numpy as np

from .. import units
from ..models.actuator import soa_force_law
from ..models.pneumatics import LineSupply, Valve
from ..parameters.layout import N_SOA
from ..parameters.tables import TailSpec
from ..parts.soa import soa_interior
from .assemble import Assembly


def tube_routes_mm(asm: Assembly) -> dict[str, float]:
    """Tube length inside the tail per pressure line at rest (mm), from the panel layouts.

    Segment 1's lines start at the push-in fittings on the root mount (no tube
    inside the tail). A line of segment s >= 2 runs from the root face through
    the tube holes of every panel before boundary panel p_s into its bonded
    port: the polyline through the hole centres at each panel's lower face,
    ending at the port's bottom.
    """
    spec = asm.spec
    routes: dict[str, float] = {}
    for s in range(1, spec.segments + 1):
        for i in range(1, 6):
            line = f"s{s}_line{i}"
            if s == 1:
                routes[line] = 0.0
                continue
            pts = []
            for lay in asm.panel_layouts:
                for c in lay.cuts:
                    if c.name == f"tube_s{s}_{i}":
                        pts.append((c.p0[0], c.p0[1], lay.z0_mm))
                    elif c.name == f"tube_port_s{s}_{i}":
                        pts.append((c.p1[0], c.p1[1], lay.z0_mm + c.p1[2]))
            p = np.asarray(pts, float)
            routes[line] = (
                float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) if len(p) > 1 else 0.0
            )
    return routes


def line_tube_lengths_mm(asm: Assembly) -> dict[str, float]:
    """Tube cut length per line (mm, to 0.1 mm): the route inside the tail with its bending
    allowance, plus the lead from the root to the valves."""
    fp = asm.spec.fabrication_package
    return {
        line: round(inside * (1.0 + fp.tube_bend_allowance) + fp.tube_lead_mm, 1)
        for line, inside in tube_routes_mm(asm).items()
    }


def soa_air_volume_mm3(asm: Assembly) -> float:
    """One SOA's air space at rest: the inner loft between the two panel faces (B-rep volume)."""
    spec = asm.spec
    return float(soa_interior(spec.soa, spec.joint.base_diameter_mm, beyond_ends_mm=0.0).volume)


def line_supply(
    asm: Assembly,
    segment: int,
    places: tuple[int, ...],
    source_gauge_pa: float,
    spec: TailSpec | None = None,
) -> LineSupply:
    """The supply of a pulse on ``places`` (1-based SOA places = the segment's line numbers): each
    line fills its SOAs (one per joint of ``segment``) through its own valve from a source at
    ``source_gauge_pa``; the other lines stay open to the atmosphere. ``spec`` (default the
    assembly's) may carry fitted values; the geometry is the assembly's."""
    spec = spec or asm.spec
    pn = spec.pneumatics
    atm = units.kpa_to_pa(spec.actuation.atmospheric_kpa)
    lengths = line_tube_lengths_mm(asm)
    bore_m = units.mm_to_m(spec.tubes.inner_diameter_mm)
    tube = [math.pi * bore_m**2 / 4 * units.mm_to_m(lengths[f"s{segment}_line{i}"]) for i in places]
    index = {p: n for n, p in enumerate(places)}
    return LineSupply(
        valve=Valve.from_catalogue(
            spec.fitted("valve_sonic_conductance_l_s_bar", pn.valve_sonic_conductance_l_s_bar),
            pn.valve_critical_pressure_ratio,
        ),
        source_pa_abs=atm + source_gauge_pa,
        atmospheric_pa=atm,
        tube_volume_m3=tuple(tube),
        soa_volume_m3=units.mm3_to_m3(soa_air_volume_mm3(asm)),
        soa_area_m2=soa_force_law(spec).area_m2,
        soas_per_line=spec.joints_per_segment,
        lines=tuple(index.get(i, -1) for i in range(1, N_SOA + 1)),
        polytropic_index=pn.polytropic_index,
        temperature_k=pn.air_temperature_k,
    )


__all__ = ["tube_routes_mm", "line_tube_lengths_mm", "soa_air_volume_mm3", "line_supply"]
