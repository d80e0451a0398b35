"""The rigid bodies of the paper's dynamic model (Eq 6-12, Fig. 2b), from the B-rep.

A joint's or a segment's moving part is everything distal of its base panel
that bends with it: the panels it carries, the SOAs of its joints and the rod
in its gaps. Its mass and inertia come from the exact solids
(:func:`bvsr_cad.assembly.inertia.from_solid`); the inertias about the centre
of mass are read in the rest pose (I_phi about the tail axis, I_theta the mean
of the two transverse ones).
"""

from __future__ import annotations

import numpy as np

from .. import units
from ..models.dynamics import RigidBody
from ..models.rod import rod_section
from .assemble import Assembly, Instance
from .inertia import Inertial, compose, from_solid


def _inertial(asm: Assembly, inst: Instance) -> Inertial:
    part = asm.part_of(inst)
    return from_solid(
        part.solid,
        asm.spec.material(part.material).density_g_cm3,
        np.asarray(inst.transform),
        asm.solid_properties(inst.part),
    )


def _rod_piece(asm: Assembly, z0_mm: float, z1_mm: float) -> Inertial:
    """The rod between two heights on the axis as a slender solid cylinder (m, I about its CoM)."""
    rod = rod_section(asm.spec)
    m = units.g_to_kg(rod.mass_g(z1_mm - z0_mm))
    length_m, r_m = units.mm_to_m(z1_mm - z0_mm), units.mm_to_m(rod.diameter_mm / 2)
    i_t = m * (3 * r_m**2 + length_m**2) / 12
    return Inertial.make(
        m, (0.0, 0.0, units.mm_to_m((z0_mm + z1_mm) / 2)), np.diag([i_t, i_t, m * r_m**2 / 2])
    )


def moving_body(asm: Assembly, first_joint: int, n_joints: int) -> RigidBody:
    """The body of joints ``first_joint .. first_joint + n_joints - 1`` (1-based) bending together.

    Its arc is the bending length of those joints, n H_j from the base panel's
    distal face to the last panel's distal face (one joint alone: its gap
    H_a, with the moving panel riding on the arc's end).
    """
    spec = asm.spec
    last = first_joint + n_joints - 1
    if not (1 <= first_joint <= last <= spec.joints):
        raise ValueError(f"joints {first_joint}..{last}: the tail has joints 1..{spec.joints}")
    h_j, gap = spec.joint.joint_height_mm, spec.joint.gap_mm
    base_face_mm = first_joint * h_j - gap  # distal face of panel first_joint - 1
    items = [_inertial(asm, asm.panel(k)) for k in range(first_joint, last + 1)]
    items += [_inertial(asm, s) for k in range(first_joint, last + 1) for s in asm.soas_of_joint(k)]
    if spec.vertebra.has_rod:
        items.append(_rod_piece(asm, base_face_mm, last * h_j + spec.joint.panel_thickness_mm))
    body = compose(items)
    inertia = body.inertia
    arc_mm = n_joints * h_j if n_joints > 1 else gap
    return RigidBody(
        body.mass_kg,
        float(inertia[2, 2]),
        float((inertia[0, 0] + inertia[1, 1]) / 2),
        units.mm_to_m(arc_mm),
    )


__all__ = ["moving_body"]
