"""The pose test's targets: both modes as the compensator solves them, every pose safe and seen, the
branch search (the nominal arm's eight configurations, tests/hil/arm/test_branches.py), and cubes
refused in one line."""

from __future__ import annotations

import numpy as np
import pytest

from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.errors import InputError
from hil.verify.cube import CYCLE_ORDER, POSE_NAMES, Cube
from hil.verify.design import (
    COMPENSATED,
    DEFAULT_CUBE_TURNS,
    MODES,
    UNCOMPENSATED,
    Design,
    check_cube,
    design_test,
    facing,
)
from tests.hil.verify.station import KEEP_IN, cell


def test_both_modes_are_the_compensators_joints_and_reach_the_cube() -> None:
    c = cell()
    design = c.design()
    positions = design.positions()
    accurate = Kinematics(c.truth)  # the model is the truth here: compensated joints put the SMR there
    ctrl = c.controller
    controller = Kinematics(Geometry(ctrl.robot, ctrl.joints, ctrl.flange, c.truth.smr))
    for name in POSE_NAMES:
        target = design.target(name)
        i = POSE_NAMES.index(name)
        q_unc, q_comp = design.joints[UNCOMPENSATED][i], design.joints[COMPENSATED][i]
        solved = c.compensator.solve(target, q_unc)
        assert np.allclose(solved.q, q_comp, atol=1e-9) and np.allclose(solved.q_controller, q_unc, atol=1e-9)
        assert np.allclose(accurate.points(q_comp, frame="base")[0], positions[i], atol=1e-9)
        assert np.allclose(controller.points(q_unc, frame="base")[0], positions[i], atol=1e-9)
        assert np.linalg.norm(accurate.points(q_unc, frame="base")[0] - positions[i]) > 1e-5  # a real error
        # one orientation for all poses, its axis at the tracker from the cube's centre
        F = accurate.flange_poses(q_comp)[0]
        assert np.allclose(F[:3, :3], design.rotation, atol=1e-9)
    axis = design.rotation[:, 2]
    to_tracker = c.truth.tracker.translation - design.cube.centre
    assert np.degrees(np.arccos(axis @ to_tracker / np.linalg.norm(to_tracker))) < 1e-6


def test_every_target_is_within_limits_upright_and_seen_by_the_true_tracker() -> None:
    c = cell(seed=5)
    design = c.design()
    spec = c.truth.spec
    for q in design.joints.values():
        assert np.all(q >= spec.lower) and np.all(q <= spec.upper)
        assert np.all(q[:, 1] <= 0.0)  # the upper arm at or above the horizontal
        for qq in q:
            _, angle = c.world.state(qq)
            assert angle < 30.0 and not c.world.blocked_by_arm(qq)


def test_visits_alternate_the_modes_cycle_by_cycle_in_the_iso_order() -> None:
    design = cell().design(cycles=2)
    visits = design.visits()
    assert [v.index for v in visits] == list(range(1, 21))
    assert [(v.cycle, v.mode, v.pose) for v in visits[:10]] == (
        [(0, UNCOMPENSATED, p) for p in CYCLE_ORDER] + [(0, COMPENSATED, p) for p in CYCLE_ORDER])
    assert [v.cycle for v in visits[10:]] == [1] * 10
    for v in visits:
        assert np.array_equal(v.q, design.joints[v.mode][POSE_NAMES.index(v.pose)])
    # the first visit is approached from the end of a cycle (P2, the last mode), as every later P1
    assert np.array_equal(design.lead_in(visits[0]), design.joints[COMPENSATED][POSE_NAMES.index("P2")])
    assert np.array_equal(design.lead_in(visits[7]), visits[6].q)
    again = Design.from_dict(design.to_dict())
    assert [tuple(v.q) for v in again.visits()] == [tuple(v.q) for v in visits]


def test_the_default_cube_serves_simulated_cells_of_several_arms() -> None:
    """The default cube (`DEFAULT_CUBE`, with its fallback turns) on random cells: trackers 2-4 m away
    in any direction, random start poses."""
    served = 0
    for robot in ("ur3e", "ur5e", "ur10e"):
        for seed in range(4):
            c = cell(robot, seed)
            for turn in DEFAULT_CUBE_TURNS:
                try:
                    c.design(cycles=2, turn=turn)
                except InputError:
                    continue
                served += 1
                break
    assert served == 12


def test_a_cube_no_configuration_serves_is_one_line_naming_it() -> None:
    c = cell()
    far = Cube(np.array([1.2, 0.0, 0.3]), 0.3)
    expected = r"^station.toml: verify.centre \(centre \[1.2, 0.0, 0.3\] m.*: no arm configuration.*reach"
    with pytest.raises(InputError, match=expected) as e:
        design_test(c.compensator, far, c.truth.smr, c.truth.tracker.translation, tracker_source="model",
                    modes=MODES, cycles=2, keep_in=KEEP_IN, acceptance_angle=30.0, start=c.home,
                    where="station.toml: verify.centre")
    assert "\n" not in str(e.value)


def test_check_cube_refuses_beyond_reach_and_outside_the_keep_in_box_before_connecting() -> None:
    smr = np.array([0.0, 0.0, 0.045])
    check_cube("ur5e", Cube(np.array([0.5, 0.0, 0.3]), 0.2), smr, KEEP_IN, "here")  # fine
    with pytest.raises(InputError, match=r"here: P\d at .* beyond a UR5e's reach \(0.85 m\)"):
        check_cube("ur5e", Cube(np.array([1.5, 0.0, 0.3]), 0.2), smr, KEEP_IN, "here")
    with pytest.raises(InputError, match="outside the keep-in box"):
        check_cube("ur5e", Cube(np.array([0.5, 0.0, 0.05]), 0.2), smr, KEEP_IN, "here")


def test_facing_points_the_tool_axis_and_keeps_it_right_handed() -> None:
    for d in ([1.0, 0.0, 0.0], [0.3, -2.0, 0.4], [0.0, 0.0, 1.0]):
        for turn in (0.0, 1.0):
            R = facing(np.array(d), turn)
            assert np.allclose(R.T @ R, np.eye(3)) and np.linalg.det(R) == pytest.approx(1.0)
            assert np.allclose(R[:, 2], np.array(d) / np.linalg.norm(d))
