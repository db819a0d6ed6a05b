"""A fast-time station's clock runs fast only while the host waits on it (`hil.station.paced_clock`)."""

from __future__ import annotations

import time

import pytest

from hil.station.paced_clock import PacedClock, simulator_pace


class FakeSimulator:
    """A simulator's clock: `rate` simulated seconds per wall second, switched by `pace`."""

    def __init__(self) -> None:
        self.rate, self.t, self.wall = 7.0, 100.0, time.monotonic()  # unpaced: its full speed
        self.calls: list[float] = []
        self.dead = False

    def now(self) -> float:
        return self.t + (time.monotonic() - self.wall) * self.rate

    def pace(self, rate: float) -> float:
        if self.dead:
            raise ConnectionRefusedError("the simulator is gone")
        self.t, self.wall, self.rate = self.now(), time.monotonic(), rate
        self.calls.append(rate)
        return self.t


def test_the_station_runs_at_the_walls_rate_between_steps_and_fast_inside_them() -> None:
    sim = FakeSimulator()
    clock = PacedClock(40.0, sim.pace)
    assert sim.calls == [1.0]  # made at the wall's rate: the plan computes first
    time.sleep(0.2)  # the host computes
    computing = clock.station()
    assert computing == pytest.approx(0.2, abs=0.05)  # not 8 s of standstill
    started = time.monotonic()
    with clock.busy(), clock.busy():  # nested: one switch
        clock.sleep(4.0)
    assert time.monotonic() - started < 1.0  # 4 station seconds in a tenth of the wall's
    assert sim.calls == [1.0, 40.0, 1.0]
    assert clock.station() - computing == pytest.approx(4.0, abs=0.5)
    assert clock.station() == pytest.approx(sim.now() - 100.0, abs=0.02)  # the simulator's own seconds
    clock.close()
    assert sim.calls[-1] == 40.0  # the simulator's full speed back


def test_a_simulator_that_stops_answering_leaves_the_clock_counting_on_the_wall() -> None:
    sim = FakeSimulator()
    clock = PacedClock(20.0, sim.pace)
    sim.dead = True
    before = clock.station()
    with clock.busy():  # no exception: the devices will say what failed
        time.sleep(0.05)
    assert clock.station() >= before


def test_a_non_positive_speed_is_refused() -> None:
    with pytest.raises(ValueError, match="speed"):
        PacedClock(0.0, FakeSimulator().pace)


def test_against_the_simulated_station_the_host_computing_is_not_multiplied(sim) -> None:
    """The real simulator's clock (its control channel's ``pace``): a wall second of computing is a
    station second, four station seconds of waiting take a tenth of a wall second at 40x."""
    clock = PacedClock(40.0, simulator_pace(sim))
    try:
        t0 = float(sim.state()["time"])
        time.sleep(0.3)
        assert float(sim.state()["time"]) - t0 == pytest.approx(0.3, abs=0.1)
        with clock.busy():
            assert float(sim.state()["speed"]) == 40.0
            clock.sleep(4.0)
        assert float(sim.state()["speed"]) == 1.0
        assert clock.station() == pytest.approx(float(sim.state()["time"]) - t0, abs=0.2)
    finally:
        clock.close()
    assert float(sim.state()["speed"]) == 40.0
