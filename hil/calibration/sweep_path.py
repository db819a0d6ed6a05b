"""A swept tour: one smooth joint path through the informative poses, sampled for servoJ.

The sweep mode (docs/design.md, the calibration campaign: the sweep mode) measures while the arm moves
instead of stopping at poses. `plan_sweep` turns the poses a selector chose into a path the controller
can stream, and `check_sweep` refuses a bad one before anything moves.

How the path is built, and why:

* **Order.** The waypoints are visited in the order that keeps the tour short: nearest neighbour from
  the start, then 2-opt (reversing any stretch of the tour that shortens it), on the time-like joint
  distance `leg_seconds` — how long a rest-to-rest cubic between two poses takes at the speed and
  acceleration limits (the joint slowest to get there sets the time). On the speed alone, short hops
  look cheaper than they are (they are acceleration-bound); the rest-to-rest time ordered 28 random
  UR5e rests (1 m/s, the quasi-static acceleration limit) 1–3 % shorter.
* **Shape.** A cubic spline through the start, the waypoints and back to rest at the last one
  (``scipy.interpolate.CubicSpline`` with clamped ends: zero velocity at both ends). A cubic spline is
  C²: the acceleration is continuous and the jerk piecewise constant, so the arm's structural modes
  (7–12 Hz, `hil.arm.dynamics`' caveat) see no step of acceleration, and the quasi-static deflection
  model the fit uses holds along it. The arm does not stop at the waypoints; it passes through them.
* **Timing.** Each segment starts at the rest-to-rest duration of a cubic (peak speed 1.5·Δ/T, peak
  acceleration 6·Δ/T², Δ the joint's distance) and is then stretched where the sampled path exceeds a
  limit and shrunk where it is far below, until every sample is within the per-joint speed and
  acceleration limits (the spline couples neighbouring segments, so this iterates; the shortest
  feasible timing found is kept). The limits are *checked on the sampled path* and a path that cannot
  be brought within them is refused (`SweepRefused`), never clamped.
* **Stops.** The static poses a sweep campaign still measures (its bootstrap and its validation poses)
  can be rests of the same tour (`stops`, each held its `dwell_s`: one for all or one per stop, since a
  validation pose is read as a stop-and-go campaign reads it while a bootstrap rest may need fewer
  readings): ordered with the waypoints, each stretch between two rests one rest-to-rest spline — no
  separate stop-and-go tour to travel. A tour of rests alone (no waypoints) is allowed: its legs
  between the rests are the sweep.
* **Sampling.** One sample per controller period (1/rate_hz; 500 Hz on e-series, UR's RTDE guide): the
  whole timing is stretched by less than one period so the last sample is the end at rest.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline

from drivers.robot.trajectory import keep_in_checkpoints
from hil.arm.catalog import RobotSpec
from hil.arm.geometry import Geometry
from hil.arm.kinematics_cache import kinematics_of
from hil.errors import InputError

#: Largest joint change (rad) between the samples whose SMR is checked against the keep-in box and the
#: tracker's line of sight: 0.05 rad moves the SMR of a 1 m arm by at most 5 cm, the order of the
#: line-of-sight check's beam clearance (3 cm, `selector.candidates.Constraints`) and far below a
#: keep-in box's size. hil's choice, as the driver's `keep_in_spacing` is the station's.
CHECK_SPACING_RAD = 0.05
#: Iterations of the segment timing (each one a spline fit and a sampling, milliseconds).
TIMING_ITERATIONS = 80


class SweepRefused(InputError):
    """A swept tour the arm must not follow: the first offending sample (and joint) is named."""


@dataclass(frozen=True)
class SweepTour:
    """A swept tour, sampled once per controller period (the targets to stream with servoJ)."""

    t: np.ndarray  # (n,) s from the tour's start
    q: np.ndarray  # (n, N) rad, encoder targets
    waypoints: np.ndarray  # (m, N) the informative poses it passes through, in order
    rate_hz: float
    #: (m,) s: when the tour passes each waypoint
    waypoint_times: np.ndarray = field(default_factory=lambda: np.zeros(0))
    #: (s, N) the poses it rests at (`plan_sweep`'s `stops`), in order, and (s,) when each rest begins
    stops: np.ndarray = field(default_factory=lambda: np.zeros((0, 6)))
    stop_times: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def duration(self) -> float:
        """Seconds from the first sample to the last (the arm at rest at both)."""
        return float(self.t[-1] - self.t[0])

    def approach_directions(self) -> np.ndarray:
        """(s, N) the sign of each joint's last motion before each stop (−1, 0 or +1): the side its lost
        motion lags from (`hil.calibration.synthetic.measure`'s `directions`)."""
        out = np.zeros_like(self.stops)
        for k, ts in enumerate(self.stop_times):
            i = round(float(ts) * self.rate_hz)
            moved = np.diff(self.q[: i + 1], axis=0)
            for j in range(self.q.shape[1]):
                nz = np.flatnonzero(np.abs(moved[:, j]) > 1e-12)
                out[k, j] = np.sign(moved[nz[-1], j]) if nz.size else 0.0
        return out

    def velocities(self) -> np.ndarray:
        """(n, N) rad/s of the sampled path, by central differences (one-sided at the ends)."""
        return np.gradient(self.q, 1.0 / self.rate_hz, axis=0)

    def accelerations(self) -> np.ndarray:
        """(n, N) rad/s² of the sampled path, by second differences (zero at the ends: at rest)."""
        a = np.zeros_like(self.q)
        if len(self.q) > 2:
            a[1:-1] = (self.q[2:] - 2 * self.q[1:-1] + self.q[:-2]) * self.rate_hz**2
        return a


def _limits(value: np.ndarray | float, n: int, name: str) -> np.ndarray:
    v = np.broadcast_to(np.asarray(value, dtype=float), (n,)).copy()
    if not np.all(np.isfinite(v) & (v > 0)):
        raise InputError(f"sweep: {name} must be positive and finite per joint, got {v.tolist()}")
    return v


def _tour_cost(points: np.ndarray, order: Sequence[int], speed: np.ndarray) -> float:
    path = points[[0, *order]]
    return float(np.sum(np.max(np.abs(np.diff(path, axis=0)) / speed, axis=1)))


def leg_seconds(A: np.ndarray, B: np.ndarray, speed: np.ndarray, accel: np.ndarray | None = None
                ) -> np.ndarray:
    """Time-like distance between the rows of A and B (broadcasting, last axis the joints): the
    rest-to-rest cubic's time max_j max(1.5·|Δq_j|/v_j, √(6·|Δq_j|/a_j)) (`_leg`'s first timing), or with
    no `accel` the speed-only max_j |Δq_j|/v_j. Short moves are acceleration-bound: on the speed alone a
    tour of rests is ordered as if a 0.1 rad hop cost a tenth of a 1 rad one, where it costs a third."""
    d = np.abs(np.asarray(B, dtype=float) - np.asarray(A, dtype=float))
    if accel is None:
        return np.max(d / speed, axis=-1)
    return np.max(np.maximum(1.5 * d / speed, np.sqrt(6.0 * d / accel)), axis=-1)


def tour_order(start: np.ndarray, waypoints: np.ndarray, speed: np.ndarray,
               accel: np.ndarray | None = None) -> list[int]:
    """Indices of `waypoints` in a short visiting order from `start` (nearest neighbour, then 2-opt),
    on the time-like distance `leg_seconds` (with `accel`, a rest-to-rest leg's time); the tour ends at
    its last waypoint."""
    pts = np.vstack([start[None], waypoints])
    D = leg_seconds(pts[:, None, :], pts[None, :, :], speed, accel)
    left = set(range(1, len(pts)))
    order, here = [], 0
    while left:
        here = min(left, key=lambda k: (D[here, k], k))
        order.append(here)
        left.remove(here)
    improved = True
    while improved:  # 2-opt on the open path with a fixed start: reverse order[i..j]
        improved = False
        for i in range(len(order) - 1):
            before = order[i - 1] if i else 0
            for j in range(i + 1, len(order)):
                after = order[j + 1] if j + 1 < len(order) else None
                old = D[before, order[i]] + (D[order[j], after] if after is not None else 0.0)
                new = D[before, order[j]] + (D[order[i], after] if after is not None else 0.0)
                if new < old - 1e-12:
                    order[i:j + 1] = order[i:j + 1][::-1]
                    improved = True
    return [k - 1 for k in order]


def _spline(knots: np.ndarray, durations: np.ndarray) -> CubicSpline:
    return CubicSpline(np.r_[0.0, np.cumsum(durations)], knots, bc_type="clamped", axis=0)


def _segment_ratios(spline: CubicSpline, durations: np.ndarray, speed: np.ndarray, accel: np.ndarray,
                    per_segment: int = 24) -> np.ndarray:
    """Per segment, the largest of |q̇|/v and √(|q̈|/a) over its samples (> 1: over a limit). The
    square root makes it the factor by which stretching that segment's time alone would fix it."""
    edges = np.r_[0.0, np.cumsum(durations)]
    s = np.linspace(0.0, 1.0, per_segment)
    t = (edges[:-1, None] + durations[:, None] * s[None, :]).ravel()
    v = np.abs(spline(t, 1)) / speed
    a = np.abs(spline(t, 2)) / accel
    r = np.maximum(v.max(axis=1), np.sqrt(a.max(axis=1)))
    return r.reshape(len(durations), per_segment).max(axis=1)


def _leg(knots: np.ndarray, speed: np.ndarray, accel: np.ndarray, rate_hz: float
         ) -> tuple[np.ndarray, np.ndarray]:
    """One rest-to-rest leg through `knots` (k ≥ 2, no repeats): its samples (n, N) from the first knot
    to the last, and when it passes each knot after the first (k − 1,) s from the leg's start."""
    delta = np.abs(np.diff(knots, axis=0))
    durations = np.max(np.maximum(1.5 * delta / speed, np.sqrt(6.0 * delta / accel)), axis=1)
    durations = np.maximum(durations, 2.0 / rate_hz)
    best: np.ndarray | None = None
    for _ in range(TIMING_ITERATIONS):
        r = _segment_ratios(_spline(knots, durations), durations, speed, accel)
        if r.max() <= 0.995 and (best is None or durations.sum() < best.sum()):
            best = durations.copy()
        # stretch what is over (with a little margin), shrink what is well under, gently
        factor = np.where(r > 0.99, r / 0.985, np.clip(r / 0.97, 0.8, 1.0))
        if np.allclose(factor, 1.0, atol=2e-3):
            break
        durations = np.maximum(durations * factor, 2.0 / rate_hz)
    if best is None:
        raise SweepRefused(f"sweep: no timing of the {len(knots) - 1} segments keeps every joint within "
                           f"max_speed {speed.round(4).tolist()} rad/s and max_acceleration "
                           f"{accel.round(4).tolist()} rad/s²")
    total = float(best.sum())
    periods = int(np.ceil(total * rate_hz - 1e-9))
    best = best * (periods / rate_hz) / total  # stretched (< 1 period): the end falls on a sample
    q = _spline(knots, best)(np.arange(periods + 1) / rate_hz)
    q[0], q[-1] = knots[0], knots[-1]
    return q, np.cumsum(best)


def plan_sweep(waypoints: np.ndarray, start: np.ndarray, *, max_speed: np.ndarray | float,
               max_acceleration: np.ndarray | float, rate_hz: float = 500.0,
               spec: RobotSpec | None = None, stops: np.ndarray | None = None,
               dwell_s: float | Sequence[float] | np.ndarray = 0.0) -> SweepTour:
    """A smooth joint path from `start` (at rest) through `waypoints` (in a short order) to rest at the
    last one, within the per-joint `max_speed` (rad/s) and `max_acceleration` (rad/s²) on every sample
    (module docstring). `SweepRefused` if no timing meets them (it never clamps).

    `stops` are poses the tour comes to rest at and holds for `dwell_s` (the static poses a sweep
    campaign still measures — its bootstrap and validation poses — visited in the same tour instead of
    a separate stop-and-go one); they are ordered with the waypoints, and the path between two stops
    is one rest-to-rest spline. `dwell_s` is one hold for every stop or one per stop (in `stops`'
    order). `waypoints` may be empty when there are stops: the tour is then its rests and the legs
    between them. With `spec` every sample is also checked against the arm's joint
    limits: a spline passing through a waypoint at a joint's limit overshoots it between samples (by
    ~10⁻⁴ rad), so waypoints must keep a margin from the limits; a tour that does not is refused naming
    the sample and joint."""
    q0 = np.asarray(start, dtype=float).ravel()
    W = np.asarray(waypoints, dtype=float)
    W = W.reshape(0, q0.size) if W.size == 0 else np.atleast_2d(W)
    S = np.zeros((0, q0.size)) if stops is None else np.asarray(stops, dtype=float)
    S = S.reshape(0, q0.size) if S.size == 0 else np.atleast_2d(S)
    if W.ndim != 2 or W.shape[0] + S.shape[0] < 1 or W.shape[1] != q0.size or S.shape[1:] != (q0.size,) \
            or not (np.isfinite(W).all() and np.isfinite(q0).all() and np.isfinite(S).all()):
        raise InputError(f"sweep: waypoints and stops must be (m, {q0.size}) finite joint angles (at least "
                         f"one of either) and start {q0.size} finite angles, got {W.shape}, {S.shape} and "
                         f"{q0.shape}")
    dwell = np.asarray(dwell_s, dtype=float)
    if dwell.ndim == 0:
        dwell = np.full(len(S), float(dwell))
    if not (np.isfinite(rate_hz) and rate_hz > 0) or dwell.shape != (len(S),) \
            or not (np.isfinite(dwell).all() and np.all(dwell >= 0)):
        raise InputError(f"sweep: rate_hz must be positive and dwell_s ≥ 0 (one for all stops or one per "
                         f"stop, {len(S)}), got {rate_hz} and {np.round(dwell_s, 4).tolist()}")
    n = q0.size
    speed = _limits(max_speed, n, "max_speed")
    accel = _limits(max_acceleration, n, "max_acceleration")
    points = np.vstack([W, S])
    order = tour_order(q0, points, speed, accel)  # most legs of a tour with rests are rest-to-rest
    is_stop = np.arange(len(points)) >= len(W)
    hold = np.round(np.r_[np.zeros(len(W)), dwell] * rate_hz).astype(int)  # periods held, per point
    pieces: list[np.ndarray] = [q0[None]]
    passes = np.zeros(len(points))
    clock = 0.0  # s at the end of the samples so far
    knots, members = [q0], []
    for pos, k in enumerate(order):
        if np.max(np.abs(points[k] - knots[-1])) > 1e-9:
            knots.append(points[k])
        members.append((k, len(knots) - 1))
        if not (is_stop[k] or pos == len(order) - 1):
            continue
        if len(knots) > 1:
            q, times = _leg(np.array(knots), speed, accel, rate_hz)
            pieces.append(q[1:])
            for m, i in members:
                passes[m] = clock + (times[i - 1] if i else 0.0)
            clock += (len(q) - 1) / rate_hz
        else:
            for m, _ in members:
                passes[m] = clock
        if is_stop[k] and hold[k]:
            pieces.append(np.repeat(knots[-1][None], hold[k], axis=0))
            clock += hold[k] / rate_hz
        knots, members = [knots[-1]], []
    q = np.vstack(pieces)
    if len(q) < 2:
        raise InputError("sweep: every waypoint is the start; nothing to sweep")
    t = np.arange(len(q)) / rate_hz
    ways = [k for k in order if not is_stop[k]]
    stop_order = [k for k in order if is_stop[k]]
    tour = SweepTour(t, q, W[ways], float(rate_hz), passes[ways], S[np.array(stop_order, dtype=int) - len(W)]
                     if stop_order else np.zeros((0, n)), passes[stop_order])
    check_sweep(tour, max_speed=speed, max_acceleration=accel, spec=spec)
    return tour


def plan_leg(knots: np.ndarray, *, max_speed: np.ndarray | float, max_acceleration: np.ndarray | float,
             rate_hz: float = 500.0) -> SweepTour:
    """One rest-to-rest leg through `knots` (k ≥ 2, m × N) in their given order, from the first at
    rest to the last at rest, within the per-joint limits: what `plan_sweep` makes of each leg, without
    its ordering (a sweep segment's vias must be passed in order). `SweepRefused` if no timing meets
    the limits."""
    K = np.asarray(knots, dtype=float)
    if K.ndim != 2 or len(K) < 2 or not np.isfinite(K).all():
        raise InputError(f"sweep leg: expected (k ≥ 2, N) finite knots, got {K.shape}")
    keep = np.r_[True, np.max(np.abs(np.diff(K, axis=0)), axis=1) > 1e-9]
    K = K[keep]
    if len(K) < 2:
        raise InputError("sweep leg: every knot is the start; nothing to sweep")
    n = K.shape[1]
    speed, accel = _limits(max_speed, n, "max_speed"), _limits(max_acceleration, n, "max_acceleration")
    q, times = _leg(K, speed, accel, rate_hz)
    t = np.arange(len(q)) / rate_hz
    tour = SweepTour(t, q, K[1:], float(rate_hz), np.asarray(times, dtype=float))
    check_sweep(tour, max_speed=speed, max_acceleration=accel)
    return tour


def check_sweep(tour: SweepTour, *, max_speed: np.ndarray | float | None = None,
                max_acceleration: np.ndarray | float | None = None, spec: RobotSpec | None = None,
                keep_in: tuple[np.ndarray, np.ndarray] | None = None, model: Geometry | None = None,
                acceptance_angle: float | None = None, spacing: float = CHECK_SPACING_RAD) -> None:
    """Raise `SweepRefused` naming the first offending sample (and joint) of `tour`, before anything
    moves; return None if it passes. What is checked, each only when its arguments are given:

    * every sample finite and, with `spec`, inside the joint limits;
    * each step's speed (|Δq|·rate, the driver's per-step check in `drivers.robot.trajectory`) within
      `max_speed` (default: `spec`'s joint speed maxima), each sample's second difference within
      `max_acceleration` (the driver checks no acceleration; the plan's promise is checked here);
    * with `keep_in` (lower, upper corners in the base frame, m) and `model`, the SMR inside the box at
      samples at most `spacing` rad apart (as the driver's `keep_in_checkpoints`), and the first and last;
    * with `model` and `acceptance_angle` (degrees), the SMR in the tracker's view at those samples:
      facing the tracker within the angle less the campaign's re-check margin and the beam clear of the
      arm (`hil.calibration.selection.hidden_reason`, the static selection's own check), the tracker
      where `model`'s registration puts it.
    """
    Q = np.asarray(tour.q, dtype=float)
    rate = float(tour.rate_hz)
    if Q.ndim != 2 or len(Q) < 2 or len(tour.t) != len(Q):
        raise SweepRefused(f"sweep: expected (n ≥ 2, N) samples with one stamp each, got {Q.shape} and "
                           f"{np.shape(tour.t)}")
    bad = np.argwhere(~np.isfinite(Q))
    if bad.size:
        i, j = (int(v) for v in bad[0])
        raise SweepRefused(f"sweep sample {i}: joint {j + 1} is not finite")
    if spec is not None:
        lo, hi = np.asarray(spec.lower, dtype=float), np.asarray(spec.upper, dtype=float)
        out = np.argwhere(np.less(Q, lo) | np.greater(Q, hi))
        if out.size:
            i, j = (int(v) for v in out[0])
            raise SweepRefused(f"sweep sample {i} (t = {tour.t[i]:.3f} s): joint {j + 1} at {Q[i, j]:.4f} "
                               f"rad is outside [{spec.lower[j]:.4f}, {spec.upper[j]:.4f}]")
        if max_speed is None:
            max_speed = spec.max_joint_speed
    n = Q.shape[1]
    if max_speed is not None:
        v = _limits(max_speed, n, "max_speed")
        step = np.abs(np.diff(Q, axis=0)) * rate
        over = np.argwhere(step > v * (1 + 1e-9))
        if over.size:
            i, j = (int(x) for x in over[0])
            raise SweepRefused(f"sweep sample {i + 1} (t = {tour.t[i + 1]:.3f} s): joint {j + 1} steps at "
                               f"{step[i, j]:.4f} rad/s, over its {v[j]:.4f} rad/s")
    if max_acceleration is not None:
        a_max = _limits(max_acceleration, n, "max_acceleration")
        acc = np.abs(tour.accelerations())
        over = np.argwhere(acc > a_max * (1 + 1e-9))
        if over.size:
            i, j = (int(x) for x in over[0])
            raise SweepRefused(f"sweep sample {i} (t = {tour.t[i]:.3f} s): joint {j + 1} accelerates at "
                               f"{acc[i, j]:.4f} rad/s², over its {a_max[j]:.4f} rad/s²")
    if model is None or (keep_in is None and acceptance_angle is None):
        return
    checked = keep_in_checkpoints(Q, spacing)
    if keep_in is not None:
        lo, hi = (np.asarray(b, dtype=float) for b in keep_in)
        pts = kinematics_of(model).points(Q[checked], frame="base")
        outside = np.flatnonzero(np.any((pts < lo) | (pts > hi), axis=1))
        if outside.size:
            i = checked[int(outside[0])]
            raise SweepRefused(f"sweep sample {i} (t = {tour.t[i]:.3f} s) puts the SMR at "
                               f"{np.round(pts[outside[0]], 4).tolist()} m, outside the keep-in box "
                               f"{lo.tolist()}..{hi.tolist()} (nothing moved)")
    if acceptance_angle is not None:
        from hil.calibration.selection import hidden_reasons

        tracker = np.asarray(model.tracker.translation, dtype=float)
        whys = hidden_reasons(model.robot, model.smr, tracker, Q[checked], acceptance_angle)
        for i, why in zip(checked, whys, strict=True):
            if why is not None:
                raise SweepRefused(f"sweep sample {i} (t = {tour.t[i]:.3f} s): the tracker would not see "
                                   f"the SMR ({why}; nothing moved)")
