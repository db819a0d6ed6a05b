"""A simulator starved while it starts is waited for; a hung or runaway one is not (issue 29).

On a loaded machine (6 busy loops beside a load of 20) the station's start took more than its 60 s
of wall time and `hil moveb run --sim` gave up before anything moved. The start timeout now bounds
the child's CPU time; a child without any CPU for `_HUNG_S` is hung; and a wall bound remains.
"""

from __future__ import annotations

import os

from mocks.ur.process import _HUNG_S, _START_WALL_FACTOR, _cpu_seconds, start_verdict


def test_a_starved_start_is_waited_for_past_the_timeout() -> None:
    # 90 s of wall time, 12 s of CPU used, busy a moment ago: starved, not stuck
    assert start_verdict(90.0, 12.0, 0.5, 60.0) is None


def test_a_hung_a_runaway_and_an_endless_start_fail() -> None:
    assert "hung" in (start_verdict(40.0, 3.0, _HUNG_S, 60.0) or "")
    assert (start_verdict(70.0, 60.0, 0.0, 60.0) or "").endswith("did not start within 60 s")
    assert start_verdict(_START_WALL_FACTOR * 60.0, 30.0, 1.0, 60.0) is not None


def test_without_proc_the_wall_timeout_applies() -> None:
    assert start_verdict(59.0, None, 59.0, 60.0) is None
    assert (start_verdict(60.0, None, 60.0, 60.0) or "").endswith("did not start within 60 s")


def test_cpu_seconds_reads_this_process() -> None:
    cpu = _cpu_seconds(os.getpid())
    assert cpu is None or cpu > 0.0
