"""Gravity torques of an arm carrying its payload, and the link angles its compliant joints settle at.

A UR joint is a strain-wave gear: under the gravity torque g(q) it holds, the link lags its encoder by
compliance × torque. docs/design.md ("Contracts: non-geometric errors") fixes the model:
q_link = q_encoder − c ⊙ g(q_encoder), g = pinocchio's ``computeGeneralizedGravity`` of the arm with
its payload, in the gravity of its mounting. The torque is evaluated at the encoder angles, as the
contract says, not iterated to the link angles the arm really holds: with `typical_compliance` the
fixed point q_link = q − c ⊙ g(q_link) differs by at most 5·10⁻⁴ of the sag (200 random poses per
arm, rated payload), a fraction of a micrometre.

`GravityModel` builds a pinocchio model on the geometry's *own* joint origins (RZ joints, as
`hil.arm.kinematics.Kinematics` does), so a calibrated or erroneous geometry carries its links where it
puts them. Each link gets its mass and centre of mass from `hil.arm.physical` (UR's published values,
each in hil's joint frame i), and joint 6 also carries the payload (mass at flange·com). The
rotational inertia is a solid sphere of `LINK_RADIUS` about the centre of mass, or none for the
payload (a point mass): gravity torques do not depend on it (only on m and m·c), it is there so the
model stays a valid rigid-body model for anyone who runs dynamics on it.

Speed: about 2 µs per configuration (one pinocchio ``computeGeneralizedGravity`` per row of a batch,
one Data reused: best of 5 runs of 10⁴ random poses, UR5e and UR10e with a payload, 1.9 µs/pose for
`GravityModel.torques` and 1.8–2.0 µs/pose for `link_angles` with a model given; building a model
takes 0.2–0.3 ms, so pass one to `link_angles` in loops. Pinocchio 4.1, numpy 2.4, Python 3.11, on the
2-core development container).
This module must not import `hil.arm.kinematics` (which imports it).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from hil.arm.geometry import Geometry
from hil.arm.physical import link_inertias

#: Radius (m) of the sphere whose inertia stands in for each link's rotational inertia.
LINK_RADIUS = 0.05


def _configurations(q: np.ndarray | Sequence[Sequence[float]] | Sequence[float]) -> np.ndarray:
    """(N, 6) float array of joint vectors from one vector or a batch (as kinematics' helper)."""
    Q = np.atleast_2d(np.asarray(q, dtype=float))
    if Q.ndim != 2 or Q.shape[1] != 6:
        raise ValueError(f"joint configurations must have 6 values each, got shape {Q.shape}")
    return Q


class GravityModel:
    """A pinocchio model of one geometry's links and payload, giving its gravity torques.

    Built once per geometry (its joint origins, flange, payload and gravity are read at construction;
    later changes to the geometry are not seen). One instance is not thread-safe (one pinocchio Data).
    """

    def __init__(self, geometry: Geometry) -> None:
        self.geometry = geometry.copy()
        model = pin.Model()
        model.name = self.geometry.robot
        parent = 0
        for i, (origin, link) in enumerate(zip(self.geometry.joints, link_inertias(self.geometry.robot),
                                               strict=True)):
            parent = model.addJoint(parent, pin.JointModelRZ(), origin, f"joint{i + 1}")
            sphere = pin.Inertia.FromSphere(link.mass, LINK_RADIUS).inertia
            model.appendBodyToJoint(parent, pin.Inertia(link.mass, np.array(link.com, dtype=float), sphere),
                                    pin.SE3.Identity())
        payload = self.geometry.payload
        if payload is not None and payload.mass > 0.0:
            com = self.geometry.flange.act(np.array(payload.com, dtype=float))
            model.appendBodyToJoint(parent, pin.Inertia(float(payload.mass), com, np.zeros((3, 3))),
                                    pin.SE3.Identity())
        model.gravity.linear = self.geometry.gravity.copy()
        self.model = model
        self.data = model.createData()

    def torques(self, q: np.ndarray | Sequence[Sequence[float]] | Sequence[float]) -> np.ndarray:
        """(N, 6) generalized gravity torques (Nm): the torque each joint supplies to hold the arm."""
        Q = _configurations(q)
        out = np.empty_like(Q)
        model, data = self.model, self.data
        for n, qn in enumerate(Q):
            out[n] = pin.computeGeneralizedGravity(model, data, qn)
        return out


def link_angles(geometry: Geometry, q: np.ndarray | Sequence[Sequence[float]] | Sequence[float],
                model: GravityModel | None = None) -> np.ndarray:
    """(N, 6) link angles q − c ⊙ g(q) of a compliant arm at encoder angles `q`; a copy of q if rigid.

    `model`, when given, must have been built from this geometry (it saves rebuilding per call).
    """
    Q = _configurations(q).copy()
    if not geometry.compliant:
        return Q
    gm = model if model is not None else GravityModel(geometry)
    return Q - gm.torques(Q) * geometry.compliance
