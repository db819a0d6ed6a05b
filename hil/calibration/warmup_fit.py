"""When has the arm warmed up? A first-order fit to a reference pose's drift.

A UR's joints warm up over tens of minutes and its aluminium links grow with them, so a reference SMR
position drifts along d(t) = a + b·exp(−t/τ) (a first-order warm-up: one time constant, each axis its
own amplitude). Comparing two consecutive reference measurements cannot tell the last micrometres of
drift from the tracker's noise (two 5-sample points of a 20 µm tracker already differ by ~10 µm), so
the warm-up is judged on the whole series instead: the three axes are fitted together (τ by a bounded
scalar search, a and b by linear least squares for each τ) and the drift still to come,
‖b‖·exp(−t_last/τ), is what the campaign compares with its limit. scipy does the search; the model is
written here because no library fits this exact shared-τ form.

When the controller reports its joint temperatures (RTDE ``joint_temperatures``) and they moved by
more than `MIN_TEMPERATURE_SPAN`, τ is fitted to their mean instead: they carry no tracker noise, so
the time constant (and with it "three time constants have passed") no longer hangs on micrometres of
noise — fitted to the positions alone, a noisy series can show a short τ and call the arm warm early.
The growth is still judged on the positions, with that τ.

A point estimate is not enough to stop on. On a noisy series (a realistic arm's reference reading
differs per visit by micrometres of repositioning; the tracker adds its own) the best τ jumps between
visits, and a short one makes both "three time constants have passed" and "little is still to come"
come true at once: a campaign on the realistic simulated UR5e stopped after 16 min with 0.2 µm "still to
come" while a third of its growth was ahead. So the fit also says what the data cannot rule
out: every τ whose profile cost is within the F bound of the best (a likelihood-ratio confidence set,
the residual variance estimated from the fit, so F rather than χ²), and for each the still-to-come
drift at the upper confidence limit of its amplitude (the linear least squares' covariance).
`remaining_upper` is the
largest of these and `time_constant_upper` the longest τ of the set; the campaign stops on those.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import scipy.optimize
import scipy.stats

#: Fewest reference measurements the fit needs (three parameters per axis plus τ, and one to judge it).
MIN_POINTS = 4
#: Joint temperatures that moved less than this (K) over the series say nothing about τ (RTDE reports
#: them as doubles; a real joint's sensor resolves about 0.1 K).
MIN_TEMPERATURE_SPAN = 0.3
#: Confidence of the upper limits (`DriftFit.remaining_upper`, `DriftFit.time_constant_upper`): one
#: chance in a hundred that more drift is still to come than the limit says (an assumption: the
#: campaign's cost of stopping too early — a model fitted on a still-growing arm — is the one to avoid,
#: and waiting one more interval costs only two minutes).
CONFIDENCE = 0.99
#: The temperature sensor's resolution (K) as the floor of the temperature fit's noise: a noise-free
#: simulated series would otherwise pin τ to a single value no real sensor could give (RTDE reports
#: doubles; a joint's sensor resolves about 0.1 K, as above).
TEMPERATURE_RESOLUTION = 0.1


#: Reference measurements (the last ones) over which flat joint temperatures say the arm is steady
#: (`temperatures_flat`): two whole intervals of the warm-up's cycling, so one quiet interval is not enough.
FLAT_POINTS = 3


def temperatures_flat(temperatures: np.ndarray | None, resolution: float = TEMPERATURE_RESOLUTION) -> bool:
    """Whether the joint temperatures of the last `FLAT_POINTS` measurements (rows: measurements, columns:
    joints, °C) all stayed within the sensor's `resolution`: evidence the arm is thermally steady.

    Why: an arm that was already warm when the warm-up began (it worked, or held itself, while hil
    bootstrapped and chose its poses) shows a flat series from which no time constant can be fitted,
    so "the series spans three time constants" is never proven and a warm arm would be cycled until
    ``max_time``. Its own flat temperatures say it is warm; the caller still asks the positions to agree.
    False without temperatures or with fewer than `FLAT_POINTS` rows.
    """
    if temperatures is None:
        return False
    T = np.asarray(temperatures, dtype=float)
    if T.ndim != 2 or len(T) < FLAT_POINTS:
        return False
    return bool(np.all(np.ptp(T[-FLAT_POINTS:], axis=0) < resolution))


@dataclass(frozen=True)
class DriftFit:
    """The fitted warm-up: time constant (s), drift still to come (m), and the fit's residual RMS (m),
    with the upper confidence limits (`CONFIDENCE`) of the drift still to come and of τ."""

    time_constant: float
    remaining: float
    rms: float
    total: float  # drift from the first reference measurement to the fitted steady state (m)
    remaining_upper: float = float("inf")  # the most drift still to come the data allow (m)
    time_constant_upper: float = float("inf")  # the longest τ the data allow (s)
    source: str = "positions"  # what τ was fitted to: "temperatures" (the joints') or "positions"

    def as_dict(self) -> dict[str, float | str]:
        return {"time_constant": self.time_constant, "remaining": self.remaining, "rms": self.rms,
                "total": self.total, "remaining_upper": self.remaining_upper,
                "time_constant_upper": self.time_constant_upper, "source": self.source}


def _solve(t: np.ndarray, tau: float, Y: np.ndarray) -> tuple[float, np.ndarray, float]:
    """Least squares of Y ≈ a + b·exp(−t/τ) at a given τ: the cost, the coefficients (2, k), and the
    factor (AᵀA)⁻¹ of b's variance (b's variance is that times the residual variance)."""
    A = np.column_stack([np.ones_like(t), np.exp(-t / tau)])
    coef, *_ = np.linalg.lstsq(A, Y, rcond=None)
    r = Y - A @ coef
    try:
        var_b = float(np.linalg.inv(A.T @ A)[1, 1])
    except np.linalg.LinAlgError:
        var_b = float("inf")
    return float(np.sum(r * r)), coef, var_b


def fit_warmup(times: np.ndarray, points: np.ndarray, tau_range: tuple[float, float] = (30.0, 7200.0),
               temperatures: np.ndarray | None = None, confidence: float = CONFIDENCE) -> DriftFit | None:
    """Fit d(t) = a + b·exp(−t/τ) to reference positions `points` (N, 3) at `times` (N,) seconds.

    None with fewer than `MIN_POINTS` measurements. τ is searched in `tau_range` (log scale): a warm-up
    faster than half a minute is not seen between reference checks, one slower than two hours is not a
    warm-up a campaign waits for. `temperatures` (N,) or (N, joints), °C: τ from their mean (module
    docstring). The upper limits at `confidence` come with the fit (module docstring); with too few
    measurements to estimate the noise they are infinite.
    """
    t = np.asarray(times, dtype=float)
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(t) < MIN_POINTS or np.ptp(t) <= 0:
        return None
    t = t - t[0]
    n = len(t)

    Y, floor, dof_y = P, 0.0, 3 * n - 7  # τ from the positions: a, b per axis and τ
    if temperatures is not None:
        T = np.asarray(temperatures, dtype=float).reshape(n, -1).mean(axis=1, keepdims=True)
        if np.ptp(T) > MIN_TEMPERATURE_SPAN:
            Y, floor, dof_y = T, TEMPERATURE_RESOLUTION ** 2 / 12.0, n - 3
    lo, hi = np.log(tau_range[0]), np.log(tau_range[1])
    grid = np.linspace(lo, hi, 81)  # the cost is not unimodal in τ at few points: grid, then refine
    costs = np.array([_solve(t, np.exp(g), Y)[0] for g in grid])
    best = grid[int(np.argmin(costs))]
    step = grid[1] - grid[0]
    res = scipy.optimize.minimize_scalar(lambda g: _solve(t, np.exp(g), Y)[0],
                                         bounds=(max(lo, best - step), min(hi, best + step)),
                                         method="bounded")
    tau = float(np.exp(res.x))
    cost_y = min(float(res.fun), float(costs.min()))
    cost, coef, _ = _solve(t, tau, P)
    b = coef[1]
    remaining = float(np.linalg.norm(b) * np.exp(-t[-1] / tau))
    total = float(np.linalg.norm(b))
    fit = DriftFit(tau, remaining, float(np.sqrt(cost / n)), total,
                   source="positions" if Y is P else "temperatures")
    dof_p = 3 * n - 6 - (1 if Y is P else 0)
    if dof_y <= 0 or dof_p <= 0:
        return fit
    # τ's confidence set: the profile cost within the F(1, dof) bound, the noise from the best fit
    # (the noise is estimated from few points, so F rather than χ² bounds: Student's correction)
    var_y = max(cost_y / dof_y, floor)
    allowed = cost_y + var_y * float(scipy.stats.f.ppf(confidence, 1, dof_y))
    taus = [tau, *np.exp(grid[costs <= allowed])]
    # each τ's still-to-come drift at the upper limit of its amplitude (three axes: 3·F(3, dof))
    k3 = float(np.sqrt(3.0 * scipy.stats.f.ppf(confidence, 3, dof_p)))
    upper = 0.0
    for s in taus:
        c, cf, var_b = _solve(t, float(s), P)
        sigma_b = float(np.sqrt(max(c, cost) / dof_p * var_b))
        upper = max(upper, (float(np.linalg.norm(cf[1])) + k3 * sigma_b) * float(np.exp(-t[-1] / s)))
    return dataclasses.replace(fit, remaining_upper=upper, time_constant_upper=float(max(taus)))
