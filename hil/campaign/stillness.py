"""When a window of tracker readings says the SMR is still: the rule `SettleMeasure` settles by.

After a move a UR's links ring: the SMR oscillates about where the joints put it and the oscillation
dies away over a few tenths of a second (the simulator's mode, `mocks.ringing`: 9 Hz, time constant
0.18 s, from published modal tests of lightweight arms; Universal Robots' own input-shaping work,
Thomsen et al., ICINCO 2019, is about suppressing exactly these low, configuration-dependent modes).
The encoders do not see it, so only the tracker's readings can say when it is over.

A window of readings is still when both hold, per axis:

* **they agree within `stability`**: the largest reading minus the smallest (the range), not their
  standard deviation. "Agree within 50 µm" said of five readings whose standard deviation is 50 µm
  lets one of them be 110 µm off the others (the deviation of one outlier among n is diluted by
  √n), and that outlier is the first reading after a stop, still ringing;
* **they do not drift**: the mean of the window's older half and the mean of its newer half differ by
  at most half of `stability`. A decaying ring read at about its own period (a reading every 0.1 s
  against a 0.11 s period) shows no oscillation, only an envelope shrinking towards the rest
  position: readings that agree within the range but fall steadily, whose mean is still displaced by
  the part of the ring they average. Half: noise alone must almost never trip it, since a refused
  window costs a reading and a loaded station's readings can be seconds apart against
  ``robot.settle_max``. One AT960 reading scatters by 7.5 µm (`hil.calibration.tracker_noise`), so a
  half mean of five by about 7 µm per axis, and 25 µm (the default's half) is 3.5σ: about one still
  window in 2000 is refused. Against the simulator's ring (tests/hil/campaign/test_stillness.py) the
  first window accepted carries at most about 25 µm of ring, where the standard deviation alone let
  up to 64 µm through.

Both are judged on the window alone, with no minimum wait: a still arm is measured at once.

**The range limit scales with the window.** `stability` is the range allowed to a window of
`REFERENCE_WINDOW` readings (``campaign.samples``' default, what the figures above were measured with).
The range of n readings of one noise σ grows with n: its expectation is d₂(n)·σ (the control-chart
constant of the range, d₂(5) = 2.326, d₂(20) = 3.735: e.g. Montgomery, *Introduction to Statistical
Quality Control*, appendix table VI), so a window of n readings may spread by
``stability · d₂(n)/d₂(5)``: the same chance of refusing a still window of noise alone whatever its
length. A fixed range refused still windows of twenty readings (the drift watch's reference, 69–102 µm
of GeoCOM noise against 50 µm) and so refused still arms for ever. The drift between the halves keeps
its limit: their means get steadier as the window grows.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache

import numpy as np

#: The drift allowed between the window's older and newer half, as a fraction of `stability` (module
#: docstring).
DRIFT_FRACTION = 0.5
#: The window length `stability` is the range limit of (``campaign.samples``' default; module docstring).
REFERENCE_WINDOW = 5


@cache
def range_factor(n: int) -> float:
    """d₂(n): the expected range of `n` readings of unit σ, ∫ 1 − Φ(x)ⁿ − (1 − Φ(x))ⁿ dx over x."""
    if n < 2:
        raise ValueError("a stillness window needs at least two readings")
    from scipy import integrate, stats  # on first use: the engine's importers need no scipy before it

    value, _ = integrate.quad(lambda x: 1.0 - stats.norm.cdf(x) ** n - stats.norm.sf(x) ** n,
                              -np.inf, np.inf)
    return float(value)


def range_limit(n: int, stability: float) -> float:
    """The range (m, per axis) a still window of `n` readings may have (module docstring)."""
    return float(stability) * range_factor(int(n)) / range_factor(REFERENCE_WINDOW)


@dataclass(frozen=True)
class Stillness:
    """The verdict on one window: `still`, and its evidence per axis (metres)."""

    still: bool
    range: np.ndarray  # largest minus smallest reading
    range_limit: float  # the range allowed to this window's length (m, `range_limit`)
    drift: np.ndarray  # mean of the newer half minus mean of the older half
    spread: np.ndarray  # sample standard deviation (what a point reports as its spread)

    def describe(self, stability: float) -> str:
        """One line for an operator: the worst axis's range and drift against their limits."""
        drift_limit = DRIFT_FRACTION * stability
        return (f"range {float(self.range.max()) * 1e6:.1f} µm (limit {self.range_limit * 1e6:.1f}), drift "
                f"{float(np.abs(self.drift).max()) * 1e6:.1f} µm (limit {drift_limit * 1e6:.1f})")


def judge(window: np.ndarray, stability: float) -> Stillness:
    """Whether the readings of `window` ((n, 3), oldest first, n ≥ 2) show a still SMR (module docstring)."""
    P = np.asarray(window, dtype=float)
    if P.ndim != 2 or len(P) < 2:
        raise ValueError("a stillness window needs at least two readings")
    half = len(P) // 2
    spread = P.std(axis=0, ddof=1)
    extent = np.ptp(P, axis=0)
    drift = P[-half:].mean(axis=0) - P[:half].mean(axis=0)
    limit = range_limit(len(P), stability)
    still = bool(np.all(extent <= limit) and np.all(np.abs(drift) <= DRIFT_FRACTION * stability))
    return Stillness(still, extent, limit, drift, spread)
