"""Comparisons with the paper (informational: ``passed`` is None)."""

from __future__ import annotations

from ..parameters import paper
from .export import Export
from .result import CheckResult


def _diff(computed: float, reported: float) -> str:
    return (
        f"computed {computed:.2f}, paper {reported:.2f}, difference {computed - reported:+.2f} "
        f"({100 * (computed - reported) / reported:+.1f} %)"
    )


def check_paper(exp: Export) -> list[CheckResult]:
    m = exp.manifest
    out: list[CheckResult] = []
    seg = float(m["mass_g"]["segment_standalone"])
    ref = paper.SEGMENT_STANDALONE_MASS
    within = abs(seg - ref.value) <= paper.SEGMENT_MASS_TOLERANCE * ref.value
    why = (
        "within 10 % of the paper"
        if within
        else "outside 10 % of the paper: adjust lightening.hole_diameter_mm; the modelled segment "
        "has no "
        "fittings, tubes, adhesive or fasteners"
    )
    out.append(
        CheckResult(
            "paper:segment_standalone_mass",
            None,
            seg,
            ref.value,
            "g",
            ref.where,
            f"{_diff(seg, ref.value)}; {why}",
        )
    )
    tail = float(m["mass_g"]["tail"])
    segments = int(m["segments"])
    ref_mass = paper.paper_tail_mass(segments)
    if ref_mass is None:
        out.append(
            CheckResult(
                "paper:tail_mass",
                None,
                tail,
                None,
                "g",
                paper.TAIL_MASS.where,
                f"the paper weighs only the 2-segment tail ({paper.TAIL_MASS.value:g} g)",
            )
        )
    else:
        out.append(
            CheckResult(
                "paper:tail_mass",
                None,
                tail,
                ref_mass.value,
                "g",
                ref_mass.where,
                _diff(tail, ref_mass.value) + "; the model has panels, SOAs and rods only: "
                "push-in fittings, tubes, adhesive, inserts and bolts are not modelled",
            )
        )
    ref_len = paper.paper_length(segments)
    length = float(m["length_mm"])
    out.append(
        CheckResult(
            "paper:tail_length",
            None,
            length,
            ref_len.value,
            "mm",
            ref_len.where,
            _diff(length, ref_len.value) + "; Table I gives N H_a + (N + 1) x 6 mm",
        )
    )
    taper = m["taper"]
    out.append(
        CheckResult(
            "paper:taper_half_angle",
            None,
            taper["half_angle_deg"],
            paper.TILT_ANGLE_SEGMENT_1.value - 90.0,
            "deg",
            "Table I alpha_2 - 90",
            f"built {taper['half_angle_deg']:.3f} deg; the paper's 1.23 deg makes the flange "
            f"pockets of neighbouring SOAs overlap; limited by: {taper['limited_by']}",
        )
    )
    fold = m["soa_fold"]
    out.append(
        CheckResult(
            "soa_fold_residual",
            None,
            fold["residual_mm"],
            0.0,
            "mm",
            "Table II",
            f"four facet rows from alpha = {fold['dihedral_deg']} deg rise "
            f"{fold['origami_height_from_dihedral_mm']:.3f} mm against H_o = "
            f"{fold['origami_height_mm']:.2f} mm; alpha that closes it: "
            f"{fold['implied_dihedral_deg']:.2f} deg; built from {fold['built_from']}",
        )
    )
    out.append(
        CheckResult(
            "soa_circumcircle_residual",
            None,
            fold["circumcircle_residual_mm"],
            0.0,
            "mm",
            "Table II D",
            f"square b rounded at R spans {fold['circumcircle_computed_mm']:.3f} mm "
            f"against D = {fold['circumcircle_table_mm']:.2f} mm",
        )
    )
    return out
