"""The selector's travel-time model: the driver's movej profile, against the simulator's own timing."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drivers.robot import RobotConfig, URRobot
from hil.arm.catalog import get_robot
from mocks.ur.testing import start_sim
from selector.errors import SelectorError
from selector.motion_time import MotionProfile, trapezoid_time


def test_trapezoid_cruise_and_triangle() -> None:
    # cruise: 2 rad at 0.5 rad/s, 1 rad/s²: 4 s at speed + 0.5 s of ramps
    assert trapezoid_time(2.0, 0.5, 1.0) == pytest.approx(4.5)
    # triangle: 0.1 rad never reaches 0.5 rad/s: 2·sqrt(0.1)
    assert trapezoid_time(0.1, 0.5, 1.0) == pytest.approx(2 * math.sqrt(0.1))
    # continuous where the two meet (d = v²/a)
    assert trapezoid_time(0.25, 0.5, 1.0) == pytest.approx(1.0)
    assert trapezoid_time(0.0, 0.5, 1.0) == 0.0


def test_the_leading_joint_is_the_slowest_at_its_own_limit() -> None:
    # UR10e: joints 1-2 at 120 °/s, 3-6 at 180 °/s; commanded 3 rad/s
    p = MotionProfile(3.0, 2.0, tuple(get_robot("ur10e").max_joint_speed))
    a = np.zeros(6)
    b = np.array([1.5, 0.0, 2.0, 0.0, 0.0, 0.0])
    v1, v3 = p.joint_speeds[0], p.joint_speeds[2]
    assert v1 < v3
    # joint 1 leads (1.5 / 2.09 > 2.0 / 3.0) although joint 3 turns further
    assert p.move_time(a, b) == pytest.approx(trapezoid_time(1.5, v1, 2.0))
    M = p.matrix(np.array([a, b]))
    assert M[0, 1] == M[1, 0] == pytest.approx(p.move_time(a, b)) and M[0, 0] == 0.0


def test_bad_profiles_are_refused() -> None:
    with pytest.raises(SelectorError):
        MotionProfile(0.0, 1.0, (3.14,) * 6)
    with pytest.raises(SelectorError):
        MotionProfile(0.5, 1.0, (3.14,) * 5)


@pytest.mark.parametrize("robot,speed,acceleration", [("ur5e", 0.5, 1.0), ("ur10e", 3.0, 2.5)])
def test_model_matches_the_simulators_own_timing_of_the_same_moves(robot: str, speed: float,
                                                                    acceleration: float) -> None:
    """Each move's time as the simulated controller ran it (its own clock, `motion_seconds`) is the model's
    to within two controller cycles, for cruise and triangle profiles and for a leading joint that is not
    the one turning furthest (UR10e at 3 rad/s)."""
    spec = get_robot(robot)
    profile = MotionProfile(speed, acceleration, tuple(spec.max_joint_speed))
    sim = start_sim(robot=robot, speed=5.0)
    rng = np.random.default_rng(4)
    try:
        with URRobot(RobotConfig(host=sim.address, speed=speed, acceleration=acceleration)) as rob:
            here = np.array([0.2, -1.3, 1.3, -1.5, -1.5, 0.3])
            rob.move_to(here)
            targets = [here + d for d in (np.array([0.05, 0, 0, 0, 0, 0]),  # a triangle
                                          np.array([1.4, 0.0, -1.9, 0.0, 0.0, 0.0]),  # cruise
                                          np.array([-1.0, 0.3, -1.2, 0.6, -0.8, 1.5]))]
            targets += [here + rng.uniform(-0.8, 0.8, 6) for _ in range(3)]
            for target in targets:
                before = sim.state()["motion_seconds"]
                rob.move_to(target)
                took = sim.state()["motion_seconds"] - before
                assert took == pytest.approx(profile.move_time(here, target), abs=2 * 0.002 + 1e-3)
                here = target
    finally:
        sim.stop()
