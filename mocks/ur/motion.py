"""Motion primitives of the simulated arm: velocity/acceleration-limited profiles and trackers.

Each primitive advances by a *scaled* time step (simulated seconds times the speed-slider fraction, which
is how a UR controller slows a program down) and returns the new commanded joint vector. The arm model
owns the state; primitives only shape it:

* `JointMove`  — movej: trapezoidal profile of the leading joint, all joints synchronised (they start and
  stop together, as on the real controller);
* `LinearMove` — movel: trapezoidal profile along the straight TCP path (translation and rotation
  interpolated together), joints from IK warm-started at the previous step;
* `Decelerate` — stopj/stopl and safety stops: the current joint velocity ramped to zero;
* `ServoTracker` — servoj/servol: follows a streamed target with a lag set by lookahead time and gain;
* `SpeedTracker` — speedj: ramps the joint velocity towards a target at a given acceleration.
"""

from __future__ import annotations

import math

import numpy as np

from mocks.ur.kin import FkFn, matrix_to_rotvec, rotvec_to_matrix, solve_ik


class MotionError(RuntimeError):
    """The controller cannot execute the motion (no IK solution on the path, ...)."""


def trapezoid_duration(d: float, v: float, a: float) -> float:
    """Time to travel distance `d` from rest to rest with speed `v` and acceleration `a`."""
    d = abs(d)
    if d <= 0.0:
        return 0.0
    if d >= v * v / a:
        return d / v + v / a
    return 2.0 * math.sqrt(d / a)


def trapezoid_fraction(t: float, d: float, v: float, a: float) -> float:
    """Fraction of distance `d` covered at time `t` along the rest-to-rest trapezoid."""
    d = abs(d)
    if d <= 0.0:
        return 1.0
    T = trapezoid_duration(d, v, a)
    if t >= T:
        return 1.0
    if t <= 0.0:
        return 0.0
    if d >= v * v / a:
        ta = v / a
        vp = v
    else:
        ta = T / 2.0
        vp = a * ta
    if t < ta:
        s = 0.5 * a * t * t
    elif t < T - ta:
        s = 0.5 * a * ta * ta + vp * (t - ta)
    else:
        tr = T - t
        s = d - 0.5 * a * tr * tr
    return min(max(s / d, 0.0), 1.0)


class JointMove:
    """movej: the leading joint runs a trapezoid with (v, a); the others are scaled to finish with it."""

    def __init__(self, q0: np.ndarray, q1: np.ndarray, v: float, a: float, vmax: np.ndarray) -> None:
        self.q0 = np.asarray(q0, dtype=float).copy()
        self.q1 = np.asarray(q1, dtype=float).copy()
        delta = self.q1 - self.q0
        # the per-joint speed limit may be lower than the commanded speed: slow the whole move down
        ratios = np.abs(delta) / np.maximum(np.minimum(v, vmax), 1e-9)
        lead = int(np.argmax(ratios))
        self._d = float(abs(delta[lead]))
        self._v = float(min(v, vmax[lead])) if v > 0 else float(vmax[lead])
        self._a = float(a) if a > 0 else 1.4
        self.tau = 0.0
        self.duration = trapezoid_duration(self._d, self._v, self._a)
        self.target = self.q1

    @property
    def acceleration(self) -> float:
        """The lead joint's acceleration (rad/s²) in the ramps of its profile."""
        return self._a

    @property
    def accel_time(self) -> float:
        """Seconds of the acceleration ramp (and of the deceleration ramp): v/a, or half a triangle."""
        if self._d <= 0:
            return 0.0
        return self._v / self._a if self._d >= self._v * self._v / self._a else self.duration / 2.0

    @property
    def done(self) -> bool:
        return self.tau >= self.duration

    def step(self, dt: float, q: np.ndarray) -> np.ndarray:
        self.tau += dt
        s = trapezoid_fraction(self.tau, self._d, self._v, self._a)
        return self.q0 + s * (self.q1 - self.q0)


class LinearMove:
    """movel: the TCP follows a straight line (and a uniform rotation) with a trapezoidal profile."""

    def __init__(
        self,
        fk_tcp: FkFn,
        q0: np.ndarray,
        T1: np.ndarray,
        v: float,
        a: float,
        *,
        rot_speed: float = 1.05,
        rot_acc: float = 1.4,
    ) -> None:
        self._fk = fk_tcp
        self.q0 = np.asarray(q0, dtype=float).copy()
        T0 = fk_tcp(self.q0)
        self._p0, self._p1 = T0[:3, 3].copy(), T1[:3, 3].copy()
        self._R0 = T0[:3, :3].copy()
        self._w = matrix_to_rotvec(T1[:3, :3] @ self._R0.T)  # base-frame rotation from R0 to R1
        self._L = float(np.linalg.norm(self._p1 - self._p0))
        self._th = float(np.linalg.norm(self._w))
        self._v, self._a = (float(v) if v > 0 else 0.25), (float(a) if a > 0 else 1.2)
        t_lin = trapezoid_duration(self._L, self._v, self._a)
        t_rot = trapezoid_duration(self._th, rot_speed, rot_acc)
        if t_lin >= t_rot:
            self._prof = (self._L, self._v, self._a)
        else:
            self._prof = (self._th, rot_speed, rot_acc)
        self.duration = max(t_lin, t_rot)
        self.tau = 0.0
        self.target_T = T1.copy()
        q1 = solve_ik(fk_tcp, T1, self.q0)
        if q1 is None:
            raise MotionError("movel: no inverse kinematics solution for the target pose")
        self.target = q1

    @property
    def done(self) -> bool:
        return self.tau >= self.duration

    def pose_at(self, s: float) -> np.ndarray:
        T = np.eye(4)
        T[:3, 3] = self._p0 + s * (self._p1 - self._p0)
        T[:3, :3] = rotvec_to_matrix(s * self._w) @ self._R0
        return T

    def step(self, dt: float, q: np.ndarray) -> np.ndarray:
        self.tau += dt
        d, v, a = self._prof
        s = trapezoid_fraction(self.tau, d, v, a) if self.duration > 0 else 1.0
        qn = solve_ik(self._fk, self.pose_at(s), q, max_iter=20)
        if qn is None or np.max(np.abs(qn - q)) > 0.5:
            raise MotionError("movel: path passes through a singularity or leaves the workspace")
        return qn


class Decelerate:
    """Ramp the current joint velocity to zero; the fastest joint decelerates at `a` (rad/s^2)."""

    def __init__(self, qd0: np.ndarray, a: float) -> None:
        self._qd0 = np.asarray(qd0, dtype=float).copy()
        vmax = float(np.max(np.abs(self._qd0)))
        self.duration = vmax / a if a > 0 and vmax > 0 else 0.0
        self.tau = 0.0
        self.target: np.ndarray | None = None

    @property
    def done(self) -> bool:
        return self.tau >= self.duration

    def step(self, dt: float, q: np.ndarray) -> np.ndarray:
        if self.duration <= 0:
            self.tau = 1.0
            return q
        t0 = self.tau
        t1 = min(self.tau + dt, self.duration)
        self.tau += dt
        # velocity k(t) = 1 - t/T; integrate exactly over [t0, t1]
        T = self.duration
        integral = (t1 - t0) - (t1 * t1 - t0 * t0) / (2.0 * T)
        return q + self._qd0 * integral


class ServoTracker:
    """servoj: follow the latest streamed target like a critically damped loop, speed-limited."""

    def __init__(self, target: np.ndarray, lookahead: float, gain: float, vmax: np.ndarray) -> None:
        self.target = np.asarray(target, dtype=float).copy()
        self.vmax = vmax
        self.set_params(lookahead, gain)
        self.done = False

    def set_params(self, lookahead: float, gain: float) -> None:
        """Time constant of the lag: tens of ms, longer with more lookahead and less gain."""
        lookahead = min(max(lookahead, 0.03), 0.2)
        gain = min(max(gain, 100.0), 2000.0)
        self.tc = 0.5 * lookahead * math.sqrt(300.0 / gain)

    def step(self, dt: float, q: np.ndarray) -> np.ndarray:
        alpha = 1.0 - math.exp(-dt / self.tc) if self.tc > 0 else 1.0
        dq = (self.target - q) * alpha
        lim = self.vmax * dt
        return q + np.clip(dq, -lim, lim)


class SpeedTracker:
    """speedj: joint velocity ramps towards the target velocity at `a`; the arm integrates it."""

    def __init__(self, qd_now: np.ndarray, qd_target: np.ndarray, a: float, vmax: np.ndarray) -> None:
        self.qd = np.asarray(qd_now, dtype=float).copy()
        self.qd_target = np.clip(np.asarray(qd_target, dtype=float), -vmax, vmax)
        self.a = a if a > 0 else 0.5
        self.done = False
        self.target: np.ndarray | None = None

    def step(self, dt: float, q: np.ndarray) -> np.ndarray:
        dv = self.qd_target - self.qd
        lim = self.a * dt
        self.qd = self.qd + np.clip(dv, -lim, lim)
        return q + self.qd * dt
