"""Joint torques of a moving arm, the link lag they cause, and where that quasi-static lag holds.

Moving, a compliant arm deflects under its inertial torques as well as under gravity. This module
extends the static contract of `hil.arm.gravity` (q_link = q_encoder − c ⊙ g(q_encoder)) to a
moving arm: q_link = q_encoder − c ⊙ τ(q, q̇, q̈), τ the joint torques of the rigid arm following
(q, q̇, q̈) — pinocchio's recursive Newton–Euler inverse dynamics (``pin.rnea``) on the *same* model
`hil.arm.gravity.GravityModel` builds (UR's published link masses and centres of mass from
`hil.arm.physical`, the payload, the mounting's gravity). At rest (q̇ = q̈ = 0) RNEA returns exactly
``computeGeneralizedGravity``, so the lag reduces to today's c ⊙ g(q) (the tests check it).

What it leaves out:

* **Rotational inertia.** The link inertias are `hil.arm.gravity`'s stand-in solid spheres of
  `LINK_RADIUS` about each centre of mass, not UR's inertia tensors: gravity does not depend on them,
  inertial torques do (a little; the masses at their lever arms dominate for the proximal joints).
  Taking UR's published tensors is the next refinement.
* **Joint friction** (Coulomb and viscous) is torque the *motor* supplies on its side of the gear:
  it never passes through the gear's compliance to the link, so it does not deflect the link.
* **Flexible-joint dynamics.** The model is quasi-static: the deflection follows the torque at
  once. A real joint with compliance c holding a link of inertia I about its axis is a spring-mass
  pair with natural frequency ωₙ = 1/√(c·I) (Spong, "Modeling and Control of Elastic Joint Robots",
  J. Dyn. Sys. Meas. Control 109(4), 1987: the link side obeys I·q̈_l = K·(q_m − q_l) + …). A change
  Δq̈ of the joint's acceleration excites a ring of amplitude Δq̈/ωₙ² about the quasi-static lag —
  the undamped step response of x'' + ωₙ²x = Δq̈, whose static part is the deflection change
  c·I·Δq̈ = Δq̈/ωₙ² (the same physics `mocks.ringing` gives the tracker: "amplitude a_tip/ωₙ²").
  The model leaves that ring out. `acceleration_limit` is therefore the acceleration whose sudden
  change would ring by more than `tolerance_rad`: ωₙ² · tolerance. With the default tolerance
  (`DEFAULT_TOLERANCE_RAD`, the tracker's one-reading σ at a metre) and `typical_compliance`,
  a UR5e stretched out (q = 0) with its rated payload at the flange is trusted to about 0.6 rad/s² in its
  shoulder joints, 3 rad/s² in the elbow and 8–10 rad/s² in wrists 1 and 2 (a UR10e to 0.3, 0.7
  and 5–7 rad/s²). Samples beyond it are the ones a stream join
  (`hil.calibration.stream_join`) leaves out.

  Caveat: ωₙ here is the joint's own mode through the compliance the *model* carries (the part of
  the windup the encoders do not see). The first structural modes measured on lightweight 6-axis
  arms are 7–12 Hz (Wu, Intelligence & Robotics 1(2), 2021, the source of `mocks.ringing`'s 9 Hz),
  lower than this joint-only ωₙ (≈ 45 Hz for the UR5e's shoulder): link bending the model does not
  carry. So the limit is an upper bound: a sweep must also keep its jerk low enough not to excite
  those modes, which a smooth (jerk-limited) path does by construction.

I = M(q)ᵢᵢ, the diagonal of the joint-space inertia matrix (``pin.crba``): the inertia joint i sees
with every other joint held, the link-side inertia of the flexible-joint model.

Not thread-safe per instance (one pinocchio Data), like `GravityModel`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from hil.arm.geometry import Geometry
from hil.arm.gravity import GravityModel, _configurations

#: rad: default ring the quasi-static model may leave out: 7.5 µm (the tracker's one-reading distance
#: σ, docs/design.md, Facts: tracker accuracy) at a 1 m lever — about a UR's reach — so what the model
#: misses stays below what the tracker can see. A choice of hil's, not a published figure.
DEFAULT_TOLERANCE_RAD = 7.5e-6

JointArray = np.ndarray | Sequence[Sequence[float]] | Sequence[float]


def _like(Q: np.ndarray, values: JointArray | None, name: str) -> np.ndarray:
    """`values` as an (N, 6) array matching the configurations `Q` (zeros when None)."""
    if values is None:
        return np.zeros_like(Q)
    V = np.atleast_2d(np.asarray(values, dtype=float))
    if V.shape != Q.shape:
        raise ValueError(f"{name} must have the shape of q {Q.shape}, got {V.shape}")
    return V


class DynamicsModel:
    """Inverse dynamics and joint modes of one geometry, on `GravityModel`'s pinocchio model."""

    def __init__(self, geometry: Geometry, gravity_model: GravityModel | None = None) -> None:
        self.gravity_model = gravity_model if gravity_model is not None else GravityModel(geometry)
        self.geometry = self.gravity_model.geometry
        self.model = self.gravity_model.model
        self.data = self.model.createData()

    def torques(self, q: JointArray, qd: JointArray | None = None, qdd: JointArray | None = None
                ) -> np.ndarray:
        """(N, 6) joint torques τ(q, q̇, q̈) (Nm) of the rigid arm, gravity included (``pin.rnea``).

        Missing velocities or accelerations are zero, so ``torques(q)`` is the gravity torque."""
        Q = _configurations(q)
        V, A = _like(Q, qd, "qd"), _like(Q, qdd, "qdd")
        out = np.empty_like(Q)
        model, data = self.model, self.data
        for n in range(len(Q)):
            out[n] = pin.rnea(model, data, Q[n], V[n], A[n])
        return out

    def inertia_diagonal(self, q: JointArray) -> np.ndarray:
        """(N, 6) M(q)ᵢᵢ (kg·m²): the inertia each joint moves with the others held (``pin.crba``)."""
        Q = _configurations(q)
        out = np.empty_like(Q)
        for n, qn in enumerate(Q):
            out[n] = np.diag(pin.crba(self.model, self.data, qn))
        return out

    def natural_frequencies(self, q: JointArray) -> np.ndarray:
        """(N, 6) ωₙ = 1/√(c·Mᵢᵢ(q)) (rad/s) of each joint's mode; inf for a rigid joint (c = 0)."""
        c = self._compliance()
        with np.errstate(divide="ignore"):
            return 1.0 / np.sqrt(c * self.inertia_diagonal(q))

    def acceleration_limit(self, q: JointArray, tolerance_rad: float = DEFAULT_TOLERANCE_RAD
                           ) -> np.ndarray:
        """(N, 6) |q̈| (rad/s²) up to which the quasi-static lag is trusted: ωₙ² · tolerance_rad.

        An acceleration change that large would ring the joint's mode by `tolerance_rad`, which the
        model leaves out (module docstring). inf for a rigid joint."""
        if not tolerance_rad > 0:
            raise ValueError(f"tolerance_rad must be > 0, got {tolerance_rad}")
        c = self._compliance()
        with np.errstate(divide="ignore"):
            return tolerance_rad / (c * self.inertia_diagonal(q))

    def _compliance(self) -> np.ndarray:
        c = self.geometry.compliance
        return np.zeros(6) if c is None else np.asarray(c, dtype=float)


def moving_link_angles(geometry: Geometry, q: JointArray, qd: JointArray | None = None,
                       qdd: JointArray | None = None, model: DynamicsModel | None = None) -> np.ndarray:
    """(N, 6) link angles q − c ⊙ τ(q, q̇, q̈) of a compliant arm moving through (q, q̇, q̈).

    At rest it is `hil.arm.gravity.link_angles`; a rigid arm's link angles are its encoder angles.
    `model`, when given, must have been built from this geometry."""
    Q = _configurations(q).copy()
    if not geometry.compliant:
        return Q
    dm = model if model is not None else DynamicsModel(geometry)
    return Q - dm.torques(Q, qd, qdd) * geometry.compliance


class MovingArm:
    """SMR positions of a compliant arm moving through (q, q̇, q̈): forward kinematics of the link
    angles q − c ⊙ τ(q, q̇, q̈) + e(q) − b ⊙ s (the contract's terms at the encoder angles, the
    inertial torque added to gravity's; the lost motion b to the side s each joint last moved, when
    the caller knows it: `hil.arm.joint_directions`, else none)."""

    def __init__(self, geometry: Geometry) -> None:
        from hil.arm.kinematics import Kinematics  # kinematics imports gravity, not this module

        self.geometry = geometry.copy()
        self.dynamics = DynamicsModel(self.geometry)
        exact = self.geometry.copy()
        exact.compliance, exact.joint_errors, exact.lost_motion = None, None, None
        self._kinematics = Kinematics(exact)  # the link angles are given to it: nothing more applied

    def link_angles(self, q: JointArray, qd: JointArray | None = None, qdd: JointArray | None = None,
                    directions: np.ndarray | None = None) -> np.ndarray:
        """(N, 6) link angles of the moving arm (`directions` (N, 6) or (6,): the lost motion's sides)."""
        Q = moving_link_angles(self.geometry, q, qd, qdd, self.dynamics)
        if self.geometry.has_joint_errors:
            Q = Q + self.geometry.joint_errors.offsets(_configurations(q))
        if directions is not None and self.geometry.has_lost_motion:
            Q = Q - self.geometry.lost_motion * np.broadcast_to(np.asarray(directions, float), Q.shape)
        return Q

    def points(self, q: JointArray, qd: JointArray | None = None, qdd: JointArray | None = None,
               frame: str = "tracker", directions: np.ndarray | None = None) -> np.ndarray:
        """(N, 3) SMR centres in the tracker (or base) frame."""
        return self._kinematics.points(self.link_angles(q, qd, qdd, directions), frame=frame)
