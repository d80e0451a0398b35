"""The one place where units change.

The CAD layer works in millimetres and degrees; robot descriptions and the
physical models work in SI (m, kg, s, rad). Every conversion goes through here.
"""

from __future__ import annotations

import math

MM_PER_M = 1000.0
G_PER_KG = 1000.0
MM3_PER_CM3 = 1000.0
PA_PER_KPA = 1000.0
PA_PER_BAR = 100_000.0
PA_PER_MPA = 1_000_000.0
#: Standard gravity (CGPM 1901), m/s^2 = N/kg.
STANDARD_GRAVITY_M_S2 = 9.80665


def mm_to_m(value_mm: float) -> float:
    return value_mm / MM_PER_M


def m_to_mm(value_m: float) -> float:
    return value_m * MM_PER_M


def deg_to_rad(value_deg: float) -> float:
    return math.radians(value_deg)


def rad_to_deg(value_rad: float) -> float:
    return math.degrees(value_rad)


def mass_g(volume_mm3: float, density_g_cm3: float) -> float:
    """Mass in grams of a volume in mm^3 at a density in g/cm^3."""
    return volume_mm3 / MM3_PER_CM3 * density_g_cm3


def g_to_kg(value_g: float) -> float:
    return value_g / G_PER_KG


def g_mm2_to_kg_m2(value_g_mm2: float):
    """Moment of inertia: g mm^2 -> kg m^2 (works on arrays too)."""
    return value_g_mm2 / G_PER_KG / (MM_PER_M * MM_PER_M)


def deg_s_to_rad_s(value_deg_s: float) -> float:
    return math.radians(value_deg_s)


def g_cm3_to_kg_m3(value_g_cm3: float) -> float:
    return value_g_cm3 * 1000.0


def nmm_to_nm(value_nmm: float) -> float:
    """Torque or rotational stiffness: N mm -> N m."""
    return value_nmm / MM_PER_M


def kpa_to_pa(value_kpa):
    return value_kpa * PA_PER_KPA


def mm2_to_m2(value_mm2: float) -> float:
    return value_mm2 / (MM_PER_M * MM_PER_M)


def mm3_to_m3(value_mm3: float) -> float:
    return value_mm3 / MM_PER_M**3
