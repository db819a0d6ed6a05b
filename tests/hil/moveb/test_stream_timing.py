"""hil notices its own servo stream running late (issue 29) and says what it can have done to the path."""

from __future__ import annotations

import numpy as np
import pytest

from hil.moveb.stream_timing import CHORD_TOLERANCE_MM, stream_timing

RATE = 500.0


def _corner(n: int = 1000, speed: float = 100.0) -> np.ndarray:
    """A path along x then y (mm), `speed` mm/s at `RATE`: the corner at sample n // 2."""
    s = np.arange(n) * speed / RATE
    half = s[n // 2]
    return np.column_stack([np.minimum(s, half), np.maximum(s - half, 0.0), np.zeros(n)])


def test_an_on_time_stream_has_no_misses() -> None:
    t = 10.0 + np.arange(1000) / RATE + np.random.default_rng(0).uniform(0, 0.5e-3, 1000)
    timing = stream_timing(t, RATE, 0.05, _corner())
    assert timing.misses == 0 and not timing.stopped and not timing.disturbed
    assert timing.warning() is None
    assert timing.max_gap_s < 3e-3


def test_a_gap_across_a_corner_is_a_disturbed_run_with_its_cut() -> None:
    t = np.arange(1000) / RATE
    t[480:] += 0.3  # hil starved for 0.3 s just before the corner; the late targets go out in a burst
    t[480:520] = t[480] + np.arange(40) * 1e-5
    t[520:] = t[519] + (np.arange(480) + 1) / RATE  # then on schedule again
    path = _corner()
    timing = stream_timing(t, RATE, 0.05, path)
    assert timing.misses == 1 and timing.max_gap_s == pytest.approx(0.302, abs=1e-6)
    # the leg runs from sample 479 straight to 519 (the burst's last): the corner at 500 is cut by
    # |(21, 0) - the chord's nearest point| = 21 · 19 / sqrt(21² + 19²) samples of 0.2 mm
    expected = 0.2 * 21 * 19 / np.hypot(21, 19)
    assert timing.chord_mm == pytest.approx(expected, rel=1e-9)
    assert timing.disturbed and timing.as_dict()["disturbed"] is True
    assert "cut the path" in (timing.warning() or "")


def test_a_gap_on_a_straight_stops_the_arm_but_cuts_nothing() -> None:
    t = np.arange(1000) / RATE
    t[200:] += 0.3
    timing = stream_timing(t, RATE, 0.05, _corner())
    assert timing.stopped and timing.chord_mm < CHORD_TOLERANCE_MM and not timing.disturbed
    assert timing.misses == 1 and "within" in (timing.warning() or "")
