"""Joining a joint stream and a tracker stream recorded during motion: the clock map from the data.

A sweep records the controller's joints (RTDE ``actual_q`` with its ``timestamp``, t_ctrl, 500 Hz) and
the tracker's points (emScon continuous mode with the tracker's stamps, t_trk, up to 1000 Hz). The two
clocks differ by an unknown offset and drift (`hil.calibration.stream_clocks`), so before a tracker point
can be paired with the joints that put the SMR there, the map

    t_ctrl = a + (1 + d)·t_trk

must be estimated. It is estimated *from the data*: with a model of the arm (the nominal geometry, or
better the current estimate — e.g. a first fit on static poses), the point predicted at the joints
interpolated to a + (1 + d)·t_trk must match the measured point. A wrong offset shifts every prediction
along the path by the tool's velocity × the error (1 ms at 0.25 m/s: 0.25 mm); the motion's speed
changes and reversals make that shift differ from any geometry error, so a and d are observable.

A fixed latency of either instrument (the time between the instant a sample describes and its stamp)
shifts every sample of its stream alike: no data can tell it from the offset, so a absorbs it. What a
sweep needs is the map between the two streams, and a is exactly that.

How (`StreamJoin`):

1. The joint stream is cut into segments at its gaps (a step longer than `gap_factor` × its median
   period). In each segment q̇ and q̈ come from a Savitzky–Golay fit (``scipy.signal.savgol_filter``,
   cubic over `derivative_window_s`: the encoders' noise differentiated twice sample to sample would
   swamp q̈), the model's SMR position is evaluated at every joint sample (`points(q, q̇, q̈)`, e.g.
   `hil.arm.dynamics.MovingArm.points`, whose deflection follows the inertial torques, each joint
   lagging by its lost motion to the side the stream shows it last moved) and
   interpolated in time by a cubic spline (``scipy.interpolate.CubicSpline``). Evaluating the model once
   per joint sample, not per trial of the map, keeps a fit over 10⁵ points to seconds.
2. Tracker samples that cannot be trusted are left out, each with its reason counted (`ClockFit.left_out`):
   ``beam lost`` (no position), ``after a gap`` (the `relock_guard_s` after a hole in the tracker
   stream: a re-locked tracker's first points; 50 ms by default, an assumption — the TPI manual gives no
   settling time after FindReflector, and 50 samples at 1 kHz cost little), ``joint gap`` (mapped
   into a hole in the joint stream or outside it, or between two joint frames more than
   `cycle_factor` controller cycles apart: across a missed frame the joints are interpolated over
   motion the controller saw and the host did not — on a simulated station at load 2 the true arm
   joined with the true clock left 66 µm RMS with such samples and 17 µm without them; the cycle is
   the stream's 10th-percentile step, the controller's period where most frames arrive),
   ``acceleration`` (the joints' |q̈| beyond the quasi-static limit,
   `hil.arm.dynamics.DynamicsModel.acceleration_limit`, at that time), ``validation pose`` (the
   joints within `guard`'s radius of a pose the campaign validates on: a sweep that rests at its
   validation poses passes through them, and a fit that saw them would be judged on what it fitted).
3. A coarse scan of the offset (every `scan_step_s` over ±`scan_window_s` around a first guess: the
   streams' first stamps, i.e. recordings started together, unless given) finds the basin; then
   Gauss–Newton (``scipy.optimize.least_squares``, analytic Jacobian: ∂r/∂a = −ṗ, ∂r/∂d = −ṗ·(t_trk −
   t_ref)) refines (a, d), with t_trk taken about its mean t_ref so the two are nearly uncorrelated.
   The trusted set is evaluated again at the solution and the fit repeated once if it changed.
4. Uncertainty: the Gauss–Newton covariance s²·(JᵀJ)⁻¹, s² the residuals' variance per coordinate.
   It is honest when the residual is white — noise and jitter; a model error that follows the path
   (a geometry off by more than the noise) is not white, and the stated σ is then too small. The
   residual RMS (`ClockFit.rms_m`) says which case a fit is in.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from itertools import pairwise

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import least_squares
from scipy.signal import savgol_filter

from hil.arm.joint_directions import directions_along
from hil.calibration.stream_clocks import ClockMap
from hil.errors import InputError

#: Model of the SMR's position: (q, q̇, q̈), each (N, 6), and the keyword ``directions`` (N, 6) (each
#: joint's side of its lost motion, `hil.arm.joint_directions`) → (N, 3) in the tracker's frame (metres).
PointsFn = Callable[..., np.ndarray]
#: The largest |q̈| (rad/s², (N, 6)) the deflection model is trusted to at configurations (N, 6).
AccelerationLimitFn = Callable[[np.ndarray], np.ndarray]

REASONS = ("beam lost", "after a gap", "joint gap", "acceleration", "validation pose")


@dataclass(frozen=True)
class JointStream:
    """The controller's stream: stamps t (N,) on its clock (s) and joint angles q (N, 6) (rad)."""

    t: np.ndarray
    q: np.ndarray

    def __post_init__(self) -> None:
        t, q = np.asarray(self.t, dtype=float), np.asarray(self.q, dtype=float)
        if t.ndim != 1 or q.shape != (len(t), 6):
            raise InputError(f"joint stream: expected t (N,) and q (N, 6), got {t.shape} and {q.shape}")
        if len(t) < 2 or not np.all(np.diff(t) > 0) or not np.isfinite(q).all():
            raise InputError("joint stream: stamps must increase strictly and every q be finite "
                             f"({len(t)} samples)")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "q", q)


@dataclass(frozen=True)
class TrackerStream:
    """The tracker's stream: stamps t (M,) on its clock (s), points p (M, 3) (m; a NaN row: lost)."""

    t: np.ndarray
    p: np.ndarray

    def __post_init__(self) -> None:
        t, p = np.asarray(self.t, dtype=float), np.asarray(self.p, dtype=float)
        if t.ndim != 1 or p.shape != (len(t), 3):
            raise InputError(f"tracker stream: expected t (M,) and p (M, 3), got {t.shape} and {p.shape}")
        if len(t) < 2 or not np.all(np.diff(t) > 0):
            raise InputError(f"tracker stream: stamps must increase strictly ({len(t)} samples)")
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "p", p)


@dataclass(frozen=True)
class ClockFit:
    """The estimated map t_ctrl = offset_s + (1 + drift)·t_trk and how well the data fix it.

    `covariance` is of (offset_s, drift); `t_ref` the tracker time the fit was centred on, where the
    offset is known best (`sigma_at_ref_s`). `left_out` counts the tracker samples not used, by reason."""

    offset_s: float
    drift: float
    covariance: np.ndarray
    t_ref: float
    sigma_at_ref_s: float
    rms_m: float
    used: int
    left_out: dict[str, int] = field(default_factory=dict)

    @property
    def map(self) -> ClockMap:
        return ClockMap(self.offset_s, self.drift)

    @property
    def sigma_offset_s(self) -> float:
        return float(np.sqrt(self.covariance[0, 0]))

    @property
    def sigma_drift(self) -> float:
        return float(np.sqrt(self.covariance[1, 1]))

    @property
    def drift_ppm(self) -> float:
        return self.drift * 1e6

    def sync_error_at(self, t_trk: np.ndarray | float, truth: ClockMap) -> np.ndarray:
        """Seconds by which this map misplaces tracker time(s) `t_trk` against a true map."""
        return self.map(t_trk) - truth(t_trk)


def _segments(t: np.ndarray, gap_factor: float) -> list[slice]:
    """Runs of the joint stream without a step longer than gap_factor × the median period."""
    dt = np.diff(t)
    cuts = np.flatnonzero(dt > gap_factor * np.median(dt)) + 1
    bounds = [0, *cuts.tolist(), len(t)]
    return [slice(a, b) for a, b in pairwise(bounds)]


class StreamJoin:
    """The two streams prepared for joining: the model's path in controller time, the trust masks."""

    def __init__(self, joints: JointStream, tracker: TrackerStream, points: PointsFn,
                 acceleration_limit: AccelerationLimitFn | None = None, *, gap_factor: float = 2.5,
                 derivative_window_s: float = 0.05, relock_guard_s: float = 0.05,
                 cycle_factor: float = 1.5, guard: tuple[np.ndarray, float] | None = None) -> None:
        """`guard`: poses (V, 6) rad and a radius (rad, the largest joint difference) within which no
        tracker sample is used (``validation pose``, module docstring)."""
        self.joints, self.tracker = joints, tracker
        steps = np.diff(joints.t)
        # the longest step between two joint frames a sample may be interpolated across (module docstring)
        self._longest_step = cycle_factor * float(np.percentile(steps, 10)) if len(steps) else np.inf
        self.relock_guard_s = relock_guard_s
        self._splines: list[CubicSpline] = []
        self._spans: list[tuple[float, float]] = []
        self._fast: list[np.ndarray] = []  # per segment: (n,) True where |q̈| exceeds the limit
        self._near: list[np.ndarray] = []  # per segment: (n,) True within the guard of a validation pose
        self._seg_t: list[np.ndarray] = []
        # each joint's side of its lost motion, the stream read in order as one (`directions_along`),
        # kept for a fit that evaluates the stream again (`hil.calibration.sweep_fit`)
        self.signs = signs = directions_along(joints.q)
        for seg in _segments(joints.t, gap_factor):
            t, q = joints.t[seg], joints.q[seg]
            period = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
            # at least 5 samples, the fewest a cubic Savitzky–Golay fit takes (a joint stream read
            # more sparsely than the window wants: a simulated controller in fast time)
            window = max(5, round(derivative_window_s / period) | 1) if period > 0 else 0
            if len(t) < max(window, 5):
                continue  # too short to differentiate: its tracker samples fall in a joint gap
            qd = savgol_filter(q, window, 3, deriv=1, delta=period, axis=0)
            qdd = savgol_filter(q, window, 3, deriv=2, delta=period, axis=0)
            p = np.asarray(points(q, qd, qdd, directions=signs[seg]), dtype=float)
            self._splines.append(CubicSpline(t, p, axis=0))
            self._spans.append((float(t[0]), float(t[-1])))
            fast = np.zeros(len(t), dtype=bool)
            if acceleration_limit is not None:
                fast = (np.abs(qdd) > np.asarray(acceleration_limit(q), dtype=float)).any(axis=1)
            self._fast.append(fast)
            self._near.append(_near(q, guard))
            self._seg_t.append(t)
        if not self._splines:
            raise InputError("joint stream: no stretch long enough to join (every segment shorter than "
                             f"the {derivative_window_s} s derivative window)")
        lost = ~np.isfinite(tracker.p).all(axis=1)
        dt = np.diff(tracker.t)
        # the first present sample after a hole (samples missing, or lost) starts a guard interval
        starts = ~lost & (np.r_[False, dt > gap_factor * np.median(dt)] | np.r_[False, lost[:-1]])
        after = np.zeros(len(tracker.t), dtype=bool)
        for i in np.flatnonzero(starts):
            after |= (tracker.t >= tracker.t[i]) & (tracker.t < tracker.t[i] + relock_guard_s)
        self._lost, self._after = lost, after & ~lost

    # ------------------------------------------------------------------ evaluation
    def _locate(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Segment index of each controller time (−1: in a gap or outside), whether too fast and
        whether near a guarded pose."""
        seg = np.full(len(tau), -1)
        fast = np.zeros(len(tau), dtype=bool)
        near = np.zeros(len(tau), dtype=bool)
        for k, ((a, b), ts, f, g) in enumerate(zip(self._spans, self._seg_t, self._fast, self._near,
                                                   strict=True)):
            inside = (tau >= a) & (tau <= b)
            if inside.any():  # between two frames a missed one apart: a joint gap too
                i = np.clip(np.searchsorted(ts, tau[inside], side="right") - 1, 0, len(ts) - 2)
                spaced = np.flatnonzero(inside)[(ts[i + 1] - ts[i]) > self._longest_step]
                inside[spaced] = False
            seg[inside] = k
            if (f.any() or g.any()) and inside.any():
                nearest = np.clip(np.searchsorted(ts, tau[inside]), 0, len(ts) - 1)
                fast[inside] = f[nearest]
                near[inside] = g[nearest]
        return seg, fast, near

    def trust(self, clock: ClockMap, among: np.ndarray | None = None) -> tuple[np.ndarray, dict[str, int]]:
        """(M,) which tracker samples the join may use under `clock`, and the others counted by reason
        (only those of `among`, (M,) bool, when given: the samples a fit did not use)."""
        seg, fast, near = self._locate(clock(self.tracker.t))
        counted = np.ones(len(seg), dtype=bool) if among is None else np.asarray(among, dtype=bool)
        reasons = Counter({r: 0 for r in REASONS})
        reasons["beam lost"] = int((self._lost & counted).sum())
        rest = ~self._lost
        reasons["after a gap"] = int((self._after & rest & counted).sum())
        rest &= ~self._after
        reasons["joint gap"] = int((rest & (seg < 0) & counted).sum())
        rest &= seg >= 0
        reasons["validation pose"] = int((rest & near & counted).sum())
        rest &= ~near
        reasons["acceleration"] = int((rest & fast & counted).sum())
        rest &= ~fast
        return rest, dict(reasons)

    def predicted(self, clock: ClockMap, which: np.ndarray | None = None, derivative: int = 0
                  ) -> np.ndarray:
        """(M, 3) the model's SMR position (or its time derivative) at each tracker sample mapped by
        `clock`; NaN where the mapped time is in no segment."""
        tau = clock(self.tracker.t if which is None else self.tracker.t[which])
        seg, _, _ = self._locate(tau)
        out = np.full((len(tau), 3), np.nan)
        for k, spline in enumerate(self._splines):
            m = seg == k
            if m.any():
                out[m] = spline(tau[m], derivative)
        return out

    def residuals(self, clock: ClockMap) -> np.ndarray:
        """(M, 3) measured − predicted point of every tracker sample under `clock` (m); NaN where a
        sample is lost or has no joints to pair with. Untrusted samples are not masked here."""
        return self.tracker.p - self.predicted(clock)

    # ------------------------------------------------------------------ the fit
    def fit(self, initial_offset_s: float | None = None, *, initial_drift: float = 0.0,
            scan_window_s: float = 0.25, scan_step_s: float = 0.002) -> ClockFit:
        """Estimate the map (module docstring, steps 3 and 4). An `InputError` when too few trusted
        samples remain (fewer than 10) to fix two parameters.

        `initial_drift` is where Gauss–Newton starts and the scan's fixed drift: 0 for two quartzes,
        speed − 1 for a fast-time simulated station, whose tracker clock runs speed times slower
        than its controller's (`mocks.emscon.server`)."""
        t_trk = self.tracker.t
        t_ref = float(np.mean(t_trk))
        a0 = (float(self.joints.t[0] - (1.0 + initial_drift) * t_trk[0]) if initial_offset_s is None
              else float(initial_offset_s))
        offsets = a0 + np.arange(-scan_window_s, scan_window_s + scan_step_s / 2, scan_step_s)
        scores = [self._score(ClockMap(a, initial_drift)) for a in offsets]
        if not np.isfinite(scores).any():
            raise InputError("stream join: the streams do not overlap in time near the first guess "
                             f"(offset {a0:.3f} s ± {scan_window_s} s)")
        guess = ClockMap(float(offsets[int(np.nanargmin(scores))]), initial_drift)
        used, left = self.trust(guess)
        for _ in range(3):
            x = self._refine(guess, used, t_ref)
            guess = ClockMap(x[0] - (1.0 + x[1]) * t_ref, x[1])
            again, left = self.trust(guess)
            if np.array_equal(again, used):
                break
            used = again
        return self._result(guess, used, left, t_ref)

    def _score(self, clock: ClockMap) -> float:
        """Mean squared residual over a thinned set of trusted samples (the coarse scan's measure)."""
        used, _ = self.trust(clock)
        idx = np.flatnonzero(used)[::10]
        if len(idx) < 10:
            return np.nan
        r = self.tracker.p[idx] - self.predicted(clock, idx)
        return float(np.nanmean(r**2))

    def _refine(self, clock: ClockMap, used: np.ndarray, t_ref: float) -> np.ndarray:
        idx = np.flatnonzero(used)
        if len(idx) < 10:
            raise InputError(f"stream join: only {len(idx)} trusted tracker samples; at least 10 needed")
        dt = self.tracker.t[idx] - t_ref
        p = self.tracker.p[idx]

        def clock_of(x: np.ndarray) -> ClockMap:
            return ClockMap(x[0] - (1.0 + x[1]) * t_ref, x[1])

        def fun(x: np.ndarray) -> np.ndarray:
            r = p - self.predicted(clock_of(x), idx)
            return np.nan_to_num(r, nan=0.0).ravel()  # a sample pushed off its segment counts nothing

        def jac(x: np.ndarray) -> np.ndarray:
            v = np.nan_to_num(self.predicted(clock_of(x), idx, derivative=1), nan=0.0)
            return np.column_stack([-v.ravel(), -(v * dt[:, None]).ravel()])

        x0 = np.array([clock.offset_s + (1.0 + clock.drift) * t_ref, clock.drift])
        sol = least_squares(fun, x0, jac=jac, method="lm", x_scale=np.array([1e-3, 1e-5]))
        return sol.x

    def _result(self, clock: ClockMap, used: np.ndarray, left: dict[str, int], t_ref: float) -> ClockFit:
        idx = np.flatnonzero(used)
        r = self.tracker.p[idx] - self.predicted(clock, idx)
        ok = np.isfinite(r).all(axis=1)
        r, idx = r[ok], idx[ok]
        v = self.predicted(clock, idx, derivative=1)
        dt = self.tracker.t[idx] - t_ref
        J = np.column_stack([-v.ravel(), -(v * dt[:, None]).ravel()])
        dof = max(r.size - 2, 1)
        s2 = float(np.sum(r**2)) / dof
        cov_ref = s2 * np.linalg.inv(J.T @ J)  # of (offset at t_ref, drift)
        # offset_s = a_ref − (1 + d)·t_ref: ∂/∂a_ref = 1, ∂/∂d = −t_ref
        T = np.array([[1.0, -t_ref], [0.0, 1.0]])
        return ClockFit(clock.offset_s, clock.drift, T @ cov_ref @ T.T, t_ref,
                        float(np.sqrt(cov_ref[0, 0])), float(np.sqrt(np.mean(np.sum(r**2, axis=1)))),
                        len(idx), left)


def _near(q: np.ndarray, guard: tuple[np.ndarray, float] | None) -> np.ndarray:
    """(n,) True where joints `q` (n, 6) lie within the guard's radius of one of its poses."""
    if guard is None or len(guard[0]) == 0:
        return np.zeros(len(q), dtype=bool)
    poses, radius = np.asarray(guard[0], dtype=float).reshape(-1, 6), float(guard[1])
    out = np.zeros(len(q), dtype=bool)
    for v in poses:  # a few validation poses: a loop keeps memory at (n, 6)
        out |= np.max(np.abs(q - v), axis=1) < radius
    return out


def join_streams(joints: JointStream, tracker: TrackerStream, points: PointsFn,
                 acceleration_limit: AccelerationLimitFn | None = None,
                 initial_offset_s: float | None = None) -> ClockFit:
    """Estimate t_ctrl = a + (1 + d)·t_trk from the two streams and a model of the arm (`StreamJoin`)."""
    return StreamJoin(joints, tracker, points, acceleration_limit).fit(initial_offset_s)
