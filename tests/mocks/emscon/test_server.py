"""The emScon simulator over a raw TCP socket, as a TPI client sees it (no hil driver involved)."""

from __future__ import annotations

import socket
import time
from collections.abc import Callable, Iterator

import numpy as np
import pytest

from drivers.tracker.emscon.packets import (
    Answer,
    Command,
    ErrorResponse,
    MultiMeasResult,
    PacketError,
    PacketReader,
    Reply,
    ResultStatus,
    SingleMeasResult,
    StatusChange,
    SystemStatusChange,
    decode_reply,
    encode_command,
)
from mocks.emscon import EmsconConfig, EmsconSimulator, ServerConfig
from mocks.geocom import StaticTarget
from mocks.geocom.target import TargetState

C = Command
OK = ResultStatus.AllOK
TRUE = np.array([1.0, 2.0, 0.5])
SCALE = 20.0  # simulated seconds per wall second
NOT_READY = StatusChange(SystemStatusChange.MEAS_STATUS_NOT_READY)
READY = StatusChange(SystemStatusChange.MEAS_STATUS_READY)


class Client:
    """A bare TPI client: send commands, collect every packet the server sends."""

    def __init__(self, url: str, timeout: float = 2.0) -> None:
        host, port = url.removeprefix("tcp://").rsplit(":", 1)
        self.sock = socket.create_connection((host, int(port)), timeout=timeout)
        self.reader = PacketReader()
        self.queue: list[Reply] = []
        self.closed = False

    def close(self) -> None:
        self.sock.close()

    def _read(self, timeout: float) -> bool:
        """Decode what arrives within ``timeout`` into the queue; False on timeout or EOF."""
        self.sock.settimeout(max(0.001, timeout))
        try:
            data = self.sock.recv(65536)
        except TimeoutError:
            return False
        except ConnectionResetError:
            data = b""
        if not data:
            self.closed = True
            return False
        self.queue += [decode_reply(p) for p in self.reader.feed(data)]
        return True

    def receive(self, timeout: float) -> list[Reply]:
        """Whatever arrives within ``timeout`` (stops early at EOF)."""
        end = time.monotonic() + timeout
        while not self.closed and (left := end - time.monotonic()) > 0:
            self._read(left)
        got, self.queue = self.queue, []
        return got

    def wait_for(self, pred: Callable[[Reply], bool], timeout: float = 10.0) -> list[Reply]:
        """Packets up to and including the first that satisfies ``pred`` (later ones stay queued).

        The default deadline only bounds a failure: a loaded machine may answer seconds late."""
        end = time.monotonic() + timeout
        while True:
            for i, reply in enumerate(self.queue):
                if pred(reply):
                    got, self.queue = self.queue[: i + 1], self.queue[i + 1 :]
                    return got
            if self.closed or time.monotonic() >= end:
                raise AssertionError(f"not received within {timeout} s; got {self.queue}")
            self._read(end - time.monotonic())

    def call(self, command: Command, *params: object) -> tuple[list[Reply], Answer]:
        """Send one command; (packets before its answer, the answer)."""
        self.sock.sendall(encode_command(command, *params))
        got = self.wait_for(lambda r: isinstance(r, Answer) and r.command == command)
        answer = got.pop()
        assert isinstance(answer, Answer)
        return got, answer

    def ok(self, command: Command, *params: object) -> tuple[object, ...]:
        _, answer = self.call(command, *params)
        assert answer.status == OK, answer
        return answer.values

    def status(self, command: Command, *params: object) -> int:
        return self.call(command, *params)[1].status


@pytest.fixture
def target() -> StaticTarget:
    return StaticTarget(TRUE.copy())


@pytest.fixture
def sim(target: StaticTarget) -> Iterator[EmsconSimulator]:
    s = EmsconSimulator(target, ServerConfig(time_scale=SCALE, instrument=EmsconConfig(seed=1))).start()
    try:
        yield s
    finally:
        s.stop()


@pytest.fixture
def client(sim: EmsconSimulator) -> Iterator[Client]:
    c = Client(sim.url)
    try:
        yield c
    finally:
        c.close()


def start_up(c: Client, mode: int = 0) -> None:
    c.ok(C.SET_UNITS, 0, 0, 0, 0, 0)
    c.ok(C.SET_ENVIRONMENT_PARAMS, 20.0, 1013.25, 50.0)
    c.ok(C.INITIALIZE)
    c.ok(C.SET_MEASUREMENT_MODE, mode)
    c.ok(C.SET_REFLECTOR, 1)
    status = c.ok(C.GET_SYSTEM_STATUS)
    assert status[1:4] == (5, 3, 2)  # initialized, laser warm, ADM ready


def test_url_is_loopback_and_refuses_other_addresses(sim: EmsconSimulator) -> None:
    assert sim.url.startswith("tcp://127.0.0.1:")
    with pytest.raises(ValueError, match="loopback"):
        ServerConfig(address="0.0.0.0")


def test_start_up_then_a_stationary_point_equals_the_truth(client: Client) -> None:
    start_up(client)
    client.ok(C.SET_STATIONARY_MODE_PARAMS, 1000, 1)
    t0 = time.monotonic()
    before, answer = client.call(C.START_MEASUREMENT)
    assert before == [] and answer == Answer(C.START_MEASUREMENT, OK)  # the answer first...
    (result,) = client.wait_for(lambda r: isinstance(r, SingleMeasResult))  # ...then the result
    assert time.monotonic() - t0 >= 1.0 / SCALE * 0.9
    assert isinstance(result, SingleMeasResult)
    sigma = np.array(result.apriori_std)
    assert np.all(np.abs(np.array(result.position) - TRUE) < 5 * sigma / np.sqrt(1000))
    assert np.all(np.array(result.std) < 2 * sigma)


def test_beam_lost_and_found_again(client: Client, target: StaticTarget) -> None:
    start_up(client)
    target.set(TRUE, visible=False, reason="a person in the beam")
    assert client.wait_for(lambda r: isinstance(r, StatusChange), 5.0) == [NOT_READY]  # noticed by itself
    assert client.status(C.START_MEASUREMENT) == ResultStatus.MeasurementStatusNotReady
    assert client.status(C.FIND_REFLECTOR, 2.3) == ResultStatus.ModuleTimedOut
    target.set(TRUE, visible=True)
    assert client.ok(C.GET_TRACKER_STATUS) == (0,)  # no re-lock by itself
    client.ok(C.FIND_REFLECTOR, 2.3)
    assert client.wait_for(lambda r: isinstance(r, StatusChange)) == [READY]
    assert client.ok(C.GET_TRACKER_STATUS) == (2,)
    client.ok(C.START_MEASUREMENT)
    client.wait_for(lambda r: isinstance(r, SingleMeasResult))
    assert NOT_READY not in client.receive(0.2)  # once per loss


def test_beam_lost_during_a_stationary_measurement(client: Client, target: StaticTarget) -> None:
    start_up(client)
    # 60 s simulated, 3 s of wall time: the beam goes while it runs even when a loaded machine stalls
    # this thread for a few tenths of a second (a 5 s one, 0.25 s of wall time, could end first)
    client.ok(C.SET_STATIONARY_MODE_PARAMS, 60_000, 1)
    client.ok(C.START_MEASUREMENT)
    time.sleep(0.05)
    target.set(TRUE, visible=False)
    got = client.wait_for(lambda r: isinstance(r, ErrorResponse))
    assert got == [NOT_READY, ErrorResponse(C.START_MEASUREMENT, ResultStatus.NoStationaryResult)]


def test_continuous_stream_timestamps_batches_and_stop(client: Client) -> None:
    start_up(client, mode=1)
    client.ok(C.SET_CONTINUOUS_TIME_MODE_PARAMS, 5, 0, 0, 0)  # 200 Hz on the tracker's clock
    t0 = time.monotonic()
    client.ok(C.START_MEASUREMENT)
    packets = [r for r in client.receive(0.5) if isinstance(r, MultiMeasResult)]
    before, answer = client.call(C.STOP_MEASUREMENT)
    wall = time.monotonic() - t0  # 0.5 s, more when a loaded machine answers the stop late
    assert answer.status == OK
    packets += [r for r in before if isinstance(r, MultiMeasResult)]
    samples = [s for p in packets for s in p.samples]
    times = np.array([s.seconds for s in samples])
    # 5 ms on the tracker's clock, which runs at the wall's rate while a fast-time station runs at its
    # speed (the server's time_scale): a wall second is
    # 200 samples (not 20 simulated seconds' 4000), in packets about 0.1 s of wall time apart
    assert 75 < len(samples) <= 200 * wall + 10 and 3 <= len(packets) <= wall / 0.1 + 3
    np.testing.assert_allclose(np.diff(times), 0.005, atol=2e-6)
    assert all(0 <= s.time2 < 1_000_000 for s in samples)
    assert np.max(np.abs(np.array([s.position for s in samples]) - TRUE)) < 1e-4
    assert not any(isinstance(r, MultiMeasResult) for r in client.receive(0.3))  # stopped


class WallMovingTarget:
    """An SMR moving at ``speed`` m/s along x in wall-clock time, as the simulated arm under servo
    streaming does whatever the simulation's speed (its targets arrive at the wall clock's rate)."""

    def __init__(self, speed: float) -> None:
        self.speed = speed
        self.t0 = time.monotonic()

    def target(self) -> TargetState:
        return TargetState(TRUE + np.array([self.speed * (time.monotonic() - self.t0), 0.0, 0.0]))


def test_continuous_stamps_run_on_a_clock_at_the_wall_rate_in_fast_time() -> None:
    """A tracker's quartz runs at the host clock's rate; in a fast-time simulation too, a continuous
    sample's stamp says when (at that rate) the SMR was where the sample says: the position against
    the stamp moves at the SMR's true speed, and the stamps span the wall time streamed. Stamps on
    simulated seconds (20 times faster) made a 0.1 m/s SMR look 20 times slower."""
    target = WallMovingTarget(0.1)
    with EmsconSimulator(target, ServerConfig(time_scale=SCALE, instrument=EmsconConfig(seed=1))) as s:
        c = Client(s.url)
        try:
            start_up(c, mode=1)
            c.ok(C.SET_CONTINUOUS_TIME_MODE_PARAMS, 10, 0, 0, 0)
            t0 = time.monotonic()
            c.ok(C.START_MEASUREMENT)
            packets = [r for r in c.receive(1.0) if isinstance(r, MultiMeasResult)]
            before, _ = c.call(C.STOP_MEASUREMENT)
            wall = time.monotonic() - t0
        finally:
            c.close()
    samples = [v for p in packets + [r for r in before if isinstance(r, MultiMeasResult)] for v in p.samples]
    times = np.array([v.seconds for v in samples])
    x = np.array([v.position[0] for v in samples])
    assert 40 < len(samples) <= 100 * wall + 10
    assert times[-1] - times[0] <= wall + 0.02
    slope, _ = np.polyfit(times, x, 1)
    assert slope == pytest.approx(0.1, rel=0.05)


def test_continuous_with_a_point_count_stops_by_itself(client: Client) -> None:
    start_up(client, mode=1)
    client.ok(C.SET_CONTINUOUS_TIME_MODE_PARAMS, 10, 25, 0, 0)
    client.ok(C.START_MEASUREMENT)
    # 0.25 s simulated (12.5 ms of wall time): wait for the 25 however late they come, then make
    # sure no more follow
    got: list[Reply] = []
    deadline = time.monotonic() + 10.0
    while sum(len(r.samples) for r in got if isinstance(r, MultiMeasResult)) < 25:
        assert time.monotonic() < deadline, f"not 25 samples within 10 s: {got}"
        got += client.receive(0.05)
    got += client.receive(0.3)
    assert sum(len(r.samples) for r in got if isinstance(r, MultiMeasResult)) == 25
    client.ok(C.START_MEASUREMENT)  # not busy any more


def test_second_client_is_refused_until_the_first_leaves(sim: EmsconSimulator, client: Client) -> None:
    client.ok(C.GET_SYSTEM_STATUS)
    second = Client(sim.url)
    # (receive stops at the EOF that follows the refusal; 5 s is for a loaded machine)
    assert second.receive(5.0) == [ErrorResponse(64, ResultStatus.MultiConnectionsNotAllowed)]
    assert second.closed
    client.ok(C.GET_TRACKER_STATUS)  # the first one is unaffected
    client.close()
    third = Client(sim.url)  # right after the first hung up
    try:
        assert third.ok(C.GET_REFLECTOR) == (1,)
    finally:
        third.close()


def test_state_survives_a_reconnect_but_not_the_measurement(sim: EmsconSimulator, client: Client) -> None:
    start_up(client, mode=1)
    client.ok(C.START_MEASUREMENT)
    client.close()
    again = Client(sim.url)
    try:
        assert not any(isinstance(r, MultiMeasResult) for r in again.receive(0.2))
        assert again.ok(C.GET_SYSTEM_STATUS)[1] == 5  # still initialized
        assert again.ok(C.GET_MEASUREMENT_MODE) == (1,)
        again.ok(C.START_MEASUREMENT)  # the old stream ended with its client
    finally:
        again.close()


def test_undecodable_packet_closes_the_connection(sim: EmsconSimulator, client: Client) -> None:
    client.sock.sendall(b"\x08\x00\x00\x00\x01\x00\x00\x00")  # a well-framed packet of type ERROR
    client.receive(5.0)  # stops at the EOF (5 s is for a loaded machine)
    assert client.closed
    fresh = Client(sim.url)
    try:
        fresh.sock.sendall(b"\xff\xff\xff\xff\x00\x00\x00\x00")  # a size no packet has
        fresh.receive(5.0)
        assert fresh.closed
    finally:
        fresh.close()


def test_fault_drop(sim: EmsconSimulator, client: Client) -> None:
    client.ok(C.GET_SYSTEM_STATUS)
    sim.drop()
    client.receive(5.0)  # stops at the EOF (5 s is for a loaded machine)
    assert client.closed
    again = Client(sim.url)
    try:
        again.ok(C.GET_SYSTEM_STATUS)
    finally:
        again.close()


def test_fault_stall(sim: EmsconSimulator, client: Client) -> None:
    # t0 before the stall begins, and a stall 4x the silence checked: a loaded machine that holds this
    # thread between the two cannot make the answer look early
    t0 = time.monotonic()
    sim.stall(1.0)
    client.sock.sendall(encode_command(C.GET_SYSTEM_STATUS))
    assert client.receive(0.25) == []
    client.wait_for(lambda r: isinstance(r, Answer))
    assert 1.0 <= time.monotonic() - t0 < 5.0


def test_fault_garbage(sim: EmsconSimulator, client: Client) -> None:
    client.ok(C.GET_SYSTEM_STATUS)
    sim.garbage()
    with pytest.raises(PacketError):
        client.receive(1.0)


def test_fault_laser_cold(sim: EmsconSimulator, client: Client) -> None:
    start_up(client)
    sim.laser_cold(60.0)  # simulated seconds: 3 s of wall time, longer than a loaded machine's stall
    assert client.ok(C.GET_SYSTEM_STATUS)[2] == 0
    assert client.status(C.START_MEASUREMENT) == ResultStatus.SensorNotWarmedUp
    deadline = time.monotonic() + 15.0
    while client.ok(C.GET_SYSTEM_STATUS)[2] != 3:  # warm again by itself
        assert time.monotonic() < deadline, "the laser never warmed up"
        time.sleep(0.05)
    client.ok(C.START_MEASUREMENT)


def test_unknown_command_is_answered_not_implemented(client: Client) -> None:
    import struct

    client.sock.sendall(struct.pack("<iii", 12, 0, 999))
    (answer,) = client.wait_for(lambda r: isinstance(r, Answer))
    assert answer == Answer(999, ResultStatus.NotImplemented)


def test_stop_is_prompt(target: StaticTarget) -> None:
    s = EmsconSimulator(target, ServerConfig(time_scale=SCALE)).start()
    c = Client(s.url)
    c.ok(C.INITIALIZE)
    t0 = time.monotonic()
    s.stop()
    # its threads notice within a 10 ms poll; one that did not would hold stop() for its 2 s join
    # timeout (the rest of the bound is for a loaded machine)
    assert time.monotonic() - t0 < 1.5
    c.receive(5.0)  # stops at the EOF
    assert c.closed
    with pytest.raises(OSError):
        Client(s.url, timeout=0.5)
