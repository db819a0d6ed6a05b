"""Forward kinematics and the identification Jacobian of the calibration model, from pinocchio.

The calibration parameters are small errors applied *multiplicatively* to the current geometry:

* a 6-D error δ = (v, ω) per joint origin, M_i ← M_i·exp(δ_i)          (6n, ``joint{i}.tx … rz``)
* a 6-D error of the flange frame, M_f ← M_f·exp(δ_f)                   (6, ``flange.*``)
* the SMR centre in the flange frame, s ← s + δ_s                        (3, ``smr.x/y/z``)
* the tracker frame in the base frame, T_bt ← T_bt·exp(δ_t)              (6, ``tracker.*``)

and, when the arm is compliant (docs/design.md, Contracts: non-geometric errors), the joints' compliance:

* c_j (rad/Nm): the link lags its encoder, q_link = q − c ⊙ g(q)                (6, ``compliance.j1 … j6``)

A geometry may also carry angle-dependent joint errors e(q) and lost motion h (`hil.arm.joint_errors`):
`link_angles` applies them after the sag, and `joint_sensitivities` gives the columns through which
any link-angle error reaches the measured point. Their low orders are parameters too, applied
additively (`hil.arm.joint_error_columns`: ``joint{j}.cos{k}``, ``joint{j}.sin{k}``,
``lost_motion.j{j}``, indices 57..98 of `EXTENDED_PARAMETER_NAMES`).

The layout above is a UR's (n = 6 joints: 51 geometric parameters, the constants below); an arm from
a URDF (`hil.arm.chain`, any n, each joint a rotation or translation about its z) has the same groups
with 6n joint columns (`parameter_layout`, `parameter_names`), and geometry only: compliance, joint
errors and thermal growth stay UR-only (refused in one line for another arm).

A measured point is p = T_bt⁻¹ · T_base_flange(q_link) · s (the tracker frame); every forward kinematics
here evaluates at the link angles of the geometry's compliance and payload (`hil.arm.gravity`), so all
that predicts positions (fk, validation, compensation) applies the sag. Only 27 combinations are
identifiable from position measurements (`identifiable_parameters`). The Jacobian of the joint-origin
errors is pinocchio's ``computeJointKinematicRegressor`` (the right-multiplied exp6 convention); the
flange, SMR and tracker columns are the closed-form derivatives of the expression above.

Batches loop over configurations in Python around pinocchio calls (about 2 µs per pose) and do the
rest with vectorised numpy, which is what the selector's tens of thousands of candidates need.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
import pinocchio as pin

from hil.arm import joint_error_columns as jec
from hil.arm.catalog import RobotSpec, get_robot
from hil.arm.chain import PRISMATIC, Chain, Robot, chain_of
from hil.arm.geometry import Geometry, pose
from hil.arm.payload import FLOOR_GRAVITY, Payload
from hil.arm.pivoted_qr import pivoted_qr
from hil.errors import InputError

_AXES = ("tx", "ty", "tz", "rx", "ry", "rz")

#: Names of the full parameter vector, in order.
PARAMETER_NAMES: tuple[str, ...] = (
    tuple(f"joint{i + 1}.{ax}" for i in range(6) for ax in _AXES)
    + tuple(f"flange.{ax}" for ax in _AXES)
    + ("smr.x", "smr.y", "smr.z")
    + tuple(f"tracker.{ax}" for ax in _AXES)
)
N_PARAMETERS = len(PARAMETER_NAMES)  # 51 geometric parameters
JOINT_SLICE = slice(0, 36)
FLANGE_SLICE = slice(36, 42)
SMR_SLICE = slice(42, 45)
TRACKER_SLICE = slice(45, 51)
#: The joints' compliance (rad/Nm), after the geometry: indices 51..56 of the full vector.
COMPLIANCE_NAMES: tuple[str, ...] = tuple(f"compliance.j{i + 1}" for i in range(6))
ALL_PARAMETER_NAMES: tuple[str, ...] = PARAMETER_NAMES + COMPLIANCE_NAMES
N_ALL_PARAMETERS = len(ALL_PARAMETER_NAMES)  # 57
COMPLIANCE_SLICE = slice(51, 57)
#: Then the low-order joint errors and the lost motion (`hil.arm.joint_error_columns`): 57..98.
EXTENDED_PARAMETER_NAMES: tuple[str, ...] = (ALL_PARAMETER_NAMES + jec.JOINT_ERROR_NAMES
                                             + jec.LOST_MOTION_NAMES)
N_EXTENDED_PARAMETERS = len(EXTENDED_PARAMETER_NAMES)  # 99
JOINT_ERROR_SLICE = slice(N_ALL_PARAMETERS, N_EXTENDED_PARAMETERS)


@dataclass(frozen=True)
class ParameterLayout:
    """Where each group of the geometric parameter vector lies for an arm of `dof` joints: 6·dof joint
    columns, then the flange's 6, the SMR's 3 and the tracker's 6 (a UR's is the module constants)."""

    dof: int

    @property
    def size(self) -> int:
        """Length of the geometric parameter vector: 6·dof + 15."""
        return 6 * self.dof + 15

    @property
    def joints(self) -> slice:
        return slice(0, 6 * self.dof)

    @property
    def flange(self) -> slice:
        return slice(6 * self.dof, 6 * self.dof + 6)

    @property
    def smr(self) -> slice:
        return slice(6 * self.dof + 6, 6 * self.dof + 9)

    @property
    def tracker(self) -> slice:
        return slice(6 * self.dof + 9, 6 * self.dof + 15)

    @property
    def names(self) -> tuple[str, ...]:
        """The geometric parameters' names, in order (`PARAMETER_NAMES` for six joints)."""
        return (tuple(f"joint{i + 1}.{ax}" for i in range(self.dof) for ax in _AXES)
                + tuple(f"flange.{ax}" for ax in _AXES) + ("smr.x", "smr.y", "smr.z")
                + tuple(f"tracker.{ax}" for ax in _AXES))

    @property
    def registration(self) -> np.ndarray:
        """Indices of the tracker pose and the SMR offset: what registering a nominal arm fits."""
        return np.r_[np.arange(self.size)[self.tracker], np.arange(self.size)[self.smr]]

    @property
    def group_order(self) -> tuple[slice, ...]:
        """Which group wins where columns are exactly equivalent (`select_identifiable`): tracker, SMR,
        the joints from base to tip, then the flange."""
        return (self.tracker, self.smr, *(slice(6 * i, 6 * i + 6) for i in range(self.dof)), self.flange)


@lru_cache(maxsize=32)
def parameter_layout(dof: int) -> ParameterLayout:
    """The geometric parameter layout of an arm of `dof` joints."""
    return ParameterLayout(int(dof))


def parameter_names(robot: Robot) -> tuple[str, ...]:
    """Names of every parameter an arm's identification can index: a UR's `EXTENDED_PARAMETER_NAMES`
    (geometry, compliance, joint errors), another arm's geometric ones (`ParameterLayout.names`)."""
    chain = chain_of(robot)
    return EXTENDED_PARAMETER_NAMES if chain.is_ur else parameter_layout(chain.dof).names


def refuse_non_ur(robot: Robot, what: str) -> None:
    """InputError (one line) when `what` (compliance, joint errors, thermal growth …) is asked of an arm
    that is not a catalog UR: they rest on the UR's gravity, joint physics and controller models."""
    chain = chain_of(robot)
    if not chain.is_ur:
        raise InputError(f"{what} is modelled for Universal Robots arms only, not for {chain.name} "
                         "(from its URDF): identify its geometry alone")


def _skew(v: np.ndarray) -> np.ndarray:
    """Batched cross-product matrices [v]× of shape (..., 3, 3)."""
    v = np.asarray(v, dtype=float)
    z = np.zeros(v.shape[:-1])
    return np.stack([
        np.stack([z, -v[..., 2], v[..., 1]], -1),
        np.stack([v[..., 2], z, -v[..., 0]], -1),
        np.stack([-v[..., 1], v[..., 0], z], -1),
    ], -2)


def as_configurations(q: np.ndarray | Sequence[Sequence[float]], dof: int = 6) -> np.ndarray:
    """(N, dof) float array of joint vectors from one vector or a batch."""
    Q = np.atleast_2d(np.asarray(q, dtype=float))
    if Q.ndim != 2 or Q.shape[1] != dof:
        raise ValueError(f"joint configurations must have {dof} values each, got shape {Q.shape}")
    return Q


class Kinematics:
    """A pinocchio model of one `Geometry`, with batched FK and the identification Jacobian.

    Building one costs about twice the forward kinematics of 16 configurations on it (a few hundred
    microseconds on a loaded machine), so a new instance is made whenever the geometry changes; an
    instance never changes. Code that evaluates one geometry many times over takes it from
    `hil.arm.kinematics_cache` instead.
    """

    def __init__(self, geometry: Geometry) -> None:
        self.geometry = geometry.copy()
        chain = self.chain = geometry.arm
        n = self.dof = chain.dof
        self.layout = parameter_layout(n)
        model = pin.Model()
        model.name = chain.name
        parent = 0
        for i, (kind, origin) in enumerate(zip(chain.kinds, self.geometry.joints, strict=True)):
            joint = pin.JointModelPZ() if kind == PRISMATIC else pin.JointModelRZ()
            parent = model.addJoint(parent, joint, origin, f"joint{i + 1}")
        model.lowerPositionLimit = chain.lower.copy()
        model.upperPositionLimit = chain.upper.copy()
        model.velocityLimit = chain.velocity.copy()
        model.addFrame(pin.Frame("flange", n, self.geometry.flange, pin.FrameType.OP_FRAME))
        self._smr_placement = self.geometry.flange * pose(self.geometry.smr)
        model.addFrame(pin.Frame("smr", n, self._smr_placement, pin.FrameType.OP_FRAME))
        self.model = model
        self.data = model.createData()
        self._tracker_inv = self.geometry.tracker.inverse()
        self._gravity: Any = None

    # --- compliance ----------------------------------------------------------------------------
    @property
    def gravity(self) -> Any:
        """The arm's `hil.arm.gravity.GravityModel` with its payload (built on first use)."""
        if self._gravity is None:
            from hil.arm.gravity import GravityModel

            self._gravity = GravityModel(self.geometry)
        return self._gravity

    def link_angles(self, q: np.ndarray, directions: np.ndarray | None = None) -> np.ndarray:
        """(N, 6) link angles at encoder readings `q`: q − c ⊙ τ(q) + e(q) − h ⊙ d (docs/design.md,
        Contracts: non-geometric errors), each term where the geometry has it.

        `directions` (6 or (N, 6), each −1, 0 or +1) is the sign of each joint's last motion before the
        reading, which lost motion needs; None: no lost motion is applied (a model told nothing about
        the approach predicts the middle of the lost-motion band).
        """
        return self._link_angles(as_configurations(q, self.dof), directions)

    def _link_angles(self, Q: np.ndarray, directions: np.ndarray | None,
                     torques: np.ndarray | None = None) -> np.ndarray:
        g = self.geometry
        if g.encoder_exact:
            return Q
        out = Q.copy()
        if g.compliant:
            out -= g.compliance * (self.gravity.torques(Q) if torques is None else torques)
        if g.has_joint_errors:
            out += g.joint_errors.offsets(Q)
        if g.has_lost_motion and directions is not None:
            out -= g.lost_motion * np.broadcast_to(np.asarray(directions, dtype=float), Q.shape)
        return out

    # --- forward kinematics --------------------------------------------------------------------
    def joint_frames(self, q: np.ndarray, directions: np.ndarray | None = None) -> np.ndarray:
        """(N, n + 1, 4, 4): the n joint frames (after their motion) and the flange, base frame."""
        Q = self.link_angles(q, directions)
        dof = self.dof
        out = np.empty((len(Q), dof + 1, 4, 4))
        model, data, flange = self.model, self.data, self.geometry.flange
        for n, qn in enumerate(Q):
            pin.forwardKinematics(model, data, qn)
            for j in range(dof):
                out[n, j] = data.oMi[j + 1].homogeneous
            out[n, dof] = (data.oMi[dof] * flange).homogeneous
        return out

    def flange_poses(self, q: np.ndarray, directions: np.ndarray | None = None) -> np.ndarray:
        """(N, 4, 4) flange poses in the robot base frame (the controller's TCP with no offset);
        `directions` as in `link_angles`."""
        Q = self.link_angles(q, directions)
        out = np.empty((len(Q), 4, 4))
        model, data, flange, last = self.model, self.data, self.geometry.flange, self.dof
        for n, qn in enumerate(Q):
            pin.forwardKinematics(model, data, qn)
            out[n] = (data.oMi[last] * flange).homogeneous
        return out

    def points(self, q: np.ndarray, frame: str = "tracker", point: str = "smr",
               directions: np.ndarray | None = None) -> np.ndarray:
        """(N, 3) positions of the SMR centre (or the flange origin) in the tracker or base frame;
        `directions` as in `link_angles`."""
        if frame not in ("tracker", "base"):
            raise ValueError(f"frame must be 'tracker' or 'base', not {frame!r}")
        if point not in ("smr", "flange"):
            raise ValueError(f"point must be 'smr' or 'flange', not {point!r}")
        F = self.flange_poses(q, directions)
        local = self.geometry.smr if point == "smr" else np.zeros(3)
        p = np.einsum("nij,j->ni", F[:, :3, :3], local) + F[:, :3, 3]
        if frame == "tracker":
            Ti = self._tracker_inv
            p = p @ Ti.rotation.T + Ti.translation
        return p

    # --- identification Jacobian ---------------------------------------------------------------
    def point_and_jacobian(self, q: np.ndarray, compliance: bool = False,
                           directions: np.ndarray | None = None,
                           joint_errors: bool = False,
                           torques: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """SMR positions in the tracker frame (N, 3) and their Jacobian (N, 3, 51), or (N, 3, 57)
        with the compliance columns when `compliance` is set, or (N, 3, 99) with the joint-error and
        lost-motion columns too when `joint_errors` is set (the compliance ones then zero unless
        `compliance`).

        Columns follow `EXTENDED_PARAMETER_NAMES`; each is the derivative for the multiplicative update
        described in the module docstring, evaluated at zero error. The compliance column of joint j
        is ∂p/∂q_j at the link angles times −g_j(q): the sag a unit of compliance adds (the change of
        g with the small geometric errors is second order and left out). The joint-error columns are
        ∂p/∂q_j times cos(k·q_j), sin(k·q_j) at the encoder angle, the lost-motion ones times −d_j
        (`directions`; zero without them).

        `torques` ((N, 6) Nm) replaces the gravity torque g(q) in the deflection and in the compliance
        columns: a moving arm's deflects under τ(q, q̇, q̈) (`hil.arm.dynamics`, used by the sweep fit).
        """
        Q = as_configurations(q, self.dof)
        n, dof, lay = len(Q), self.dof, self.layout
        if compliance:
            refuse_non_ur(self.chain, "joint compliance")
        if joint_errors:
            refuse_non_ur(self.chain, "angle-dependent joint errors and lost motion")
        if torques is not None:
            torques = np.asarray(torques, dtype=float)
            if torques.shape != Q.shape:
                raise ValueError(f"torques must have the shape of q {Q.shape}, got {torques.shape}")
        elif compliance or self.geometry.compliant:
            torques = self.gravity.torques(Q)
        Q_link = self._link_angles(Q, directions, torques)
        J_joint = np.empty((n, 3, 6 * dof))
        R6 = np.empty((n, 3, 3))
        p_base = np.empty((n, 3))
        axes = np.empty((n, dof, 3))
        origins = np.empty((n, dof, 3))
        sensitivities = compliance or joint_errors
        model, data, placement = self.model, self.data, self._smr_placement
        for k, qk in enumerate(Q_link):
            pin.forwardKinematics(model, data, qk)
            reg = pin.computeJointKinematicRegressor(model, data, dof, pin.LOCAL_WORLD_ALIGNED, placement)
            J_joint[k] = reg[:3]
            M6 = data.oMi[dof]
            R6[k] = M6.rotation
            p_base[k] = M6.act(placement.translation)
            if sensitivities:
                for j in range(dof):
                    axes[k, j] = data.oMi[j + 1].rotation[:, 2]
                    origins[k, j] = data.oMi[j + 1].translation
        Ti = self._tracker_inv
        Rt = Ti.rotation  # base -> tracker rotation
        p = p_base @ Rt.T + Ti.translation
        width = N_EXTENDED_PARAMETERS if joint_errors else N_ALL_PARAMETERS if compliance else lay.size
        J = np.zeros((n, 3, width)) if joint_errors and not compliance else np.empty((n, 3, width))
        J[:, :, lay.joints] = np.einsum("ij,njk->nik", Rt, J_joint)
        R_bs = np.einsum("ij,njk->nik", Rt, R6 @ self.geometry.flange.rotation)  # flange axes in tracker
        s = self.geometry.smr
        J[:, :, lay.flange] = np.concatenate([R_bs, -R_bs @ _skew(s)], axis=2)
        J[:, :, lay.smr] = R_bs
        J[:, :, lay.tracker] = np.concatenate(
            [np.broadcast_to(-np.eye(3), (n, 3, 3)), _skew(p)], axis=2)
        if sensitivities:
            dp_dq = np.cross(axes, p_base[:, None, :] - origins)  # (n, 6, 3) base frame
            dp_dq = np.einsum("ij,nkj->nik", Rt, dp_dq)  # (n, 3, 6) tracker frame
            if compliance:
                J[:, :, COMPLIANCE_SLICE] = dp_dq * -torques[:, None, :]
            if joint_errors:
                J[:, :, JOINT_ERROR_SLICE] = jec.columns(dp_dq, Q, directions)
        return p, J

    def joint_sensitivities(self, q: np.ndarray, directions: np.ndarray | None = None) -> np.ndarray:
        """(N, 3, 6) ∂p/∂q_link: how the SMR (tracker frame) moves per radian of each link angle.

        Every link-angle error enters the point through this: the compliance, joint-error and
        lost-motion columns of an identification are these columns times ∂q_link/∂(their parameter).
        """
        Q_link = self.link_angles(q, directions)
        n, dof = len(Q_link), self.dof
        axes = np.empty((n, dof, 3))
        origins = np.empty((n, dof, 3))
        p_base = np.empty((n, 3))
        model, data, placement = self.model, self.data, self._smr_placement
        for k, qk in enumerate(Q_link):
            pin.forwardKinematics(model, data, qk)
            for j in range(dof):
                axes[k, j] = data.oMi[j + 1].rotation[:, 2]
                origins[k, j] = data.oMi[j + 1].translation
            p_base[k] = data.oMi[dof].act(placement.translation)
        # a revolute joint moves the point by axis × lever, a prismatic one along its axis
        prismatic = np.array([k == PRISMATIC for k in self.chain.kinds])
        dp_dq = np.where(prismatic[None, :, None], axes,
                         np.cross(axes, p_base[:, None, :] - origins))  # (n, dof, 3) base frame
        return np.einsum("ij,nkj->nik", self._tracker_inv.rotation, dp_dq)

    def jacobian(self, q: np.ndarray, params: np.ndarray | None = None,
                 directions: np.ndarray | None = None) -> np.ndarray:
        """(N, 3, P) identification Jacobian, restricted to the parameter indices `params` (indices
        51..56 are compliance columns, 57.. joint-error and lost-motion ones, computed only then;
        `directions` as in `point_and_jacobian`)."""
        idx = None if params is None else np.asarray(params)
        geo = self.layout.size
        compliance = idx is not None and bool(np.any((idx >= geo) & (idx < geo + 6)))
        joint_errors = idx is not None and bool(np.any(idx >= N_ALL_PARAMETERS))
        _, J = self.point_and_jacobian(q, compliance, directions, joint_errors)
        return J if idx is None else J[:, :, idx]


def apply_update(geometry: Geometry, delta: np.ndarray) -> Geometry:
    """The geometry after a full-length parameter step (51, 57 with compliance, or 99 with the joint
    errors and lost motion), applied multiplicatively on SE(3) (the rest additively)."""
    delta = np.asarray(delta, dtype=float)
    g = geometry.copy()
    lay = parameter_layout(len(g.joints))
    g.joints = [M * pin.exp6(delta[6 * i: 6 * i + 6]) for i, M in enumerate(g.joints)]
    g.flange = g.flange * pin.exp6(delta[lay.flange])
    g.smr = g.smr + delta[lay.smr]
    if g.reflectors is not None:  # the first reflector is the SMR
        g.reflectors[0] = g.smr
    g.tracker = g.tracker * pin.exp6(delta[lay.tracker])
    if g.chain is not None:  # an arm from its URDF: the geometry is all its parameters
        return g
    if delta.size > lay.size and np.any(delta[COMPLIANCE_SLICE] != 0.0):
        base = np.zeros(6) if g.compliance is None else g.compliance
        g.compliance = base + delta[COMPLIANCE_SLICE]
    if delta.size > N_ALL_PARAMETERS:
        g.joint_errors, g.lost_motion = jec.apply_terms(g.joint_errors, g.lost_motion,
                                                        delta[JOINT_ERROR_SLICE])
    return g


def deviation_from(reference: Geometry, geometry: Geometry, compliance: bool = False,
                   joint_errors: bool = False) -> np.ndarray:
    """Full-length parameter vector δ with `geometry` = `reference` updated by δ (log on SE(3)): 51
    long, 57 with the compliance difference, 99 with the joint errors' and lost motion's too (a
    missing block counts as zero)."""
    lay = parameter_layout(len(geometry.joints))
    if len(reference.joints) != lay.dof:
        raise ValueError(f"a deviation needs arms of one joint count, got {len(reference.joints)} and "
                         f"{lay.dof}")
    width = N_EXTENDED_PARAMETERS if joint_errors else N_ALL_PARAMETERS if compliance else lay.size
    out = np.zeros(width)
    for i in range(lay.dof):
        out[6 * i: 6 * i + 6] = pin.log6(reference.joints[i].inverse() * geometry.joints[i]).vector
    out[lay.flange] = pin.log6(reference.flange.inverse() * geometry.flange).vector
    out[lay.smr] = geometry.smr - reference.smr
    out[lay.tracker] = pin.log6(reference.tracker.inverse() * geometry.tracker).vector
    if compliance:
        out[COMPLIANCE_SLICE] = ((np.zeros(6) if geometry.compliance is None else geometry.compliance)
                                 - (np.zeros(6) if reference.compliance is None else reference.compliance))
    if joint_errors:
        out[JOINT_ERROR_SLICE] = (jec.term_values(geometry.joint_errors, geometry.lost_motion)
                                  - jec.term_values(reference.joint_errors, reference.lost_motion))
    return out


# Which group wins where columns are exactly equivalent: the tracker pose absorbs the base (joint 1
# origin) error, the SMR offset absorbs the flange error (so a calibrated model keeps the nominal
# flange, which the ROS kinematics YAML cannot carry), then joints from base to tip.
_GROUP_ORDER: tuple[slice, ...] = (
    TRACKER_SLICE, SMR_SLICE, *(slice(6 * i, 6 * i + 6) for i in range(6)), FLANGE_SLICE,
)
#: Relative size below which a projected (unit-norm) column counts as dependent.
RANK_TOLERANCE = 1e-7
#: A joint's compliance is identified only when a typical cobot compliance (`hil.arm.physical`) moves
#: the SMR by more than this (RMS over generic poses, m): a quarter of a tracker's 20 µm per-axis noise.
#: Below it the column is numerically independent but carries no information (joint 1 of a floor arm
#: holds no gravity torque at all; joint 6 only what an off-axis payload gives it).
MIN_COMPLIANCE_EFFECT = 1e-6


def generic_geometry(robot: Robot) -> Geometry:
    """Nominal geometry at a generic point: SMR off the joint-6 axis, tracker in a general pose.

    At a special point (SMR on the axis) one parameter looks unidentifiable that is identifiable
    in general, so the identifiable set is chosen here and not at the user's guess.
    """
    return Geometry.nominal(robot, smr=(0.031, -0.047, 0.083),
                           tracker=pose((2.1, -1.3, 0.4), (0.05, -0.08, 2.4)))


def generic_configurations(robot: Robot, count: int = 60, seed: int = 7) -> np.ndarray:
    """Deterministic random configurations used to find the identifiable set: a UR's uniform in ±π
    (every joint of a UR turns that far), another arm's uniform within its limits
    (`Chain.sampling_range`), with at least 2·(6n + 15)/3 configurations so the stacked Jacobian has
    twice the rows it needs."""
    rng = np.random.default_rng(seed)
    chain = chain_of(robot)
    if chain.is_ur:
        return rng.uniform(-np.pi, np.pi, size=(count, 6))
    lo, hi = chain.sampling_range()
    count = max(count, -(-2 * parameter_layout(chain.dof).size // 3))
    return rng.uniform(lo, hi, size=(count, chain.dof))


def select_identifiable(J: np.ndarray, tol: float = RANK_TOLERANCE,
                        groups: Sequence[slice] | None = None) -> np.ndarray:
    """Indices of a maximal set of independent columns of the stacked Jacobian `J` (rows × 51, or
    × 57 with the compliance columns, or × 99 with the joint errors' and lost motion's, which come
    last in that order: geometry wins where they are equivalent, then compliance).

    Pivoted QR (`hil.arm.pivoted_qr`: the columns LAPACK's geqp3 picks) on unit-norm columns, group by
    group in `_GROUP_ORDER`: each group's columns are first projected on the complement of the columns
    already chosen, and pivoted QR then keeps those whose residual exceeds `tol`. Within a group the
    pivoting picks the best-conditioned columns; across groups the order settles exact equivalences so
    the set is stable. `groups` replaces that order for other column layouts (a 6-D fit's,
    `hil.arm.tool_frame`; an arm from a URDF's, `ParameterLayout.group_order`).
    """
    J = np.asarray(J, dtype=float)
    norms = np.linalg.norm(J, axis=0)
    Js = J / np.where(norms > 0, norms, 1.0)
    basis = np.zeros((J.shape[0], 0))
    chosen: list[int] = []
    if groups is None:
        groups = _GROUP_ORDER + ((COMPLIANCE_SLICE,) if J.shape[1] > N_PARAMETERS else ())
        if J.shape[1] > N_ALL_PARAMETERS:  # joint errors last, harmonic by harmonic, then lost motion
            groups += tuple(slice(g[0], g[-1] + 1) for g in jec.term_groups().values())
    for group in groups:
        idx = np.arange(J.shape[1])[group]
        cols = Js[:, idx] - basis @ (basis.T @ Js[:, idx])
        cols[:, norms[idx] == 0] = 0.0
        q, diag, piv = pivoted_qr(cols)
        k = int(np.sum(diag > tol))
        chosen.extend(int(i) for i in idx[piv[:k]])
        basis = np.hstack([basis, q[:, :k]])
    return np.array(sorted(chosen), dtype=int)


def numerical_rank(J: np.ndarray, tol: float = RANK_TOLERANCE) -> int:
    """Rank of `J` with unit-norm columns, by plain pivoted QR (a cross-check of the selection)."""
    norms = np.linalg.norm(J, axis=0)
    Js = J[:, norms > 0] / norms[norms > 0]
    d = pivoted_qr(Js)[1]
    return int(np.sum(d > tol * d[0]))


@lru_cache(maxsize=32)
def _identifiable_cached(robot: str) -> tuple[int, ...]:
    kin = Kinematics(generic_geometry(robot))
    J = kin.jacobian(generic_configurations(robot)).reshape(-1, N_PARAMETERS)
    return tuple(select_identifiable(J))


@lru_cache(maxsize=16)
def _identifiable_chain_cached(chain: Chain) -> tuple[int, ...]:
    kin = Kinematics(generic_geometry(chain))
    J = kin.jacobian(generic_configurations(chain))
    groups = parameter_layout(chain.dof).group_order
    return tuple(select_identifiable(J.reshape(-1, J.shape[2]), groups=groups))


def identifiable_parameters(robot: Robot) -> np.ndarray:
    """Indices (into `PARAMETER_NAMES`, or `parameter_names` of another arm) of the identifiable
    parameter set: 27 for a UR arm; for an arm from a URDF whatever the same pivoted QR at the generic
    point finds for its chain."""
    if isinstance(robot, Chain) and not robot.is_ur:
        return np.array(_identifiable_chain_cached(robot), dtype=int)
    name = robot.name if isinstance(robot, RobotSpec | Chain) else get_robot(robot).name
    return np.array(_identifiable_cached(name), dtype=int)


@lru_cache(maxsize=64)
def _identifiable_compliance_cached(robot: str, payload: Payload | None,
                                    gravity: tuple[float, float, float]) -> tuple[int, ...]:
    from hil.arm.physical import typical_compliance

    g = generic_geometry(robot)
    g.payload, g.gravity = payload, np.asarray(gravity, float)
    Q = generic_configurations(robot)
    J = Kinematics(g).jacobian(Q, np.arange(N_ALL_PARAMETERS))
    effect = np.sqrt(np.mean(np.sum(J[:, :, COMPLIANCE_SLICE] ** 2, axis=1), axis=0))
    effect *= typical_compliance(robot)
    J[:, :, COMPLIANCE_SLICE][:, :, effect < MIN_COMPLIANCE_EFFECT] = 0.0
    return tuple(select_identifiable(J.reshape(-1, N_ALL_PARAMETERS)))


def identifiable_with_compliance(robot: str | RobotSpec, payload: Payload | None = None,
                                 gravity: np.ndarray | None = None) -> np.ndarray:
    """Indices (into `ALL_PARAMETER_NAMES`) of the geometry's identifiable set plus the joints whose
    compliance the arm's gravity torques make identifiable, for this payload and mounting.

    Found numerically like the geometry's (at the generic point, generic poses), after dropping the
    joints whose sag stays below `MIN_COMPLIANCE_EFFECT`: on a floor arm joint 1 holds no torque and
    joint 6 only what an off-axis payload gives it.
    """
    name = robot.name if isinstance(robot, RobotSpec) else get_robot(robot).name
    g = FLOOR_GRAVITY if gravity is None else np.asarray(gravity, float)
    return np.array(_identifiable_compliance_cached(name, payload, tuple(float(v) for v in g)), dtype=int)


@lru_cache(maxsize=64)
def _identifiable_joint_errors_cached(robot: str, compliance: bool, payload: Payload | None,
                                      gravity: tuple[float, float, float]) -> tuple[int, ...]:
    g = generic_geometry(robot)
    g.payload, g.gravity = payload, np.asarray(gravity, float)
    base = (identifiable_with_compliance(robot, payload, g.gravity) if compliance
            else identifiable_parameters(robot))
    Q = generic_configurations(robot)
    # each joint approached from either side at random: where the data do, lost motion is no constant
    directions = np.random.default_rng(13).choice([-1.0, 1.0], size=Q.shape)
    J = Kinematics(g).jacobian(Q, np.arange(N_EXTENDED_PARAMETERS), directions)
    keep = np.zeros(N_EXTENDED_PARAMETERS, dtype=bool)
    keep[base] = True
    keep[JOINT_ERROR_SLICE] = True
    J[:, :, ~keep] = 0.0  # the geometry's and compliance's set as chosen, nothing else of theirs
    chosen = select_identifiable(J.reshape(-1, N_EXTENDED_PARAMETERS))
    return tuple(int(i) for i in chosen if i >= N_ALL_PARAMETERS)


def identifiable_joint_errors(robot: str | RobotSpec, compliance: bool = False,
                              payload: Payload | None = None,
                              gravity: np.ndarray | None = None) -> np.ndarray:
    """Indices (into `EXTENDED_PARAMETER_NAMES`, 57..98) of the joint-error and lost-motion terms
    independent of the geometry's identifiable set (and of the identifiable compliances when
    `compliance`), found numerically at the generic point as `select_identifiable` finds the
    geometry's, with each joint approached from either side at random.

    What this finds for every UR in the catalog (e-series and CB3, with and without compliance): all
    orders 1–3 of every joint and the lost motion of every joint are independent of the geometry. No
    harmonic is *exactly* a geometric error — a joint's constant offset is (the order 0, never a
    candidate), and a placement error before or after the joint's rotation moves the point by a
    constant or by a once-per-turn rotation of a fixed vector, while a·cos(q) of the angle rotates by
    cos q·Rz(q), which holds a twice-per-turn part. But the overlap is large for order 1: after
    projecting out the 27 geometric columns a unit order-1 column keeps only 0.63–0.76 of its norm on
    joints 3, 5 and 6 (0.72–0.93 on joints 1, 2 and 4), orders 2 and 3 keep 0.85–0.96 (every UR:
    `bench/joint_errors.py`), so order 1 costs the most poses to resolve. Lost motion is independent
    only when the directions vary: approached from one side it is a constant, the joint's offset —
    which is why `hil.calibration.joint_error_selection` offers it only for joints whose directions in
    the data take both signs.
    """
    name = robot.name if isinstance(robot, RobotSpec) else get_robot(robot).name
    g = FLOOR_GRAVITY if gravity is None else np.asarray(gravity, float)
    return np.array(_identifiable_joint_errors_cached(name, compliance, payload if compliance else None,
                                                      tuple(float(v) for v in g)), dtype=int)
