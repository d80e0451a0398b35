"""Masses: from the meshes and the densities, and their sums."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .. import units
from .export import Export
from .result import CheckResult

MASS_TOLERANCE = 0.002  # the mesh mass and the B-rep mass agree to 0.2 %
SUM_TOLERANCE_G = 1e-6


def masses_reads(exp: Export) -> tuple[list[str], Any]:
    """What :func:`check_masses` reads: each part's :func:`part_mass_reads` and kind (the sums leave
    the rigid twin out), and the manifest's ``mass_g``."""
    reads = [part_mass_reads(p) for p in exp.parts]
    return [f for files, _ in reads for f in files], {
        "parts": [[p["kind"], values] for p, (_, values) in zip(exp.parts, reads)],
        "mass_g": exp.manifest["mass_g"],
    }


def part_mass_reads(part: dict[str, Any]) -> tuple[list[str], Any]:
    """What :func:`check_part_mass` reads: the part's STL and its entry's mass, density and
    counts."""
    return [part["files"]["stl"]], [
        part["name"],
        part["material"],
        part["density_g_cm3"],
        part["mass_g"],
        part["count"],
        part.get("instances", []),
    ]


def check_part_mass(exp: Export, part: dict[str, Any]) -> list[CheckResult]:
    """One part's mass from its mesh and density against its entry, and its count against its
    instances."""
    name = part["name"]
    mesh = exp.mesh(part["files"]["stl"])
    mesh_mass = units.mass_g(float(mesh.volume), float(part["density_g_cm3"]))
    rel = abs(mesh_mass - part["mass_g"]) / part["mass_g"]
    n = len(part.get("instances", []))
    return [
        CheckResult(
            f"mass_from_density:{name}",
            rel <= MASS_TOLERANCE,
            mesh_mass,
            part["mass_g"],
            "g",
            part["files"]["stl"],
            f"mesh volume x {part['density_g_cm3']} g/cm3 ({part['material']}); "
            f"differs by {100 * rel:.3f} %",
        ),
        CheckResult(
            f"count_matches_instances:{name}",
            n == part["count"],
            part["count"],
            n,
            "",
            "manifest.json",
        ),
    ]


def check_masses(
    exp: Export, memo: Callable[..., list[CheckResult]] | None = None
) -> list[CheckResult]:
    """Every part's mass and count (``memo``: a :class:`~bvsr_cad.checks.memo.CheckMemo`, whose
    cache keeps each part's verdicts while its STL and entry are unchanged: a rod-material edit
    loads the rod's mesh alone), and the sums."""
    out: list[CheckResult] = []
    total = 0.0
    for part in exp.parts:
        out += (
            memo("part_mass", part_mass_reads(part), lambda part=part: check_part_mass(exp, part))
            if memo is not None
            else check_part_mass(exp, part)
        )
        if (
            part["kind"] != "rigid_tail"
        ):  # the rigid comparison tail is a second product, not part of the BVSR
            total += part["count"] * part["mass_g"]
    tail = float(exp.manifest["mass_g"]["tail"])
    out.append(
        CheckResult(
            "mass_parts_sum_to_tail",
            abs(total - tail) <= SUM_TOLERANCE_G,
            total,
            tail,
            "g",
            "manifest.json",
            "sum of count x mass over the parts",
        )
    )
    segs = exp.manifest["mass_g"].get("segments", [])
    out.append(
        CheckResult(
            "mass_segments_sum_to_tail",
            abs(sum(segs) - tail) <= SUM_TOLERANCE_G,
            sum(segs),
            tail,
            "g",
            "manifest.json",
            "shared boundary panels count half to each segment",
        )
    )
    return out
