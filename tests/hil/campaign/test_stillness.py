"""The stillness rule (`hil.campaign.stillness`) against the simulator's ringing arm and pure noise."""

from __future__ import annotations

import numpy as np
import pytest

from hil.campaign.stillness import DRIFT_FRACTION, judge, range_factor, range_limit
from mocks.ringing import Ringing

STABILITY = 50e-6
SIGMA = 7.5e-6  # one AT960 reading's distance σ (hil.calibration.tracker_noise)


def ring_readings(acceleration: float, lever: float, delay: float, spacing: float, n: int,
                  integration: float) -> np.ndarray:
    """(n,) true offsets along the ring of readings after a 1 s move: the first ends `delay` s after the
    stop, one every `spacing` s, each averaging the ring over the `integration` s before it."""
    ring = Ringing()
    ring.record(0.0, 1.0, 0.5, acceleration, np.array([lever, 0.0, 0.0]))
    ends = 1.0 + delay + spacing * np.arange(n)
    if integration <= 0:
        return ring.offsets(ends)[:, 0]
    back = integration * (np.arange(16) + 0.5) / 16
    return ring.offsets((ends[:, None] - back[None]).ravel())[:, 0].reshape(n, 16).mean(axis=1)


def first_window(P: np.ndarray, rule) -> int:
    """Index after the first 5-reading window `rule` accepts."""
    return next(k for k in range(5, len(P) + 1) if rule(P[k - 5:k]))


def old_rule(w: np.ndarray) -> bool:
    return float(w.std(axis=0, ddof=1).max()) <= STABILITY


def new_rule(w: np.ndarray) -> bool:
    return judge(w, STABILITY).still


def test_one_reading_far_off_is_not_still_though_the_deviation_is_within_the_limit():
    window = np.zeros((5, 3))
    window[0, 0] = 110e-6  # the first reading after a stop, still ringing
    assert window.std(axis=0, ddof=1).max() <= STABILITY  # the standard deviation dilutes it
    verdict = judge(window, STABILITY)
    assert not verdict.still and verdict.range[0] == pytest.approx(110e-6)
    assert "range 110.0 µm (limit 50.0)" in verdict.describe(STABILITY)


def test_a_steady_fall_within_the_range_is_drift():
    window = np.zeros((5, 3))
    window[:, 1] = np.array([48.0, 30.0, 16.0, 8.0, 4.0]) * 1e-6  # a ring's envelope read at its period
    verdict = judge(window, STABILITY)
    assert verdict.range[1] <= STABILITY and not verdict.still
    assert abs(verdict.drift[1]) > DRIFT_FRACTION * STABILITY


def test_a_still_noisy_window_is_still():
    rng = np.random.default_rng(1)
    verdicts = [judge(rng.normal(0.0, SIGMA, (5, 3)), STABILITY).still for _ in range(1000)]
    # noise alone almost never costs a reading
    assert np.mean(verdicts) > 0.99


def test_a_window_needs_two_readings():
    with pytest.raises(ValueError, match="two readings"):
        judge(np.zeros((1, 3)), STABILITY)


def test_the_accepted_window_is_past_the_ring():
    """Readings of the simulated arm's ring (stops of 1-4 rad/s², the SMR 0.5-0.8 m from the lead joint;
    a GeoCOM reading's 0.1 s integration or an emScon 1 kHz instant) at the spacings a fast or a slow
    client makes, from just after the stop: the first window the rule accepts carries less than half
    the ring the standard-deviation rule let through."""
    rng = np.random.default_rng(0)
    worst = {"old": 0.0, "new": 0.0}
    for integration in (0.1, 0.0):
        for acceleration, lever in ((1.0, 0.5), (2.0, 0.6), (4.0, 0.8)):
            for delay in (0.01, 0.05, 0.1, 0.2, 0.3):
                for spacing in (0.02, 0.05, 0.1, 0.11, 0.15, 0.25, 0.5):
                    truth = ring_readings(acceleration, lever, delay, spacing, 120, integration)
                    for _ in range(5):
                        noise = rng.normal(0, SIGMA, (len(truth), 3))
                        P = np.column_stack([truth, np.zeros((len(truth), 2))]) + noise
                        for name, rule in (("old", old_rule), ("new", new_rule)):
                            k = first_window(P, rule)
                            worst[name] = max(worst[name], abs(float(truth[k - 5:k].mean())))
    assert worst["old"] > 50e-6  # what the standard deviation let through
    assert worst["new"] < worst["old"] / 2 and worst["new"] < 27e-6


def test_the_range_limit_grows_with_the_window_as_the_range_of_noise_does():
    """d₂(n) against its tabulated values, and windows of 5 and 20 readings of noise alone almost never
    refused."""
    assert [round(range_factor(n), 3) for n in (2, 5, 10, 20)] == [1.128, 2.326, 3.078, 3.735]
    assert range_limit(5, STABILITY) == pytest.approx(STABILITY)
    assert range_limit(20, STABILITY) == pytest.approx(STABILITY * 3.735 / 2.326, rel=1e-3)
    rng = np.random.default_rng(3)
    sigma = SIGMA  # per axis (the simulated GeoCOM's 6-9 µm at 2-3 m)
    refused = {n: np.mean([not judge(rng.normal(0.0, sigma, (n, 3)), STABILITY).still for _ in range(3000)])
               for n in (5, 20)}
    assert refused[5] < 0.01 and refused[20] < 0.01, refused


def test_a_long_window_with_one_ringing_reading_is_not_still():
    window = np.zeros((20, 3))
    window[0, 2] = 1.1 * range_limit(20, STABILITY)
    assert not judge(window, STABILITY).still
