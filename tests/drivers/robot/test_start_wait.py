"""`start_move` / `wait_move` (the two halves of `move_to`) against the simulated controller, in process
and through the isolated client: the first returns with the arm on its way, the second watches the
move to its end; a stop in between aborts it; faults during the gap surface in `wait_move`."""

from __future__ import annotations

import time

import numpy as np
import pytest

from drivers.robot import MotionAborted, ProtectiveStop, RobotConfig, RobotError, URRobot
from drivers.robot.isolated import IsolatedURRobot
from mocks.ur.process import SimProcess
from tests.drivers.robot.test_ur_driver import Q_A, Q_FAR, assert_arm_stopped


def config(sim: SimProcess) -> RobotConfig:
    return RobotConfig(host=sim.address, speed=1.0, acceleration=2.0)


@pytest.mark.parametrize("kind", [URRobot, IsolatedURRobot])
def test_start_returns_with_the_arm_on_its_way_and_wait_sees_it_arrive(sim: SimProcess, kind) -> None:
    slow_ok = RobotConfig(host=sim.address, speed=1.0, acceleration=2.0, min_speed_fraction=0.05)
    with kind(slow_ok) as robot:
        robot.move_to(Q_A)
        # the slider at 5 % makes the move last ~4 s of wall time, so that "returned before the arm got
        # there" does not depend on how fast a loaded machine answers the state query below
        sim.inject("speed_slider", fraction=0.05)
        target = robot.start_move(Q_FAR)
        assert np.allclose(target, Q_FAR)
        assert sim.state()["moving"]  # returned before the arm got there
        sim.inject("speed_slider", fraction=1.0)
        time.sleep(0.05)  # something else runs meanwhile (the engine's commit)
        reading = robot.wait_move(samples=3)
        assert reading.samples == 3 and np.allclose(reading.q, Q_FAR, atol=1e-4)
        assert not sim.state()["moving"]
        with pytest.raises(RobotError, match="without a move"):
            robot.wait_move()  # the move was waited for already


@pytest.mark.parametrize("kind", [URRobot, IsolatedURRobot])
def test_a_stop_between_start_and_wait_aborts_the_move(sim: SimProcess, kind) -> None:
    with kind(config(sim)) as robot:
        robot.move_to(Q_A)
        robot.start_move(Q_FAR)
        robot.stop()
        with pytest.raises(MotionAborted):
            robot.wait_move()
        assert_arm_stopped(sim)
        assert not np.allclose(sim.state()["q"], Q_FAR, atol=1e-3)


def test_a_protective_stop_while_nobody_watches_surfaces_in_wait(sim: SimProcess) -> None:
    with URRobot(config(sim)) as robot:
        robot.move_to(Q_A)
        robot.start_move(Q_FAR)
        sim.inject("protective_stop")
        time.sleep(0.05)
        with pytest.raises(ProtectiveStop):
            robot.wait_move()
        assert_arm_stopped(sim)
