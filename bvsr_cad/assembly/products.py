"""The fabrication products beside the tail: the SOA mold set and the rigid PLA twin.

Built here, below the writers, like every other part, and handed to the
exporters as objects (:mod:`bvsr_cad.exporters.mold_files` and
:mod:`bvsr_cad.exporters.fabrication_files` only serialise them). The twin's
robot description is a one-link model (:func:`rigid_robot_model`) whose
inertial is the exact B-rep mass properties of its pieces, composed with
:func:`bvsr_cad.assembly.inertia.compose`.
"""

from __future__ import annotations

from dataclasses import dataclass

import build123d as bd
import numpy as np

from ..parameters.tables import TailSpec
from ..parameters.twin import RIGID_TWIN_MATERIAL
from ..parts.kernel import location
from ..parts.mold import MoldSet, mold_set
from ..parts.rigid_tail import RigidPiece, rigid_tail_pieces
from .assemble import Assembly
from .inertia import Inertial, SolidProperties, compose, from_solid

#: The rigid twin's material (a PLA print, as the paper's rigid comparison tail), checked at load.
RIGID_MATERIAL = RIGID_TWIN_MATERIAL


def mold_set_inputs(spec: TailSpec) -> tuple:
    """Everything of the parameters the mold set is made from (:func:`build_mold_set`'s arguments to
    :func:`bvsr_cad.parts.mold.mold_set`; the build keys the mold set's cache entry by them)."""
    return spec.soa, spec.joint.base_diameter_mm, spec.casting


def build_mold_set(asm: Assembly) -> MoldSet:
    """The casting mold set of the assembly's SOA."""
    return mold_set(*mold_set_inputs(asm.spec))


def build_rigid_twin(asm: Assembly) -> list[RigidPiece]:
    """The rigid twin's pieces (print frames), one per joint and the tip panel."""
    soa_transforms = {
        k: [np.asarray(i.transform) for i in asm.soas_of_joint(k)]
        for k in range(1, asm.spec.panels)
    }
    return rigid_tail_pieces(asm.spec, asm.panel_layouts, soa_transforms)


def piece_transform_mm(piece: RigidPiece) -> np.ndarray:
    """Print frame -> tail frame of a twin piece (a shift up to its bed face)."""
    T = np.eye(4)
    T[2, 3] = piece.z0_mm
    return T


@dataclass(frozen=True)
class RigidRobot:
    """The twin as one rigid body fixed to the mount (SI), with its solids in the tail frame
    (mm)."""

    name: str
    material: str
    inertial: Inertial  # tail frame, metres
    solids_mm: tuple[bd.Shape, ...]
    timestep_s: float


def rigid_robot_model(
    asm: Assembly, pieces: list[RigidPiece], props: list[SolidProperties] | None = None
) -> RigidRobot:
    """``props``: the pieces' B-rep properties when already measured
    (:meth:`SolidProperties.of`)."""
    density = asm.spec.material(RIGID_MATERIAL).density_g_cm3
    props = props if props is not None else [SolidProperties.of(p.solid) for p in pieces]
    inertial = compose(
        from_solid(p.solid, density, piece_transform_mm(p), q) for p, q in zip(pieces, props)
    )
    solids = tuple(p.solid.moved(location(piece_transform_mm(p))) for p in pieces)
    return RigidRobot(
        f"{asm.spec.name}_rigid", RIGID_MATERIAL, inertial, solids, asm.spec.robot.timestep_s
    )
