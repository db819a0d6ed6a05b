"""How long the arm takes between two measurement poses: the driver's own joint-space motion profile.

hil moves between poses with ``movej`` (ur_rtde ``moveJ(q, speed, acceleration)``, the station's
``robot.speed`` and ``robot.acceleration``). On a UR controller ``speed`` and ``acceleration`` are those
of the *leading* joint — the one whose move takes longest at its speed limit — and the other joints are
scaled to start and stop with it. The leading joint runs a rest-to-rest trapezoid (URScript manual,
``movej``: "a: joint acceleration of leading axis, v: joint speed of leading axis"). A joint's speed is
the smaller of ``speed`` and its own maximum, so on arms whose base joints are slower (UR10e: 120 °/s
against 180 °/s for the wrist) the leading joint need not be the one that turns furthest:

    t(a, b) = T(|Δ_k|, v_k, acc),  k = argmaxⱼ |Δⱼ| / v_j,  v_j = min(speed, vmax_j),
    T(d, v, acc) = d / v + v / acc    when d ≥ v² / acc (cruise reached),
                   2·√(d / acc)       otherwise (triangle).

After the move a pose costs its *dwell*: the wait until the arm is steady and the tracker's measurement
(`Dwell`). The selector and the visiting order plan with these times, not with a distance proxy, because
what an end-of-line cell pays for is seconds of robot time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from selector.errors import SelectorError


def trapezoid_time(d: np.ndarray | float, v: np.ndarray | float, acc: float) -> np.ndarray:
    """Rest-to-rest time (s) over distance `d` with speed `v` and acceleration `acc` (broadcasts)."""
    d = np.abs(np.asarray(d, dtype=float))
    v = np.asarray(v, dtype=float)
    cruise = d >= v * v / acc
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.where(cruise, d / v + v / acc, 2.0 * np.sqrt(d / acc))
    return np.where(d > 0, t, 0.0)


@dataclass(frozen=True)
class MotionProfile:
    """The station's movej: commanded `speed` (rad/s) and `acceleration` (rad/s²) of the leading joint,
    capped per joint by the arm's `max_joint_speed` (rad/s)."""

    speed: float
    acceleration: float
    max_joint_speed: tuple[float, ...]

    def __post_init__(self) -> None:
        if not (self.speed > 0 and self.acceleration > 0):
            raise SelectorError("the motion profile needs a positive speed and acceleration")
        if len(self.max_joint_speed) != 6 or min(self.max_joint_speed) <= 0:
            raise SelectorError("the motion profile needs 6 positive joint speed limits")

    @property
    def joint_speeds(self) -> np.ndarray:
        """Each joint's speed when it leads: the commanded speed, or its own limit if lower."""
        return np.minimum(float(self.speed), np.asarray(self.max_joint_speed, dtype=float))

    def move_times(self, A: np.ndarray, B: np.ndarray) -> np.ndarray:
        """Times (s) of the moves A[i] → B[i] (broadcasting over leading dimensions, last axis 6)."""
        delta = np.abs(np.asarray(B, dtype=float) - np.asarray(A, dtype=float))
        v = self.joint_speeds
        lead = np.argmax(delta / v, axis=-1)
        d = np.take_along_axis(delta, lead[..., None], axis=-1)[..., 0]
        return trapezoid_time(d, v[lead], float(self.acceleration))

    def move_time(self, a: np.ndarray, b: np.ndarray) -> float:
        """Time (s) of one move a → b."""
        return float(self.move_times(np.asarray(a, float)[None], np.asarray(b, float)[None])[0])

    def matrix(self, Q: np.ndarray, R: np.ndarray | None = None) -> np.ndarray:
        """(len(Q), len(R)) move times from every row of `Q` to every row of `R` (default: `Q`)."""
        Q = np.asarray(Q, dtype=float)
        R = Q if R is None else np.asarray(R, dtype=float)
        return self.move_times(Q[:, None, :], R[None, :, :])

    def tour_time(self, Q: np.ndarray, start: np.ndarray | None = None) -> float:
        """Total move time visiting the rows of `Q` in order (from `start` if given)."""
        Q = np.asarray(Q, dtype=float)
        if start is not None:
            Q = np.vstack([np.asarray(start, float)[None], Q])
        if len(Q) < 2:
            return 0.0
        return float(self.move_times(Q[:-1], Q[1:]).sum())

    def as_dict(self) -> dict[str, object]:
        return {"speed": float(self.speed), "acceleration": float(self.acceleration),
                "max_joint_speed": [float(v) for v in self.max_joint_speed],
                "model": "movej: trapezoid of the leading joint, the others synchronised"}


@dataclass(frozen=True)
class Dwell:
    """Robot time spent at each pose after its move: waiting until steady, reading, measuring (s).

    `settle` is the wait before the tracker's readings count (a fixed wait, or the expected time until
    they are stable), `measure` the tracker's measuring time for one point (its samples), `overhead`
    the rest (joint reading, the controller's steady check, messages).
    """

    settle: float = 0.3
    measure: float = 0.5
    overhead: float = 0.05

    @property
    def seconds(self) -> float:
        return float(self.settle + self.measure + self.overhead)

    def as_dict(self) -> dict[str, float]:
        return {"settle": float(self.settle), "measure": float(self.measure),
                "overhead": float(self.overhead), "per_pose": self.seconds}
