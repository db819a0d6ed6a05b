"""A failed ur_rtde call is named by the controller state, even when that state arrives late.

The control script stops on a protective stop a few frames before the receive thread holds the
frame with the safety bits; under load the gap reaches tens of milliseconds. These fakes make the
gap deterministic, which the simulator on a loaded machine cannot.
"""

# ruff: noqa: N802  (the fakes carry ur_rtde's camelCase method names)

from __future__ import annotations

import time

import numpy as np
import pytest

from drivers.robot import ConnectionLost, KeepInZone, ProgramStopped, ProtectiveStop, RobotConfig, URRobot
from drivers.robot.ur import PROTECTIVE_STOPPED_BIT, RUNTIME_PLAYING


class LaggingReceive:
    """A receive interface that reports the protective stop `lag` s after the control call failed."""

    def __init__(self, lag: float | None) -> None:
        self.lag = lag  # None: the state never explains the failure
        self.failed_at: float | None = None

    def isConnected(self) -> bool:
        return True

    def _stopped(self) -> bool:
        return (self.lag is not None and self.failed_at is not None
                and time.monotonic() - self.failed_at >= self.lag)

    def getSafetyStatusBits(self) -> int:
        return 1 << PROTECTIVE_STOPPED_BIT if self._stopped() else 0

    def getRuntimeState(self) -> int:
        return RUNTIME_PLAYING

    def getTargetSpeedFraction(self) -> float:
        return 1.0

    def getActualQ(self) -> list[float]:
        return [0.0] * 6


class StoppedControl:
    """A control interface whose script has just stopped: calls fail or are refused."""

    def __init__(self, receive: LaggingReceive) -> None:
        self.receive = receive

    def isConnected(self) -> bool:
        return True

    def getForwardKinematics(self, q: list[float], tcp: list[float]) -> list[float]:
        self.receive.failed_at = time.monotonic()
        raise RuntimeError("getForwardKinematics() function did not succeed!")

    def moveJ(self, q: list[float], v: float, a: float, asynchronous: bool) -> bool:
        self.receive.failed_at = time.monotonic()
        return False


def robot_with(lag: float | None, **kw: object) -> tuple[URRobot, LaggingReceive]:
    robot = URRobot(RobotConfig(host="127.0.0.1", **kw))  # type: ignore[arg-type]
    receive = LaggingReceive(lag)
    robot._r, robot._c = receive, StoppedControl(receive)
    return robot, receive


BOX = KeepInZone(lower=(-2.0, -2.0, -2.0), upper=(2.0, 2.0, 2.0))


def test_a_failed_call_waits_for_the_state_that_explains_it() -> None:
    robot, _ = robot_with(lag=0.08, keep_in=BOX)
    with pytest.raises(ProtectiveStop):
        robot.validate_target([0.1] * 6)


def test_a_refused_move_waits_for_the_state_that_explains_it() -> None:
    robot, _ = robot_with(lag=0.08)
    with pytest.raises(ProtectiveStop):
        robot.move_to([0.1] * 6)


def test_an_unexplained_failure_is_a_lost_link_after_the_grace() -> None:
    robot, _ = robot_with(lag=None, keep_in=BOX, explain_timeout=0.2)
    t0 = time.monotonic()
    with pytest.raises(ConnectionLost, match="did not succeed"):
        robot.validate_target(np.full(6, 0.1))
    assert 0.2 <= time.monotonic() - t0 < 1.0


def test_an_unexplained_refusal_is_a_stopped_program() -> None:
    robot, _ = robot_with(lag=None, explain_timeout=0.1)
    with pytest.raises(ProgramStopped, match="did not accept"):
        robot.move_to([0.1] * 6)


def test_a_state_later_than_the_grace_is_not_waited_for() -> None:
    # the state comes 3 s after the failure: far past the 0.1 s grace even when a loaded machine
    # stalls this thread for a few tenths of a second before its last look at the state
    robot, _ = robot_with(lag=3.0, keep_in=BOX, explain_timeout=0.1)
    with pytest.raises(ConnectionLost):
        robot.validate_target([0.1] * 6)
