"""Compensation of single targets: exact round trip through the controller's model, branch kept."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.controller_model import ControllerCalibration
from hil.arm.geometry import pose
from hil.arm.ik import UnreachableError
from hil.calibration.synthetic import random_truth
from hil.compensation.solve import Compensator

NEAR = np.array([0.3, -1.2, 1.5, -1.9, -1.6, 0.2])


@pytest.fixture(scope="module")
def compensator() -> Compensator:
    rng = np.random.default_rng(11)
    truth = random_truth("ur5e", rng)
    cal = ControllerCalibration(rng.normal(0, 1e-3, 6), rng.normal(0, 5e-4, 6), rng.normal(0, 5e-4, 6),
                                rng.normal(0, 1e-3, 6))
    return Compensator(truth, cal.geometry("ur5e"), pose((0.01, -0.02, 0.12), (0.1, 0.0, 0.3)))


def test_round_trip_lands_on_the_target_to_a_nanometre(compensator: Compensator) -> None:
    rng = np.random.default_rng(5)
    for _ in range(40):
        target = compensator.accurate_pose(NEAR + rng.normal(0, 0.3, 6))
        c = compensator.solve(target, NEAR)
        # the controller receives `command`, solves it with its own model on its branch ...
        q = compensator.controller_joints(c.command, c.q_controller)
        # ... and the arm (the accurate model) puts the tool on the target
        reached = compensator.accurate_pose(q)
        assert np.linalg.norm(reached.translation - target.translation) < 1e-9
        assert np.linalg.norm(pin.log3(reached.rotation.T @ target.rotation)) < 1e-9
        assert 1e-5 < c.shift < 0.05  # a real correction, of millimetres


def test_uncompensated_target_misses_by_the_model_difference(compensator: Compensator) -> None:
    target = compensator.accurate_pose(NEAR)
    c = compensator.solve(target, NEAR)
    missed = compensator.accurate_pose(c.q_controller)  # the controller sent the target as it is
    assert np.linalg.norm(missed.translation - target.translation) > 1e-4


def test_the_branch_is_the_controllers(compensator: Compensator) -> None:
    # the same pose from two seeds on different elbow branches keeps each seed's branch
    up = compensator.accurate_pose(NEAR)
    flipped = NEAR * np.array([1, 1, -1, 1, 1, 1]) + np.array([0, -1.0, 0, 0.8, 0, 0])
    other = compensator.controller_joints(compensator.controller_pose(NEAR), flipped)
    for seed in (NEAR, other):
        c = compensator.solve(up, seed)
        assert np.sign(c.q[2]) == np.sign(c.q_controller[2]) == np.sign(seed[2])
        assert np.max(np.abs(c.q - c.q_controller)) < 0.05


def test_unreachable_target_names_where(compensator: Compensator) -> None:
    far = pin.SE3(np.eye(3), np.array([3.0, 0.0, 0.5]))
    ok = compensator.accurate_pose(NEAR)
    with pytest.raises(UnreachableError, match="line 7: IK did not converge"):
        compensator.solve_all([ok, far], NEAR, where=["line 3", "line 7"])


def test_models_of_different_robots_are_refused() -> None:
    with pytest.raises(ValueError, match="ur10e"):
        Compensator(random_truth("ur5e", np.random.default_rng(1)),
                    ControllerCalibration().geometry("ur10e"))
