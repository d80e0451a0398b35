"""Rigid-body inertials in SI and their composition (parallel-axis theorem).

An :class:`Inertial` is a mass, a centre of mass and an inertia tensor about
that centre, all expressed in one frame. :func:`compose` is the one function
that moves and adds them; every link inertia of the robot description goes
through it.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from .. import units


@dataclass(frozen=True)
class Inertial:
    mass_kg: float
    com_m: tuple[float, float, float]
    inertia_kg_m2: tuple[tuple[float, float, float], ...]  # about the CoM, frame axes

    @property
    def com(self) -> np.ndarray:
        return np.asarray(self.com_m, float)

    @property
    def inertia(self) -> np.ndarray:
        return np.asarray(self.inertia_kg_m2, float)

    def transformed(self, T_frame_self: np.ndarray) -> Inertial:
        """The same body expressed in another frame (T maps self-frame points there, metres)."""
        T = np.asarray(T_frame_self, float)
        R, p = T[:3, :3], T[:3, 3]
        return Inertial.make(self.mass_kg, R @ self.com + p, R @ self.inertia @ R.T)

    @staticmethod
    def make(mass_kg: float, com_m, inertia_kg_m2) -> Inertial:
        I = np.asarray(inertia_kg_m2, float)
        I = (I + I.T) / 2.0
        return Inertial(
            float(mass_kg),
            tuple(float(v) for v in com_m),
            tuple(tuple(float(v) for v in row) for row in I),
        )

    @staticmethod
    def point(mass_kg: float, inertia_kg_m2: float) -> Inertial:
        """A tiny valid inertial at the frame origin (virtual links)."""
        return Inertial.make(mass_kg, (0.0, 0.0, 0.0), np.eye(3) * inertia_kg_m2)


def compose(items: Iterable[Inertial]) -> Inertial:
    """Sum of bodies given in one frame: total mass, combined CoM, and the
    inertia about that CoM by the parallel-axis theorem."""
    items = list(items)
    if not items:
        raise ValueError("compose: nothing to compose")
    m = sum(i.mass_kg for i in items)
    if m <= 0:
        raise ValueError(f"compose: total mass {m} kg is not positive")
    c = sum(i.mass_kg * i.com for i in items) / m
    I = np.zeros((3, 3))
    for i in items:
        d = i.com - c
        I += i.inertia + i.mass_kg * (np.dot(d, d) * np.eye(3) - np.outer(d, d))
    return Inertial.make(m, c, I)


def shift_inertia(inertia_kg_m2: np.ndarray, mass_kg: float, offset_m: np.ndarray) -> np.ndarray:
    """Inertia about a point ``offset_m`` away from the CoM (parallel-axis theorem)."""
    d = np.asarray(offset_m, float)
    return np.asarray(inertia_kg_m2, float) + mass_kg * (np.dot(d, d) * np.eye(3) - np.outer(d, d))


@dataclass(frozen=True)
class SolidProperties:
    """A solid's B-rep volume properties at unit density, in its own frame (mm): what
    :func:`from_solid` reads, computed once per solid by :meth:`Assembly.solid_properties`."""

    volume_mm3: float
    com_mm: np.ndarray  # (3,)
    inertia_mm5: np.ndarray  # (3, 3) about the centre of mass, unit density

    @classmethod
    def of(cls, solid) -> SolidProperties:
        """One integration of the B-rep (OCCT's ``BRepGProp::VolumeProperties``) for all three:
        build123d's ``volume``, ``center(CenterOf.MASS)`` and ``matrix_of_inertia`` each run that
        same call, so the values are theirs to the bit, from one integration instead of three."""
        from OCP.BRepGProp import BRepGProp
        from OCP.GProp import GProp_GProps

        props = GProp_GProps()
        BRepGProp.VolumeProperties_s(solid.wrapped, props)
        com, inertia = props.CentreOfMass(), props.MatrixOfInertia()
        return cls(
            props.Mass(),
            np.array((com.X(), com.Y(), com.Z())),
            np.array([[inertia.Value(i + 1, j + 1) for j in range(3)] for i in range(3)], float),
        )


def from_solid(
    solid,
    density_g_cm3: float,
    T_frame_part_mm: np.ndarray | None = None,
    props: SolidProperties | None = None,
) -> Inertial:
    """Exact B-rep mass properties of a build123d solid (mm) at a density, in SI.

    ``T_frame_part_mm`` places the solid's own frame in the target frame (mm); ``props``: the
    solid's properties when already computed (OCCT integrates the B-rep on every query).
    """
    props = props if props is not None else SolidProperties.of(solid)
    vol_mm3 = props.volume_mm3
    density_g_mm3 = density_g_cm3 / units.MM3_PER_CM3
    com_mm = props.com_mm
    I_g_mm2 = props.inertia_mm5 * density_g_mm3
    own = Inertial.make(
        units.g_to_kg(vol_mm3 * density_g_mm3),
        com_mm / units.MM_PER_M,
        units.g_mm2_to_kg_m2(I_g_mm2),
    )
    if T_frame_part_mm is None:
        return own
    T = np.asarray(T_frame_part_mm, float).copy()
    T[:3, 3] /= units.MM_PER_M
    return own.transformed(T)


def principal(inertial: Inertial) -> tuple[np.ndarray, np.ndarray]:
    """(principal moments ascending, rotation whose columns are the principal axes)."""
    w, v = np.linalg.eigh(inertial.inertia)
    if np.linalg.det(v) < 0:
        v[:, 0] *= -1
    return w, v


def validity_problems(inertial: Inertial, rel_tol: float = 1e-9) -> list[str]:
    """Positive mass, positive-definite inertia, triangle inequality of the principal moments."""
    out = []
    if not inertial.mass_kg > 0:
        out.append(f"mass {inertial.mass_kg} kg is not positive")
    w, _ = principal(inertial)
    if not np.all(w > 0):
        out.append(f"principal moments {w} are not all positive")
    a, b, c = sorted(w)
    if a + b < c * (1 - rel_tol):
        out.append(f"principal moments {a:.3e} + {b:.3e} < {c:.3e} (triangle inequality)")
    return out
