"""The simulated controller keeps its 500 Hz beside busy threads of its own process (issue 29: "lost RTDE
link" under load): while it runs, another thread hands the interpreter back within a quarter cycle.

A busy Python thread stands in for the trackers' and the world's work; it is deterministic contention
for the GIL, not machine load.
"""

from __future__ import annotations

import sys
import threading
import time
from collections.abc import Iterator

import pytest

from mocks.ur.controller import GIL_SHARE_OF_CYCLE, SimConfig, SimController
from mocks.ur.testing import random_loopback

WINDOW_S = 1.5


@pytest.fixture
def default_interval() -> Iterator[float]:
    """CPython's default switch interval (5 ms) for the test, whatever the process had."""
    before = sys.getswitchinterval()
    sys.setswitchinterval(0.005)
    try:
        yield 0.005
    finally:
        sys.setswitchinterval(before)


def _controller() -> SimController:
    cfg = SimConfig(address=random_loopback(), rtde_port=0, dashboard_port=0, script_port=0, primary_port=0,
                    secondary_port=0, control_port=None)
    return SimController(cfg).start()


def _ticks_in(controller: SimController, seconds: float) -> int:
    start = controller.tick_count
    time.sleep(seconds)
    return controller.tick_count - start


def test_a_running_controller_hands_over_within_a_quarter_cycle(default_interval: float) -> None:
    c = _controller()
    try:
        assert sys.getswitchinterval() <= GIL_SHARE_OF_CYCLE / 500.0 + 1e-12
        second = _controller()
        second.stop()
        assert sys.getswitchinterval() <= GIL_SHARE_OF_CYCLE / 500.0 + 1e-12  # the first still runs
    finally:
        c.stop()
    assert sys.getswitchinterval() == pytest.approx(default_interval)  # the process's own, back


def test_the_tick_thread_keeps_its_rate_beside_a_busy_thread(default_interval: float) -> None:
    """With the default 5 ms interval the busy thread cut the ticks to a fifth of the quiet rate."""
    c = _controller()
    stop = threading.Event()

    def busy() -> None:
        while not stop.is_set():
            sum(range(10_000))

    try:
        quiet = _ticks_in(c, WINDOW_S)
        hog = threading.Thread(target=busy, daemon=True)
        hog.start()
        try:
            contended = _ticks_in(c, WINDOW_S)
        finally:
            stop.set()
            hog.join()
    finally:
        c.stop()
    assert contended >= 0.5 * quiet, (contended, quiet)
