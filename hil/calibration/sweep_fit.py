"""The sweep's fit: the kinematic parameters and the clock map identified together from the two streams.

A sweep records the controller's joints on its clock and the tracker's points on its own
(`hil.calibration.stream_join`). The join alone estimates the map t_ctrl = a + (1 + d)·t_trk against a
*given* model, and a model 40–170 µm off biases the offset by 3–180 µs (`bench/stream_sync.py`): the
model error that follows the path looks like a time shift. So the map is fitted *jointly* with the
model here (docs/design.md, the calibration campaign: the sweep mode):

    minimise  Σᵢ ‖pᵢ − p(θ; q(τᵢ), q̇(τᵢ), q̈(τᵢ))‖² + Σ_static ‖p − p(θ; q)‖² + prior(θ),
    τᵢ = a_ref + (1 + d)·(t_trkᵢ − t_ref)

with θ the same identifiable set as `hil.calibration.identification.identify` (geometry, compliance,
the joint-error terms asked for) and the same MAP prior (`hil.calibration.prior`, its weights σ̂²/τ²
iterated with the noise σ̂ the fit finds), and the two clock columns beside the identification
Jacobian: ∂p/∂a_ref = ṗ and ∂p/∂d = ṗ·(t_trk − t_ref), ṗ = Σⱼ ∂p/∂q_j · q̇_j the model's SMR velocity
(∂p/∂q_j is the identification Jacobian's joint-j rz column: a rotation about a joint origin's z axis
is that joint's rotation). t_ref is the used samples' mean tracker time, so a_ref and d are nearly
uncorrelated; the result reports the map as `ClockFit` (offset at t_trk = 0, covariance transformed).

The model of a moving arm deflects under the inertial torques (`hil.arm.dynamics`): q_link = q −
c ⊙ τ(q, q̇, q̈), and the compliance columns are ∂p/∂q_j · (−τ_j) — the static columns with τ for g
(`Kinematics.point_and_jacobian(..., torques=τ)`). τ is evaluated on the current geometry's dynamics
at every evaluation. q̇ and q̈ come from a Savitzky–Golay fit of the joint stream (as the join's, cubic
over 50 ms), q, q̇ and q̈ interpolated to τᵢ by a cubic spline per gap-free segment. A moving joint
lags by its lost motion as a standing one does, to the side it last moved (the contract's rule,
`hil.arm.joint_directions`): each sample takes the directions the joint stream shows at τᵢ, so the
lost-motion columns are the stream's own and its reversals identify them, still rows or none.

Steps (`fit_sweep`):

1. `StreamJoin` with the start model (the static bootstrap's first fit) gives the first clock (its
   coarse scan finds the basin) and which tracker samples can be trusted: beam lost, just after a
   re-lock, mapped into a joint-stream gap, beyond the quasi-static acceleration limit — counted by
   reason.
2. A subsample of the trusted samples, evenly spaced in time (`SAMPLES`, 3000 by default: the 27–31
   parameters and the clock are then determined by 9000 rows, and the statistical error of a
   prediction falls below a micrometre — σ ≈ 10 µm per axis over √3000 per parameter direction —
   while a Levenberg–Marquardt evaluation stays at a fraction of a second; every sample more adds
   time, not accuracy, since the model's own errors dominate then).
3. Levenberg–Marquardt over θ (a multiplicative SE(3) step, `apply_update`, as `identify`) and
   (a_ref, d) (additive), with the MAP prior from the start (its weights σ̂²/τ² from the join's residual
   at first, then from the fit's σ̂ until the two agree to 2 %). `identify` runs a plain least-squares
   fit first to judge outliers; here, without the prior, the near-degenerate joint-error directions
   made it creep for a hundred iterations (9000 rows each), and a stream's outliers are left out by
   reason instead. The static poses are ordinary rows (their clock columns zero, their deflection
   gravity's, their lost motion by their approach directions).
4. The trusted set is evaluated again under the fitted clock; when it changed, steps 2–3 run once more.

No outlier test: a stream's outliers are its beam breaks and re-locks, which step 1 leaves out by
reason; the leave-one-out F test of `identify` judges poses, not thousands of correlated samples.
The covariance is σ̂²·(JᵀJ + W)⁻¹ with a white residual assumed — honest when the model's error is below
the noise, which the joint fit is there to achieve; `rms_m` shows which case a fit is in.
"""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.signal import savgol_filter

from hil.arm.dynamics import DEFAULT_TOLERANCE_RAD, DynamicsModel, MovingArm
from hil.arm.geometry import Geometry
from hil.arm.joint_directions import directions_along
from hil.arm.kinematics import N_ALL_PARAMETERS, Kinematics, apply_update, deviation_from
from hil.calibration.identification import (
    PRIOR_PASSES,
    FitResult,
    IdentificationError,
    _parameters,
    _PriorRows,
    _statistics,
)
from hil.calibration.measurements import Measurements
from hil.calibration.prior import manufacturing_prior
from hil.calibration.stream_clocks import ClockMap
from hil.calibration.stream_join import ClockFit, JointStream, StreamJoin, TrackerStream, _segments
from hil.errors import InputError

#: Tracker samples the fit uses (module docstring, step 2).
SAMPLES = 3000
#: The left-out reason of a trusted sample the even subsample of `SAMPLES` passed over.
THINNED = "thinned"
#: Savitzky–Golay window for q̇ and q̈ (s), and the gap rule: the join's (`StreamJoin`'s defaults).
DERIVATIVE_WINDOW_S = 0.05
GAP_FACTOR = 2.5
MAX_ITER = 60
#: The LM stops when a step lowers the cost by less than this fraction: the RMS then moves by half of it,
#: 5·10⁻¹⁰ of ~20 µm, far below anything a validation can see. (`identify`'s 10⁻¹² costs a sweep's
#: 9000 rows tens of iterations creeping along the prior-flattened valleys of the joint-error terms.)
RELATIVE_DROP = 1e-9


@dataclass
class SweepFit:
    """What the joint fit found: the model, the clock map, and which samples it used."""

    geometry: Geometry  # identified (the same Geometry type `identify` returns)
    clock: ClockFit  # t_ctrl = a + (1 + d)·t_trk with its covariance
    used: int  # tracker samples used
    left_out: dict[str, int] = field(default_factory=dict)  # by reason (`stream_join.REASONS`)
    rms_m: float = 0.0  # RMS of the 3-D residuals of the stream samples used (m)
    fit: FitResult | None = None  # the identification's statistics (static rows first in it)
    trusted: int = 0  # tracker samples that could have been used (the subsample's population)
    iterations: int = 0


class _JointPath:
    """q, q̇, q̈ of the joint stream at any controller time inside a gap-free segment."""

    def __init__(self, joints: JointStream, signs: np.ndarray | None = None) -> None:
        """`signs`: the stream's directions of motion (`directions_along(joints.q)`) when known."""
        self._splines: list[CubicSpline] = []
        self._spans: list[tuple[float, float]] = []
        for seg in _segments(joints.t, GAP_FACTOR):
            t, q = joints.t[seg], joints.q[seg]
            if len(t) < 5:
                continue
            period = float(np.median(np.diff(t)))
            window = max(5, round(DERIVATIVE_WINDOW_S / period) | 1)  # a cubic fit takes 5 at least
            if len(t) < window:
                continue
            qd = savgol_filter(q, window, 3, deriv=1, delta=period, axis=0)
            qdd = savgol_filter(q, window, 3, deriv=2, delta=period, axis=0)
            self._splines.append(CubicSpline(t, np.hstack([q, qd, qdd]), axis=0))
            self._spans.append((float(t[0]), float(t[-1])))
        if not self._splines:
            raise InputError("sweep fit: the joint stream has no gap-free stretch long enough to "
                             f"differentiate ({DERIVATIVE_WINDOW_S} s)")
        self.first = joints.q[0]
        # each joint's side of its lost motion after each frame, the stream read in order as one
        # (a jump across a gap turns a joint as the unrecorded move between did)
        self._t = np.asarray(joints.t, float)
        self._signs = directions_along(joints.q) if signs is None else np.asarray(signs, float)

    def directions(self, tau: np.ndarray) -> np.ndarray:
        """(M, 6) each joint's direction of motion at controller times τ (the last frame's at or before)."""
        k = np.clip(np.searchsorted(self._t, tau, side="right") - 1, 0, len(self._t) - 1)
        return self._signs[k]

    def at(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(q, q̇, q̈, inside): each (M, 6), and (M,) whether τ fell in a segment (else zeros)."""
        out = np.zeros((len(tau), 18))
        inside = np.zeros(len(tau), dtype=bool)
        for (a, b), spline in zip(self._spans, self._splines, strict=True):
            m = (tau >= a) & (tau <= b)
            if m.any():
                out[m] = spline(tau[m])
                inside |= m
        return out[:, :6], out[:, 6:12], out[:, 12:], inside


@dataclass
class _Problem:
    """The rows of one fit: stream samples (tracker time, point) and static poses."""

    robot: str
    path: _JointPath
    t: np.ndarray  # (n,) tracker stamps of the used samples
    p: np.ndarray  # (n, 3)
    t_ref: float
    static: Measurements | None
    idx: np.ndarray
    compliance: bool
    joint_errors: bool
    dynamics: bool

    def _state(self, geometry: Geometry, clock: np.ndarray
               ) -> tuple[Kinematics, np.ndarray, np.ndarray, np.ndarray | None, np.ndarray, np.ndarray]:
        """The kinematics, q, q̇, the deflecting torques (None: rigid), which samples are inside and
        each joint's direction of motion (its lost motion's side)."""
        tau = clock[0] + (1.0 + clock[1]) * (self.t - self.t_ref)
        q, qd, qdd, inside = self.path.at(tau)
        directions = self.path.directions(tau)
        q[~inside] = self.path.first  # a finite stand-in; the sample's rows are zeroed
        kin = Kinematics(geometry)
        torques = None
        if self.compliance or geometry.compliant:
            dyn = DynamicsModel(geometry, kin.gravity)
            torques = dyn.torques(q, qd, qdd) if self.dynamics else dyn.torques(q)
        return kin, q, qd, torques, inside, directions

    def residual(self, geometry: Geometry, clock: np.ndarray) -> np.ndarray:
        """(rows,) measured − model, static rows first: what an LM trial needs (no Jacobian)."""
        kin, q, _, torques, inside, directions = self._state(geometry, clock)
        exact = geometry.copy()
        exact.compliance, exact.joint_errors, exact.lost_motion = None, None, None
        q_link = kin._link_angles(q, directions, torques)
        r = self.p - Kinematics(exact).points(q_link)
        r[~inside] = 0.0
        if self.static is None:
            return r.ravel()
        return np.r_[(self.static.p - kin.points(self.static.q, directions=self.static.directions)).ravel(),
                     r.ravel()]

    def evaluate(self, geometry: Geometry, clock: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(residual (rows,), Jacobian (rows, len(idx) + 2)) at `geometry` and clock (a_ref, d)."""
        kin, q, qd, torques, inside, directions = self._state(geometry, clock)
        p, J = kin.point_and_jacobian(q, self.compliance, directions, self.joint_errors, torques)
        rz = np.arange(6) * 6 + 5
        pdot = np.einsum("nij,nj->ni", J[:, :, rz], qd)  # ∂p/∂q_j · q̇_j
        n = len(self.t)
        rows = np.zeros((n, 3, len(self.idx) + 2))
        rows[:, :, :-2] = J[:, :, self.idx]
        rows[:, :, -2] = pdot
        rows[:, :, -1] = pdot * (self.t - self.t_ref)[:, None]
        r = self.p - p
        r[~inside] = 0.0  # a sample pushed off its segment by a trial clock counts nothing
        rows[~inside] = 0.0
        r_all, J_all = r.ravel(), rows.reshape(-1, len(self.idx) + 2)
        if self.static is not None:
            ps, Js = kin.point_and_jacobian(self.static.q, self.compliance, self.static.directions,
                                            self.joint_errors)
            Jst = np.zeros((len(ps), 3, len(self.idx) + 2))
            Jst[:, :, :-2] = Js[:, :, self.idx]
            r_all = np.r_[(self.static.p - ps).ravel(), r_all]
            J_all = np.vstack([Jst.reshape(-1, len(self.idx) + 2), J_all])
        return r_all, J_all


def _lm(problem: _Problem, geometry: Geometry, clock: np.ndarray, prior: _PriorRows | None,
        max_iter: int) -> tuple[Geometry, np.ndarray, int, bool]:
    """Levenberg–Marquardt over θ (multiplicative, as `identify`'s) and the clock (additive)."""
    k = len(problem.idx)
    width = Kinematics(geometry).point_and_jacobian(np.zeros((1, 6)), problem.compliance, None,
                                                    problem.joint_errors)[1].shape[2]

    def cost_of(r: np.ndarray, g: Geometry) -> float:
        return float(r @ r) + (prior.cost(g, problem.compliance) if prior else 0.0)

    r, J = problem.evaluate(geometry, clock)
    cost = cost_of(r, geometry)
    lam = 1e-3
    for it in range(1, max_iter + 1):
        A = J.T @ J
        g = J.T @ r
        if prior is not None:
            A[:k, :k] += np.diag(prior.weights)
            g[:k] -= prior.weights * prior.offset(geometry, problem.compliance)
        D = np.maximum(np.diag(A), 1e-30)
        improved = False
        while lam < 1e12:
            step = np.linalg.solve(A + lam * np.diag(D), g)
            full = np.zeros(width)
            full[problem.idx] = step[:k]
            cand_g, cand_c = apply_update(geometry, full), clock + step[k:]
            r_c = problem.residual(cand_g, cand_c)
            cost_c = cost_of(r_c, cand_g)
            if cost_c < cost:
                improved = True
                break
            lam *= 4.0
        if not improved:
            return geometry, clock, it, True
        drop = cost - cost_c
        geometry, clock, cost = cand_g, cand_c, cost_c
        r, J = problem.evaluate(geometry, clock)
        lam = max(lam / 3.0, 1e-12)
        if drop <= RELATIVE_DROP * cost + 1e-30 or np.max(np.abs(step) * np.sqrt(D)) < 1e-12:
            return geometry, clock, it, True
    return geometry, clock, max_iter, False


def _streams_sha256(joints: JointStream, tracker: TrackerStream, static: Measurements | None) -> str:
    """The data's fingerprint, so a model names what it was fitted to (as `identify`'s)."""
    h = hashlib.sha256()
    for a in (joints.t, joints.q, tracker.t, tracker.p, *(() if static is None else (static.q, static.p))):
        h.update(np.ascontiguousarray(a, dtype=float).tobytes())
    return h.hexdigest()


def _subsample(trusted: np.ndarray, count: int) -> np.ndarray:
    idx = np.flatnonzero(trusted)
    if len(idx) <= count:
        return idx
    return idx[np.unique(np.linspace(0, len(idx) - 1, count).round().astype(int))]


def without_intervals(tracker: TrackerStream, intervals: Sequence[tuple[float, float]]) -> TrackerStream:
    """`tracker` less its samples stamped inside any of `intervals` ((start, end) on the tracker's clock,
    s, ends included): the stretches a fit must not see — a sweep campaign's validation rests, whose
    poses must stay poses the fit never saw, so the validation means what a stop-and-go one does. The
    hole each leaves is a gap to the join (the 50 ms after it are left out as "after a gap")."""
    keep = np.ones(len(tracker.t), dtype=bool)
    for a, b in intervals:
        if not (np.isfinite(a) and np.isfinite(b) and a <= b):
            raise InputError(f"sweep fit: an interval to leave out must be finite with start ≤ end, got "
                             f"({a}, {b})")
        keep &= ~((tracker.t >= a) & (tracker.t <= b))
    if keep.sum() < 2:
        raise InputError("sweep fit: the intervals left out cover the whole tracker stream")
    return TrackerStream(tracker.t[keep], tracker.p[keep])


def fit_sweep(start: Geometry, joints: JointStream, tracker: TrackerStream, *,
              static: Measurements | None = None, compliance: bool = True,
              initial_offset_s: float | None = None, dynamics: bool = True,
              joint_errors: Sequence[int] = (), prior: bool = True, samples: int = SAMPLES,
              initial_drift: float = 0.0, max_iter: int = MAX_ITER,
              acceleration_tolerance_rad: float | None = DEFAULT_TOLERANCE_RAD,
              guard: tuple[np.ndarray, float] | None = None) -> SweepFit:
    """Fit the kinematic parameters and the clock map together (module docstring).

    `start` is the first model (the static bootstrap's fit: tracker pose, SMR, payload, mounting);
    its compliance (or, when it has none and `compliance` is set, zero) is where the fit starts.
    `static` poses are added as ordinary rows. `dynamics` False deflects the moving arm by gravity
    alone (c ⊙ g(q), the static contract) — to show what the inertial torques are worth.
    `joint_errors` as `identify`'s; the lost-motion terms are identified by the stream's reversals
    (each sample lags to the side its joints last moved) and by any `static` rows' directions.
    `initial_offset_s`/`initial_drift` seed the join's coarse scan. `acceleration_tolerance_rad` is
    the ring the quasi-static deflection may leave out (`DynamicsModel.acceleration_limit`); None
    trusts every acceleration (a benchmark's question, not a station's). `guard` (poses (V, 6), a
    radius in rad): no tracker sample whose joints lie that near one of the poses is used — the
    validation poses a tour rests at (`hil.calibration.stream_join`, ``validation pose``).
    """
    robot = start.robot
    if not isinstance(robot, str):
        raise InputError("sweep fit: only catalog UR arms (their dynamics are modelled)")
    if samples < 50:
        raise InputError(f"sweep fit: samples must be at least 50, got {samples}")
    geometry = start.copy()
    if compliance and geometry.compliance is None:
        geometry.compliance = np.zeros(6)
    idx = _parameters(robot, compliance, geometry, joint_errors)
    extended = bool(np.any(idx >= N_ALL_PARAMETERS))
    limit_model = geometry.copy()
    if limit_model.compliance is None or not np.any(limit_model.compliance):
        from hil.arm.physical import typical_compliance

        limit_model.compliance = typical_compliance(robot)  # the limit needs a compliance's order
    points = (MovingArm(geometry).points if dynamics
              else (lambda q, qd, qdd, directions=None: MovingArm(geometry).points(q, directions=directions)))
    limits, ring = DynamicsModel(limit_model), acceleration_tolerance_rad
    join = StreamJoin(joints, tracker, points,
                      None if ring is None else (lambda q: limits.acceleration_limit(q, ring)), guard=guard)
    first = join.fit(initial_offset_s, initial_drift=initial_drift)
    path = _JointPath(joints, join.signs)
    clock_map = first.map
    iterations = 0
    trusted, left = join.trust(clock_map)
    rows_sigma: float | None = None
    for _ in range(2):
        use = _subsample(trusted, samples)
        if len(use) < 10:
            raise InputError(f"sweep fit: only {len(use)} trusted tracker samples; at least 10 needed")
        t_ref = float(np.mean(tracker.t[use]))
        problem = _Problem(robot, path, tracker.t[use], tracker.p[use], t_ref, static, idx, compliance,
                           extended, dynamics)
        clock = np.array([float(clock_map(t_ref)), clock_map.drift])
        rows = None
        if prior:
            # no plain least-squares pass first (`identify` runs one to judge outliers, which a stream's
            # are not): without the prior the near-degenerate joint-error directions make it creep for
            # a hundred iterations. σ̂ starts at the join's residual per axis and is iterated to agreement.
            tolerance = manufacturing_prior(robot, idx)
            sigma2 = (first.rms_m if rows_sigma is None else rows_sigma) ** 2 / 3.0
            for _pass in range(PRIOR_PASSES + 2):
                rows = _PriorRows(Geometry.nominal(robot), tolerance, tolerance.weights(np.sqrt(sigma2)))
                geometry, clock, its, converged = _lm(problem, geometry, clock, rows, max_iter)
                iterations += its
                r, J = problem.evaluate(geometry, clock)
                _, new_sigma2, _ = _statistics(J, r, np.r_[rows.weights, 0.0, 0.0])
                settled = abs(new_sigma2 - sigma2) <= 0.02 * sigma2
                sigma2 = new_sigma2
                if settled:
                    break
            rows_sigma = float(np.sqrt(3.0 * sigma2))
        else:
            geometry, clock, its, converged = _lm(problem, geometry, clock, None, max_iter)
            iterations += its
            r, J = problem.evaluate(geometry, clock)
        k = len(idx)
        clock_map = ClockMap(clock[0] - (1.0 + clock[1]) * t_ref, clock[1])
        again, left = join.trust(clock_map)
        if np.array_equal(again[use], np.ones(len(use), dtype=bool)) or np.array_equal(again, trusted):
            trusted = again
            break
        trusted = again
    if not converged:
        raise IdentificationError(f"sweep fit: did not converge in {max_iter} iterations")
    # every tracker sample counted once: used, or left out for the reason the final clock gives it (a
    # trusted one the even subsample passed over: `THINNED`), so used + left out = the stream
    unused = np.ones(len(tracker.t), dtype=bool)
    unused[use] = False
    _, left = join.trust(clock_map, among=unused)
    left[THINNED] = int((trusted & unused).sum())
    weights = None if rows is None else np.r_[rows.weights, 0.0, 0.0]
    inv, sigma2, cond = _statistics(J, r, weights)
    cov = sigma2 * inv
    T = np.array([[1.0, -t_ref], [0.0, 1.0]])  # (a_ref, d) → (offset at t_trk = 0, d)
    cov_clock = cov[k:, k:]
    n_static = 0 if static is None else len(static)
    res_stream = r[3 * n_static:].reshape(-1, 3)
    rms_stream = float(np.sqrt(np.mean(np.sum(res_stream**2, axis=1))))
    clock_fit = ClockFit(clock_map.offset_s, clock_map.drift, T @ cov_clock @ T.T, t_ref,
                         float(np.sqrt(cov_clock[0, 0])), rms_stream, len(use), left)
    res = r.reshape(-1, 3)
    norms = np.linalg.norm(res, axis=1)
    cov_theta = cov[:k, :k]
    std = np.sqrt(np.maximum(np.diag(cov_theta), 0.0))
    values = deviation_from(Geometry.nominal(robot), geometry, compliance, extended)[idx]
    fit = FitResult(
        geometry=geometry, robot=robot, indices=idx, values=values, std=std, covariance=cov_theta,
        rms=float(np.sqrt(np.mean(norms**2))), max_error=float(norms.max()), sigma=float(np.sqrt(sigma2)),
        initial_rms=first.rms_m, iterations=iterations, condition=cond, residuals=res,
        used=np.ones(len(res), dtype=bool), source="sweep",
        sha256=_streams_sha256(joints, tracker, static), prior=None if rows is None else rows.prior,
        prior_weights=None if rows is None else rows.weights)
    return SweepFit(geometry, clock_fit, len(use), left, rms_stream, fit, int(trusted.sum()), iterations)
