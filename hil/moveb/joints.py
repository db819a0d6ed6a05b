"""Joint speeds along a MOVEB path: a speed ceiling for the feed profile, and the check after timing.

The feed profile bounds the tool's Cartesian speed, but near a wrist or elbow singularity a modest
tool speed can ask a joint for more than its datasheet maximum; the controller would then fault
(or, worse, lag behind the path it was given). So the path is solved once on a geometric grid
(IK of the same model the run uses), and each joint's speed per unit of tool speed, |dq_j/ds|,
turns the joint maxima into a tool-speed ceiling along s:

    v(s) ≤ min_j  f·q̇max_j / |dq_j/ds|

(f the allowed fraction of the datasheet speeds). The ceiling enters the feed profile beside the
curvature limits, so the profile slows down smoothly around the hard spot instead of the run being
refused. After timing, the joint trajectory at the controller's samples is checked against the same
maxima: the grid is finite, so a residual excess is possible; `retime` lowers the ceiling locally by
the measured excess and times again, and gives up (naming the arc length) only if that does not settle.

Joint accelerations are measured the same way (second differences at the controller rate) and
always reported. UR publishes no joint acceleration maxima, so a limit is the user's choice
(`hil moveb run --joint-acceleration`) and it is a check, not a retiming: the peak is usually the
tangential part dq/ds·s̈ where the tool speeds up from rest, which a lower speed ceiling does not
reduce, so a path over the limit is refused before any motion, naming the arc length and the
Cartesian limits that would lower it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import minimum_filter1d

from hil.errors import InputError


class JointSpeedError(InputError):
    """The path cannot be timed within the joint speed maxima."""


def joint_speed_ceiling(s: np.ndarray, Q: np.ndarray, max_speed: np.ndarray) -> np.ndarray:
    """Tool-speed ceiling (mm/s) at arc lengths `s` (mm) from joint angles `Q` (N, 6) along the path.

    |dq/ds| comes from central differences; the ceiling is lowered to its minimum over neighbouring
    samples, because the feed profile interpolates it between them.
    """
    s = np.asarray(s, float)
    dq = np.abs(np.gradient(np.asarray(Q, float), s, axis=0))  # rad/mm
    with np.errstate(divide="ignore"):
        v = np.min(np.asarray(max_speed, float)[None, :] / np.maximum(dq, 1e-300), axis=1)
    return minimum_filter1d(v, size=3, mode="nearest")


@dataclass(frozen=True)
class JointSpeeds:
    """Peak joint speeds and accelerations of a timed joint trajectory, against the allowed maxima."""

    peak: np.ndarray  # (6,) rad/s
    allowed: np.ndarray  # (6,) rad/s
    worst_sample: int  # index of the sample with the largest speed ratio
    peak_acceleration: np.ndarray  # (6,) rad/s²
    allowed_acceleration: np.ndarray | None = None  # (6,) rad/s², None: not limited

    @property
    def ratio(self) -> np.ndarray:
        return self.peak / self.allowed

    @property
    def ok(self) -> bool:
        acc_ok = (self.allowed_acceleration is None
                  or bool(np.all(self.peak_acceleration <= self.allowed_acceleration)))
        return bool(np.all(self.peak <= self.allowed)) and acc_ok

    def as_dict(self) -> dict[str, object]:
        acc = None if self.allowed_acceleration is None else self.allowed_acceleration.tolist()
        return {"peak_rad_s": self.peak.tolist(), "allowed_rad_s": self.allowed.tolist(),
                "peak_fraction": self.ratio.tolist(),
                "peak_acceleration_rad_s2": self.peak_acceleration.tolist(),
                "allowed_acceleration_rad_s2": acc}


def joint_speeds(Q: np.ndarray, rate_hz: float, allowed: np.ndarray,
                 allowed_acceleration: np.ndarray | None = None) -> JointSpeeds:
    """Peak |Δq|·rate and |Δ²q|·rate² per joint over consecutive controller samples."""
    Q = np.asarray(Q, float)
    allowed = np.asarray(allowed, float)
    acc_allowed = None if allowed_acceleration is None else np.asarray(allowed_acceleration, float)
    qd = np.abs(np.diff(Q, axis=0)) * rate_hz
    qdd = np.abs(np.diff(Q, n=2, axis=0)) * rate_hz ** 2
    peak_acc = qdd.max(axis=0) if len(qdd) else np.zeros(6)
    if not len(qd):
        return JointSpeeds(np.zeros(6), allowed, 0, peak_acc, acc_allowed)
    ratio = qd / allowed[None, :]
    return JointSpeeds(qd.max(axis=0), allowed, int(np.argmax(ratio.max(axis=1))), peak_acc, acc_allowed)


def retime(time_path: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]], s_grid: np.ndarray,
           ceiling: np.ndarray, rate_hz: float, allowed: np.ndarray, attempts: int = 4,
           allowed_acceleration: np.ndarray | None = None) -> tuple[np.ndarray, JointSpeeds]:
    """Time the path under `ceiling` until the joint speeds at the controller samples are allowed.

    `time_path(ceiling)` returns (s, Q): arc lengths and joint angles at the controller's samples.
    Where a sample exceeds the maxima, the ceiling around its arc length is scaled by the excess
    (with a 2 % margin) and the path is timed again. Then the accelerations are checked against
    `allowed_acceleration` when given (module docstring). Returns (Q, its joint speeds).
    """
    allowed = np.asarray(allowed, float)
    acc = None if allowed_acceleration is None else np.asarray(allowed_acceleration, float)
    ceiling = np.asarray(ceiling, float).copy()
    for _ in range(attempts):
        s, Q = time_path(ceiling)
        speeds = joint_speeds(Q, rate_hz, allowed, acc)
        if np.all(speeds.peak <= speeds.allowed):
            break
        qd = np.abs(np.diff(Q, axis=0)) * rate_hz
        excess = np.max(qd / allowed[None, :], axis=1)  # per interval between samples
        s_mid = 0.5 * (s[1:] + s[:-1])
        factor = np.ones(len(s_grid))
        span = max(float(np.max(np.diff(s))) * 4.0, 1e-6)  # the neighbourhood a slow-down must cover
        for k in np.flatnonzero(excess > 1.0):
            near = np.abs(s_grid - s_mid[k]) <= span
            factor[near] = np.minimum(factor[near], 0.98 / excess[k])
        ceiling *= factor
    else:
        worst = speeds.worst_sample
        j = int(np.argmax(speeds.ratio))
        raise JointSpeedError(f"s = {s[worst]:.1f} mm: joint {j + 1} would need {speeds.peak[j]:.2f} rad/s "
                              f"(allowed {speeds.allowed[j]:.2f}) even after slowing down; the path passes "
                              "too close to a singularity")
    if not speeds.ok:
        assert acc is not None
        qdd = np.abs(np.diff(Q, n=2, axis=0)) * rate_hz ** 2
        k, j = np.unravel_index(int(np.argmax(qdd / acc[None, :])), qdd.shape)
        raise JointSpeedError(f"s = {s[k + 1]:.1f} mm: joint {j + 1} would accelerate at {qdd[k, j]:.2f} "
                              f"rad/s² (allowed {acc[j]:.2f}); lower --acceleration and --jerk (from rest "
                              "and at speed changes) or --velocity (in bends)")
    return Q, speeds
