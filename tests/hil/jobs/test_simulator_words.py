"""After a fault on a simulated station the job says whether the simulator went silent (issue 29): its
longest pause between cycles against ur_rtde's 2.5 s, so a link lost under load is told apart."""

from __future__ import annotations

from typing import Any

from hil.jobs.station import simulator_words


class Simulator:
    def __init__(self, state: dict[str, Any] | None) -> None:
        self._state = state

    def state(self) -> dict[str, Any]:
        if self._state is None:
            raise ConnectionError("the control channel is gone")
        return self._state


def test_a_starved_simulator_is_named_as_the_cause() -> None:
    words = simulator_words(Simulator({"max_tick_gap_s": 3.1, "late_ticks": 812}))
    assert words is not None and "3.10 s" in words and "starved" in words and "812" in words


def test_a_simulator_that_kept_sending_clears_itself() -> None:
    words = simulator_words(Simulator({"max_tick_gap_s": 0.04, "late_ticks": 0}))
    assert words is not None and "0.04 s" in words and "kept sending" in words


def test_a_real_station_or_a_dead_simulator_says_nothing() -> None:
    assert simulator_words(None) is None
    assert simulator_words(Simulator(None)) is None
