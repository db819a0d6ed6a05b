"""The simulated arm heats while it works (`mocks.heating`), on a virtual clock."""

from __future__ import annotations

import pytest

from hil.arm.thermal import Thermal
from mocks.heating import IDLE_HEAT, Heating

THERMAL = Thermal(rise=6.0, time_constant=900.0)


class Arm:
    """A clock and what the arm did: `advance(dt, moving, holding)`."""

    def __init__(self) -> None:
        self.t, self.moved, self.holding = 0.0, 0.0, True

    def advance(self, dt: float, moving: bool) -> None:
        self.t += dt
        self.moved += dt if moving else 0.0


def heating(arm: Arm) -> Heating:
    return Heating(THERMAL, lambda: arm.t, lambda: arm.moved, lambda: arm.holding)


def test_an_arm_moving_all_the_time_follows_the_truths_warm_up_curve() -> None:
    arm = Arm()
    h = heating(arm)
    for _ in range(300):  # 50 min in 10 s steps
        arm.advance(10.0, moving=True)
        assert h.rise() == pytest.approx(THERMAL.rise_at(arm.t), rel=1e-9)


def test_an_arm_standing_still_reaches_only_its_holding_share_and_a_braked_one_stays_cold() -> None:
    arm = Arm()
    h = heating(arm)
    for _ in range(200):  # 10 time constants
        arm.advance(45.0, moving=False)
        h.rise()
    assert h.rise() == pytest.approx(IDLE_HEAT * THERMAL.rise, rel=1e-4)
    arm.holding = False
    arm.advance(9000.0, moving=False)
    assert h.rise() == pytest.approx(0.0, abs=1e-4 * THERMAL.rise)  # braked: it cools to ambient


def test_a_waiting_arm_warms_the_rest_of_the_way_once_it_moves() -> None:
    """What a campaign meets: the arm waits (pose selection), then the warm-up cycles it."""
    arm = Arm()
    h = heating(arm)
    arm.advance(1800.0, moving=False)
    waited = h.rise()
    assert waited < IDLE_HEAT * THERMAL.rise
    arm.advance(900.0, moving=True)  # one time constant of motion closes 63 % of the gap
    expected = THERMAL.rise + (waited - THERMAL.rise) * 0.36787944117144233
    assert h.rise() == pytest.approx(expected, rel=1e-9)


def test_a_half_moving_interval_heats_as_the_fraction_of_it_spent_moving() -> None:
    arm = Arm()
    h = heating(arm)
    arm.t, arm.moved = 100.0, 50.0
    u = 0.5 + IDLE_HEAT * 0.5
    assert h.rise() == pytest.approx(THERMAL.rise * u * (1 - 2.718281828459045 ** (-100 / 900)), rel=1e-9)


def test_an_arm_that_starts_warm_stays_warm_while_it_works_and_cools_while_it_stands() -> None:
    arm = Arm()
    h = Heating(THERMAL, lambda: arm.t, lambda: arm.moved, lambda: arm.holding, start=THERMAL.rise)
    arm.advance(600.0, moving=True)
    assert h.rise() == pytest.approx(THERMAL.rise, rel=1e-12)
    arm.advance(THERMAL.time_constant, moving=False)  # one time constant toward the holding share
    held = IDLE_HEAT * THERMAL.rise
    assert h.rise() == pytest.approx(held + (THERMAL.rise - held) * 2.718281828459045 ** -1, rel=1e-9)
