"""Compensation of single targets: exact round trip through the controller's model, branch kept, and
the controller's branch the configuration nearest `near`, as UR's IK picks it."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.branches import joint_distance, nearest_turns, nominal_branches
from hil.arm.controller_model import ControllerCalibration
from hil.arm.geometry import pose
from hil.arm.ik import UnreachableError, solve_ik
from hil.arm.kinematics import Kinematics
from hil.calibration.synthetic import random_truth
from hil.compensation.poses import CANONICAL_NEAR
from hil.compensation.solve import TOLERANCE, Compensator
from tests.hil.arm.configurations import away_from_singularities, configuration
from tests.hil.compensation.world import ROBOT, make_world

NEAR = np.array([0.3, -1.2, 1.5, -1.9, -1.6, 0.2])


@pytest.fixture(scope="module")
def compensator() -> Compensator:
    rng = np.random.default_rng(11)
    truth = random_truth("ur5e", rng, rigid=True)
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
        Compensator(random_truth("ur5e", np.random.default_rng(1), ideal=True),
                    ControllerCalibration().geometry("ur10e"))


@pytest.mark.parametrize("cancelling", [False, True])
def test_near_on_each_configuration_keeps_that_configuration(cancelling: bool) -> None:
    # the controller's own IK picks the configuration nearest qnear: with qnear on any of the eight,
    # that one, for the controller's model (random factory deltas) and for the accurate solution
    world = make_world(21, cancelling)
    comp = world.compensator(pose((0.0, 0.0, 0.1)))
    rng = np.random.default_rng(7)
    poses = 0
    while poses < 3:
        q = rng.uniform(-np.pi, np.pi, 6)
        target = comp.controller_pose(q)
        seeds = nominal_branches(ROBOT, target * comp.tcp.inverse())
        if len(seeds) < 8 or not all(away_from_singularities(ROBOT, b) for b in seeds):
            continue
        poses += 1
        assert len({configuration(ROBOT, b) for b in seeds}) == 8
        for b in seeds:
            c = comp.solve(target, b)
            signs = configuration(ROBOT, b)
            assert configuration(ROBOT, c.q_controller) == configuration(ROBOT, c.q) == signs
            assert joint_distance(c.q_controller, b) < 0.05  # millimetre deltas: milliradians
            assert np.allclose(comp.controller_joints(target, b), c.q_controller, atol=1e-12)


def _all_controller_solutions(comp: Compensator, target: pin.SE3, near: np.ndarray) -> list[np.ndarray]:
    """Every configuration of the controller's model at `target`, each joint at its turn nearest `near`
    (brute force: least squares from every nominal configuration)."""
    kin, spec = Kinematics(comp.controller), comp.controller.spec
    out = []
    for seed in nominal_branches(ROBOT, target * comp.tcp.inverse()):
        try:
            q = solve_ik(kin, target * comp.tcp.inverse(), seed, tolerance=TOLERANCE)
        except UnreachableError:
            continue
        out.append(nearest_turns(q, near, spec.lower, spec.upper))
    return out


def test_a_far_near_takes_the_nearest_configuration_not_where_least_squares_lands() -> None:
    world = make_world(3)
    comp = world.compensator()
    kin = Kinematics(comp.controller)
    near = np.asarray(CANONICAL_NEAR)  # `hil compensate` without --near
    rng = np.random.default_rng(1)
    elsewhere = 0
    for _ in range(60):
        q = rng.uniform(-np.pi, np.pi, 6)
        if not away_from_singularities(ROBOT, q):
            continue
        target = comp.controller_pose(q)
        nearest = min(_all_controller_solutions(comp, target, near), key=lambda s: joint_distance(s, near))
        got = comp.controller_joints(target, near)
        assert np.allclose(got, nearest, atol=1e-9)
        assert np.allclose(comp.solve(target, near).q_controller, got, atol=1e-12)
        try:  # what damped least squares from `near` alone (the former answer, a path's step) gives
            plain = solve_ik(kin, target, near, tolerance=TOLERANCE)
        except UnreachableError:
            continue
        assert np.allclose(comp.solve(target, near, search=False).q_controller, plain, atol=1e-12)
        if configuration(ROBOT, plain) != configuration(ROBOT, nearest):
            assert joint_distance(plain, near) > joint_distance(nearest, near)
            elsewhere += 1
    assert elsewhere >= 5  # least squares from a far `near` often lands on another configuration


def test_least_squares_from_near_landing_elsewhere_is_corrected() -> None:
    # one case written out: the target is where joints q put the tool, 1.8 rad (joint 1) from the
    # canonical near; least squares from near converges to another configuration (shoulder and elbow
    # flipped) 3.3 rad away. The controller, and so compensation, takes q's own configuration.
    world = make_world(3)
    comp = world.compensator()
    near = np.asarray(CANONICAL_NEAR)
    q = np.array([1.8, -1.0, 1.8, -1.9, -2.3, 1.7])
    target = comp.controller_pose(q)
    plain = solve_ik(Kinematics(comp.controller), target, near, tolerance=TOLERANCE)
    assert configuration(ROBOT, plain) != configuration(ROBOT, q)
    assert joint_distance(plain, near) > 3.0
    c = comp.solve(target, near)
    assert np.allclose(c.q_controller, q, atol=1e-9)
    assert configuration(ROBOT, c.q) == configuration(ROBOT, q)
