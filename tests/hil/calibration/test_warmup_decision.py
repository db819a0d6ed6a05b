"""The warm-up's stopping decision (`hil.calibration.warmup_decision.decide_warm`) on synthetic series of
joint temperatures and reference drift whose truth is known: it never calls a warming arm warm with more
than the limit of drift still to come, calls an arm that was warm from the start warm within a few
measurements, and says why at every check."""

from __future__ import annotations

import numpy as np
import pytest

from hil.calibration.warmup_decision import FIT, FLAT, decide_warm
from hil.calibration.warmup_fit import FLAT_POINTS, MIN_POINTS, temperatures_flat

LIMIT = 10e-6  # the example station's warmup.limit (m)
AMBIENT = 25.0  # °C, the simulated controller's lab (mocks.ur.arm.AMBIENT_TEMPERATURE)
TAU = 900.0  # s, the simulated arm's warm-up (docs/design.md, Facts: thermal growth)


Series = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def warming(rng: np.random.Generator, *, interval: float, per_kelvin: float, start: float, steady: float,
            scatter: float, n: int, tau: float = TAU) -> Series:
    """Times, joint temperatures (n, 6), reference positions (n, 3) and the true drift still to come
    of an arm warming from ΔT `start` to `steady` K (first order, `tau`), its reference moving
    `per_kelvin` m/K in a random direction with `scatter` m per axis of per-visit noise (the tracker's
    and the arm's repositioning). The temperatures carry the ripple of a reference visit's pause: a
    first-order response to a heat input that drops to a quarter for 15 s of each interval, as a real
    joint's does while it holds the arm (the simulator's keeps its temperature then: `mocks.heating`)."""
    times = interval * np.arange(n) + rng.uniform(0.0, 5.0, n)
    rise = steady + (start - steady) * np.exp(-times / tau)
    ripple = 0.02 * (steady - start) * np.sin(2 * np.pi * times / interval)
    temps = AMBIENT + np.repeat((rise + ripple)[:, None], 6, axis=1)
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction)
    points = per_kelvin * rise[:, None] * direction + rng.normal(0.0, scatter, (n, 3))
    return times, temps, points, per_kelvin * (steady - rise)


def first_warm(times, temps, points):
    for k in range(1, len(times) + 1):
        d = decide_warm(times[:k], points[:k], LIMIT, temperatures=temps[:k])
        if d.warm:
            return k - 1, d
    return None, None


@pytest.mark.parametrize("interval, per_kelvin", [(120.0, 17e-6), (120.0, 28e-6), (60.0, 17e-6),
                                                  (60.0, 28e-6)])
def test_a_warming_arm_is_never_warm_with_more_than_the_limit_to_come(interval, per_kelvin):
    """A UR5e's reference (17 µm/K: 2.3e-5 /K over 0.7 m of arm, `bench/warmup_stop.py` measured 16.7 µm/K
    on the simulated one) and a UR10e's (28 µm/K over 1.2 m) warming from the 1 K an arm gains holding
    itself while hil chooses its poses to the 4.5 K of the warm-up's cycling, sampled every 1 or 2 min
    with 3–10 µm of per-visit scatter: wherever the rule stops, less than the limit is left in truth;
    and it does stop (by the fit) before `max_time`."""
    rng = np.random.default_rng(int(interval + per_kelvin * 1e6))
    stops = 0
    for _ in range(8):
        times, temps, points, left = warming(rng, interval=interval, per_kelvin=per_kelvin, start=1.0,
                                             steady=4.5, scatter=rng.uniform(3e-6, 10e-6),
                                             n=int(3600 / interval) + 1)
        k, d = first_warm(times, temps, points)
        if k is None:
            continue
        stops += 1
        assert left[k] < LIMIT, (k, left[k], d.reason)
        assert d.rule == FIT  # the temperatures rose: the fit decides, not "flat"
    assert stops >= 6


def test_the_flat_temperature_rule_alone_stopped_a_warming_arm_early():
    """The rule before this one called an arm warm whenever its temperatures stayed within 0.1 K over the
    last three measurements and the reference moved less than the limit among them — true on a warming
    UR10e sampled every minute with some 20 µm still to come. `decide_warm` waits (the test above can
    fail)."""
    rng = np.random.default_rng(5)
    early = 0
    for _ in range(8):
        times, temps, points, left = warming(rng, interval=60.0, per_kelvin=28e-6, start=1.0, steady=4.5,
                                             scatter=3e-6, n=61)
        for k in range(FLAT_POINTS, len(times) + 1):
            last = points[k - FLAT_POINTS:k]
            moved = np.linalg.norm(last[:, None] - last[None, :], axis=2).max()
            if temperatures_flat(temps[:k]) and moved < LIMIT:
                early += left[k - 1] >= LIMIT
                decision = decide_warm(times[:k], points[:k], LIMIT, temperatures=temps[:k])
                assert not decision.warm or left[k - 1] < LIMIT
                break
    assert early > 0


def test_an_arm_warm_from_the_start_is_warm_within_a_few_measurements():
    """Flat joint temperatures over the whole series (a warm arm: no curve to fit) and a still reference:
    warm at the fit's fewest measurements (`MIN_POINTS`), by the flat rule, and it says so."""
    rng = np.random.default_rng(8)
    times = 120.0 * np.arange(6)
    temps = AMBIENT + 4.4 + rng.uniform(-0.02, 0.02, (6, 6))
    points = rng.normal(0.0, 2e-6, (6, 3))
    k, d = first_warm(times, temps, points)
    assert k == MIN_POINTS - 1 and d.rule == FLAT
    assert d.flat
    assert "no warm-up to fit" in d.reason and d.flat_moved < LIMIT
    # a reference that still moves by the limit is not still: not warm, however flat the joints
    moving = points.copy()
    moving[-1] += [2 * LIMIT, 0.0, 0.0]
    assert not decide_warm(times[:MIN_POINTS], moving[-MIN_POINTS:], LIMIT,
                           temperatures=temps[:MIN_POINTS]).warm


def test_every_check_says_why_and_with_what_evidence():
    rng = np.random.default_rng(2)
    times, temps, points, _ = warming(rng, interval=120.0, per_kelvin=17e-6, start=1.0, steady=4.5,
                                      scatter=5e-6, n=31)
    early = decide_warm(times[:3], points[:3], LIMIT, temperatures=temps[:3])
    assert not early.warm and early.fit is None and "too few" in early.reason
    mid = decide_warm(times[:10], points[:10], LIMIT, temperatures=temps[:10])
    assert not mid.warm and mid.reason.startswith("not yet:")
    ev = mid.evidence()
    assert ev["time_constant_source"] == "temperatures" and ev["temperatures_flat"] is False
    assert ev["remaining_upper"] >= ev["remaining"] and ev["time_constant_upper"] >= ev["time_constant"]
    assert ev["span"] == pytest.approx(times[9] - times[0]) and ev["temperature_span"] > 2.0
    k, done = first_warm(times, temps, points)
    assert k is not None and done.reason.startswith("warm: at most")
    assert done.span >= 3 * done.fit.time_constant_upper and done.fit.remaining_upper < LIMIT
    # the fit's τ is the arm's (from the temperatures, not the scattered positions)
    assert done.fit.time_constant == pytest.approx(TAU, rel=0.1)


def test_a_fast_warming_arm_whose_temperatures_rose_is_warm_by_the_fit_soon_after():
    """An arm that warms in a 2-minute time constant (tests/hil/campaign/test_realistic_arm.py's truth)
    rose from 1.5 K to 4.5 K within the first intervals: its temperatures moved, so the flat rule is not
    its rule, and the fit, which sees the curve flatten, calls it warm within a quarter of an hour."""
    rng = np.random.default_rng(1)
    for _ in range(3):
        times, temps, points, left = warming(rng, interval=120.0, per_kelvin=17e-6, start=1.5, steady=4.5,
                                             scatter=5e-6, n=31, tau=120.0)
        k, d = first_warm(times, temps, points)
        assert k is not None and d.rule == FIT and times[k] < 15 * 60 and left[k] < LIMIT
