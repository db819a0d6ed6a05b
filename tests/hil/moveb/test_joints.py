from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hil.arm.geometry import Geometry
from hil.arm.ik import solve_path
from hil.arm.kinematics import Kinematics
from hil.errors import InputError
from hil.moveb.joints import JointSpeedError, joint_speed_ceiling, joint_speeds, retime
from hil.moveb.path_plan import plan_program
from hil.moveb.program import load_program
from hil.moveb.run import solve_trajectory, tool_targets
from hil.moveb.timing import Limits

EXAMPLES = Path(__file__).parents[3] / "hil" / "moveb" / "examples"
Q0 = np.array([0.3, -1.2, 1.5, -1.8, -1.57, 0.2])
LIMITS = Limits(velocity=250.0, acceleration=2000.0, jerk=20000.0, normal_acceleration=2000.0)
GEOMETRY = Geometry.nominal("ur5e", smr=(0.0, 0.0, 0.045))


def test_ceiling_is_the_joint_maximum_over_the_joint_rate_per_mm() -> None:
    s = np.linspace(0.0, 100.0, 101)
    Q = np.zeros((101, 6))
    Q[:, 1] = 0.002 * s  # joint 2: 0.002 rad per mm
    Q[:, 3] = -0.01 * s  # joint 4: 0.01 rad per mm, the binding one
    ceiling = joint_speed_ceiling(s, Q, np.full(6, 2.0))
    assert np.allclose(ceiling, 2.0 / 0.01)


def test_timed_trajectory_stays_within_the_joint_speeds_and_slows_down_only_where_needed() -> None:
    plan = plan_program(load_program(EXAMPLES / "square.moveb"), "G2")
    free = solve_trajectory(plan, GEOMETRY, LIMITS, 500.0, Q0)
    fraction = 0.03  # low enough that the joints, not the Cartesian limits, bind on the sides
    assert np.any(free.speeds.peak > fraction * GEOMETRY.spec.max_joint_speed)  # the ceiling must act
    slow = solve_trajectory(plan, GEOMETRY, LIMITS, 500.0, Q0, joint_speed_fraction=fraction)
    qd = np.abs(np.diff(slow.Q, axis=0)) * 500.0
    assert np.all(qd <= fraction * GEOMETRY.spec.max_joint_speed * (1 + 1e-9))
    assert slow.speeds.ok and slow.speeds.ratio.max() > 0.9  # close to the limit, not far below it
    assert free.cycle_time < slow.cycle_time < 3.0 * free.cycle_time
    # still the same path, and the Cartesian limits still hold
    v = np.linalg.norm(np.diff(slow.samples.position, axis=0), axis=1) * 500.0
    assert v.max() <= LIMITS.velocity * 1.001
    kin = Kinematics(GEOMETRY)
    pts = kin.points(slow.Q, frame="base") * 1e3
    assert np.abs(pts - slow.samples.position).max() < 1e-6


def test_retime_gives_up_naming_the_arc_length() -> None:
    s = np.linspace(0.0, 10.0, 11)

    def always_too_fast(_ceiling: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        Q = np.zeros((11, 6))
        Q[6:, 2] = 1.0  # a jump no speed limit can absorb
        return s, Q

    with pytest.raises(JointSpeedError, match=r"s = 5\.0 mm: joint 3 would need"):
        retime(always_too_fast, s, np.full(11, 100.0), 500.0, np.full(6, 3.0))


def test_joint_speeds_report() -> None:
    Q = np.zeros((3, 6))
    Q[2, 0] = 0.01
    speeds = joint_speeds(Q, 100.0, np.full(6, 2.0))
    assert speeds.peak[0] == pytest.approx(1.0) and speeds.ok and speeds.worst_sample == 1


def test_joint_accelerations_are_reported() -> None:
    t = np.arange(11) / 100.0
    Q = np.zeros((11, 6))
    Q[:, 2] = 0.5 * 4.0 * t ** 2  # joint 3 accelerates at 4 rad/s²
    speeds = joint_speeds(Q, 100.0, np.full(6, 2.0))
    assert speeds.peak_acceleration[2] == pytest.approx(4.0) and speeds.peak_acceleration[0] == 0.0
    assert speeds.as_dict()["allowed_acceleration_rad_s2"] is None and speeds.ok
    assert not joint_speeds(Q, 100.0, np.full(6, 2.0), np.full(6, 3.9)).ok


def test_a_joint_acceleration_limit_refuses_the_path_or_lets_it_run_unchanged() -> None:
    plan = plan_program(load_program(EXAMPLES / "square.moveb"), "G2")
    free = solve_trajectory(plan, GEOMETRY, LIMITS, 500.0, Q0)
    peak = free.speeds.peak_acceleration.max()
    assert peak > 0.5
    within = solve_trajectory(plan, GEOMETRY, LIMITS, 500.0, Q0, joint_acceleration=1.01 * peak)
    assert np.array_equal(within.Q, free.Q)
    assert within.speeds.as_dict()["allowed_acceleration_rad_s2"] == [1.01 * peak] * 6
    with pytest.raises(JointSpeedError, match=r"square\.moveb: s = [\d.]+ mm: joint \d would accelerate "
                                              r"at [\d.]+ rad/s² \(allowed [\d.]+\); lower --acceleration"):
        solve_trajectory(plan, GEOMETRY, LIMITS, 500.0, Q0, joint_acceleration=0.9 * peak)
    gentle = Limits(LIMITS.velocity, LIMITS.acceleration / 2, LIMITS.jerk / 2, LIMITS.normal_acceleration)
    assert solve_trajectory(plan, GEOMETRY, gentle, 500.0, Q0, joint_acceleration=0.9 * peak).speeds.ok


def test_path_outside_the_keep_in_box_is_refused_before_any_motion() -> None:
    plan = plan_program(load_program(EXAMPLES / "square.moveb"), "G2")
    box = (np.array([-1.0, -1.0, 0.0]), np.array([0.45, 1.0, 1.0]))  # cuts the square at x = 450 mm
    with pytest.raises(InputError, match=r"square\.moveb: s = .* leaves the keep-in box at \(450\.\d"):
        solve_trajectory(plan, GEOMETRY, LIMITS, 500.0, Q0, keep_in=box)


def test_bad_joint_speed_fraction() -> None:
    plan = plan_program(load_program(EXAMPLES / "square.moveb"), "G2")
    with pytest.raises(InputError, match="joint speed fraction"):
        solve_trajectory(plan, GEOMETRY, LIMITS, 500.0, Q0, joint_speed_fraction=1.5)


def test_geometric_ik_and_timed_ik_agree() -> None:
    plan = plan_program(load_program(EXAMPLES / "weld_seam.moveb"), "G3")
    traj = solve_trajectory(plan, GEOMETRY, LIMITS, 125.0, Q0)
    kin = Kinematics(GEOMETRY)
    geo = plan.at(plan.sample_grid(1.0, per_bridge=16))
    # the path starts on the configuration nearest Q0 (the controller's choice), then follows it
    Qg = solve_path(kin, tool_targets(geo.position, geo.z_axis, geo.x_axis, GEOMETRY.smr), traj.Q[0],
                    max_step=0.1)
    # the same branch: the joints interpolated from the grid match those at the controller samples
    for j in range(6):
        assert np.abs(np.interp(traj.samples.s, geo.s, Qg[:, j]) - traj.Q[:, j]).max() < 1e-3
