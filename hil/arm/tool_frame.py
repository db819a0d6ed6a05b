"""The measured tool — a frame (a camera, a 6-DoF probe) and several reflectors on the flange — and the
Jacobian of what an instrument measures of it, for a 6-D and a several-reflector fit.

A tracker measuring one SMR sees a point; a camera on a chessboard, or a tracker's 6-DoF probe, sees a
frame, and a tool with several reflectors several points. With T_bt the instrument frame in the base
frame, T_bf(q) the flange, R_tool the measured frame's orientation in the flange frame and s_k the
reflectors' centres in the flange frame (s_1 = the SMR offset, the measured frame's origin):

    p_k = T_bt⁻¹ · T_bf(q) · s_k                 (instrument frame, each reflector k = 1..R)
    R   = R_btᵀ · R_bf(q) · R_tool               (measured frame -> instrument frame)

and the orientation residual is the small rotation vector log(R_measured · R_modelᵀ), in the instrument
frame: a step δ of the parameters turns the model by J_o·δ, so the residual falls by J_o·δ, as a
position residual falls by J_p·δ.

**Parameters.** A fit's local layout: the 51 geometric parameters of `hil.arm.kinematics` (applied as
there), then ``tool.rx, tool.ry, tool.rz`` (R_tool ← R_tool·exp(ω)), then ``reflector<k>.x/y/z`` for
k = 2..R (s_k ← s_k + δ). Their names in a model file (`POSE_PARAMETER_NAMES`) follow
`EXTENDED_PARAMETER_NAMES`, so compliance and joint-error indices keep their meaning.

**What is identifiable** (`identifiable_tool_parameters`): the same pivoted QR as for positions, with the
groups ordered tracker, SMR, tool rotation, reflectors, joints, flange, so the tool absorbs the flange's
error (one rigid transform after joint 6 is all the data see). With orientations the tool rotation is
identified beside the position fit's 27 (30 for a UR: FIGAROH reports 30 for its 6-D UR10 fit, the
shared camera file's source); each further reflector adds its 3 offsets.

**Any serial arm** (a chain read from its URDF): the local layout is its geometric layout
(`parameter_layout(dof)`: 6·N joint columns, flange, SMR, tracker) followed by the tool's columns, and
the regressor is taken at its last joint; a UR's is the module constants (N = 6). Names follow
`pose_parameter_names`.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import pinocchio as pin

from hil.arm.chain import Robot, chain_of
from hil.arm.geometry import Geometry
from hil.arm.kinematics import (
    EXTENDED_PARAMETER_NAMES,
    N_PARAMETERS,
    Kinematics,
    _skew,
    apply_update,
    deviation_from,
    generic_configurations,
    generic_geometry,
    parameter_layout,
    parameter_names,
    select_identifiable,
)

#: Most reflectors one tool may carry. No file hil has met carries more than a few (FIGAROH's marker
#: files number them x1..); sixteen bounds the model file's names, not a physical limit.
MAX_REFLECTORS = 16
TOOL_ROTATION_NAMES: tuple[str, ...] = ("tool.rx", "tool.ry", "tool.rz")
REFLECTOR_NAMES: tuple[str, ...] = tuple(f"reflector{k}.{a}" for k in range(2, MAX_REFLECTORS + 1)
                                         for a in "xyz")
#: Every parameter name a model may carry: the position fit's, then the tool's.
POSE_PARAMETER_NAMES: tuple[str, ...] = EXTENDED_PARAMETER_NAMES + TOOL_ROTATION_NAMES + REFLECTOR_NAMES
#: Where the tool's parameters start among `POSE_PARAMETER_NAMES`.
FIRST_TOOL_PARAMETER = len(EXTENDED_PARAMETER_NAMES)
#: The local layout's tool rotation columns.
TOOL_SLICE = slice(N_PARAMETERS, N_PARAMETERS + 3)


def width(reflectors: int, dof: int = 6) -> int:
    """Columns of the local layout for a tool with `reflectors` reflectors on an arm of `dof` joints."""
    return parameter_layout(dof).size + 3 + 3 * (reflectors - 1)


def tool_slice(dof: int = 6) -> slice:
    """Local columns of the tool rotation on an arm of `dof` joints (`TOOL_SLICE` for six)."""
    size = parameter_layout(dof).size
    return slice(size, size + 3)


def reflector_slice(k: int, dof: int = 6) -> slice:
    """Local columns of reflector k (0-based, k ≥ 1; reflector 0 is the SMR's) on an arm of `dof`
    joints."""
    start = parameter_layout(dof).size + 3 + 3 * (k - 1)
    return slice(start, start + 3)


def pose_parameter_names(robot: Robot) -> tuple[str, ...]:
    """Every parameter name a model of `robot` may carry: its position fit's (`parameter_names`: a UR's
    include compliance and joint errors), then the tool's (`POSE_PARAMETER_NAMES` for a UR)."""
    return parameter_names(robot) + TOOL_ROTATION_NAMES + REFLECTOR_NAMES


def to_names(local: np.ndarray, robot: Robot = "ur5e") -> np.ndarray:
    """Indices into `pose_parameter_names(robot)` of local columns `local` (a UR by default: into
    `POSE_PARAMETER_NAMES`)."""
    idx = np.asarray(local, dtype=int)
    size = parameter_layout(chain_of(robot).dof).size
    return np.where(idx < size, idx, idx - size + len(parameter_names(robot)))


def tool_rotation(geometry: Geometry) -> np.ndarray:
    """The measured frame's orientation in the flange frame (the identity when none was identified)."""
    return np.eye(3) if geometry.tool_rotation is None else geometry.tool_rotation


def reflector_offsets(geometry: Geometry) -> np.ndarray:
    """(R, 3) every reflector's centre in the flange frame (the SMR alone when there is one)."""
    return geometry.smr[None, :].copy() if geometry.reflectors is None else geometry.reflectors.copy()


def with_tool(geometry: Geometry, reflectors: int, orientation: bool) -> Geometry:
    """`geometry` carrying a tool of `reflectors` reflectors (new ones at the SMR) and, with
    `orientation`, a tool rotation (the identity when it had none)."""
    g = geometry.copy()
    if orientation and g.tool_rotation is None:
        g.tool_rotation = np.eye(3)
    if reflectors > 1:
        old = reflector_offsets(g)
        rows = np.vstack([old, np.repeat(g.smr[None, :], max(0, reflectors - len(old)), axis=0)])
        g.reflectors = rows[:reflectors]
        g.reflectors[0] = g.smr
    return g


def predict(geometry: Geometry, q: np.ndarray, frame: str = "tracker") -> tuple[np.ndarray, np.ndarray]:
    """(m, R, 3) reflector positions and (m, 3, 3) measured-frame orientations, in the instrument
    (``"tracker"``) or the robot base (``"base"``) frame; the arm as `Kinematics` moves it (its
    compliance and joint errors included)."""
    if frame not in ("tracker", "base"):
        raise ValueError(f"frame must be 'tracker' or 'base', not {frame!r}")
    F = Kinematics(geometry).flange_poses(q)
    Ti = geometry.tracker.inverse() if frame == "tracker" else pin.SE3.Identity()
    s = reflector_offsets(geometry)
    base = np.einsum("nij,kj->nki", F[:, :3, :3], s) + F[:, None, :3, 3]
    p = base @ Ti.rotation.T + Ti.translation
    R = np.einsum("ij,njk,kl->nil", Ti.rotation, F[:, :3, :3], tool_rotation(geometry))
    return p, R


def rotation_residuals(measured: np.ndarray, model: np.ndarray) -> np.ndarray:
    """(m, 3) log(R_measured · R_modelᵀ): the small rotation (instrument frame) from model to measured."""
    return np.array([pin.log3(a @ b.T) for a, b in zip(measured, model, strict=True)]).reshape(-1, 3)


def frame_and_jacobian(geometry: Geometry, q: np.ndarray,
                       orientation: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Model positions (m, R, 3), orientations (m, 3, 3) and the Jacobian (m, 3R [+ 3], local width).

    Rows per pose: each reflector's x, y, z, then (with `orientation`) the measured frame's small
    rotation. Columns: the local layout (module docstring), each the derivative for its multiplicative
    update at zero error. The joint columns are pinocchio's ``computeJointKinematicRegressor`` at each
    reflector (its angular rows are the frame's); the others are closed forms.
    """
    kin = Kinematics(geometry)
    dof = kin.dof
    lay = parameter_layout(dof)
    if not geometry.encoder_exact:
        raise ValueError("the tool-frame Jacobian models the geometry only (no compliance or joint errors)")
    Q = np.atleast_2d(np.asarray(q, dtype=float))
    m = len(Q)
    s = reflector_offsets(geometry)
    R_count = len(s)
    placements = [geometry.flange * pin.SE3(np.eye(3), sk) for sk in s]
    reg_lin = np.empty((m, R_count, 3, 6 * dof))
    reg_ang = np.empty((m, 3, 6 * dof))
    R_last = np.empty((m, 3, 3))
    model, data = kin.model, kin.data
    for n, qn in enumerate(Q):
        pin.forwardKinematics(model, data, qn)
        for k, placement in enumerate(placements):
            reg = pin.computeJointKinematicRegressor(model, data, dof, pin.LOCAL_WORLD_ALIGNED, placement)
            reg_lin[n, k] = reg[:3]
            if k == 0:
                reg_ang[n] = reg[3:]
        R_last[n] = data.oMi[dof].rotation
    p, R = predict(geometry, Q)
    Rt = geometry.tracker.inverse().rotation  # base -> instrument
    R_bs = np.einsum("ij,njk->nik", Rt, R_last @ geometry.flange.rotation)  # flange axes, instrument frame
    rows = 3 * R_count + (3 if orientation else 0)
    J = np.zeros((m, rows, width(R_count, dof)))
    for k in range(R_count):
        r = slice(3 * k, 3 * k + 3)
        J[:, r, lay.joints] = np.einsum("ij,njk->nik", Rt, reg_lin[:, k])
        J[:, r, lay.flange] = np.concatenate([R_bs, -R_bs @ _skew(s[k])], axis=2)
        J[:, r, lay.smr if k == 0 else reflector_slice(k, dof)] = R_bs
        J[:, r, lay.tracker] = np.concatenate([np.broadcast_to(-np.eye(3), (m, 3, 3)), _skew(p[:, k])],
                                              axis=2)
    if orientation:
        o = slice(3 * R_count, rows)
        J[:, o, lay.joints] = np.einsum("ij,njk->nik", Rt, reg_ang)
        J[:, o, lay.flange.start + 3: lay.flange.stop] = R_bs
        J[:, o, lay.tracker.start + 3: lay.tracker.stop] = -np.eye(3)
        J[:, o, tool_slice(dof)] = R_bs @ tool_rotation(geometry)
    return p, R, J


def apply_tool_update(geometry: Geometry, delta: np.ndarray) -> Geometry:
    """The geometry after a local-layout step: the geometric parameters (51 on a UR) as `apply_update`,
    the tool rotation multiplicatively, the further reflectors additively."""
    delta = np.asarray(delta, dtype=float)
    dof = len(geometry.joints)
    g = apply_update(geometry, delta[:parameter_layout(dof).size])
    if g.tool_rotation is not None:
        g.tool_rotation = g.tool_rotation @ pin.exp3(delta[tool_slice(dof)])
    if g.reflectors is not None:
        for k in range(1, len(g.reflectors)):
            g.reflectors[k] = g.reflectors[k] + delta[reflector_slice(k, dof)]
        g.reflectors[0] = g.smr
    return g


def tool_deviation(reference: Geometry, geometry: Geometry) -> np.ndarray:
    """Local-layout vector δ with `geometry` ≈ `reference` updated by δ (logs on SE(3) and SO(3))."""
    s, s0 = reflector_offsets(geometry), reflector_offsets(reference)
    dof = len(geometry.joints)
    out = np.zeros(width(len(s), dof))
    out[:parameter_layout(dof).size] = deviation_from(reference, geometry)
    out[tool_slice(dof)] = pin.log3(tool_rotation(reference).T @ tool_rotation(geometry))
    for k in range(1, len(s)):
        out[reflector_slice(k, dof)] = s[k] - (s0[k] if k < len(s0) else s0[0])
    return out


def group_order(reflectors: int, dof: int = 6) -> tuple[slice, ...]:
    """The identifiable-set groups of the local layout: tracker, SMR, tool rotation, further reflectors,
    joints 1..N, flange (module docstring)."""
    lay = parameter_layout(dof)
    return (lay.tracker, lay.smr, tool_slice(dof), *(reflector_slice(k, dof) for k in range(1, reflectors)),
            *(slice(6 * i, 6 * i + 6) for i in range(dof)), lay.flange)


def generic_tool(robot: Robot, reflectors: int, orientation: bool) -> Geometry:
    """`generic_geometry` with a tool at a generic point: a tilted frame, reflectors spread off-axis."""
    g = generic_geometry(robot)
    if orientation:
        g.tool_rotation = pin.rpy.rpyToMatrix(0.3, -0.2, 0.7)
    if reflectors > 1:
        spread = np.array([[0.0, 0.0, 0.0], [0.052, 0.011, -0.02], [-0.017, 0.061, 0.013],
                           [0.023, -0.044, 0.037]])
        extra = [g.smr + spread[k % 4] + 0.013 * (k // 4) for k in range(reflectors)]
        g.reflectors = np.array(extra)
        g.reflectors[0] = g.smr
    return g


@lru_cache(maxsize=64)
def _identifiable_cached(robot: Robot, reflectors: int, orientation: bool) -> tuple[int, ...]:
    g = generic_tool(robot, reflectors, orientation)
    _, _, J = frame_and_jacobian(g, generic_configurations(robot), orientation)
    groups = group_order(reflectors, chain_of(robot).dof)
    return tuple(select_identifiable(J.reshape(-1, J.shape[2]), groups=groups))


def identifiable_tool_parameters(robot: Robot, reflectors: int, orientation: bool) -> np.ndarray:
    """Local columns a fit of `reflectors` positions per pose (and, with `orientation`, the measured
    frame's orientation) identifies: 27 + 3·(R − 1), and 3 more with orientations, on a UR; for any
    arm, its position fit's set plus the same (`robot` a catalog name or a chain)."""
    return np.array(_identifiable_cached(robot, int(reflectors), bool(orientation)), dtype=int)


def registration_columns(reflectors: int, orientation: bool, dof: int = 6) -> np.ndarray:
    """Local columns of what places the tool and the instrument (tracker pose, SMR offset, the tool
    rotation with orientations, the further reflectors): what a nominal model fits."""
    lay = parameter_layout(dof)
    cols = [np.arange(lay.size)[lay.tracker], np.arange(lay.size)[lay.smr]]
    if orientation:
        ts = tool_slice(dof)
        cols.append(np.arange(ts.start, ts.stop))
    cols += [np.arange(reflector_slice(k, dof).start, reflector_slice(k, dof).stop)
             for k in range(1, reflectors)]
    return np.concatenate(cols).astype(int)
