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
    """The export's masses, size and SOA fold against what the paper reports."""
    m = exp.manifest
    return [*_mass_results(m), *_size_results(m), *_soa_fold_results(m)]


def _mass_results(m: dict) -> list[CheckResult]:
    """A standalone segment's mass and the tail's against the paper's weighings."""
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
    segment = CheckResult(
        "paper:segment_standalone_mass",
        None,
        seg,
        ref.value,
        "g",
        ref.where,
        f"{_diff(seg, ref.value)}; {why}",
    )
    tail = float(m["mass_g"]["tail"])
    ref_mass = paper.paper_tail_mass(int(m["segments"]))
    if ref_mass is None:
        return [
            segment,
            CheckResult(
                "paper:tail_mass",
                None,
                tail,
                None,
                "g",
                paper.TAIL_MASS.where,
                f"the paper weighs only the 2-segment tail ({paper.TAIL_MASS.value:g} g)",
            ),
        ]
    return [
        segment,
        CheckResult(
            "paper:tail_mass",
            None,
            tail,
            ref_mass.value,
            "g",
            ref_mass.where,
            _diff(tail, ref_mass.value) + "; the model has panels, SOAs and rods only: "
            "push-in fittings, tubes, adhesive, inserts and bolts are not modelled",
        ),
    ]


def _size_results(m: dict) -> list[CheckResult]:
    """The tail's length against Table I's and its taper against Table I's tilt angle."""
    ref_len = paper.paper_length(int(m["segments"]))
    length = float(m["length_mm"])
    taper = m["taper"]
    return [
        CheckResult(
            "paper:tail_length",
            None,
            length,
            ref_len.value,
            "mm",
            ref_len.where,
            _diff(length, ref_len.value) + "; Table I gives N H_a + (N + 1) x 6 mm",
        ),
        CheckResult(
            "paper:taper_half_angle",
            None,
            taper["half_angle_deg"],
            paper.TILT_ANGLE_SEGMENT_1.value - 90.0,
            "deg",
            "Table I alpha_2 - 90",
            f"built {taper['half_angle_deg']:.3f} deg; the paper's 1.23 deg makes the flange "
            f"pockets of neighbouring SOAs overlap; limited by: {taper['limited_by']}",
        ),
    ]


def _soa_fold_results(m: dict) -> list[CheckResult]:
    """How far Table II's SOA dimensions are from closing: the fold's height from its dihedral
    angle, and the rounded square's span against D."""
    fold = m["soa_fold"]
    return [
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
        ),
        CheckResult(
            "soa_circumcircle_residual",
            None,
            fold["circumcircle_residual_mm"],
            0.0,
            "mm",
            "Table II D",
            f"square b rounded at R spans {fold['circumcircle_computed_mm']:.3f} mm "
            f"against D = {fold['circumcircle_table_mm']:.2f} mm",
        ),
    ]
