"""Forward kinematics and the identification Jacobian of the calibration model, from pinocchio.

The calibration parameters are small errors applied *multiplicatively* to the current geometry:

* a 6-D error δ = (v, ω) per joint origin, M_i ← M_i·exp(δ_i)          (36, ``joint{i}.tx … rz``)
* a 6-D error of the flange frame, M_f ← M_f·exp(δ_f)                   (6, ``flange.*``)
* the SMR centre in the flange frame, s ← s + δ_s                        (3, ``smr.x/y/z``)
* the tracker frame in the base frame, T_bt ← T_bt·exp(δ_t)              (6, ``tracker.*``)

A measured point is p = T_bt⁻¹ · T_base_flange(q) · s (the tracker frame). Only 27 combinations are
identifiable from position measurements (`identifiable_parameters`). The Jacobian of the joint-origin
errors is pinocchio's ``computeJointKinematicRegressor`` (the right-multiplied exp6 convention); the
flange, SMR and tracker columns are the closed-form derivatives of the expression above.

Batches loop over configurations in Python around pinocchio calls (about 2 µs per pose) and do the
rest with vectorised numpy, which is what the selector's tens of thousands of candidates need.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np
import pinocchio as pin
import scipy.linalg

from hil.arm.catalog import RobotSpec, get_robot
from hil.arm.geometry import Geometry, pose

_AXES = ("tx", "ty", "tz", "rx", "ry", "rz")

#: Names of the full parameter vector, in order.
PARAMETER_NAMES: tuple[str, ...] = (
    tuple(f"joint{i + 1}.{ax}" for i in range(6) for ax in _AXES)
    + tuple(f"flange.{ax}" for ax in _AXES)
    + ("smr.x", "smr.y", "smr.z")
    + tuple(f"tracker.{ax}" for ax in _AXES)
)
N_PARAMETERS = len(PARAMETER_NAMES)  # 51
JOINT_SLICE = slice(0, 36)
FLANGE_SLICE = slice(36, 42)
SMR_SLICE = slice(42, 45)
TRACKER_SLICE = slice(45, 51)


def _skew(v: np.ndarray) -> np.ndarray:
    """Batched cross-product matrices [v]× of shape (..., 3, 3)."""
    v = np.asarray(v, dtype=float)
    z = np.zeros(v.shape[:-1])
    return np.stack([
        np.stack([z, -v[..., 2], v[..., 1]], -1),
        np.stack([v[..., 2], z, -v[..., 0]], -1),
        np.stack([-v[..., 1], v[..., 0], z], -1),
    ], -2)


def as_configurations(q: np.ndarray | Sequence[Sequence[float]]) -> np.ndarray:
    """(N, 6) float array of joint vectors from one vector or a batch."""
    Q = np.atleast_2d(np.asarray(q, dtype=float))
    if Q.ndim != 2 or Q.shape[1] != 6:
        raise ValueError(f"joint configurations must have 6 values each, got shape {Q.shape}")
    return Q


class Kinematics:
    """A pinocchio model of one `Geometry`, with batched FK and the identification Jacobian.

    Rebuilding is cheap (microseconds), so a new instance is made whenever the geometry changes;
    an instance never changes.
    """

    def __init__(self, geometry: Geometry) -> None:
        self.geometry = geometry.copy()
        spec = get_robot(geometry.robot)
        model = pin.Model()
        model.name = spec.name
        parent = 0
        for i, origin in enumerate(self.geometry.joints):
            parent = model.addJoint(parent, pin.JointModelRZ(), origin, f"joint{i + 1}")
        model.lowerPositionLimit = spec.lower.copy()
        model.upperPositionLimit = spec.upper.copy()
        model.velocityLimit = spec.max_joint_speed.copy()
        model.addFrame(pin.Frame("flange", 6, self.geometry.flange, pin.FrameType.OP_FRAME))
        self._smr_placement = self.geometry.flange * pose(self.geometry.smr)
        model.addFrame(pin.Frame("smr", 6, self._smr_placement, pin.FrameType.OP_FRAME))
        self.model = model
        self.data = model.createData()
        self._tracker_inv = self.geometry.tracker.inverse()

    # --- forward kinematics --------------------------------------------------------------------
    def joint_frames(self, q: np.ndarray) -> np.ndarray:
        """(N, 7, 4, 4): the six joint frames (after their rotation) and the flange, base frame."""
        Q = as_configurations(q)
        out = np.empty((len(Q), 7, 4, 4))
        model, data, flange = self.model, self.data, self.geometry.flange
        for n, qn in enumerate(Q):
            pin.forwardKinematics(model, data, qn)
            for j in range(6):
                out[n, j] = data.oMi[j + 1].homogeneous
            out[n, 6] = (data.oMi[6] * flange).homogeneous
        return out

    def flange_poses(self, q: np.ndarray) -> np.ndarray:
        """(N, 4, 4) flange poses in the robot base frame (the controller's TCP with no offset)."""
        Q = as_configurations(q)
        out = np.empty((len(Q), 4, 4))
        model, data, flange = self.model, self.data, self.geometry.flange
        for n, qn in enumerate(Q):
            pin.forwardKinematics(model, data, qn)
            out[n] = (data.oMi[6] * flange).homogeneous
        return out

    def points(self, q: np.ndarray, frame: str = "tracker", point: str = "smr") -> np.ndarray:
        """(N, 3) positions of the SMR centre (or the flange origin) in the tracker or base frame."""
        if frame not in ("tracker", "base"):
            raise ValueError(f"frame must be 'tracker' or 'base', not {frame!r}")
        if point not in ("smr", "flange"):
            raise ValueError(f"point must be 'smr' or 'flange', not {point!r}")
        F = self.flange_poses(q)
        local = self.geometry.smr if point == "smr" else np.zeros(3)
        p = np.einsum("nij,j->ni", F[:, :3, :3], local) + F[:, :3, 3]
        if frame == "tracker":
            Ti = self._tracker_inv
            p = p @ Ti.rotation.T + Ti.translation
        return p

    # --- identification Jacobian ---------------------------------------------------------------
    def point_and_jacobian(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """SMR positions in the tracker frame (N, 3) and their Jacobian (N, 3, 51).

        Columns follow `PARAMETER_NAMES`; each is the derivative for the multiplicative update
        described in the module docstring, evaluated at zero error.
        """
        Q = as_configurations(q)
        n = len(Q)
        J_joint = np.empty((n, 3, 36))
        R6 = np.empty((n, 3, 3))
        p_base = np.empty((n, 3))
        model, data, placement = self.model, self.data, self._smr_placement
        for k, qk in enumerate(Q):
            pin.forwardKinematics(model, data, qk)
            reg = pin.computeJointKinematicRegressor(model, data, 6, pin.LOCAL_WORLD_ALIGNED, placement)
            J_joint[k] = reg[:3]
            M6 = data.oMi[6]
            R6[k] = M6.rotation
            p_base[k] = M6.act(placement.translation)
        Ti = self._tracker_inv
        Rt = Ti.rotation  # base -> tracker rotation
        p = p_base @ Rt.T + Ti.translation
        J = np.empty((n, 3, N_PARAMETERS))
        J[:, :, JOINT_SLICE] = np.einsum("ij,njk->nik", Rt, J_joint)
        R_bs = np.einsum("ij,njk->nik", Rt, R6 @ self.geometry.flange.rotation)  # flange axes in tracker
        s = self.geometry.smr
        J[:, :, FLANGE_SLICE] = np.concatenate([R_bs, -R_bs @ _skew(s)], axis=2)
        J[:, :, SMR_SLICE] = R_bs
        J[:, :, TRACKER_SLICE] = np.concatenate(
            [np.broadcast_to(-np.eye(3), (n, 3, 3)), _skew(p)], axis=2)
        return p, J

    def jacobian(self, q: np.ndarray, params: np.ndarray | None = None) -> np.ndarray:
        """(N, 3, P) identification Jacobian, restricted to the parameter indices `params`."""
        _, J = self.point_and_jacobian(q)
        return J if params is None else J[:, :, params]


def apply_update(geometry: Geometry, delta: np.ndarray) -> Geometry:
    """The geometry after a full-length (51) parameter step, applied multiplicatively on SE(3)."""
    delta = np.asarray(delta, dtype=float)
    g = geometry.copy()
    g.joints = [M * pin.exp6(delta[6 * i: 6 * i + 6]) for i, M in enumerate(g.joints)]
    g.flange = g.flange * pin.exp6(delta[FLANGE_SLICE])
    g.smr = g.smr + delta[SMR_SLICE]
    g.tracker = g.tracker * pin.exp6(delta[TRACKER_SLICE])
    return g


def deviation_from(reference: Geometry, geometry: Geometry) -> np.ndarray:
    """Full-length (51) parameter vector δ with `geometry` = `reference` updated by δ (log on SE(3))."""
    out = np.zeros(N_PARAMETERS)
    for i in range(6):
        out[6 * i: 6 * i + 6] = pin.log6(reference.joints[i].inverse() * geometry.joints[i]).vector
    out[FLANGE_SLICE] = pin.log6(reference.flange.inverse() * geometry.flange).vector
    out[SMR_SLICE] = geometry.smr - reference.smr
    out[TRACKER_SLICE] = pin.log6(reference.tracker.inverse() * geometry.tracker).vector
    return out


# Which group wins where columns are exactly equivalent: the tracker pose absorbs the base (joint 1
# origin) error, the SMR offset absorbs the flange error (so a calibrated model keeps the nominal
# flange, which the ROS kinematics YAML cannot carry), then joints from base to tip.
_GROUP_ORDER: tuple[slice, ...] = (
    TRACKER_SLICE, SMR_SLICE, *(slice(6 * i, 6 * i + 6) for i in range(6)), FLANGE_SLICE,
)
#: Relative size below which a projected (unit-norm) column counts as dependent.
RANK_TOLERANCE = 1e-7


def generic_geometry(robot: str | RobotSpec) -> Geometry:
    """Nominal geometry at a generic point: SMR off the joint-6 axis, tracker in a general pose.

    At a special point (SMR on the axis) one parameter looks unidentifiable that is identifiable
    in general, so the identifiable set is chosen here and not at the user's guess.
    """
    return Geometry.nominal(robot, smr=(0.031, -0.047, 0.083),
                           tracker=pose((2.1, -1.3, 0.4), (0.05, -0.08, 2.4)))


def generic_configurations(robot: str | RobotSpec, count: int = 60, seed: int = 7) -> np.ndarray:
    """Deterministic random configurations used to find the identifiable set."""
    rng = np.random.default_rng(seed)
    return rng.uniform(-np.pi, np.pi, size=(count, 6))


def select_identifiable(J: np.ndarray, tol: float = RANK_TOLERANCE) -> np.ndarray:
    """Indices of a maximal set of independent columns of the stacked Jacobian `J` (rows × 51).

    Pivoted QR (LAPACK geqp3) on unit-norm columns, group by group in `_GROUP_ORDER`: each group's
    columns are first projected on the complement of the columns already chosen, and pivoted QR then
    keeps those whose residual exceeds `tol`. Within a group the pivoting picks the best-conditioned
    columns; across groups the order settles exact equivalences so the set is stable.
    """
    J = np.asarray(J, dtype=float)
    norms = np.linalg.norm(J, axis=0)
    Js = J / np.where(norms > 0, norms, 1.0)
    basis = np.zeros((J.shape[0], 0))
    chosen: list[int] = []
    for group in _GROUP_ORDER:
        idx = np.arange(N_PARAMETERS)[group]
        cols = Js[:, idx] - basis @ (basis.T @ Js[:, idx])
        cols[:, norms[idx] == 0] = 0.0
        q, r, piv = scipy.linalg.qr(cols, mode="economic", pivoting=True)
        diag = np.abs(np.diag(r))
        k = int(np.sum(diag > tol))
        chosen.extend(int(i) for i in idx[piv[:k]])
        basis = np.hstack([basis, q[:, :k]])
    return np.array(sorted(chosen), dtype=int)


def numerical_rank(J: np.ndarray, tol: float = RANK_TOLERANCE) -> int:
    """Rank of `J` with unit-norm columns, by plain pivoted QR (a cross-check of the selection)."""
    norms = np.linalg.norm(J, axis=0)
    Js = J[:, norms > 0] / norms[norms > 0]
    r = scipy.linalg.qr(Js, mode="r", pivoting=True)[0]
    d = np.abs(np.diag(r))
    return int(np.sum(d > tol * d[0]))


@lru_cache(maxsize=32)
def _identifiable_cached(robot: str) -> tuple[int, ...]:
    kin = Kinematics(generic_geometry(robot))
    J = kin.jacobian(generic_configurations(robot)).reshape(-1, N_PARAMETERS)
    return tuple(select_identifiable(J))


def identifiable_parameters(robot: str | RobotSpec) -> np.ndarray:
    """Indices (into `PARAMETER_NAMES`) of the identifiable parameter set: 27 for a UR arm."""
    name = robot.name if isinstance(robot, RobotSpec) else get_robot(robot).name
    return np.array(_identifiable_cached(name), dtype=int)
