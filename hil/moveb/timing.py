"""The feed profile: arc length against time under Cartesian velocity, acceleration and jerk limits
and the curvature's normal-acceleration (and normal-jerk) limits, sampled at the controller rate.

The method works on any sampled curvature profile κ(s), so the MOVEB curve and the baselines are
timed by the same code (the benchmark's "cycle time under the same limits").

1. A speed ceiling along s: v ≤ v_max, κ·v² ≤ a_n (normal acceleration) and |dκ/ds|·v³ ≤ j_max
   (the normal jerk of travelling a curvature change at speed v). dκ/ds is the difference of κ over
   one controller cycle's travel at full speed: a curvature *jump* (G1 blends) then costs what a
   controller really pays — the acceleration step must fit in a cycle — instead of depending on how
   finely the curve was sampled.
2. The ceiling is eroded so that the filter's time-averaging (step 4) cannot carry a higher speed
   into a curvature peak: every point s' with ceiling c' lowers the ceiling to c' over ±c'·T around
   it (T the jerk filter's length). Why that radius is enough: the filtered position at time t is
   the mean of the unfiltered one over [t − T, t], so when it is at s' the unfiltered motion spent
   that window on a stretch through s'; inside ±c'·T the unfiltered speed is ≤ c', so reaching the
   edge from s' takes ≥ T, the stretch lies inside, and the filtered speed (the mean of the
   unfiltered over the same window) is ≤ c'. A slow point thus only widens by its own (short)
   travel in T, not by v_max·T. Radii are grouped in levels 10 % apart, each applied at its level's
   largest radius (conservative), so the erosion costs a few min-filters.
3. Forward and backward passes under the tangential acceleration a_max (exact and vectorised:
   v²(s) = min over s' ≤ s of v_lim²(s') + 2a(s − s'), a cumulative minimum), at rest at both ends.
4. The speed is resampled in time at the controller period and smoothed with a moving average of
   length T = 2·a_max/j_max: a moving average of a profile bounded by v_max and a_max stays bounded
   by them, and its jerk is (a(t) − a(t − T))/T ≤ 2·a_max/T = j_max. The arc length is the integral
   (rescaled by < 1e-9 to end exactly at the curve's length).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from hil.errors import InputError
from hil.files.quantities import quantity


@dataclass(frozen=True)
class Limits:
    """Cartesian limits of the tool point (mm, s)."""

    velocity: float = 250.0  # mm/s
    acceleration: float = 2000.0  # mm/s², tangential
    jerk: float = 20000.0  # mm/s³, tangential and normal
    normal_acceleration: float = 2000.0  # mm/s², κ·v²

    def __post_init__(self) -> None:
        for name, row in (("velocity", "tool speed"), ("acceleration", "tool acceleration"),
                          ("jerk", "tool jerk"), ("normal_acceleration", "tool acceleration")):
            quantity(row).check(float(getattr(self, name)), f"limit {name}")


@dataclass(frozen=True)
class TimeLaw:
    """Arc length at the controller's samples: t[k] = k/rate, s[k] in mm."""

    t: np.ndarray
    s: np.ndarray
    rate_hz: float

    @property
    def cycle_time(self) -> float:
        return float(self.t[-1])

    @property
    def velocity(self) -> np.ndarray:
        return np.gradient(self.s, self.t)


def speed_ceiling(s: np.ndarray, kappa: np.ndarray, limits: Limits, rate_hz: float) -> np.ndarray:
    """Step 1 of the module docstring on a uniform grid `s`."""
    ds = s[1] - s[0]
    reach = max(round(limits.velocity / rate_hz / ds), 1)  # one cycle's travel at full speed
    pad = np.r_[np.full(reach, kappa[0]), kappa, np.full(reach, kappa[-1])]
    dk = np.abs(pad[2 * reach:] - pad[:-2 * reach]) / (2 * reach * ds)
    with np.errstate(divide="ignore"):
        v = np.minimum(limits.velocity, np.sqrt(limits.normal_acceleration / np.maximum(kappa, 1e-300)))
        v = np.minimum(v, np.cbrt(limits.jerk / np.maximum(dk, 1e-300)))
    return v


def erode_by_travel(vlim: np.ndarray, ds: float, horizon: float, step: float = 1.1) -> np.ndarray:
    """Step 2 of the module docstring: each point's ceiling c lowers its neighbours within c·horizon.

    Written by hand: scipy's min-filters take one window for all points, and this one varies with
    the ceiling. Points are grouped by radius in geometric levels (ratio `step`); each level is one
    `minimum_filter1d` at its largest radius, so a point may act a little (< `step`) wider than
    needed, never narrower. Points at the highest ceiling cannot lower anything and are skipped.
    """
    # imported here, not with the module: `Limits` is read by jobs that must refuse bad input fast
    # (a MOVEB run refuses a controller of another robot), and scipy.ndimage is a third of a second
    from scipy.ndimage import minimum_filter1d

    out = np.array(vlim, dtype=float)
    top = out.max()
    radius = np.ceil(out * horizon / ds).astype(np.int64)
    active = out < top
    if not active.any():
        return out
    r_lo, r_hi = int(radius[active].min()), int(radius[active].max())
    edges = [r_lo - 1]
    while edges[-1] < r_hi:
        edges.append(max(edges[-1] + 1, math.ceil(edges[-1] * step)))
    for lo, hi in itertools.pairwise(edges):
        level = active & (radius > lo) & (radius <= hi)
        if level.any():
            masked = np.where(level, vlim, np.inf)
            out = np.minimum(out, minimum_filter1d(masked, size=2 * hi + 1, mode="nearest"))
    return out


def feed_profile(s: np.ndarray, kappa: np.ndarray, limits: Limits, rate_hz: float,
                 ds: float | None = None, ceiling: tuple[np.ndarray, np.ndarray] | None = None) -> TimeLaw:
    """The time law of a curve given its curvature κ at arc lengths s (mm, 1/mm).

    `ceiling` (arc lengths, speeds in mm/s) is a further speed limit along the path, joined to step 1
    before the rest: the joint-speed ceiling of `hil.moveb.joints`.
    """
    s = np.asarray(s, float)
    length = float(s[-1] - s[0])
    if not length > 0:
        raise InputError("the path has zero length")
    if ds is None:
        ds = min(0.05, length / 1000.0)
    n = max(math.ceil(length / ds), 2)
    grid = np.linspace(0.0, length, n + 1)
    ds = grid[1]
    k = np.interp(grid, s - s[0], np.asarray(kappa, float))
    T = 2.0 * limits.acceleration / limits.jerk
    vlim = speed_ceiling(grid, k, limits, rate_hz)
    if ceiling is not None:
        cs, cv = (np.asarray(c, float) for c in ceiling)
        vlim = np.minimum(vlim, np.interp(grid, cs - s[0], cv))
    dt = 1.0 / rate_hz
    taps = max(round(T / dt), 1)
    vlim = erode_by_travel(vlim, ds, (taps + 1) * dt)  # the filter's true length, one sample spare
    vlim[0] = vlim[-1] = 0.0
    a = limits.acceleration
    v2 = vlim ** 2
    fwd = 2 * a * grid + np.minimum.accumulate(v2 - 2 * a * grid)
    bwd = -2 * a * grid + np.minimum.accumulate((v2 + 2 * a * grid)[::-1])[::-1]
    v = np.sqrt(np.maximum(np.minimum(fwd, bwd), 0.0))
    mean = 0.5 * (v[1:] + v[:-1])
    if np.any(mean <= 0):
        raise InputError("the feed profile stops inside the path (a limit is zero there)")
    t = np.r_[0.0, np.cumsum(ds / mean)]
    tc = np.arange(0.0, t[-1] + dt, dt)
    vc = np.interp(tc, t, v)
    vf = np.convolve(vc, np.full(taps, 1.0 / taps))
    sf = np.r_[0.0, np.cumsum(0.5 * (vf[1:] + vf[:-1]) * dt)]
    sf *= length / sf[-1]
    return TimeLaw(np.arange(len(sf)) * dt, sf, rate_hz)
