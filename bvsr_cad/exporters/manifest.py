"""manifest.json: what an export holds, for tests and outside tools."""

from __future__ import annotations

from typing import Any

import build123d as bd

from .. import __version__
from ..assembly.assemble import Assembly, instance_solid, segment_masses_g
from ..parameters.panel_rules import binding_constraint, max_feasible_taper_deg
from ..parameters.tables import AUTO, SoaTable
from ..parts.kernel import bounds


def tail_length_mm(asm: Assembly) -> float:
    """Measured on the placed solids: the z extent of the whole tail."""
    box = bounds(bd.Compound([instance_solid(asm, i) for i in asm.instances]))
    return float(box.max.Z - box.min.Z)


def manifest_dict(
    asm: Assembly, params_sha256: str, files: dict[str, dict[str, str]], assembly_step: str
) -> dict[str, Any]:
    """The manifest of an export before the checks: its tail's counts, size, taper and SOA fold,
    its parts and their files, the assembly's instances and the masses."""
    spec = asm.spec
    parts = _part_entries(asm, files)
    in_tail, standalone = segment_masses_g(asm)
    return {
        "name": spec.name,
        "version": __version__,
        "params_sha256": params_sha256,
        "params_file": "params.toml",
        "units": {"length": "mm", "mass": "g", "angle": "deg"},
        "segments": spec.segments,
        "joints": spec.joints,
        "panels": spec.panels,
        "length_mm": tail_length_mm(asm),
        "taper": _taper_section(asm),
        "soa_fold": _soa_fold_section(spec.soa),
        "parts": parts,
        "assembly": {
            "step": assembly_step,
            "instances": [
                {
                    "name": i.name,
                    "part": i.part,
                    "segments": list(i.segments),
                    "transform": [list(r) for r in i.transform],
                }
                for i in asm.instances
            ],
        },
        "mass_g": {
            "segment_standalone": standalone[0],
            "segments_standalone": standalone,
            "segments": in_tail,
            "tail": sum(asm.mass_g(i.part) for i in asm.instances),
        },
        "checks": [],
    }


def _part_entries(asm: Assembly, files: dict[str, dict[str, str]]) -> list[dict[str, Any]]:
    """The manifest's ``parts``: each part's kind, material, process, count, volume, mass,
    instances, files (``files``, by part name) and print orientation."""
    parts = []
    for name, p in asm.parts.items():
        insts = asm.instances_of(name)
        mat = asm.spec.material(p.material)
        parts.append(
            {
                "name": name,
                "kind": p.kind,
                "material": p.material,
                "material_name": mat.name,
                "density_g_cm3": mat.density_g_cm3,
                "process": p.process,
                "count": len(insts),
                "volume_mm3": p.solid.volume,
                "mass_g": asm.mass_g(name),
                "instances": [i.name for i in insts],
                "files": files[name],
                "print_transform": [list(r) for r in p.print_transform],
                "info": p.info,
            }
        )
    return parts


def _taper_section(asm: Assembly) -> dict[str, Any]:
    """The manifest's ``taper``: the half angle built, the largest feasible and what limits it,
    and the tip panel's pitch and rim diameters."""
    spec = asm.spec
    return {
        "mode": "auto" if spec.taper.half_angle_deg == AUTO else "fixed",
        "half_angle_deg": asm.taper_half_angle_deg,
        "feasible_max_deg": max_feasible_taper_deg(spec),
        "limited_by": binding_constraint(spec),
        "pitch_diameter_tip_mm": 2 * asm.panel_layouts[-1].pitch_radius_lower_mm,
        "panel_diameter_tip_mm": 2 * asm.panel_layouts[-1].rim_radius_upper_mm,
    }


def _soa_fold_section(soa: SoaTable) -> dict[str, Any]:
    """The manifest's ``soa_fold``: the SOA's fold as built and how far Table II's dihedral angle
    and circumcircle are from closing it."""
    return {
        "built_from": soa.fold_height_from,
        "dihedral_deg": soa.dihedral_deg,
        "row_rise_mm": soa.row_rise_mm,
        "origami_height_from_dihedral_mm": soa.row_rise_from_dihedral_mm * soa.facet_rows,
        "origami_height_mm": soa.origami_height_mm,
        "residual_mm": soa.row_rise_from_dihedral_mm * soa.facet_rows - soa.origami_height_mm,
        "implied_dihedral_deg": soa.implied_dihedral_deg,
        "built_height_mm": soa.built_height_mm,
        "valley_interior_mm": soa.short_side_mm - 2 * soa.wall_offset_mm,
        "circumcircle_table_mm": soa.circumcircle_mm,
        "circumcircle_computed_mm": soa.computed_circumcircle_mm,
        "circumcircle_residual_mm": soa.computed_circumcircle_mm - soa.circumcircle_mm,
    }
