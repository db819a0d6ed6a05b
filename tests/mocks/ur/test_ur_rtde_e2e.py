"""The real ur_rtde 1.6.5 client against the simulated controller, end to end."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import dashboard_client
import numpy as np
import pytest
import rtde_control
import rtde_receive

from hil.arm.controller_model import ControllerCalibration
from mocks.ur.hil_model import controller_fk
from mocks.ur.kin import FkFn, matrix_to_pose, pose_to_matrix
from mocks.ur.process import SimProcess
from mocks.ur.testing import start_sim

Q_A = [0.2, -1.3, 1.3, -1.5, -1.5, 0.3]
Q_B = [-0.4, -1.7, 1.6, -1.2, -1.6, -0.2]


@pytest.fixture
def clients(shared_sim: SimProcess) -> Iterator[tuple[object, object, SimProcess]]:
    r = rtde_receive.RTDEReceiveInterface(shared_sim.address)
    c = rtde_control.RTDEControlInterface(shared_sim.address)
    try:
        yield c, r, shared_sim
    finally:
        c.stopScript()
        c.disconnect()
        r.disconnect()


def model_of(sim: SimProcess) -> FkFn:
    """The FK the simulated controller moves and reports with: nominal DH plus its own deltas."""
    return controller_fk("ur5e", ControllerCalibration.from_dict(sim.info["controller"]))


def wait_for(pred, timeout: float = 5.0) -> bool:  # type: ignore[no-untyped-def]
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(0.002)
    return False


def test_connect_reports_version_and_streams_state(clients) -> None:  # type: ignore[no-untyped-def]
    c, r, sim = clients
    assert c.isConnected() and r.isConnected() and c.isProgramRunning()
    t0 = r.getTimestamp()
    assert wait_for(lambda: r.getTimestamp() > t0)  # streaming (a loaded machine may hold a frame back)
    assert r.getRobotMode() == 7 and r.getSafetyMode() == 1 and r.getRuntimeState() == 2
    q = np.array(r.getActualQ())
    assert np.allclose(r.getActualTCPPose()[:3], model_of(sim)(q)[:3, 3], atol=1e-6)
    assert sim.state()["program"] == "rtde_control"


def test_movej_reaches_the_target_and_reports_the_controllers_tcp(clients) -> None:  # type: ignore[no-untyped-def]
    c, r, sim = clients
    FK = model_of(sim)
    assert c.moveJ(Q_A, 1.0, 2.0)
    # the receive thread may still hold a frame from before the end of the move
    assert wait_for(lambda: np.allclose(r.getActualQ(), Q_A, atol=2e-5))
    q = np.array(r.getActualQ())
    assert np.allclose(q, Q_A, atol=2e-5)  # encoder noise only
    assert np.std(q - Q_A) > 0  # ... and there is some
    assert np.allclose(r.getActualTCPPose(), matrix_to_pose(FK(q)), atol=1e-6)
    assert c.isSteady()
    # FK through the control script, with a TCP offset (the driver always passes one)
    tcp = [0.0, 0.0, 0.05, 0.0, 0.0, 0.0]
    expected = matrix_to_pose(FK(np.array(Q_B)) @ pose_to_matrix(np.array(tcp)))
    assert np.allclose(c.getForwardKinematics(Q_B, tcp), expected, atol=1e-9)
    # IK round trip near the current joints
    q_ik = c.getInverseKinematics(list(matrix_to_pose(FK(np.array(Q_A) + 0.05))), Q_A)
    assert np.allclose(q_ik, np.array(Q_A) + 0.05, atol=1e-6)


def test_movel_keeps_the_tcp_on_a_straight_line(clients) -> None:  # type: ignore[no-untyped-def]
    c, r, _ = clients
    assert c.moveJ(Q_A, 1.5, 3.0)
    p0 = np.array(r.getActualTCPPose())
    p1 = p0.copy()
    p1[:3] += [0.08, -0.05, 0.06]
    assert c.moveL(p1.tolist(), 0.1, 0.5, True)
    samples = []
    while c.getAsyncOperationProgress() >= 0:
        samples.append(np.array(r.getActualTCPPose()[:3]))
        time.sleep(0.002)
    assert len(samples) > 5
    d = (p1[:3] - p0[:3]) / np.linalg.norm(p1[:3] - p0[:3])
    off_line = [np.linalg.norm((s - p0[:3]) - np.dot(s - p0[:3], d) * d) for s in samples]
    assert max(off_line) < 1e-4
    assert wait_for(lambda: np.allclose(r.getActualTCPPose(), p1, atol=1e-4))


def test_async_move_then_stop_halts_before_the_target(clients) -> None:  # type: ignore[no-untyped-def]
    c, r, sim = clients
    assert c.moveJ(Q_A, 1.0, 2.0)
    # slow (0.6 rad at 0.05 rad/s: 12 s simulated, 2.4 s of wall time at 5x), so that the stop below
    # lands mid-move even when a loaded machine sends it a few tenths of a second late
    assert c.moveJ(Q_B, 0.05, 1.0, True)
    assert c.getAsyncOperationProgress() >= 0
    time.sleep(0.1)  # at least 0.5 s simulated: the arm has left Q_A
    c.stopJ(2.0, False)  # returns None in ur_rtde 1.6.5
    assert wait_for(lambda: not sim.state()["moving"])
    q = np.array(r.getActualQ())
    assert not np.allclose(q, Q_B, atol=1e-2) and not np.allclose(q, Q_A, atol=1e-3)
    assert c.getAsyncOperationProgress() < 0


def test_servo_streaming_follows_with_lag(clients) -> None:  # type: ignore[no-untyped-def]
    c, r, _ = clients
    assert c.moveJ(Q_A, 1.5, 3.0)
    q = np.array(Q_A)
    lags = []
    for i in range(200):
        t0 = c.initPeriod()
        q = q + np.array([0.0005, 0, 0, 0, 0, 0])
        assert c.servoJ(q.tolist(), 0.0, 0.0, 0.002, 0.1, 300)
        if 50 <= i < 150:
            lags.append(q[0] - r.getActualQ()[0])
        c.waitPeriod(t0)
    # the controller lags the command; the median, as one stall of a loaded machine (the arm catches
    # up while the loop sleeps) leaves a few samples with no lag but more than the last step
    assert np.median(lags) > 0.0005
    assert c.servoStop(5.0)
    assert wait_for(lambda: abs(r.getActualQd()[0]) < 1e-6)
    assert abs(r.getActualQ()[0] - q[0]) < 0.05


def test_speedj_and_speed_stop(clients) -> None:  # type: ignore[no-untyped-def]
    c, r, _ = clients
    assert c.moveJ(Q_A, 1.5, 3.0)
    assert c.speedJ([0.2, 0, 0, 0, 0, 0], 1.0, 0.0)
    assert wait_for(lambda: r.getActualQd()[0] > 0.15)
    assert c.speedStop(5.0)
    # the receive interface's copy may be a frame behind the stop (its own thread, 2 ms frames):
    # 0.2 rad/s at 5 rad/s² takes 40 ms to stop; the deadline is for a loaded machine's late frames
    # (without the stop the joint would turn on at 0.2 rad/s)
    assert wait_for(lambda: abs(r.getActualQd()[0]) < 1e-6)


def test_dashboard_commands(shared_sim: SimProcess) -> None:
    db = dashboard_client.DashboardClient(shared_sim.address)
    db.connect()
    try:
        assert db.isInRemoteControl()
        assert db.getSerialNumber() == "20235500001"
        assert db.polyscopeVersion().startswith("5.15.0")
        assert "RUNNING" in db.robotmode() and "NORMAL" in db.safetymode()
        assert db.getRobotModel() == "UR5"
        db.closeSafetyPopup()
        db.unlockProtectiveStop()  # nothing to unlock: accepted
    finally:
        db.disconnect()


def test_protective_stop_mid_move_fails_the_move_and_unlocks_after_5s(sim: SimProcess) -> None:
    r = rtde_receive.RTDEReceiveInterface(sim.address)
    c = rtde_control.RTDEControlInterface(sim.address)
    try:
        def stop_once_moving() -> None:  # not after a fixed delay: a loaded machine may finish first
            wait_for(lambda: bool(sim.state()["moving"]), timeout=10.0)
            sim.inject("protective_stop")

        timer = threading.Thread(target=stop_once_moving, daemon=True)
        timer.start()
        # slow (0.4 rad at 0.03 rad/s: 13 s simulated, 1.3 s of wall time at 10x), so that the stop
        # lands mid-move even when a loaded machine stalls the watcher between seeing and injecting
        assert c.moveJ(Q_B, 0.03, 1.0) is False  # the blocking move returns False
        timer.join()
        # the receive thread may still hold the frame before the stop: wait for the one that says it
        assert wait_for(r.isProtectiveStopped) and c.isProgramRunning() is False
        assert wait_for(lambda: not sim.state()["moving"])
        db = dashboard_client.DashboardClient(sim.address)
        db.connect()
        with pytest.raises(RuntimeError, match="5s"):
            db.unlockProtectiveStop()
        time.sleep(0.6)  # 6 s of simulated time at 10x
        db.unlockProtectiveStop()
        db.disconnect()
        assert wait_for(lambda: not r.isProtectiveStopped())
        assert c.reuploadScript() and wait_for(c.isProgramRunning)
        assert c.moveJ(Q_A, 1.5, 3.0)
    finally:
        c.disconnect()
        r.disconnect()


def test_not_in_remote_control_is_refused_by_the_client(sim: SimProcess) -> None:
    sim.inject("remote_control", on=False)
    with pytest.raises(RuntimeError, match="remote control"):
        rtde_control.RTDEControlInterface(sim.address)


def test_several_simulators_at_once() -> None:
    sims = [start_sim(speed=5.0) for _ in range(3)]
    pairs: list[tuple[rtde_receive.RTDEReceiveInterface, rtde_control.RTDEControlInterface]] = []
    try:
        assert len({s.address for s in sims}) == 3
        for s in sims:
            pairs.append((rtde_receive.RTDEReceiveInterface(s.address),
                          rtde_control.RTDEControlInterface(s.address)))
        targets = [np.array(Q_A) + 0.1 * i for i in range(3)]
        for (_, c), q in zip(pairs, targets, strict=True):
            assert c.moveJ(q.tolist(), 1.5, 3.0, True)
        for (r, c), q in zip(pairs, targets, strict=True):
            assert wait_for(lambda c=c: c.getAsyncOperationProgress() < 0)
            # done is the end of the profile; the arm settles (and the receive thread catches up) after it
            assert wait_for(lambda r=r, q=q: np.allclose(r.getActualQ(), q, atol=1e-4))
    finally:
        # before the simulators go: a client left connected reconnects forever and aborts the
        # interpreter at exit
        for r, c in pairs:
            c.disconnect()
            r.disconnect()
        for s in sims:
            s.stop()
