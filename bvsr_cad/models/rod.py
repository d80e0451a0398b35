"""The vertebra rod's cross-section: the one home of its E I, E A and mass per length.

The rod is a solid round bar of diameter d in the vertebra material. Every
model that needs its stiffness or its mass (the statics, the workspace's
lumped masses, the robot descriptions) calls this module; a calibrated
stiffness then reaches all of them by changing one input.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from .. import units
from ..parameters.tables import NO_ROD, TailSpec


@dataclass(frozen=True)
class RodSection:
    """A solid round rod: diameter (mm), Young's modulus (MPa = N/mm^2), density (g/cm^3)."""

    material: str  # key into spec.materials
    diameter_mm: float
    youngs_modulus_mpa: float
    density_g_cm3: float
    fitted_flexural_rigidity_n_mm2: float | None = None  # `bvsr calibrate`'s effective E I, if any

    @property
    def area_mm2(self) -> float:
        """A = pi d^2 / 4."""
        return math.pi * self.diameter_mm**2 / 4.0

    @property
    def second_moment_mm4(self) -> float:
        """I = pi d^4 / 64 (solid circle about a diameter)."""
        return math.pi * self.diameter_mm**4 / 64.0

    @property
    def flexural_rigidity_n_mm2(self) -> float:
        """E I in N mm^2: the material's E times pi d^4 / 64, or the calibrated effective value."""
        if self.fitted_flexural_rigidity_n_mm2 is not None:
            return self.fitted_flexural_rigidity_n_mm2
        return self.youngs_modulus_mpa * self.second_moment_mm4

    @property
    def axial_rigidity_n(self) -> float:
        """E A in N."""
        return self.youngs_modulus_mpa * self.area_mm2

    def bending_stiffness_nmm_per_rad(self, length_mm: float) -> float:
        """E I / L of a piece of length L bent into an arc (Eq 10): N mm per rad."""
        return self.flexural_rigidity_n_mm2 / length_mm

    def bending_stiffness_nm_per_rad(self, length_mm: float) -> float:
        """E I / L in N m per rad."""
        return units.nmm_to_nm(self.bending_stiffness_nmm_per_rad(length_mm))

    def axial_stiffness_n_per_m(self, length_mm: float) -> float:
        """E A / L of a piece of length L in N/m."""
        return self.axial_rigidity_n / length_mm * units.MM_PER_M

    @property
    def mass_per_length_g_mm(self) -> float:
        return units.mass_g(self.area_mm2, self.density_g_cm3)

    def mass_g(self, length_mm: float) -> float:
        return self.mass_per_length_g_mm * length_mm


def rod_section(spec: TailSpec) -> RodSection:
    """The vertebra rod of ``spec`` (its material, diameter, modulus and density).

    No rod (``vertebra.material = "none"``): a section of zero stiffness and zero mass. A fitted E I
    (``[calibration.fitted] rod_flexural_rigidity_n_mm2``) belongs to the rod the measured tail had
    (``calibration.rod_material``, ``rod_diameter_mm``; a file calibrated before they were recorded
    describes its own rod). That rod gets the value as fitted; another rod gets its own table E I
    times the same ratio fitted / table, so a study over rods keeps the calibration's correction
    without giving every rod the measured rod's stiffness.
    """
    v = spec.vertebra
    if not v.has_rod:
        return RodSection(NO_ROD, v.diameter_mm, 0.0, 0.0, None)
    table = _table_section(spec, v.material, v.diameter_mm)
    fitted = spec.calibration.fitted.get("rod_flexural_rigidity_n_mm2")
    cal = spec.calibration
    measured = (cal.rod_material or v.material, cal.rod_diameter_mm or v.diameter_mm)
    if (
        fitted is None or measured[0] == NO_ROD
    ):  # a fit of an invertebrate tail has no rod E I to carry over
        return table
    if measured == (v.material, v.diameter_mm):
        return dataclasses.replace(table, fitted_flexural_rigidity_n_mm2=float(fitted))
    ratio = float(fitted) / _table_section(spec, *measured).flexural_rigidity_n_mm2
    return dataclasses.replace(
        table, fitted_flexural_rigidity_n_mm2=ratio * table.flexural_rigidity_n_mm2
    )


def _table_section(spec: TailSpec, material: str, diameter_mm: float) -> RodSection:
    """A rod of ``material`` and ``diameter_mm`` with the material table's modulus (no
    calibration)."""
    mat = spec.material(material)
    return RodSection(material, diameter_mm, mat.youngs_modulus_mpa, mat.density_g_cm3)


def joint_rod_stiffness_nmm_per_rad(spec: TailSpec) -> float:
    """E I / L of the rod across one joint gap (L = H_a)."""
    return rod_section(spec).bending_stiffness_nmm_per_rad(spec.joint.gap_mm)
