"""Checks on a whole joint trajectory before it is streamed (pure: no I/O, no ur_rtde).

They live apart from the driver so the isolated client's parent process can size its timeout with
the same `keep_in_checkpoints` the child will use, without importing anything that talks to the arm.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from drivers.robot.errors import JointLimitViolation, TargetRejected


def check_trajectory(Q: object, lower: Sequence[float], upper: Sequence[float],
                     max_step: Sequence[float] | None = None) -> np.ndarray:
    """`Q` as an (N, 6) float array, or the refusal naming the first bad sample and joint.

    Every sample is checked (vectorised) before anything moves; nothing is ever clamped. With
    `max_step` (rad per controller period, per joint: the joint speed maxima over the rate), a step
    between consecutive samples above it is refused too: the planner slows down for its joint
    speeds, so such a step is a planning error (or a branch jump) the arm must not be asked to follow.
    """
    try:
        Qa = np.array(Q, dtype=float)
    except (TypeError, ValueError) as exc:
        raise TargetRejected(f"trajectory is not an N x 6 array of joint angles: {exc}") from None
    if Qa.ndim != 2 or Qa.shape[1] != 6 or Qa.shape[0] == 0:
        raise TargetRejected(f"trajectory must be N x 6 joint angles (N >= 1), got shape {Qa.shape}")
    bad = np.argwhere(~np.isfinite(Qa))
    if bad.size:
        i, j = (int(v) for v in bad[0])
        raise JointLimitViolation(f"sample {i}: joint {j + 1} target is not finite ({Qa[i, j]})")
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    bad = np.argwhere((Qa < lo) | (Qa > hi))
    if bad.size:
        i, j = (int(v) for v in bad[0])
        raise JointLimitViolation(f"sample {i}: joint {j + 1} target {Qa[i, j]:.4f} rad is outside "
                                  f"[{lo[j]:.4f}, {hi[j]:.4f}] (trajectory refused, nothing moved)")
    if max_step is not None and len(Qa) > 1:
        step = np.abs(np.diff(Qa, axis=0))
        limit = np.asarray(max_step, dtype=float)
        bad = np.argwhere(step > limit * (1.0 + 1e-9))
        if bad.size:
            i, j = (int(v) for v in bad[0])
            raise TargetRejected(f"sample {i + 1}: joint {j + 1} would move {step[i, j]:.4f} rad in one "
                                 f"period (at most {limit[j]:.4f}: its speed limit) (trajectory refused, "
                                 "nothing moved)")
    return Qa


def keep_in_checkpoints(Q: np.ndarray, spacing: float) -> list[int]:
    """Indices of the samples whose TCP is checked against the keep-in zone.

    The first and the last sample, and every sample at least `spacing` rad (largest joint change)
    from the previous checked one: a dense 500 Hz trajectory then costs a few controller FK round
    trips (about 4 ms each) instead of thousands, at a known joint-space resolution.
    """
    idx = [0]
    last = Q[0]
    for i in range(1, len(Q)):
        if float(np.max(np.abs(Q[i] - last))) >= spacing:
            idx.append(i)
            last = Q[i]
    if idx[-1] != len(Q) - 1:
        idx.append(len(Q) - 1)
    return idx
