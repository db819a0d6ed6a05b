"""The robot driver against the simulated controller: motion, refusals, and every fault as a typed error."""

from __future__ import annotations

import os
import signal
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import replace

import numpy as np
import pytest

from drivers.robot import (
    ConnectionLost,
    ControllerInfo,
    EmergencyStop,
    JointLimitViolation,
    KeepInZone,
    KeepInZoneViolation,
    MotionAborted,
    NotInRemoteControl,
    ProgramStopped,
    ProtectiveStop,
    RobotConfig,
    RobotUnreachable,
    SpeedSliderReduced,
    UnsupportedVersion,
    URRobot,
)
from drivers.robot.isolated import IsolatedURRobot
from mocks.ur.controller import SimConfig
from mocks.ur.process import SimProcess
from mocks.ur.testing import random_loopback, start_sim

Q_A = [0.2, -1.3, 1.3, -1.5, -1.5, 0.3]
Q_FAR = [-1.2, -1.9, 1.9, -1.0, -1.2, -0.8]


def config(sim: SimProcess, **kw: object) -> RobotConfig:
    return RobotConfig(host=sim.address, speed=1.0, acceleration=2.0, **kw)  # type: ignore[arg-type]


@pytest.fixture
def robot(sim: SimProcess) -> Iterator[URRobot]:
    rob = URRobot(config(sim))
    rob.open()
    try:
        yield rob
    finally:
        rob.close()


@contextmanager
def once_moving(sim: SimProcess, action: Callable[[], object], *, real_time: bool = True) -> Iterator[None]:
    """Within the block, run `action` from another thread as soon as the simulated arm is seen moving.

    Not after a fixed delay: at the fixture's 10x a move lasts ~0.2 s of wall time, less than a loaded
    machine's stall, so a timer can fire before the move was sent (a stop then is lost: `start_move`
    clears it) or after the arm arrived. `real_time` puts the simulator at 1x for the rest of the test
    (a move then lasts seconds), so that a stall between seeing the move and acting on it still lands
    mid-move; a `follow` stream keeps wall time anyway and needs no slowing. Fails when the arm was not
    seen moving within 10 s.
    """
    if real_time:
        sim.inject("set_speed", speed=1.0)
    seen = threading.Event()

    def watch() -> None:
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline:
            if sim.state()["moving"]:
                seen.set()
                action()
                return
            time.sleep(0.005)

    watcher = threading.Thread(target=watch, daemon=True)
    watcher.start()
    yield
    watcher.join(15.0)
    assert seen.is_set(), "the arm was never seen moving"


def assert_arm_stopped(sim: SimProcess) -> None:
    end = time.monotonic() + 10.0  # a generous deadline: a loaded machine answers the queries late
    while sim.state()["moving"]:
        assert time.monotonic() < end, "the arm is still moving"
        time.sleep(0.01)
    q0 = sim.state()["q"]
    time.sleep(0.05)
    assert sim.state()["q"] == q0


def test_constructor_does_no_io() -> None:
    URRobot(RobotConfig(host="127.254.254.254"))  # nothing listens there; must not raise


def test_open_reads_identity(robot: URRobot) -> None:
    assert robot.info is not None
    assert robot.info.model == "UR5e" and robot.info.serial == "20235500001"
    assert robot.info.software_version.startswith("5.15.0") and robot.info.rate_hz == 500.0


def same_model(info: ControllerInfo, block: dict[str, list[float]]) -> bool:
    """`info.kinematics` (full DH values) describes the controller block (deltas) `block`."""
    from hil.arm.controller_model import DELTA_KEYS, ControllerCalibration

    assert info.kinematics is not None
    cal = ControllerCalibration.from_dh("ur5e", *info.kinematics.dh())
    return all(np.allclose(getattr(cal, k), block[k], rtol=0, atol=1e-12) for k in DELTA_KEYS)


def test_open_reads_the_controllers_own_kinematic_model(robot: URRobot, sim: SimProcess) -> None:
    assert robot.info is not None and same_model(robot.info, sim.info["controller"])


def test_a_silent_primary_port_leaves_the_model_unknown(caplog: pytest.LogCaptureFixture) -> None:
    s = start_sim(SimConfig(primary_port=0))  # served elsewhere: nothing answers on 30001
    robot = URRobot(RobotConfig(host=s.address, connect_timeout=2.0))
    try:
        with caplog.at_level("WARNING", logger="drivers.robot.ur"):
            info = robot.open()
        assert info.kinematics is None and info.model == "UR5e"
        assert "kinematic model is unknown" in caplog.text
        robot.move_to(Q_A)  # the campaign runs on without it
    finally:
        robot.close()
        s.stop()


def test_a_cb3_controller_runs_at_125_hz_and_follows_a_trajectory() -> None:
    from mocks.ur.testing import start_sim

    cb3 = start_sim(robot="ur5", speed=1.0)
    try:
        with URRobot(config(cb3)) as rob:
            assert rob.info is not None and rob.info.model == "UR5"
            assert rob.info.software_version.startswith("3.15") and rob.info.rate_hz == 125.0
            q0 = np.asarray(rob.read_joints(1).q)
            traj = q0 + np.linspace(0.0, 0.05, 125)[:, None] * np.array([1.0, 0, 0, 0, 0, 1.0])
            res = rob.follow(traj, settle=0.1)
            # a low percentile: a loaded machine delays many periods, hardly ever shortens one (see
            # tests/drivers/robot/test_follow.py assert_on_period)
            d = np.diff(res.times)
            assert abs(np.percentile(d, 10) - 1 / 125) < 1e-3
            assert np.allclose(rob.read_joints(5).q, traj[-1], atol=1e-3)
    finally:
        cb3.stop()


def test_move_to_settles_and_reads_averaged_joints(robot: URRobot, sim: SimProcess) -> None:
    reading = robot.move_to(Q_A, samples=20)
    assert reading.samples == 20
    assert np.allclose(reading.q, Q_A, atol=6e-6)  # the mean of 20 readings: 5 µrad / √20 each, 5 σ
    assert np.all(reading.spread > 0) and np.all(reading.spread < 1e-5)  # encoder noise, ~5 µrad
    assert np.allclose(sim.state()["q"], Q_A, atol=1e-12)


def test_out_of_limits_target_is_refused_without_moving(sim: SimProcess) -> None:
    with URRobot(config(sim, joint_lower=(-3.0,) * 6, joint_upper=(3.0,) * 6)) as rob:
        q_before = sim.state()["q"]
        with pytest.raises(JointLimitViolation, match="joint 2"):
            rob.move_to([0.0, -3.2, 1.0, 0.0, 0.0, 0.0])
        with pytest.raises(JointLimitViolation):
            rob.move_to([0.0, float("nan"), 1.0, 0.0, 0.0, 0.0])
        assert sim.state()["q"] == q_before and not sim.state()["moving"]


def test_keep_in_zone_is_checked_along_the_path(sim: SimProcess) -> None:
    zone = KeepInZone(lower=(-1.0, -1.0, 0.2), upper=(1.0, 1.0, 1.5))
    with URRobot(config(sim, keep_in=zone)) as rob:
        rob.move_to(Q_A)  # inside
        q_before = sim.state()["q"]
        with pytest.raises(KeepInZoneViolation):
            rob.move_to([0.2, -0.2, 0.2, -1.5, -1.5, 0.3])  # arm stretched low: TCP below z = 0.2
        assert sim.state()["q"] == q_before


def test_protective_stop_mid_move(robot: URRobot, sim: SimProcess) -> None:
    with once_moving(sim, lambda: sim.inject("protective_stop")), pytest.raises(ProtectiveStop):
        robot.move_to(Q_FAR)
    assert_arm_stopped(sim)
    assert not np.allclose(sim.state()["q"], Q_FAR, atol=1e-3)


def test_emergency_stop_mid_move(robot: URRobot, sim: SimProcess) -> None:
    with once_moving(sim, lambda: sim.inject("emergency_stop")), pytest.raises(EmergencyStop):
        robot.move_to(Q_FAR)
    assert_arm_stopped(sim)


def test_dropped_connection_mid_move(sim: SimProcess) -> None:
    """Through the isolated client (as the product drives the arm): ur_rtde's own reconnection after
    a dropped link can crash its process (see URRobot.reconnect); here that is a ConnectionLost."""
    robot = IsolatedURRobot(config(sim))
    robot.open()
    try:
        drop = once_moving(sim, lambda: sim.inject("drop_connection", refuse_s=1.0))
        with drop, pytest.raises(ConnectionLost):
            robot.move_to(Q_FAR)
        assert_arm_stopped(sim)
        deadline = time.monotonic() + 20
        while True:  # the controller accepts connections again after 1 s: reconnect until it works
            try:
                robot.reconnect()
                break
            except (ConnectionLost, RobotUnreachable, ProgramStopped):
                assert time.monotonic() < deadline, "could not reconnect"
                time.sleep(0.5)
        reading = robot.move_to(Q_A)
        assert np.allclose(reading.q, Q_A, atol=1e-3)
    finally:
        robot.close()


def test_isolated_client_survives_the_death_of_its_process(sim: SimProcess) -> None:
    robot = IsolatedURRobot(config(sim))
    robot.open()
    try:
        assert robot.info is not None and robot.info.model == "UR5e"
        assert same_model(robot.info, sim.info["controller"])  # carried across the process boundary
        first = robot._proc
        first.kill()  # what a segfault of ur_rtde looks like from outside
        first.join(5)
        with pytest.raises(ConnectionLost, match="process died"):
            robot.read_joints(3)
        robot.reconnect()
        assert robot._proc is not first and robot.read_joints(3).samples == 3
        with once_moving(sim, robot.stop), pytest.raises(MotionAborted):  # from another thread mid-move
            robot.move_to(Q_FAR)
        assert_arm_stopped(sim)
    finally:
        robot.close()


def test_isolated_client_ignores_the_terminals_signals_and_ctrl_c_mid_call_stops_the_arm(
        sim: SimProcess, capfd: pytest.CaptureFixture[str]) -> None:
    robot = IsolatedURRobot(config(sim))
    robot.open()
    try:
        child = robot._proc
        for sig in (signal.SIGINT, signal.SIGHUP):  # Ctrl-C and a hang-up reach the whole process group
            os.kill(child.pid, sig)
        assert robot.read_joints(2).samples == 2 and child.is_alive()  # the parent decides what they mean

        def interrupt(*_: object) -> None:
            raise KeyboardInterrupt

        previous = signal.signal(signal.SIGUSR1, interrupt)  # stands for Ctrl-C in this process
        try:
            ctrl_c = once_moving(sim, lambda: os.kill(os.getpid(), signal.SIGUSR1))
            with ctrl_c, pytest.raises(KeyboardInterrupt):
                robot.move_to(Q_FAR)
        finally:
            signal.signal(signal.SIGUSR1, previous)
        assert_arm_stopped(sim)
        assert robot._proc is None and not child.is_alive()  # the call's late reply can answer nothing
        robot.reconnect()
        assert robot.read_joints(2).samples == 2
    finally:
        robot.close()
    assert "Traceback" not in capfd.readouterr().err


def test_program_stopped_mid_move(robot: URRobot, sim: SimProcess) -> None:
    with once_moving(sim, lambda: sim.inject("stop_program")), pytest.raises(ProgramStopped):
        robot.move_to(Q_FAR)
    assert_arm_stopped(sim)


def test_speed_slider_below_100_percent(robot: URRobot, sim: SimProcess) -> None:
    sim.inject("speed_slider", fraction=0.5)
    with pytest.raises(SpeedSliderReduced):
        robot.move_to(Q_FAR)
    assert not sim.state()["moving"]
    sim.inject("speed_slider", fraction=1.0)
    # the driver reads the slider from its RTDE stream: wait for a frame that says 100 %, or the move
    # below is refused before moving (for the old 50 %) instead of being stopped mid-move
    deadline = time.monotonic() + 10.0
    while True:
        try:
            robot.check_status()
            break
        except SpeedSliderReduced:
            assert time.monotonic() < deadline, "the driver never saw the slider back at 100 %"
            time.sleep(0.01)
    slider = once_moving(sim, lambda: sim.inject("speed_slider", fraction=0.3))
    with slider, pytest.raises(SpeedSliderReduced):
        robot.move_to(Q_A)
    assert_arm_stopped(sim)  # the driver stopped it itself


def test_stop_from_another_thread_aborts_the_move(robot: URRobot, sim: SimProcess) -> None:
    with once_moving(sim, robot.stop), pytest.raises(MotionAborted):
        robot.move_to(Q_FAR)
    assert_arm_stopped(sim)


def test_not_in_remote_control_at_open(sim: SimProcess) -> None:
    sim.inject("remote_control", on=False)
    with pytest.raises(NotInRemoteControl):
        URRobot(config(sim)).open()


def test_protective_stop_active_at_open_then_reconnect_after_unlock(sim: SimProcess) -> None:
    sim.inject("protective_stop")
    rob = URRobot(config(sim))
    with pytest.raises(ProtectiveStop):
        rob.open()
    time.sleep(0.6)  # past the 5 s (simulated) unlock delay
    from drivers.robot.probe import DashboardLine

    with DashboardLine(sim.address, 2.0) as dash:
        assert dash.ask("unlock protective stop") == "Protective stop releasing"
    rob.open()
    try:
        rob.move_to(Q_A)
    finally:
        rob.close()


def test_emergency_stop_active_at_open(sim: SimProcess) -> None:
    sim.inject("emergency_stop")
    with pytest.raises(EmergencyStop):
        URRobot(config(sim)).open()


def test_unreachable() -> None:
    with pytest.raises(RobotUnreachable):
        URRobot(RobotConfig(host=random_loopback(), connect_timeout=1.0)).open()


def test_unsupported_version() -> None:
    s = start_sim(SimConfig(version=(5, 4, 0, 0)))
    try:
        with pytest.raises(UnsupportedVersion, match="5.4.0"):
            URRobot(config(s)).open()
        with pytest.raises(UnsupportedVersion):
            URRobot(replace(config(s), allowed_versions=((10, 0),))).open()
    finally:
        s.stop()


def test_servo_stream_follows_a_trajectory(robot: URRobot, sim: SimProcess) -> None:
    robot.move_to(Q_A)
    traj = [np.array(Q_A) + np.array([0.3, 0, 0, 0, 0, 0]) * (i / 150) for i in range(151)]
    # the end held for 0.2 s, as a servo application does: servoStop stops the arm where it is, and the
    # arm lags the stream by tens of ms (more when the sender was late, as on a loaded machine)
    traj += [traj[-1]] * 100
    with robot.servo(lookahead=0.05, gain=1000) as stream:
        for q in traj:
            stream.step(q)
    assert len(stream.periods) == 250
    # a low percentile: a loaded machine delays many periods, hardly ever shortens one (see
    # tests/drivers/robot/test_follow.py assert_on_period)
    assert 0.0015 < float(np.percentile(stream.periods, 10)) < 0.003
    time.sleep(0.1)
    assert np.allclose(robot.read_joints(5).q, traj[-1], atol=5e-3)


def test_close_right_after_a_stop_from_another_thread_ends_the_script_at_once(sim: SimProcess) -> None:
    """The engine's Ctrl-C: stop the arm (the isolated client's stop pipe answers at once, its stopJ
    still under way), then close. ur_rtde's commands share one register: a stopScript sent beside the
    stopJ was cleared by it and then waited for the script to end, until the proxy's call timeout
    killed the client (24 s after Ctrl-C in `hil calibrate --sim`)."""
    robot = IsolatedURRobot(config(sim))
    robot.open()
    closed: list[float] = []
    try:
        with once_moving(sim, robot.stop):
            robot.start_move(Q_FAR)
        began = time.monotonic()
        robot.close()
        closed.append(time.monotonic() - began)
    finally:
        robot.close()
    assert_arm_stopped(sim)
    assert sim.state()["runtime_state"] == "STOPPED"  # the control script ended
    # the stop itself takes about 1 s at 1x (STOP_DECEL); the proxy's timeout for close is 20 s
    assert closed[0] < 8.0, f"close took {closed[0]:.1f} s"
