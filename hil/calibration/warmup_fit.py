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
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.optimize

#: Fewest reference measurements the fit needs (three parameters per axis plus τ, and one to judge it).
MIN_POINTS = 4
#: Joint temperatures that moved less than this (K) over the series say nothing about τ (RTDE reports
#: them as doubles; a real joint's sensor resolves about 0.1 K).
MIN_TEMPERATURE_SPAN = 0.3


@dataclass(frozen=True)
class DriftFit:
    """The fitted warm-up: time constant (s), drift still to come (m), and the fit's residual RMS (m)."""

    time_constant: float
    remaining: float
    rms: float
    total: float  # drift from the first reference measurement to the fitted steady state (m)

    def as_dict(self) -> dict[str, float]:
        return {"time_constant": self.time_constant, "remaining": self.remaining, "rms": self.rms,
                "total": self.total}


def fit_warmup(times: np.ndarray, points: np.ndarray, tau_range: tuple[float, float] = (30.0, 7200.0),
               temperatures: np.ndarray | None = None) -> DriftFit | None:
    """Fit d(t) = a + b·exp(−t/τ) to reference positions `points` (N, 3) at `times` (N,) seconds.

    None with fewer than `MIN_POINTS` measurements. τ is searched in `tau_range` (log scale): a warm-up
    faster than half a minute is not seen between reference checks, one slower than two hours is not a
    warm-up a campaign waits for. `temperatures` (N,) or (N, joints), °C: τ from their mean (module
    docstring).
    """
    t = np.asarray(times, dtype=float)
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(t) < MIN_POINTS or np.ptp(t) <= 0:
        return None
    t = t - t[0]

    def solve(log_tau: float, Y: np.ndarray) -> tuple[float, np.ndarray]:
        A = np.column_stack([np.ones_like(t), np.exp(-t / np.exp(log_tau))])
        coef, *_ = np.linalg.lstsq(A, Y, rcond=None)
        r = Y - A @ coef
        return float(np.sum(r * r)), coef

    Y = P
    if temperatures is not None:
        T = np.asarray(temperatures, dtype=float).reshape(len(t), -1).mean(axis=1, keepdims=True)
        if np.ptp(T) > MIN_TEMPERATURE_SPAN:
            Y = T
    lo, hi = np.log(tau_range[0]), np.log(tau_range[1])
    grid = np.linspace(lo, hi, 41)  # the cost is not unimodal in τ at few points: grid, then refine
    best = grid[int(np.argmin([solve(g, Y)[0] for g in grid]))]
    step = grid[1] - grid[0]
    res = scipy.optimize.minimize_scalar(lambda g: solve(g, Y)[0], bounds=(max(lo, best - step),
                                         min(hi, best + step)), method="bounded")
    cost, coef = solve(float(res.x), P)
    tau = float(np.exp(res.x))
    b = coef[1]
    remaining = float(np.linalg.norm(b) * np.exp(-t[-1] / tau))
    total = float(np.linalg.norm(b))
    return DriftFit(tau, remaining, float(np.sqrt(cost / len(t))), total)
