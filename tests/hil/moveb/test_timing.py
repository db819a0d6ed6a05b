"""The feed profile keeps every ceiling at every controller sample, however narrow the slow zone."""

from __future__ import annotations

import numpy as np
import pytest

from hil.moveb.timing import Limits, erode_by_travel, feed_profile, speed_ceiling

LIMITS = Limits(velocity=250.0, acceleration=2000.0, jerk=20000.0, normal_acceleration=2000.0)


def speeds_at_samples(law) -> tuple[np.ndarray, np.ndarray]:
    """Mean speed over each controller period and the arc length at its middle."""
    v = np.diff(law.s) * law.rate_hz
    return 0.5 * (law.s[1:] + law.s[:-1]), v


@pytest.mark.parametrize("rate", [500.0, 125.0])
@pytest.mark.parametrize("seed", range(4))
def test_no_sample_is_faster_than_the_ceiling_where_it_is(rate: float, seed: int) -> None:
    rng = np.random.default_rng(seed)
    s = np.linspace(0.0, 300.0, 6001)
    kappa = np.zeros_like(s)
    for centre in rng.uniform(20, 280, 4):  # corners of various sharpness and width
        kappa += rng.uniform(0.2, 3.0) * np.exp(-0.5 * ((s - centre) / rng.uniform(0.3, 3.0)) ** 2)
    dip = rng.uniform(30, 270)  # a narrow slow zone from outside (a joint-speed ceiling, say)
    ceiling_v = np.where(np.abs(s - dip) < rng.uniform(0.5, 4.0), rng.uniform(5, 60), 1e9)
    law = feed_profile(s, kappa, LIMITS, rate, ceiling=(s, ceiling_v))
    mid, v = speeds_at_samples(law)
    allowed = np.minimum(np.interp(mid, s, speed_ceiling(s, kappa, LIMITS, rate)),
                         np.interp(mid, s, ceiling_v))
    assert np.all(v <= allowed * 1.01 + 0.05)
    assert law.s[-1] == pytest.approx(300.0)


def test_a_slow_point_widens_by_its_own_travel_not_by_full_speed() -> None:
    ds, horizon = 0.05, 0.2
    vlim = np.full(4001, 250.0)
    vlim[2000] = 20.0  # its travel in `horizon`: 4 mm = 80 samples
    out = erode_by_travel(vlim, ds, horizon)
    slow = np.flatnonzero(out <= 20.0)
    assert 80 <= 2000 - slow[0] <= 80 * 1.1 + 1 and 80 <= slow[-1] - 2000 <= 80 * 1.1 + 1
    assert np.all(out[out > 20.0] == 250.0)


def test_erosion_never_raises_a_ceiling() -> None:
    rng = np.random.default_rng(7)
    vlim = rng.uniform(1.0, 250.0, 5000)
    assert np.all(erode_by_travel(vlim, 0.05, 0.2) <= vlim)


def test_a_tight_ceiling_costs_less_time_than_a_full_speed_window() -> None:
    s = np.linspace(0.0, 400.0, 8001)
    kappa = np.zeros_like(s)
    kappa[np.abs(s - 200.0) < 0.5] = 1.0  # one sharp corner: about 45 mm/s there
    law = feed_profile(s, kappa, LIMITS, 500.0)
    # the old rule held the corner's speed over ±v_max·T = ±50 mm; the profile must do better
    old_hold = 2 * 50.0 / np.sqrt(LIMITS.normal_acceleration / 1.0)
    assert law.cycle_time < 400.0 / LIMITS.velocity + old_hold
