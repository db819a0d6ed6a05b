"""Unit tests of the simulator's pieces that need no network: profiles, kinematics, arm, script parser."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mocks.ur.arm import ArmConfig, SimArm
from mocks.ur.kin import (
    dh_fk_factory,
    matrix_to_pose,
    matrix_to_rotvec,
    pose_to_matrix,
    rotvec_to_matrix,
    solve_ik,
)
from mocks.ur.motion import trapezoid_duration, trapezoid_fraction
from mocks.ur.script import ControlScript, parse_program
from mocks.ur.status import RuntimeState, SafetyMode

FK = dh_fk_factory("ur5e")


class ManualClock:
    """A clock the test advances by hand, so arm tests are exact and independent of wall time."""

    def __init__(self) -> None:
        self.t = 0.0
        self.speed = 1.0

    def now(self) -> float:
        return self.t


def make_arm(**kw: object) -> tuple[SimArm, ManualClock]:
    clock = ManualClock()
    arm = SimArm(ArmConfig(encoder_noise=0.0, **kw), FK, clock)  # type: ignore[arg-type]
    return arm, clock


def run(arm: SimArm, clock: ManualClock, seconds: float, dt: float = 0.002) -> list[np.ndarray]:
    qs = []
    for _ in range(round(seconds / dt)):
        clock.t += dt
        arm.tick()
        qs.append(arm.q.copy())
    return qs


def test_ur5e_flange_at_zero_matches_the_published_table() -> None:
    assert np.allclose(FK(np.zeros(6))[:3, 3], [-0.8172, -0.2329, 0.0628], atol=1e-4)


@given(st.lists(st.floats(-3.0, 3.0), min_size=3, max_size=3))
def test_rotvec_round_trip(r: list[float]) -> None:
    R = rotvec_to_matrix(np.array(r))
    assert np.allclose(rotvec_to_matrix(matrix_to_rotvec(R)), R, atol=1e-9)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(-2.5, 2.5), min_size=6, max_size=6))
def test_ik_recovers_a_pose_from_a_nearby_seed(q: list[float]) -> None:
    qa = np.array(q)
    T = FK(qa)
    sol = solve_ik(FK, T, qa + 0.05)
    if sol is not None:  # near singularities the damped solver may legitimately give up
        assert np.allclose(FK(sol), T, atol=1e-6)
    assert np.allclose(matrix_to_pose(pose_to_matrix(matrix_to_pose(T))), matrix_to_pose(T), atol=1e-9)


@given(st.floats(1e-4, 5.0), st.floats(0.05, 3.0), st.floats(0.1, 10.0))
def test_trapezoid_is_monotonic_and_ends_at_the_distance(d: float, v: float, a: float) -> None:
    T = trapezoid_duration(d, v, a)
    ts = np.linspace(0, T, 50)
    s = [trapezoid_fraction(t, d, v, a) for t in ts]
    assert s[0] == 0.0 and s[-1] == pytest.approx(1.0)
    assert all(b >= a_ - 1e-12 for a_, b in itertools.pairwise(s))
    # speed never exceeds v (finite differences along the profile)
    speeds = np.diff(np.array(s) * d) / np.diff(ts)
    assert np.max(speeds) <= v * 1.01 + 1e-9


def test_movej_is_synchronised_speed_limited_and_exact() -> None:
    arm, clock = make_arm()
    q1 = arm.q + np.array([1.0, 0.5, -0.25, 0.1, 0.0, -0.6])
    motion = arm.start_movej(q1, 1.0, 2.0)
    expected = trapezoid_duration(1.0, 1.0, 2.0)
    assert motion.duration == pytest.approx(expected)
    qs = np.array(run(arm, clock, expected + 0.1))
    assert arm.motion is None and np.allclose(arm.q, q1, atol=1e-12)
    vel = np.abs(np.diff(qs, axis=0)) / 0.002
    assert vel[:, 0].max() <= 1.0 + 1e-6
    # synchronised: every joint has covered the same fraction at every instant
    frac = (qs - qs[0]) / (q1 - qs[0] + 1e-300)
    moving = [0, 1, 2, 3, 5]
    assert np.allclose(frac[:, moving], frac[:, [0]], atol=2e-3)


def test_speed_slider_slows_the_move_down() -> None:
    arm, clock = make_arm()
    arm.set_speed_slider(0.5)
    q1 = arm.q + 0.5
    motion = arm.start_movej(q1, 1.0, 2.0)
    run(arm, clock, motion.duration + 0.05)
    assert arm.motion is not None  # half speed: not there yet
    run(arm, clock, motion.duration)
    assert arm.motion is None and np.allclose(arm.q, q1)


def test_protective_stop_mid_move_brakes_and_stops_the_program() -> None:
    arm, clock = make_arm()
    arm.program = ControlScript(parse_program("def rtde_control():\n  x = 1\nend\n"))  # type: ignore[arg-type]
    q1 = arm.q + 1.0
    arm.start_movej(q1, 1.0, 2.0)
    run(arm, clock, 0.5)
    arm.protective_stop("test")
    assert arm.safety_mode == SafetyMode.PROTECTIVE_STOP
    assert arm.runtime_state == RuntimeState.STOPPED
    run(arm, clock, 0.5)
    assert arm.motion is None and np.max(np.abs(arm.qd)) < 1e-9
    assert not np.allclose(arm.q, q1)
    ok, msg = arm.unlock_protective_stop()
    assert not ok and "5s" in msg  # too early: 1 s after the stop
    clock.t += 5.0
    assert arm.unlock_protective_stop() == (True, "Protective stop releasing")
    assert arm.safety_mode == SafetyMode.NORMAL


def test_target_outside_joint_limits_is_a_protective_stop() -> None:
    arm, _ = make_arm()
    assert arm.start_movej(np.full(6, 7.0), 1.0, 1.0) is None
    assert arm.safety_mode == SafetyMode.PROTECTIVE_STOP


def test_program_parser_reads_register_offset_and_path() -> None:
    text = (
        "def rtde_control():\n"
        "    global reg_offset_float = # float register offset\n24\n"
        "    global reg_offset_int = # int register offset\n24\n"
        "    def exec_move_path():\n        textmsg(\"exec_move_path\")\n        # inject move path\n"
        "\tsignal_async_progress(0)\n\tmovej([0.1,0.2,0.3,0.4,0.5,0.6],a=1.4,v=1.05,r=0)\n"
        "\tmovel(p[0.3,0.1,0.4,0,3.14,0],a=1.2,v=0.25,r=0)\n    end\nend\n"
    )
    prog = parse_program(text)
    assert prog is not None and prog.name == "rtde_control" and prog.reg_offset == 24
    assert [m.kind for m in prog.path] == ["j", "l"]
    assert prog.path[0].target == [0.1, 0.2, 0.3, 0.4, 0.5, 0.6] and prog.path[1].v == 0.25
    assert parse_program("movej([0,0,0,0,0,0])\n") is None
