"""Issue 19 (smaller): the ur_rtde client process never outlives the process that drives it.

After a ``kill -9`` of its parent the client was seen alive for minutes: it noticed the closed pipe
only between calls, so a move in progress went on, unsupervised, to its end (and ur_rtde could then
block on the link). Now it watches its parent: it stops the arm and exits within two seconds or so.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from drivers.robot.isolated import _PARENT_POLL, _STOP_GRACE
from mocks.ur.process import SimProcess
from mocks.ur.testing import start_sim
from tests.proc_tree import command_line, descendants, wait_gone

ROOT = Path(__file__).resolve().parents[3]

# The driving process: opens the isolated client and starts a slow move of joint 1 (about 7 s at
# 0.2 rad/s), saying so on stdout, then waits for its kill.
DRIVER = """
import sys, time
import numpy as np
from drivers.robot.isolated import IsolatedURRobot
from drivers.robot.model import RobotConfig

if __name__ == "__main__":
    robot = IsolatedURRobot(RobotConfig(host=sys.argv[1], speed=0.2, acceleration=2.0))
    robot.open()
    q = np.array(robot.read_joints().q)
    q[0] += 1.4
    print("moving", flush=True)
    robot.move_to(q)
    print("arrived", flush=True)
    time.sleep(60)
"""


@pytest.fixture
def slow_sim() -> SimProcess:
    """A simulator in real time: the move outlasts the kill by seconds."""
    s = start_sim(speed=1.0)
    try:
        yield s
    finally:
        s.stop()


def test_kill_9_of_the_parent_stops_the_arm_and_ends_the_client(tmp_path, slow_sim):
    script = tmp_path / "driver.py"
    script.write_text(DRIVER)
    driver = subprocess.Popen([sys.executable, str(script), slow_sim.address], cwd=ROOT,
                              stdout=subprocess.PIPE, text=True,
                              env={**os.environ, "PYTHONPATH": str(ROOT)})
    try:
        assert driver.stdout is not None and driver.stdout.readline() == "moving\n"
        deadline = time.monotonic() + 10
        while not slow_sim.state()["moving"]:
            assert time.monotonic() < deadline, "the move did not start"
            time.sleep(0.02)
        children = descendants(driver.pid)
        assert any("spawn_main" in command_line(pid) for pid in children), children
        os.kill(driver.pid, signal.SIGKILL)
        driver.wait(5)
        killed = time.monotonic()
        # its promise: noticed within a poll, the arm stopped and the process ended within the grace
        # (the move itself had over 5 s to go); the margin is for a loaded machine
        bound = _PARENT_POLL + _STOP_GRACE + 1.5
        assert wait_gone(children, bound) == set(), "a child of the killed process is still running"
        while slow_sim.state()["moving"]:
            assert time.monotonic() - killed < bound, "the arm went on moving without its driver"
            time.sleep(0.02)
    finally:
        if driver.poll() is None:
            driver.kill()
            driver.wait(5)
