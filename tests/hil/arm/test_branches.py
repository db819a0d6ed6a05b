"""The nominal arm's configurations of a pose (seeds of the controller's branch search), their turns
nearest a qnear within the limits, and the bound that lets the search stop early."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.branches import (
    branches_near,
    joint_distance,
    nearest_turns,
    nominal_branches,
    other_branches_distance,
)
from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from tests.hil.arm.configurations import away_from_singularities, configuration


def _wrapped(q: np.ndarray) -> np.ndarray:
    return np.remainder(np.asarray(q) + math.pi, 2 * math.pi) - math.pi


@pytest.mark.parametrize("robot", ["ur5e", "ur10e", "ur3e", "ur16e", "ur5"])
def test_every_branch_reproduces_the_nominal_forward_kinematics(robot: str) -> None:
    kin = Kinematics(Geometry.nominal(robot))
    rng = np.random.default_rng(2)
    eight = 0
    for _ in range(60):
        q = rng.uniform(-math.pi, math.pi, 6)
        target = pin.SE3(kin.flange_poses(q)[0])
        branches = nominal_branches(robot, target)
        assert 1 <= len(branches) <= 8
        for b in branches:  # each one reaches the target, to rounding ...
            assert np.abs(kin.flange_poses(b)[0] - target.homogeneous).max() < 1e-12
            assert np.all(b >= -math.pi) and np.all(b < math.pi)
        # ... the configuration it came from is among them, and they are all different configurations
        assert any(np.allclose(_wrapped(b - q), 0, atol=1e-7) for b in branches)
        if away_from_singularities(robot, q):
            signs = {configuration(robot, b) for b in branches}
            assert len(signs) == len(branches)
            eight += len(branches) == 8
    assert eight >= 10  # most poses have all eight


def test_a_pose_beyond_reach_has_no_branch() -> None:
    assert nominal_branches("ur5e", pin.SE3(np.eye(3), np.array([3.0, 0.0, 0.5]))) == []
    assert nominal_branches("ur5e", pin.SE3(np.eye(3), np.array([0.0, 0.0, 0.5]))) == []  # on the base axis


def test_each_joint_takes_the_turn_nearest_near_that_the_limits_allow() -> None:
    spec = get_robot("ur5e")  # ±2π, the elbow ±π
    near = np.array([5.5, -5.5, 3.0, 0.0, 6.0, -1.0])
    q = np.array([-0.5, 0.5, -3.0, 2 * math.pi, 0.2, 3.0])
    got = nearest_turns(q, near, spec.lower, spec.upper)
    # joint 1: −0.5 + 2π = 5.78; joint 2: 0.5 − 2π; joint 3: −3.0 only (3.28 is beyond the elbow's π);
    # joint 4: 0; joint 5: 0.2 + 2π = 6.48 is beyond 2π, so 0.2; joint 6: 3.0 − 2π
    assert np.allclose(got, [-0.5 + 2 * math.pi, 0.5 - 2 * math.pi, -3.0, 0.0, 0.2, 3.0 - 2 * math.pi])
    # a batch, and a joint with no turn inside the limits
    batch = nearest_turns(np.array([q, q]), near, spec.lower, spec.upper)
    assert np.allclose(batch, [got, got])
    assert np.isnan(nearest_turns(np.array([3.0]), np.array([0.0]), np.array([-1.0]), np.array([1.0]))[0])


def test_nearest_turns_matches_a_brute_force_search() -> None:
    rng = np.random.default_rng(4)
    for _ in range(500):
        lower = rng.uniform(-8.0, 0.0, 6)
        upper = lower + rng.uniform(0.5, 14.0, 6)
        q, near = rng.uniform(-10.0, 10.0, 6), rng.uniform(lower, upper)
        got = nearest_turns(q, near, lower, upper)
        for j in range(6):
            turns = [v for v in q[j] + 2 * math.pi * np.arange(-6, 7) if lower[j] <= v <= upper[j]]
            if not turns:
                assert np.isnan(got[j])
            else:
                assert got[j] == pytest.approx(min(turns, key=lambda v: abs(v - near[j])), abs=1e-12)


def test_branches_come_nearest_first_at_their_turns() -> None:
    kin = Kinematics(Geometry.nominal("ur5e"))
    spec = get_robot("ur5e")
    rng = np.random.default_rng(8)
    for _ in range(30):
        near = rng.uniform(spec.lower, spec.upper)
        target = pin.SE3(kin.flange_poses(rng.uniform(-math.pi, math.pi, 6))[0])
        seeds = nominal_branches("ur5e", target)
        ordered = branches_near(seeds, near, "ur5e")
        assert ordered.shape == (len(seeds), 6)
        distances = [joint_distance(s, near) for s in ordered]
        assert distances == sorted(distances)
        for s in ordered:  # the same poses, within the limits, no other turn of a joint nearer `near`
            assert any(np.allclose(_wrapped(s - b), 0, atol=1e-12) for b in seeds)
            assert np.all(s >= spec.lower) and np.all(s <= spec.upper)
            for turn in (-2 * math.pi, 2 * math.pi):
                other = s + turn
                inside = (other >= spec.lower) & (other <= spec.upper)
                assert np.all(~inside | (np.abs(other - near) >= np.abs(s - near)))
    assert branches_near([], np.zeros(6), "ur5e").shape == (0, 6)


@pytest.mark.parametrize("robot", ["ur5e", "ur3e"])
def test_other_branches_lie_no_nearer_than_the_bound(robot: str) -> None:
    kin = Kinematics(Geometry.nominal(robot))
    spec = get_robot(robot)
    rng = np.random.default_rng(6)
    for _ in range(200):
        q = rng.uniform(-math.pi, math.pi, 6)
        near = np.clip(q + rng.normal(0, 1.0, 6), spec.lower, spec.upper)
        target = pin.SE3(kin.flange_poses(q)[0])
        q = nearest_turns(q, near, spec.lower, spec.upper)
        bound = other_branches_distance(robot, target, q, near)
        others = [b for b in branches_near(nominal_branches(robot, target), near, robot)
                  if not np.allclose(_wrapped(b - q), 0, atol=1e-7)]
        for b in others:
            assert joint_distance(b, near) >= bound - 1e-9
