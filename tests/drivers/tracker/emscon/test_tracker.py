"""`EmsconTracker` against the emScon simulator: start-up, points, re-lock, paths, readiness and faults.

A recording proxy sits between the driver and the simulator where the exact exchange matters, so the
packets the driver sends are compared byte for byte with packets built from the header's layouts.
"""

from __future__ import annotations

import contextlib
import socket
import struct
import threading
import time
from collections.abc import Iterator

import numpy as np
import pytest

from drivers.tracker import (
    Atmosphere,
    ConnectionLost,
    EmsconConfig,
    EmsconError,
    EmsconTracker,
    LinkError,
    NotReady,
    PointStatus,
    TargetLost,
    TcpConfig,
)
from drivers.tracker.emscon.packets import HEADER, PacketReader
from mocks.emscon.instrument import EmsconConfig as SimConfig
from mocks.emscon.server import EmsconSimulator, ServerConfig
from mocks.geocom.noise import NOISELESS
from mocks.geocom.target import StaticTarget

TRUTH = np.array([2.1, -0.7, 0.4])
SCALE = 20.0  # simulated seconds per wall second


def simulator(target: StaticTarget, scale: float = SCALE, **instrument: object) -> EmsconSimulator:
    config = ServerConfig(instrument=SimConfig(**instrument), time_scale=scale)  # type: ignore[arg-type]
    return EmsconSimulator(target, config).start()


def driver(url: str, **kw: object) -> EmsconTracker:
    settings: dict[str, object] = {"timeout": 1.0, "measure_time_ms": 200,
                                   "atmosphere": Atmosphere(21.5, 990.0, humidity_percent=40.0)}
    settings.update(kw)
    config = EmsconConfig(TcpConfig(url, connect_timeout=2.0), **settings)  # type: ignore[arg-type]
    return EmsconTracker(config)


@contextlib.contextmanager
def opened(url: str, **kw: object) -> Iterator[EmsconTracker]:
    tr = driver(url, **kw).open()
    try:
        yield tr
    finally:
        tr.close()


@pytest.fixture
def target() -> StaticTarget:
    return StaticTarget(TRUTH.copy())


@pytest.fixture
def sim(target: StaticTarget) -> Iterator[EmsconSimulator]:
    s = simulator(target)
    yield s
    s.stop()


@pytest.fixture
def tracker(sim: EmsconSimulator) -> Iterator[EmsconTracker]:
    tr = driver(sim.url).open()
    yield tr
    tr.close()


# ------------------------------------------------------------------------------ exact exchange
class Recorder:
    """A TCP proxy that keeps every packet the client sends (framed), then forwards it."""

    def __init__(self, upstream: str) -> None:
        host, port = upstream.removeprefix("tcp://").split(":")
        self.upstream = (host, int(port))
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.url = f"tcp://127.0.0.1:{self.listener.getsockname()[1]}"
        self.sent: list[bytes] = []
        self._stop = threading.Event()
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        conn, _ = self.listener.accept()
        up = socket.create_connection(self.upstream)
        reader = PacketReader()

        def pump(src: socket.socket, dst: socket.socket, record: bool) -> None:
            with contextlib.suppress(OSError):
                while data := src.recv(65536):
                    if record:
                        self.sent.extend(reader.feed(data))
                    dst.sendall(data)
            with contextlib.suppress(OSError):
                dst.shutdown(socket.SHUT_WR)

        threading.Thread(target=pump, args=(up, conn, False), daemon=True).start()
        pump(conn, up, True)

    def close(self) -> None:
        self.listener.close()


def command(cmd: int, fmt: str = "", *values: object) -> bytes:
    """A ...CT packet built from the header's layout: lPacketSize, type 0, ES_Command, parameters."""
    body = struct.pack("<i", cmd) + (struct.pack("<" + fmt, *values) if fmt else b"")
    return struct.pack("<ii", 8 + len(body), 0) + body


def test_start_up_sends_the_documented_sequence_byte_for_byte(sim: EmsconSimulator) -> None:
    proxy = Recorder(sim.url)
    try:
        tr = driver(proxy.url, reflector="RRR 0.5in").open()
        tr.close()
    finally:
        proxy.close()
    deadline = time.monotonic() + 2
    while len(proxy.sent) < 14 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert proxy.sent[:13] == [
        command(1),  # ES_C_GetSystemStatus
        command(122),  # ES_C_GetMeasurementStatusInfo
        command(26, "i", 0),  # SetCoordinateSystemType RHR
        command(5, "iiiii", 0, 0, 0, 0, 0),  # SetUnits metre, radian, °C, mbar, %RH
        command(20, "ddd", 21.5, 990.0, 40.0),  # SetEnvironmentParams
        command(7),  # Initialize (the simulator starts uninitialized)
        command(1), command(122),  # the laser's state
        command(24, "i", 0),  # SetMeasurementMode stationary
        command(28, "ii", 200, 1),  # SetStationaryModeParams 200 ms, ADM on
        command(43, "di", 0.05, 5000),  # SetSearchParams
        command(42),  # GetReflectors
        command(40, "i", 2),  # SetReflector "RRR 0.5in"
    ]
    assert proxy.sent[13:15] == [command(132), command(142)]  # GetTrackerInfo, GetSystemSoftwareVersion
    assert proxy.sent[-1] == command(52)  # StopMeasurement on close
    assert all(HEADER.unpack_from(p)[0] == len(p) for p in proxy.sent)


def test_open_identifies_the_tracker_and_applies_the_settings(
        sim: EmsconSimulator, tracker: EmsconTracker) -> None:
    ident = tracker.identity
    assert ident is not None and (ident.name, ident.serial_number) == ("AT960-SIM", 960_001)
    assert ident.interface == "emScon TPI 3.6.0" and ident.firmware == (3, 6, 0)
    st = tracker.status()
    assert st.initialized and st.laser_ready and st.reflector_found
    assert tracker.lock_status() == "locked in" and tracker.ready()


def test_a_point_is_the_truth_within_the_noise(tracker: EmsconTracker) -> None:
    p = tracker.measure_point(3)
    assert p.samples == 3 and p.status is PointStatus.OK and p.relocks == 0
    assert np.linalg.norm(p.xyz - TRUTH) < 60e-6  # MPE-class noise, averaged over 200 ms each
    assert all(0 <= s < 20e-6 for s in p.spread)
    one = tracker.measure_point(1)
    assert all(0 < s < 60e-6 for s in one.spread)  # the tracker's own standard deviation


def test_noiseless_point_is_exact_and_the_atmosphere_is_corrected(target: StaticTarget) -> None:
    s = simulator(target, noise=NOISELESS, true_temperature_c=21.5, true_pressure_mbar=990.0)
    try:
        with driver(s.url) as tr:
            assert np.allclose(tr.measure_point(1).xyz, TRUTH, atol=1e-9)
        with driver(s.url, atmosphere=Atmosphere(30.0, 990.0)) as tr:  # 10 K wrong: about 10 ppm long
            d = np.linalg.norm(tr.measure_point(1).xyz) - np.linalg.norm(TRUTH)
            assert 5e-6 * np.linalg.norm(TRUTH) < abs(d) < 20e-6 * np.linalg.norm(TRUTH)
    finally:
        s.stop()


def test_an_unknown_reflector_is_refused_naming_the_known_ones(sim: EmsconSimulator) -> None:
    with pytest.raises(EmsconError, match=r"'CCR 7/8in'.*1: RRR 1.5in, 2: RRR 0.5in, 3: TBR 0.5in"):
        driver(sim.url, reflector="CCR 7/8in").open()
    assert not sim.connected or _wait(lambda: not sim.connected)


# ------------------------------------------------------------------------------ the beam
def test_a_blocked_beam_is_target_lost_after_the_bounded_relocks(target: StaticTarget,
                                                                 tracker: EmsconTracker) -> None:
    target.set(TRUTH, visible=False, reason="someone in the beam")
    with pytest.raises(TargetLost, match="after 2 re-lock attempts.*ES_RS_MeasurementStatusNotReady"):
        tracker.measure_point(1)
    assert tracker.lock_status() == "locked out" and not tracker.relock()
    target.set(TRUTH, visible=True)
    assert tracker.relock() and tracker.lock_status() == "locked in"
    assert np.linalg.norm(tracker.measure_point(1).xyz - TRUTH) < 100e-6


def test_a_beam_back_during_the_relocks_gives_the_point_and_counts_them(target: StaticTarget,
                                                                         sim: EmsconSimulator) -> None:
    with opened(sim.url, search_timeout_ms=4000) as tr:  # a search takes up to 4 simulated seconds
        target.set(TRUTH, visible=False)
        threading.Timer(0.05, lambda: target.set(TRUTH, visible=True)).start()
        p = tr.measure_point(1)
    assert 1 <= p.relocks <= 2 and np.linalg.norm(p.xyz - TRUTH) < 100e-6


def test_a_beam_lost_mid_measurement_is_target_lost(target: StaticTarget, sim: EmsconSimulator) -> None:
    with opened(sim.url, measure_time_ms=20_000, max_relocks=0) as tr:  # 1 s of wall time
        threading.Timer(0.1, lambda: target.set(TRUTH, visible=False)).start()
        with pytest.raises(TargetLost, match="ES_RS_NoStationaryResult"):
            tr.measure_point(1)


# ------------------------------------------------------------------------------ readiness
def test_a_cold_laser_is_not_ready_until_it_warms(target: StaticTarget) -> None:
    # 40 simulated seconds = 2 s of wall time: longer than a loaded machine takes to connect
    s = simulator(target, warmup_s=40.0)
    try:
        with pytest.raises(NotReady, match="warming up"):
            driver(s.url).open()
        _wait(lambda: not s.connected)
        with driver(s.url, warmup_timeout=10.0) as tr:  # waits for it
            assert tr.ready() and tr.measure_point(1).samples == 1
            s.laser_cold(40.0)
            with pytest.raises(NotReady, match="ES_RS_SensorNotWarmedUp"):
                tr.measure_point(1)
            assert not tr.ready()
            assert _wait(tr.ready, 6.0)
            assert tr.measure_point(1).samples == 1
    finally:
        s.stop()


def test_a_second_client_is_refused_while_one_is_connected(
        sim: EmsconSimulator, tracker: EmsconTracker) -> None:
    with pytest.raises(ConnectionLost, match="MultiConnectionsNotAllowed"):
        driver(sim.url).open()
    assert tracker.measure_point(1).samples == 1  # the first client is not disturbed


# ------------------------------------------------------------------------------ link faults
def test_a_dropped_connection_is_connection_lost_then_reopens(
        sim: EmsconSimulator, tracker: EmsconTracker) -> None:
    sim.drop()
    with pytest.raises(ConnectionLost):
        tracker.measure_point(1)
    assert _wait(lambda: not sim.connected)
    tracker.close()
    tracker.open()
    assert tracker.measure_point(1).samples == 1


def test_garbage_on_the_line_resynchronises_by_reconnecting(
        sim: EmsconSimulator, tracker: EmsconTracker) -> None:
    sim.garbage()
    time.sleep(0.05)
    p = tracker.measure_point(1)  # the garbled read is retried once, on a fresh connection
    assert np.linalg.norm(p.xyz - TRUTH) < 100e-6


def test_a_stalled_server_times_out_and_the_late_answer_is_never_paired(sim: EmsconSimulator) -> None:
    # a timeout that a loaded machine's scheduling does not reach, a stall well past it
    with opened(sim.url, timeout=1.0, link_retries=0) as tr:
        sim.stall(1.6)
        with pytest.raises(LinkError, match="no answer"):
            tr.measure_point(1)
        time.sleep(1.0)
        # the stalled command's late answer is on the old connection: the driver reconnects first
        p = tr.measure_point(1)
        assert np.linalg.norm(p.xyz - TRUTH) < 100e-6 and p.relocks == 0


# ------------------------------------------------------------------------------ paths
def test_continuous_mode_streams_time_stamped_samples_then_returns_to_points(target: StaticTarget) -> None:
    s = simulator(target, scale=1.0)  # a real tracker's clock runs at the wall clock's rate
    try:
        with opened(s.url) as tr:
            t0 = time.monotonic()
            samples = list(tr.stream(500.0, max_samples=400))  # 2 ms apart on the tracker's clock
            t1 = time.monotonic()
            assert tr.measure_point(1).samples == 1  # back in stationary mode
    finally:
        s.stop()
    assert len(samples) == 400 and all(s.position is not None for s in samples)
    t = np.array([s.t for s in samples])
    gaps = np.diff(t)
    # the tracker's own sample times, not arrival times: exact spacing, except where a less-delayed
    # packet lowered the offset (then a gap shrinks, never grows)
    assert np.median(gaps) == pytest.approx(0.002, abs=1e-6) and np.all(gaps < 0.002 + 1e-6)
    assert t0 - 0.05 < t[0] and t[-1] <= t1  # mapped onto this process's clock, never in the future
    xyz = np.array([p.position for p in samples])
    assert np.all(np.linalg.norm(xyz - TRUTH, axis=1) < 200e-6)


def test_a_stalled_reader_does_not_map_the_stream_late(target: StaticTarget) -> None:
    """The first packets wait 0.3 s behind a stalled reader (a loaded machine): the offset comes from
    the least-delayed packet, so the samples are not mapped 0.3 s late."""
    s = simulator(target, scale=1.0)
    stalled = [False]

    def clock() -> float:
        if not stalled[0]:  # the stream's first look at the clock, just after the tracker started
            stalled[0] = True
            time.sleep(0.3)
        return time.monotonic()

    try:
        with opened(s.url) as tr:
            samples, arrived = [], []
            for sample in tr.stream(200.0, max_samples=200, clock=clock):
                samples.append(sample)
                arrived.append(time.monotonic())
    finally:
        s.stop()
    t = np.array([x.t for x in samples])
    assert np.all(t <= np.array(arrived))  # no sample mapped later than it was handed over
    # once the backlog is read the samples are mapped within a flush period (100 ms) of arrival
    assert arrived[-1] - t[-1] < 0.15


def test_a_beam_lost_mid_stream_yields_a_lost_sample_and_no_relock(target: StaticTarget,
                                                                   tracker: EmsconTracker) -> None:
    stop = threading.Event()
    threading.Timer(0.15, lambda: target.set(TRUTH, visible=False)).start()
    threading.Timer(0.6, stop.set).start()
    samples = list(tracker.stream(200.0, stop=stop))
    lost = [s for s in samples if s.position is None]
    first = samples.index(lost[0])
    assert first > 0 and all("beam lost" in s.reason for s in lost)  # measured before the loss
    assert all(s.position is None for s in samples[first:])  # no re-lock mid-path
    assert 0.25 * 200 < len(lost) < 0.5 * 200 + 5  # one per 5 ms period of the ~0.45 s without beam
    assert np.allclose(np.diff([s.t for s in lost]), 1 / 200)
    target.set(TRUTH, visible=True)
    assert tracker.relock() and tracker.measure_point(1).samples == 1


def test_a_stream_starts_after_the_beam_was_lost_while_the_arm_moved_to_its_start(
        target: StaticTarget, sim: EmsconSimulator, tracker: EmsconTracker) -> None:
    """The SMR turned away while the arm moved to the path's start (the tracker notices by itself and
    drops the lock) and faces the tracker again there: ES_C_StartMeasurement answers
    ES_RS_MeasurementStatusNotReady, the tracker is not ready *yet*. The stream searches, waits for
    MeasStatus_Ready and streams; it was a TargetLost (a MOVEB run on emScon failed 3 of 3)."""
    target.set(TRUTH, visible=False)
    assert _wait(lambda: not sim.instrument.locked)
    target.set(TRUTH, visible=True)
    samples = list(tracker.stream(200.0, max_samples=40))
    assert len(samples) == 40 and all(s.position is not None for s in samples)


def test_a_stream_whose_smr_stays_hidden_is_a_lost_target_after_a_bounded_search(
        target: StaticTarget, sim: EmsconSimulator) -> None:
    with opened(sim.url, search_timeout_ms=2000) as tr:  # 2 simulated seconds: 0.1 s of wall time
        target.set(TRUTH, visible=False)
        assert _wait(lambda: not sim.instrument.locked)
        t0 = time.monotonic()
        with pytest.raises(TargetLost, match="found no reflector: ES_RS_MeasurementStatusNotReady"):
            list(tr.stream(200.0, max_samples=10))
        assert time.monotonic() - t0 < tr.config.timeout + tr.config.ready_timeout + 2.0


def _wait(pred: object, timeout: float = 2.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if pred():  # type: ignore[operator]
            return True
        time.sleep(0.01)
    return False


def test_a_failed_search_can_park_the_beam_in_the_bird_bath(target: StaticTarget,
                                                            sim: EmsconSimulator) -> None:
    proxy = Recorder(sim.url)
    try:
        with opened(proxy.url, bird_bath_on_loss=True, search_timeout_ms=200) as tr:
            target.set(TRUTH, visible=False)
            assert not tr.relock()
            assert proxy.sent[-2:] == [command(63, "d", 2.0), command(54)]  # FindReflector, GoBirdBath
            target.set(TRUTH, visible=True)  # the SMR is back, but the beam waits in the bird bath
            assert tr.lock_status() == "locked out"
            assert tr.relock() and tr.measure_point(1).samples == 1
    finally:
        proxy.close()
