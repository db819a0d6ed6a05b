"""Is the arm warm? The warm-up's stopping rule on one series of reference measurements, with its evidence.

Kept apart from the campaign (`hil.campaign.warmup` measures, this decides) so the rule can be replayed
on any series — a synthetic one whose truth is known, or a finished campaign's stored one — and so every
check can say *why* it went on or stopped: the fit (`hil.calibration.warmup_fit`), its time constant
and its upper limit, the drift still to come and its upper limit, how long the series is against
three of those time constants, and the flat-temperature evidence.

The rule (docs/design.md, Plans: warm up). The arm is warm when

* **the fit** says less than ``limit`` of drift is still to come over a series spanning three time
  constants, both at the fit's upper confidence limits (`DriftFit.remaining_upper`,
  `DriftFit.time_constant_upper`); or
* **the arm was warm already** (judged, as the fit, from the `MIN_POINTS`-th measurement on): its
  joint temperatures never moved by `MIN_TEMPERATURE_SPAN` over the
  whole series (no curve to fit a time constant to), stayed within the sensor's resolution over the
  last `FLAT_POINTS` measurements, and the reference moved less than ``limit`` among them.

The second rule is for an arm that starts warm and only for it. On a warming arm, temperatures flat to
0.1 K over two 2-minute intervals say little: near the end of a 15-minute warm-up they change by under
a quarter of what is still to come in those four minutes, so "flat" comes true with up to 0.43 K still
ahead — 8 µm of drift on a UR5e's reference (2.3e-5 /K over 0.8 m of arm), 13 µm on a UR10e's, more
than the 10 µm limit — while the reference's own motion among three visits (a quarter of what is to
come, under the tracker's and the arm's scatter) does not catch it. A series whose temperatures did
rise is judged by the fit, which sees how far they still have to go.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hil.calibration.warmup_fit import (
    FLAT_POINTS,
    MIN_TEMPERATURE_SPAN,
    DriftFit,
    fit_warmup,
    temperatures_flat,
)

#: Which rule called the arm warm (`WarmupDecision.rule`).
FIT, FLAT = "fit", "flat"


@dataclass(frozen=True)
class WarmupDecision:
    """One check's verdict and its evidence (every length in m, every time in s, temperatures in K).

    `rule`: `FIT` or `FLAT` when warm, "" when not. `span`: the series' length, compared with three
    of the fit's longest time constant. `temperature_span`: how far the joints' mean temperature moved
    over the series (None without temperatures). `flat`: whether the last `FLAT_POINTS` temperatures
    stayed within the sensor's resolution (None without temperatures or with too few); `flat_moved`:
    how far the reference moved among those measurements. `reason`: the verdict in one line.
    """

    warm: bool
    rule: str
    reason: str
    fit: DriftFit | None
    span: float
    limit: float
    temperature_span: float | None = None
    flat: bool | None = None
    flat_moved: float | None = None

    def evidence(self) -> dict[str, float | str | bool | None]:
        """The decision as the flat JSON fields of the warm-up's events and result block (`hil.campaign`)."""
        f = self.fit
        return {"warm": self.warm, "rule": self.rule, "decision": self.reason, "span": self.span,
                "remaining": None if f is None else f.remaining,
                "remaining_upper": None if f is None else f.remaining_upper,
                "time_constant": None if f is None else f.time_constant,
                "time_constant_upper": None if f is None else f.time_constant_upper,
                "time_constant_source": None if f is None else f.source,
                "temperature_span": self.temperature_span, "temperatures_flat": self.flat,
                "flat_moved": self.flat_moved}


def _um(metres: float) -> str:
    return f"{metres * 1e6:.1f} µm"


def decide_warm(times: np.ndarray, positions: np.ndarray, limit: float,
                temperatures: np.ndarray | None = None) -> WarmupDecision:
    """The rule (module docstring) on reference `positions` (N, 3; m, relative to any origin) at
    `times` (N,; s), with the joints' `temperatures` (N, joints; °C) when every measurement has them.
    Before `hil.calibration.warmup_fit.MIN_POINTS` measurements there is no fit and no verdict: a flat
    series of three is judged at its fourth, as the fit is."""
    t = np.asarray(times, dtype=float).reshape(-1)
    P = np.asarray(positions, dtype=float).reshape(-1, 3)
    T = None if temperatures is None else np.asarray(temperatures, dtype=float).reshape(len(t), -1)
    span = float(t[-1] - t[0]) if len(t) else 0.0
    fit = fit_warmup(t, P, temperatures=T) if len(t) else None
    t_span = None if T is None else float(np.ptp(T.mean(axis=1)))
    flat = None if T is None or len(T) < FLAT_POINTS else temperatures_flat(T)
    moved = None
    if len(P) >= FLAT_POINTS:
        last = P[-FLAT_POINTS:]
        moved = float(np.linalg.norm(last[:, None, :] - last[None, :, :], axis=2).max())
    common = {"fit": fit, "span": span, "limit": limit, "temperature_span": t_span, "flat": flat,
              "flat_moved": moved}

    if fit is not None:
        three = 3.0 * fit.time_constant_upper
        if fit.remaining_upper < limit and span >= three:
            return WarmupDecision(True, FIT, (
                f"warm: at most {_um(fit.remaining_upper)} of drift still to come (limit {_um(limit)}) over "
                f"{span / 60:.0f} min, at least three of the longest time constants the fit allows "
                f"({three / 60:.0f} min)"), **common)
    # an arm warm before the warm-up began: no curve, flat joints, a still reference
    if (fit is not None and flat and t_span is not None and t_span < MIN_TEMPERATURE_SPAN
            and moved is not None and moved < limit):
        return WarmupDecision(True, FLAT, (
            f"warm: the joint temperatures moved {t_span:.2f} K over the series (no warm-up to fit) and "
            f"stayed within the sensor's resolution over the last {FLAT_POINTS} measurements, among which "
            f"the reference moved {_um(moved)} (limit {_um(limit)})"), **common)
    if fit is None:
        return WarmupDecision(False, "", "not yet: too few measurements for the fit", **common)
    three = 3.0 * fit.time_constant_upper
    if fit.remaining_upper >= limit:
        reason = (f"not yet: about {_um(fit.remaining)} of drift still to come, and the series cannot rule "
                  f"out {_um(fit.remaining_upper)} (limit {_um(limit)})")
    else:
        reason = (f"not yet: at most {_um(fit.remaining_upper)} still to come, but the series spans "
                  f"{span / 60:.0f} min, under three of the longest time constants the fit allows "
                  f"({three / 60:.0f} min)")
    return WarmupDecision(False, "", reason, **common)
