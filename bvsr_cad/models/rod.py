"""The vertebra rod's cross-section: the one home of its E I, E A and mass per length.

The rod is a solid round bar of diameter d in the vertebra material. Every
model that needs its stiffness or its mass (the statics, the workspace's
lumped masses, the robot descriptions) calls this module; a calibrated
stiffness then reaches all of them by changing one input.
"""

from __future__ import annotations

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
        return math.pi * self.diameter_mm ** 2 / 4.0

    @property
    def second_moment_mm4(self) -> float:
        """I = pi d^4 / 64 (solid circle about a diameter)."""
        return math.pi * self.diameter_mm ** 4 / 64.0

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
    (``calibration.rod_material``, ``rod_diameter_mm``); another rod gets its own table E I times the
    same ratio fitted / table (:func:`fitted_rigidity_ratio`), so a study over rods keeps the
    calibration's correction without giving every rod the measured rod's stiffness.
    """
    v = spec.vertebra
    if not v.has_rod:
        return RodSection(NO_ROD, v.diameter_mm, 0.0, 0.0, None)
    mat = spec.material(v.material)
    ratio = fitted_rigidity_ratio(spec)
    cal = spec.calibration
    if ratio is None:
        fitted = None
    elif (cal.rod_material or v.material, cal.rod_diameter_mm or v.diameter_mm) == (v.material, v.diameter_mm):
        fitted = float(cal.fitted["rod_flexural_rigidity_n_mm2"])  # the measured rod itself: the value as fitted
    else:
        fitted = ratio * mat.youngs_modulus_mpa * math.pi * v.diameter_mm ** 4 / 64.0
    return RodSection(v.material, v.diameter_mm, mat.youngs_modulus_mpa, mat.density_g_cm3, fitted)


def fitted_rigidity_ratio(spec: TailSpec) -> float | None:
    """The calibration's E I as a fraction of its rod's table E I (None: no fitted E I).

    A file calibrated before the rod was recorded (no ``calibration.rod_material``) is taken to
    describe its own rod."""
    fitted = spec.calibration.fitted.get("rod_flexural_rigidity_n_mm2")
    if fitted is None:
        return None
    cal = spec.calibration
    material = cal.rod_material or spec.vertebra.material
    if material == NO_ROD:  # a fit of an invertebrate tail has no rod E I to carry over
        return None
    diameter_mm = cal.rod_diameter_mm or spec.vertebra.diameter_mm
    table_n_mm2 = spec.material(material).youngs_modulus_mpa * math.pi * diameter_mm ** 4 / 64.0
    return float(fitted) / table_n_mm2


def joint_rod_stiffness_nmm_per_rad(spec: TailSpec) -> float:
    """E I / L of the rod across one joint gap (L = H_a)."""
    return rod_section(spec).bending_stiffness_nmm_per_rad(spec.joint.gap_mm)
