"""The station serves emScon beside GeoCOM, on the robot simulator's clock, with its faults injectable."""

from __future__ import annotations

import time
from collections.abc import Iterator

import numpy as np
import pytest

from drivers.tracker.emscon.packets import (
    Command,
    ResultStatus,
    SingleMeasResult,
    StatusChange,
    SystemStatusChange,
    encode_command,
)
from hil.arm.geometry import Geometry
from mocks.station import start_station
from mocks.ur.process import SimProcess
from mocks.world import World
from tests.mocks.emscon.test_server import Client

C = Command
SPEED = 10.0


@pytest.fixture(scope="module")
def station() -> Iterator[SimProcess]:
    sim = start_station(speed=SPEED, seed=3, ideal=True)
    try:
        yield sim
    finally:
        sim.stop()


def test_emscon_measures_the_same_world_and_its_faults_are_injectable(station: SimProcess) -> None:
    svc = station.info["services"][0]
    url = svc["tracker_emscon_url"]
    assert url.startswith(f"tcp://{station.address}:") and svc["tracker_url"].startswith("socket://")
    c = Client(url)
    try:
        c.ok(C.INITIALIZE)
        assert c.ok(C.GET_TRACKER_STATUS) == (2,)  # locked on the SMR at the start pose
        c.ok(C.START_MEASUREMENT)  # 1 s of simulated time: 0.1 s at 10x
        (result,) = c.wait_for(lambda r: isinstance(r, SingleMeasResult))
        assert isinstance(result, SingleMeasResult)
        world = World(Geometry.from_dict(svc["truth"]), lambda: np.array(svc["home"]))
        np.testing.assert_allclose(result.position, world.target().position, atol=5e-5)
        station.inject("emscon_laser_cold", seconds=3600)
        assert c.status(C.START_MEASUREMENT) == ResultStatus.SensorNotWarmedUp
        station.inject("block_beam", on=True, reason="a person")
        assert c.wait_for(lambda r: isinstance(r, StatusChange), 5.0) == [
            StatusChange(SystemStatusChange.MEAS_STATUS_NOT_READY)]
        station.inject("block_beam", on=False)
        c.ok(C.FIND_REFLECTOR, 2.0)
        station.inject("emscon_garbage")
        with pytest.raises(Exception, match="stream out of step"):
            c.receive(5.0)
    finally:
        c.close()
    second = Client(url)  # the garbage closed nothing: the client gave up, the server accepts anew
    try:
        assert second.ok(C.GET_SYSTEM_STATUS)[2] == 0  # the laser is still cold
        # a stall 5x the silence checked: a loaded machine that holds this thread between the inject
        # and the check cannot make the stalled answer arrive inside it
        station.inject("emscon_stall", seconds=1.0)
        second.sock.sendall(encode_command(C.GET_TRACKER_STATUS))
        assert second.receive(0.2) == []
        assert second.ok(C.GET_REFLECTOR) == (1,)  # (after the stalled answer)
        station.inject("emscon_drop")
        assert second.receive(5.0) == [] and second.closed  # (receive stops at the EOF)
    finally:
        second.close()


def test_the_station_carries_two_real_clocks_and_the_true_map_between_them(station: SimProcess) -> None:
    from hil.calibration.stream_clocks import ClockMap, StationClocks

    svc = station.info["services"][0]
    clocks = StationClocks.from_dict(svc["clocks"])
    assert clocks == StationClocks.realistic()  # an ideal arm still has two instruments
    truth = ClockMap(**svc["clock_map"])
    # the tracker's clock counts the station's time over its nominal speed: SPEED times slower
    assert truth.drift == pytest.approx(SPEED * clocks.controller.rate / clocks.tracker.rate - 1.0, rel=1e-12)
    # the map holds at every instant, also after the station was paced to the wall's rate and back
    # (`hil.station.paced_clock`): the pair is one read of the simulated time, so exactly
    for pace in (SPEED, 1.0, SPEED, 1.0):
        station.inject("pace", speed=pace)
        time.sleep(0.2)
        trk, ctrl = station.state()["services"]["clock_pair"]
        assert float(truth(trk)) == pytest.approx(ctrl, abs=1e-6)
        assert trk > clocks.tracker.offset_s  # the tracker's stamps are its own clock's, not the host's
    station.inject("pace", speed=SPEED)
