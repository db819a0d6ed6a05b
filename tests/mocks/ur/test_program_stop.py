"""When the program stops, the simulated arm stops: it never finishes a move nobody drives any more.

A real UR controller brings the arm to a controlled stop on its trajectory when its program stops (UR
user manual, "Stop Categories": category 2) — whether the operator pressed stop (dashboard ``stop``), the
script ended (ur_rtde's ``stopScript``) or another program replaced it. A simulator that let the last
motion run on would hide a driver bug that would crash a real arm. Each test starts a long, slow
asynchronous ``moveJ`` through the real ur_rtde client, stops the program mid-move and checks that the
arm is still within a bounded time and distance, far from the target.
"""

from __future__ import annotations

import socket
import time
from collections.abc import Callable, Iterator

import dashboard_client
import pytest
import rtde_control

from mocks.ur.process import SimProcess
from mocks.ur.testing import start_sim

Q_START = [0.2, -1.3, 1.3, -1.5, -1.5, 0.3]
Q_FAR = [2.7, -1.3, 1.3, -1.5, -1.5, 0.3]  # 2.5 rad of joint 0 away: about 10 s at 0.25 rad/s
SLOW_V, SLOW_A = 0.25, 1.0
# A stop at 4 rad/s^2 from 0.25 rad/s takes 8 mm of joint travel; the rest of the bound is the latency
# of the stop request on a loaded machine (1.2 s of simulated motion at full speed).
MAX_TRAVEL_AFTER_STOP = 0.3  # rad
STOP_WITHIN = 2.0  # s, real time (the simulator runs at real speed here)


@pytest.fixture(scope="module")
def real_time_sim() -> Iterator[SimProcess]:
    """A simulator at real speed, so a slow move cannot finish while the test looks at it."""
    s = start_sim(speed=1.0)
    try:
        yield s
    finally:
        s.stop()


@pytest.fixture
def moving(real_time_sim: SimProcess) -> Iterator[tuple[rtde_control.RTDEControlInterface, SimProcess]]:
    """The arm halfway into a slow asynchronous moveJ towards Q_FAR, driven by the real ur_rtde client."""
    sim = real_time_sim
    sim.inject("set_joints", q=Q_START)
    c = rtde_control.RTDEControlInterface(sim.address)
    try:
        assert c.moveJ(Q_FAR, SLOW_V, SLOW_A, True)
        assert _wait(lambda: sim.state()["q"][0] > Q_START[0] + 0.1, 5.0), "the move did not start"
        yield c, sim
    finally:
        if sim.state()["program"] != "rtde_control":
            sim.inject("stop_program")  # whatever replaced the control script: ur_rtde waits for it
        elif c.isConnected():
            c.stopScript()
        c.disconnect()


def _wait(pred: Callable[[], bool], timeout: float) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():
            return True
        time.sleep(0.01)
    return False


def _assert_stops(sim: SimProcess, q_at_stop: float) -> None:
    """Within STOP_WITHIN the arm is still, close to where it was told to stop, far from the target."""
    assert _wait(lambda: not sim.state()["moving"], STOP_WITHIN), (
        f"the arm is still moving {STOP_WITHIN} s after its program stopped: {sim.state()}")
    st = sim.state()
    assert st["runtime_state"] == "STOPPED"
    travel = st["q"][0] - q_at_stop
    assert 0.0 <= travel <= MAX_TRAVEL_AFTER_STOP, f"joint 0 went on {travel:.3f} rad after the stop"
    assert Q_FAR[0] - st["q"][0] > 1.0  # nowhere near the end of the move
    time.sleep(0.2)
    assert sim.state()["q"][0] == pytest.approx(st["q"][0], abs=1e-9)  # and it stays there


def test_stop_script_mid_move_stops_the_arm(moving) -> None:  # type: ignore[no-untyped-def]
    c, sim = moving
    q_at_stop = sim.state()["q"][0]
    c.stopScript()  # command 255: the control script ends on its next cycle
    _assert_stops(sim, q_at_stop)


def test_dashboard_stop_mid_move_stops_the_arm(moving) -> None:  # type: ignore[no-untyped-def]
    _, sim = moving
    d = dashboard_client.DashboardClient(sim.address)
    d.connect()
    try:
        q_at_stop = sim.state()["q"][0]
        d.stop()
    finally:
        d.disconnect()
    _assert_stops(sim, q_at_stop)


def test_a_new_program_stops_the_motion_of_the_one_it_replaces(moving) -> None:  # type: ignore[no-untyped-def]
    _, sim = moving
    q_at_stop = sim.state()["q"][0]
    with socket.create_connection((sim.address, int(sim.info["script_port"])), timeout=5.0) as s:
        s.sendall(b"def hil_idle():\n  sleep(30.0)\nend\n")
    assert _wait(lambda: sim.state()["program"] == "hil_idle", STOP_WITHIN)
    assert _wait(lambda: not sim.state()["moving"], STOP_WITHIN), f"still moving: {sim.state()}"
    st = sim.state()
    assert st["runtime_state"] == "PLAYING"  # the new program runs; the old motion is gone with the old one
    assert 0.0 <= st["q"][0] - q_at_stop <= MAX_TRAVEL_AFTER_STOP
    time.sleep(0.2)
    assert sim.state()["q"][0] == pytest.approx(st["q"][0], abs=1e-9)
