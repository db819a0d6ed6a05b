"""Driver ↔ simulator over a real pty and over socket://, including every fault case."""

from __future__ import annotations

import itertools
import logging
import threading
from collections.abc import Iterator

import numpy as np
import pytest

from drivers.tracker import (
    Atmosphere,
    ChecksumError,
    ConnectionLost,
    GarbledReply,
    GeoComTracker,
    SerialConfig,
    TargetLost,
    TrackerConfig,
    TrackerTimeout,
    UnstablePoint,
)
from drivers.tracker.geocom.commands import MeasureProgram
from drivers.tracker.geometry import polar_to_cartesian
from mocks.geocom import (
    NOISELESS,
    GeoComSimulator,
    InstrumentConfig,
    LinkConfig,
    NoiseSpec,
    SimulatorConfig,
    StaticTarget,
)

TRUE = np.array([1.2, 2.1, 0.4])


def make_sim(noise: NoiseSpec = NOISELESS, **instrument: float) -> tuple[GeoComSimulator, StaticTarget]:
    target = StaticTarget(TRUE.copy())
    cfg = SimulatorConfig(
        instrument=InstrumentConfig(noise=noise, **instrument),  # type: ignore[arg-type]
        link=LinkConfig(max_chunk=7),  # replies arrive in pieces
    )
    return GeoComSimulator(target, cfg).start(), target


@pytest.fixture(params=["pty", "tcp"])
def link(request: pytest.FixtureRequest) -> str:
    return str(request.param)


@pytest.fixture
def sim() -> Iterator[tuple[GeoComSimulator, StaticTarget]]:
    s, target = make_sim()
    yield s, target
    s.stop()


def url_of(s: GeoComSimulator, link: str) -> str:
    return s.pty_path if link == "pty" else s.url  # type: ignore[return-value]


def tracker(url: str, **kw: object) -> GeoComTracker:
    return GeoComTracker(TrackerConfig(SerialConfig(url), **{"timeout": 0.5, **kw}))  # type: ignore[arg-type]


def test_identity_and_exact_point(sim: tuple[GeoComSimulator, StaticTarget], link: str) -> None:
    s, target = sim
    with tracker(url_of(s, link)) as tr:
        assert tr.identity is not None
        assert (tr.identity.name, tr.identity.serial_number) == ("AT960-SIM", 960001)
        point = tr.measure_point(samples=3)
        np.testing.assert_allclose(point.position, TRUE, atol=1e-9)
        assert point.samples == 3 and point.status.value == "ok" and point.relocks == 0
        target.set([-0.5, 1.0, -0.3])
        np.testing.assert_allclose(tr.measure_point().position, [-0.5, 1.0, -0.3], atol=1e-9)


def test_noisy_point_is_within_leica_class_error() -> None:
    s, _ = make_sim(NoiseSpec())
    try:
        with tracker(str(s.pty_path)) as tr:
            point = tr.measure_point(samples=10)
        err = np.linalg.norm(point.xyz - TRUE)
        assert 0 < err < 30e-6  # noise present but averaged: well inside the MPE (~30 µm here)
        assert all(0 < sp < 20e-6 for sp in point.spread)
    finally:
        s.stop()


def test_atmospheric_correction_is_applied_at_connect() -> None:
    s, _ = make_sim(true_temperature_c=35.0, true_pressure_mbar=950.0)
    try:
        with tracker(str(s.pty_path), atmosphere=None) as tr:  # instrument keeps its reference air
            uncorrected = tr.measure_point()
        with tracker(str(s.pty_path), atmosphere=Atmosphere(35.0, 950.0)) as tr:
            corrected = tr.measure_point()
            assert s.instrument.atm[1:3] == (950.0, 35.0)
    finally:
        s.stop()
    assert abs(np.linalg.norm(uncorrected.xyz) - np.linalg.norm(TRUE)) > 50e-6  # ~38 ppm at 2.4 m
    np.testing.assert_allclose(corrected.position, TRUE, atol=1e-9)


def test_unstable_point_is_rejected() -> None:
    s, _ = make_sim(NoiseSpec(distance_sigma_m=1e-3, angle_sigma_rad=0.0))
    try:
        tr = tracker(str(s.pty_path), stability_threshold_m=50e-6)
        with tr, pytest.raises(UnstablePoint) as info:
            tr.measure_point(samples=5)
        assert max(info.value.spread_m) > 50e-6
    finally:
        s.stop()


# ------------------------------------------------------------------------------ lost target
def test_short_beam_break_relocks_and_measures(sim: tuple[GeoComSimulator, StaticTarget]) -> None:
    s, _ = sim
    with tracker(str(s.pty_path)) as tr:
        s.faults.lose_target(checks=2)  # lock status sees it, lock-in fails, search + lock-in succeed
        point = tr.measure_point(samples=2)
    np.testing.assert_allclose(point.position, TRUE, atol=1e-9)
    assert point.relocks == 1


def test_persistent_beam_break_raises_after_bounded_relocks(
    sim: tuple[GeoComSimulator, StaticTarget],
) -> None:
    s, _ = sim
    with tracker(str(s.pty_path), max_relocks=2) as tr:
        s.faults.lose_target()
        before = s.instrument.requests
        with pytest.raises(TargetLost, match="2 re-lock attempts"):
            tr.measure_point()
        assert s.instrument.requests - before < 15  # bounded, not a retry storm


def test_target_facing_away_is_lost(sim: tuple[GeoComSimulator, StaticTarget]) -> None:
    s, target = sim
    with tracker(str(s.pty_path), max_relocks=1) as tr:
        target.set(TRUE, visible=False, reason="SMR faces away (75° > 60°)")
        with pytest.raises(TargetLost):
            tr.measure_point()
        target.set(TRUE)
        np.testing.assert_allclose(tr.measure_point().position, TRUE, atol=1e-9)  # re-locks itself


# ------------------------------------------------------------------------------ link faults
def simple_mea(tr: GeoComTracker, timeout: float | None = None) -> np.ndarray:
    r = tr.commands.client.call(2108, [100, 1], timeout=timeout)
    assert r.rc == 0
    return polar_to_cartesian(*(float(v) for v in r.values[:3]))


def test_late_reply_is_discarded_by_trid_never_returned(
    sim: tuple[GeoComSimulator, StaticTarget], link: str, monkeypatch: pytest.MonkeyPatch,
    caplog: pytest.LogCaptureFixture,
) -> None:
    """The order of events is forced, not timed: the first reply is held by the simulator until the
    second request is on the wire, so it always arrives late (the first call always times out) and
    always during the second call, after that call's resync flush. (A fixed 0.15 s delay against a
    0.05 s and a 1 s timeout raced the scheduler: on a loaded machine the second call timed out.)"""
    s, target = sim
    release = threading.Event()
    held = threading.Event()
    take = s.faults.take_reply_fault

    def hold_one_reply() -> object:  # the simulator's link thread, the reply already computed
        if not held.is_set():
            held.set()
            assert release.wait(10.0), "the test never released the held reply"
        return take()

    with tracker(url_of(s, link)) as tr:
        tr.commands.do_measure(MeasureProgram.RTRK_DIST)
        monkeypatch.setattr(s.faults, "take_reply_fault", hold_one_reply)
        with pytest.raises(TrackerTimeout):
            simple_mea(tr, timeout=0.05)
        assert held.is_set()
        transport = tr.commands.client.transport
        write = transport.write

        def write_then_release(data: bytes) -> None:
            write(data)
            release.set()  # the late reply (old position) leaves now: during the next call

        monkeypatch.setattr(transport, "write", write_then_release)
        target.set([0.3, 0.3, 0.3])
        with caplog.at_level(logging.INFO, logger="drivers.tracker.geocom.protocol"):
            point = simple_mea(tr, timeout=10.0)  # returns as soon as its own reply is in
        np.testing.assert_allclose(point, [0.3, 0.3, 0.3], atol=1e-9)
        assert "discarding stale reply" in caplog.text


def test_stalled_half_line_then_resync(sim: tuple[GeoComSimulator, StaticTarget], link: str) -> None:
    s, target = sim
    with tracker(url_of(s, link)) as tr:
        tr.commands.do_measure(MeasureProgram.RTRK_DIST)
        s.faults.stall_next_reply(0.15, split=0.6)
        with pytest.raises(TrackerTimeout):
            simple_mea(tr, timeout=0.05)
        target.set([0.2, -0.4, 0.1])
        np.testing.assert_allclose(simple_mea(tr, timeout=1.0), [0.2, -0.4, 0.1], atol=1e-9)


@pytest.mark.parametrize(
    ("fault", "error"),
    [
        ("garble_next_reply", GarbledReply),
        ("wrong_trid_next_reply", TrackerTimeout),
        ("drop_next_reply", TrackerTimeout),
        ("truncate_next_reply", TrackerTimeout),
    ],
)
def test_link_faults_are_typed_then_resync(
    sim: tuple[GeoComSimulator, StaticTarget], fault: str, error: type[Exception]
) -> None:
    s, _ = sim
    with tracker(str(s.pty_path), timeout=1.0) as tr:
        tr.commands.do_measure(MeasureProgram.RTRK_DIST)
        getattr(s.faults, fault)()
        with pytest.raises(error):
            simple_mea(tr)
        np.testing.assert_allclose(simple_mea(tr), TRUE, atol=1e-9)


def test_measure_point_retries_once_after_a_link_fault(sim: tuple[GeoComSimulator, StaticTarget]) -> None:
    s, _ = sim
    with tracker(str(s.pty_path), timeout=1.0) as tr:
        s.faults.garble_next_reply()
        np.testing.assert_allclose(tr.measure_point(samples=2).position, TRUE, atol=1e-9)
        s.faults.garble_next_reply()
        s.faults.garble_next_reply()
        with pytest.raises(GarbledReply):
            tr.measure_point()


@pytest.mark.parametrize("fault", ["bad_crc_next_reply", "corrupt_digit_next_reply"])
def test_crc_catches_corruption(sim: tuple[GeoComSimulator, StaticTarget], fault: str) -> None:
    s, _ = sim
    with tracker(str(s.pty_path), crc=True) as tr:
        tr.commands.do_measure(MeasureProgram.RTRK_DIST)
        getattr(s.faults, fault)()
        with pytest.raises(ChecksumError):
            simple_mea(tr)
        np.testing.assert_allclose(tr.measure_point().position, TRUE, atol=1e-9)


def test_device_vanishing_mid_read(sim: tuple[GeoComSimulator, StaticTarget], link: str) -> None:
    s, _ = sim
    with tracker(url_of(s, link)) as tr:
        s.faults.unplug()
        with pytest.raises(ConnectionLost):
            tr.measure_point()


@pytest.mark.parametrize("url", ["/dev/does-not-exist-tracker", "socket://127.0.0.1:1", "bogus://nowhere"])
def test_nonexistent_url(url: str) -> None:
    with pytest.raises(ConnectionLost, match="cannot open"):
        tracker(url).open()


def test_unknown_rpc_is_an_error_not_a_value(sim: tuple[GeoComSimulator, StaticTarget]) -> None:
    s, _ = sim
    with tracker(str(s.pty_path)) as tr:
        reply = tr.client.call(4242)
        assert reply.rc == 3081 and reply.values == ()


def test_concurrent_callers_each_get_their_own_reply(sim: tuple[GeoComSimulator, StaticTarget]) -> None:
    s, _ = sim
    errors: list[BaseException] = []
    with tracker(str(s.pty_path)) as tr:

        def worker(kind: int) -> None:
            try:
                for _ in range(15):
                    if kind == 0:
                        assert tr.commands.get_instrument_number() == 960001
                    else:
                        assert tr.commands.get_instrument_name() == "AT960-SIM"
            except BaseException as exc:  # collected and re-raised below
                errors.append(exc)

        threads = [threading.Thread(target=worker, args=(i % 2,)) for i in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(10)
    assert not errors


# ------------------------------------------------------------------------------ continuous
class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.now += seconds


def test_stream_on_a_fixed_grid(sim: tuple[GeoComSimulator, StaticTarget]) -> None:
    s, _ = sim
    clock = FakeClock()
    with tracker(str(s.pty_path)) as tr:
        samples = list(tr.stream(50.0, max_samples=5, clock=clock, sleep=clock.sleep))
    assert [round(x.t - 100.0, 9) for x in samples] == [0.0, 0.02, 0.04, 0.06, 0.08]
    for x in samples:
        assert x.position is not None
        np.testing.assert_allclose(x.position, TRUE, atol=1e-9)


def test_stream_reports_lost_samples_and_stops_cleanly(sim: tuple[GeoComSimulator, StaticTarget]) -> None:
    s, _ = sim
    stop = threading.Event()
    with tracker(str(s.pty_path)) as tr:
        s.faults.lose_target(checks=1)
        got = []
        for sample in tr.stream(200.0, stop=stop, duration=5.0):
            got.append(sample)
            if len(got) == 3:
                stop.set()
    assert len(got) == 3
    assert got[0].position is None and "lost" in got[0].reason
    assert got[1].position is None  # lost lock stays lost until re-locked: no silent recovery
    assert all(a.t < b.t for a, b in itertools.pairwise(got))


def test_stream_needs_a_bound(sim: tuple[GeoComSimulator, StaticTarget]) -> None:
    s, _ = sim
    with tracker(str(s.pty_path)) as tr, pytest.raises(ValueError):
        next(tr.stream(10.0))
