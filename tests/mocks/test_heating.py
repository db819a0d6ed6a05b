"""The simulated arm heats while it moves (`mocks.heating`), by its seconds of motion."""

from __future__ import annotations

import pytest

from hil.arm.thermal import Thermal
from mocks.heating import Heating

THERMAL = Thermal(rise=6.0, time_constant=900.0)


class Arm:
    """A clock and what the arm did: `advance(dt, moving)`."""

    def __init__(self) -> None:
        self.t, self.moved = 0.0, 0.0

    def advance(self, dt: float, moving: bool) -> None:
        self.t += dt
        self.moved += dt if moving else 0.0


def heating(arm: Arm) -> Heating:
    return Heating(THERMAL, lambda: arm.moved)


def test_an_arm_moving_all_the_time_follows_the_truths_warm_up_curve() -> None:
    arm = Arm()
    h = heating(arm)
    for _ in range(300):  # 50 min in 10 s steps
        arm.advance(10.0, moving=True)
        assert h.rise() == pytest.approx(THERMAL.rise_at(arm.t), rel=1e-9)


def test_an_arm_standing_still_keeps_its_temperature() -> None:
    """Standing still lasts as long as the host takes in fast time: it neither warms nor cools the arm."""
    arm = Arm()
    h = heating(arm)
    arm.advance(9000.0, moving=False)
    assert h.rise() == 0.0
    arm.advance(300.0, moving=True)
    warm = h.rise()
    arm.advance(3000.0, moving=False)
    assert h.rise() == warm == pytest.approx(THERMAL.rise_at(300.0), rel=1e-12)


def test_the_temperature_depends_on_the_motion_done_not_on_the_pauses_between() -> None:
    """The same 20 minutes of motion, cut by pauses of any length (a busy or an idle host), and queried
    as often or as seldom as the trackers happen to: the same ΔT."""
    rises = []
    for pause, queries in ((0.0, 1), (2.0, 3), (40.0, 1), (400.0, 7)):
        arm = Arm()
        h = heating(arm)
        for _ in range(120):
            arm.advance(10.0, moving=True)
            arm.advance(pause, moving=False)
            for _ in range(queries):
                h.rise()
        rises.append(h.rise())
    assert rises == pytest.approx([THERMAL.rise_at(1200.0)] * 4, rel=1e-12)


def test_an_arm_that_starts_warm_stays_warm() -> None:
    arm = Arm()
    h = Heating(THERMAL, lambda: arm.moved, start=THERMAL.rise)
    arm.advance(600.0, moving=True)
    arm.advance(600.0, moving=False)
    assert h.rise() == pytest.approx(THERMAL.rise, rel=1e-12)
