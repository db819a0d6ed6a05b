"""The engine holds the drivers' typed devices: the test fakes are `Robot` and `Tracker`, and what
only some arms can do (send a move and wait for it apart, report joint temperatures) is a declared
protocol the engine checks, not an attribute it probes for."""

from __future__ import annotations

import numpy as np

from drivers.robot.model import ReadsJointTemperatures, Robot, SplitMoves
from drivers.tracker.device import Tracker
from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry
from hil.campaign.engine import Engine
from hil.campaign.steps import ReadConditions
from tests.hil.campaign.fakes import FakeArm, FakeTracker
from tests.hil.campaign.thermal_fakes import AMBIENT, WarmingArm


def test_the_fakes_are_the_drivers_devices() -> None:
    arm = FakeArm(np.zeros(6))
    tracker = FakeTracker(arm, Geometry.nominal("ur5e"))
    assert isinstance(arm, Robot) and isinstance(tracker, Tracker)
    assert not isinstance(arm, SplitMoves) and not isinstance(arm, ReadsJointTemperatures)
    assert np.allclose(tracker.sample().xyz, tracker.kin.points(arm.q)[0], atol=1e-3)


def test_joint_temperatures_are_read_from_an_arm_that_reports_them_only() -> None:
    def conditions(arm: FakeArm) -> tuple[float, ...] | None:
        engine = Engine(arm, FakeTracker(arm, Geometry.nominal("ur5e")), "c1", get_robot("ur5e"))

        def plan():
            return (yield ReadConditions())

        return engine.run(plan()).temperatures

    assert conditions(FakeArm(np.zeros(6))) is None
    assert conditions(WarmingArm(np.zeros(6))) == (AMBIENT,) * 6
