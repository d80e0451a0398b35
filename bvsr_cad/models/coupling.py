"""Mimic couplings of the URDF for simulators that ignore <mimic> (PyBullet).

PyBullet loads the URDF's mimic joints as independent joints. Call
:func:`couple_mimic_joints` before every ``stepSimulation``: each mimic joint
is driven by a stiff position motor to ``multiplier * q_master + offset``
(and the matching velocity), which is how the bending chain
Rz(phi) Ry(theta/2) Tz(chord) Ry(theta/2) Rz(-phi) stays one constant-curvature arc.

Example::

    import pybullet as pb
    from bvsr_cad.models.coupling import mimic_joints, couple_mimic_joints
    body = pb.loadURDF("robot/bvsr.urdf", useFixedBase=True, flags=pb.URDF_USE_INERTIA_FROM_FILE)
    mimics = mimic_joints("robot/bvsr.urdf")
    for _ in range(1000):
        couple_mimic_joints(pb, body, mimics)
        pb.stepSimulation()
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class MimicJoint:
    joint: str
    master: str
    multiplier: float
    offset: float


def mimic_joints(urdf_path: str | Path) -> list[MimicJoint]:
    """Every <mimic> of a URDF file."""
    out = []
    for j in ET.parse(urdf_path).getroot().iter("joint"):
        m = j.find("mimic")
        if m is not None:
            out.append(
                MimicJoint(
                    j.get("name"),
                    m.get("joint"),
                    float(m.get("multiplier", 1.0)),
                    float(m.get("offset", 0.0)),
                )
            )
    return out


def couple_mimic_joints(
    pb, body: int, mimics: list[MimicJoint], max_force: float = 1e4, physics_client: int = 0
) -> None:
    """Drive every mimic joint to follow its master (call before each step).

    Args:
        pb: the ``pybullet`` module.
        body: the unique id returned by ``loadURDF``.
        mimics: from :func:`mimic_joints`.
        max_force: motor force or torque limit; far above what the SOAs produce.
        physics_client: the PyBullet client id.
    """
    index = {}
    for i in range(pb.getNumJoints(body, physicsClientId=physics_client)):
        index[pb.getJointInfo(body, i, physicsClientId=physics_client)[1].decode()] = i
    for m in mimics:
        q, qd = pb.getJointState(body, index[m.master], physicsClientId=physics_client)[:2]
        pb.setJointMotorControl2(
            body,
            index[m.joint],
            pb.POSITION_CONTROL,
            targetPosition=m.multiplier * q + m.offset,
            targetVelocity=m.multiplier * qd,
            force=max_force,
            positionGain=1.0,
            velocityGain=1.0,
            physicsClientId=physics_client,
        )
