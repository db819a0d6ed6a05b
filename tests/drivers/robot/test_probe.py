"""`drivers.robot.probe`: who the controller is, asked without taking control (`ask_controller`), and the
model spelling it shares with `URRobot.open` — against the simulated controller."""

from __future__ import annotations

import time

import pytest

from drivers.robot import RobotConfig, RobotUnreachable, URRobot
from drivers.robot.probe import ask_controller, controller_model
from mocks.ur.process import SimProcess
from mocks.ur.testing import random_loopback, start_sim


def test_the_question_answers_what_open_reports_and_takes_nothing(sim: SimProcess) -> None:
    before = sim.state()
    t0 = time.monotonic()
    info = ask_controller(sim.address, 2.0)
    seconds = time.monotonic() - t0
    assert (info.model, info.serial, info.series, info.rate_hz) == ("UR5e", "20235500001", "e", 500.0)
    assert info.software_version.startswith("5.15.0") and info.version[:2] == (5, 15)
    assert info.kinematics is None  # the primary interface is not read
    after = sim.state()
    # nothing uploaded or started: no control script, no program, the arm where it was
    assert after["programs_received"] == before["programs_received"] and after["program"] is None
    assert after["q"] == before["q"] and not after["moving"]
    assert seconds < 1.0, seconds  # a few loopback round trips (about 4 ms measured), not a connect
    with URRobot(RobotConfig(host=sim.address)) as robot:
        opened = robot.info
    assert opened is not None
    assert (opened.model, opened.serial, opened.software_version, opened.version, opened.series,
            opened.rate_hz) == (info.model, info.serial, info.software_version, info.version, info.series,
                                info.rate_hz)


def test_a_cb3_controller_is_a_ur5_without_a_serial_from_its_dashboard() -> None:
    cb3 = start_sim(robot="ur5", speed=1.0)
    try:
        info = ask_controller(cb3.address, 2.0)
    finally:
        cb3.stop()
    assert (info.model, info.serial, info.series, info.rate_hz) == ("UR5", "", "cb3", 125.0)
    assert info.software_version.startswith("3.15")


def test_nothing_answering_is_unreachable() -> None:
    with pytest.raises(RobotUnreachable, match="no RTDE answer"):
        ask_controller(random_loopback(), 1.0)


@pytest.mark.parametrize(("reported", "major", "model"), [
    ("UR5", 5, "UR5e"), ("UR10", 5, "UR10e"), ("UR16", 5, "UR16e"), ("UR20", 5, "UR20"), ("UR30", 5, "UR30"),
    ("UR5", 3, "UR5"), ("UR10", 3, "UR10"),
])
def test_the_e_of_an_e_series_model_comes_from_its_software_version(reported: str, major: int,
                                                                     model: str) -> None:
    assert controller_model(reported, major) == model
