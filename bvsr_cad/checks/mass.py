"""Masses: from the meshes and the densities, and their sums."""

from __future__ import annotations

from typing import Any

from .. import units
from .export import Export
from .result import CheckResult

MASS_TOLERANCE = 0.002  # the mesh mass and the B-rep mass agree to 0.2 %
SUM_TOLERANCE_G = 1e-6


def masses_reads(exp: Export) -> tuple[list[str], Any]:
    """What :func:`check_masses` reads: every part's STL and entry (name, kind, material, density, mass,
    count, instances) and the manifest's ``mass_g``."""
    parts = [[p["name"], p["kind"], p["material"], p["density_g_cm3"], p["mass_g"], p["count"],
              p.get("instances", []), p["files"]["stl"]] for p in exp.parts]
    return [p["files"]["stl"] for p in exp.parts], {"parts": parts, "mass_g": exp.manifest["mass_g"]}


def check_masses(exp: Export) -> list[CheckResult]:
    out: list[CheckResult] = []
    total = 0.0
    for part in exp.parts:
        name = part["name"]
        mesh = exp.mesh(part["files"]["stl"])
        mesh_mass = units.mass_g(float(mesh.volume), float(part["density_g_cm3"]))
        rel = abs(mesh_mass - part["mass_g"]) / part["mass_g"]
        out.append(CheckResult(f"mass_from_density:{name}", rel <= MASS_TOLERANCE, mesh_mass, part["mass_g"],
                               "g", part["files"]["stl"],
                               f"mesh volume x {part['density_g_cm3']} g/cm3 ({part['material']}); "
                               f"differs by {100 * rel:.3f} %"))
        n = len(part.get("instances", []))
        out.append(CheckResult(f"count_matches_instances:{name}", n == part["count"], part["count"], n, "",
                               "manifest.json"))
        if part["kind"] != "rigid_tail":  # the rigid comparison tail is a second product, not part of the BVSR
            total += part["count"] * part["mass_g"]
    tail = float(exp.manifest["mass_g"]["tail"])
    out.append(CheckResult("mass_parts_sum_to_tail", abs(total - tail) <= SUM_TOLERANCE_G, total, tail, "g",
                           "manifest.json", "sum of count x mass over the parts"))
    segs = exp.manifest["mass_g"].get("segments", [])
    out.append(CheckResult("mass_segments_sum_to_tail", abs(sum(segs) - tail) <= SUM_TOLERANCE_G, sum(segs), tail,
                           "g", "manifest.json", "shared boundary panels count half to each segment"))
    return out
