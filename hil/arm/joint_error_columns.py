"""The joint-error and lost-motion parameters of an identification: their names, columns and updates.

The calibration parameter vector (`hil.arm.kinematics`: 51 geometric, then 6 compliances) is extended
by the low-order terms of each joint's angle error and by each joint's lost motion (docs/design.md,
Contracts: non-geometric errors; `hil.arm.joint_errors` holds the model):

* ``joint{j}.cos{k}``, ``joint{j}.sin{k}`` (rad): a_jk and b_jk of e_j(q) = Σ a·cos(k·q_j) + b·sin(k·q_j),
  for k = 1 … `MAX_FIT_ORDER`                                                        (6·2·K columns)
* ``lost_motion.j{j}`` (rad): h_j, the link lagging the encoder by h_j·d_j, d_j = sign(last motion)
                                                                                          (6 columns)

Every link-angle error reaches the measured point through ∂p/∂q_link (`Kinematics.joint_sensitivities`),
so the columns are that sensitivity times ∂q_link/∂(parameter): cos(k·q_j), sin(k·q_j) at the encoder
angle q_j, and −d_j. Updates are additive (the parameters enter the link angle linearly).

Only low orders are candidates: a handful of poses cannot resolve more, the fit's run time grows with
each candidate, and the orders that matter physically are low — an encoder mounted off its axis reads a
once-per-turn error, an out-of-round output bearing or encoder disc twice per turn; the strain-wave
gear's own transmission error runs at 2·ratio per turn (hundreds) and stays in the residual.
"""

from __future__ import annotations

import numpy as np

from hil.arm.joint_errors import Harmonic, JointErrors

#: Highest harmonic order identified (orders 1 … 3; the module docstring says why so few).
MAX_FIT_ORDER = 3
#: Where the joint-error parameters start in the extended vector: after the 51 geometric parameters
#: and the 6 compliances (`hil.arm.kinematics.ALL_PARAMETER_NAMES`).
FIRST = 57
N_HARMONIC = 6 * MAX_FIT_ORDER * 2
HARMONIC_SLICE = slice(FIRST, FIRST + N_HARMONIC)
LOST_MOTION_SLICE = slice(FIRST + N_HARMONIC, FIRST + N_HARMONIC + 6)
N_EXTENDED = FIRST + N_HARMONIC + 6  # 99

JOINT_ERROR_NAMES: tuple[str, ...] = tuple(
    f"joint{j + 1}.{kind}{k}" for j in range(6) for k in range(1, MAX_FIT_ORDER + 1)
    for kind in ("cos", "sin"))
LOST_MOTION_NAMES: tuple[str, ...] = tuple(f"lost_motion.j{j + 1}" for j in range(6))


def harmonic_index(joint: int, order: int, kind: str) -> int:
    """Index in the extended vector of joint `joint`'s (0-based) `kind` ("cos"/"sin") term of `order`."""
    if not 1 <= order <= MAX_FIT_ORDER:
        raise ValueError(f"harmonic order {order} outside 1..{MAX_FIT_ORDER}")
    return FIRST + (joint * MAX_FIT_ORDER + order - 1) * 2 + (0 if kind == "cos" else 1)


def lost_motion_index(joint: int) -> int:
    """Index in the extended vector of joint `joint`'s (0-based) lost motion."""
    return LOST_MOTION_SLICE.start + joint


def term_groups() -> dict[str, tuple[int, ...]]:
    """Every candidate group, by name: ``joint3.k2`` (its cos and sin columns), ``lost_motion.j3``.

    A group is the unit a model adds or leaves out: a harmonic's phase is not known in advance, so its
    cos and sin go in together.
    """
    out: dict[str, tuple[int, ...]] = {}
    for j in range(6):
        for k in range(1, MAX_FIT_ORDER + 1):
            out[f"joint{j + 1}.k{k}"] = (harmonic_index(j, k, "cos"), harmonic_index(j, k, "sin"))
    for j in range(6):
        out[f"lost_motion.j{j + 1}"] = (lost_motion_index(j),)
    return out


def columns(dp_dq: np.ndarray, Q: np.ndarray, directions: np.ndarray | None) -> np.ndarray:
    """(N, 3, 42) joint-error and lost-motion columns from ∂p/∂q_link `dp_dq` (N, 3, 6) at encoder
    angles `Q` (N, 6); the lost-motion columns are zero without `directions` (nothing to lag by)."""
    Q = np.asarray(Q, dtype=float)
    n = len(Q)
    k = np.arange(1, MAX_FIT_ORDER + 1)
    angle = Q[:, :, None] * k  # (N, 6, K)
    trig = np.stack([np.cos(angle), np.sin(angle)], axis=-1).reshape(n, 6, 2 * MAX_FIT_ORDER)
    harm = (dp_dq[:, :, :, None] * trig[:, None, :, :]).reshape(n, 3, N_HARMONIC)
    if directions is None:
        lost = np.zeros((n, 3, 6))
    else:
        d = np.broadcast_to(np.asarray(directions, dtype=float), Q.shape)
        lost = -dp_dq * d[:, None, :]
    return np.concatenate([harm, lost], axis=2)


def apply_terms(joint_errors: JointErrors | None, lost_motion: np.ndarray | None,
                delta: np.ndarray) -> tuple[JointErrors | None, np.ndarray | None]:
    """The blocks after adding the 42-long step `delta` (harmonics, then lost motion); a block the
    step does not touch is returned as it was (None stays None)."""
    delta = np.asarray(delta, dtype=float)
    harm = delta[:N_HARMONIC].reshape(6, MAX_FIT_ORDER, 2)
    errors = joint_errors
    if np.any(harm != 0.0):
        current = joint_errors.joints if joint_errors is not None else ((),) * 6
        joints = []
        for j, terms in enumerate(current):
            by_order = {h.order: h for h in terms}
            for k in range(1, MAX_FIT_ORDER + 1):
                a, b = harm[j, k - 1]
                if a == 0.0 and b == 0.0:
                    continue
                old = by_order.get(k, Harmonic(k, 0.0, 0.0))
                by_order[k] = Harmonic(k, old.cos + float(a), old.sin + float(b))
            joints.append(tuple(by_order[k] for k in sorted(by_order)))
        errors = JointErrors(tuple(joints))
    lost = lost_motion
    step = delta[N_HARMONIC:N_HARMONIC + 6]
    if np.any(step != 0.0):
        lost = (np.zeros(6) if lost_motion is None else lost_motion) + step
    return errors, lost


def term_values(joint_errors: JointErrors | None, lost_motion: np.ndarray | None) -> np.ndarray:
    """The 42-long vector of a geometry's blocks in this layout (orders above `MAX_FIT_ORDER` have no
    place in it and are left out; a missing block counts as zero)."""
    out = np.zeros(N_HARMONIC + 6)
    if joint_errors is not None:
        for j, terms in enumerate(joint_errors.joints):
            for h in terms:
                if h.order <= MAX_FIT_ORDER:
                    i = harmonic_index(j, h.order, "cos") - FIRST
                    out[i], out[i + 1] = h.cos, h.sin
    if lost_motion is not None:
        out[N_HARMONIC:] = lost_motion
    return out
