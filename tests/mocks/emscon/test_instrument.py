"""The simulated emScon instrument as packets in and out, on an explicit simulated clock (no sockets)."""

from __future__ import annotations

import math
import struct

import numpy as np
import pytest

from drivers.tracker.emscon.packets import (
    HEADER,
    Answer,
    Command,
    ErrorResponse,
    MeasurementStatusInfo,
    MeasValue,
    MultiMeasResult,
    PacketError,
    Reply,
    ResultStatus,
    SingleMeasResult,
    StatusChange,
    SystemStatusChange,
    decode_reply,
    encode_command,
)
from hil.calibration.stream_clocks import InstrumentClock
from mocks.emscon import EmsconConfig, EmsconInstrument
from mocks.geocom import NOISELESS, NoiseSpec, StaticTarget, atmospheric_ppm

TRUE = np.array([1.0, 2.0, 0.5])
C = Command
OK = ResultStatus.AllOK
NOT_READY = StatusChange(SystemStatusChange.MEAS_STATUS_NOT_READY)
READY = StatusChange(SystemStatusChange.MEAS_STATUS_READY)


class Bench:
    """An instrument, its target and a hand-driven clock."""

    def __init__(self, config: EmsconConfig | None = None) -> None:
        self.target = StaticTarget(TRUE.copy())
        # searches answer at once here; their duration has a test of its own
        default = EmsconConfig(noise=NOISELESS, find_s=0.0, failed_search_s=0.0)
        self.inst = EmsconInstrument(self.target, config or default)
        self.now = 0.0

    def send(self, command: Command, *params: object) -> list[Reply]:
        return [decode_reply(p) for p in self.inst.handle(encode_command(command, *params), self.now)]

    def ok(self, command: Command, *params: object) -> Answer:
        replies = self.send(command, *params)
        assert len(replies) == 1 and isinstance(replies[0], Answer), replies
        assert replies[0].command == command and replies[0].status == OK, replies
        return replies[0]

    def status(self, command: Command, *params: object) -> int:
        (answer,) = self.send(command, *params)
        assert isinstance(answer, Answer) and answer.command == command
        assert answer.values == ()  # results only with AllOK
        return answer.status

    def advance(self, seconds: float, flush: bool = True, watch: bool = False) -> list[Reply]:
        self.now += seconds
        return [decode_reply(p) for p in self.inst.tick(self.now, flush, watch)]

    def ready(self) -> None:
        self.ok(C.INITIALIZE)


@pytest.fixture
def bench() -> Bench:
    return Bench()


def test_defaults_and_start_up_sequence(bench: Bench) -> None:
    assert bench.ok(C.GET_UNITS).values == (0, 0, 0, 0, 0)
    assert bench.ok(C.GET_ENVIRONMENT_PARAMS).values == (20.0, 1013.25, 50.0)
    assert bench.ok(C.GET_MEASUREMENT_MODE).values == (0,)
    assert bench.ok(C.GET_COORDINATE_SYSTEM_TYPE).values == (0,)
    assert bench.ok(C.GET_REFLECTOR).values == (1,)
    status = bench.ok(C.GET_SYSTEM_STATUS).values
    assert status == (0, 4, 3, 2, 3, 6, 0, 0, 0, 960_001)  # compensation set, laser warm, ADM ready
    assert bench.ok(C.GET_TRACKER_STATUS).values == (0,)  # not ready before Initialize
    bench.ok(C.SET_UNITS, 0, 0, 0, 0, 0)
    bench.ok(C.SET_ENVIRONMENT_PARAMS, 21.5, 980.0, 40.0)
    bench.ok(C.INITIALIZE)
    bench.ok(C.SET_MEASUREMENT_MODE, 0)
    bench.ok(C.SET_REFLECTOR, 2)
    assert bench.ok(C.GET_SYSTEM_STATUS).values[1] == 5  # initialized
    assert bench.ok(C.GET_TRACKER_STATUS).values == (2,)
    assert bench.ok(C.GET_ENVIRONMENT_PARAMS).values == (21.5, 980.0, 40.0)
    assert bench.ok(C.GET_REFLECTOR).values == (2,)
    assert bench.ok(C.GET_SYSTEM_SOFTWARE_VERSION).values == ("emScon 3.6.0 SIM",)
    flags = MeasurementStatusInfo(bench.ok(C.GET_MEASUREMENT_STATUS_INFO).values[1])
    assert flags == (MeasurementStatusInfo.TRACKER_FOUND | MeasurementStatusInfo.TRACKER_COMPENSATION_FOUND
                     | MeasurementStatusInfo.ADM_FOUND | MeasurementStatusInfo.ADM_COMPENSATION_FOUND
                     | MeasurementStatusInfo.IN_FACE1 | MeasurementStatusInfo.INITIALIZED
                     | MeasurementStatusInfo.REFLECTOR_FOUND)


@pytest.mark.parametrize(
    ("command", "params", "status"),
    [
        (C.SET_UNITS, (2, 0, 0, 0, 0), ResultStatus.WrongParameter),
        (C.SET_UNITS, (0, 2, 0, 0, 0), ResultStatus.WrongParameter),
        (C.SET_UNITS, (0, 0, 1, 0, 0), ResultStatus.WrongParameter),
        (C.SET_ENVIRONMENT_PARAMS, (80.0, 1013.0, 50.0), ResultStatus.MeteoDataOutOfRange),
        (C.SET_ENVIRONMENT_PARAMS, (20.0, 300.0, 50.0), ResultStatus.MeteoDataOutOfRange),
        (C.SET_ENVIRONMENT_PARAMS, (20.0, 1013.0, 101.0), ResultStatus.MeteoDataOutOfRange),
        (C.SET_COORDINATE_SYSTEM_TYPE, (6,), ResultStatus.NotImplemented),
        (C.SET_MEASUREMENT_MODE, (2,), ResultStatus.NotImplemented),
        (C.SET_MEASUREMENT_MODE, (42,), ResultStatus.WrongParameter),
        (C.SET_REFLECTOR, (7,), ResultStatus.WrongParameter),
        (C.SET_STATIONARY_MODE_PARAMS, (0, 1), ResultStatus.WrongParameter1),
        (C.SET_STATIONARY_MODE_PARAMS, (100, 2), ResultStatus.WrongParameter2),
        (C.SET_CONTINUOUS_TIME_MODE_PARAMS, (0, 0, 0, 0), ResultStatus.WrongParameter1),
        (C.SET_CONTINUOUS_TIME_MODE_PARAMS, (10, -1, 0, 0), ResultStatus.WrongParameter2),
        (C.SET_CONTINUOUS_TIME_MODE_PARAMS, (10, 0, 1, 0), ResultStatus.NotImplemented),
        (C.SET_SEARCH_PARAMS, (0.0, 1000), ResultStatus.WrongParameter1),
        (C.SET_SEARCH_PARAMS, (0.1, 0), ResultStatus.WrongParameter2),
        (C.SET_STATISTIC_MODE, (3, 0), ResultStatus.WrongParameter1),
        (C.START_MEASUREMENT, (), ResultStatus.TrackerNotInitialized),
        (C.FIND_REFLECTOR, (3.0,), ResultStatus.TrackerNotInitialized),
        (C.EXIT_APPLICATION, (), ResultStatus.NotImplemented),  # tabled but not simulated
    ],
)
def test_refusals(bench: Bench, command: Command, params: tuple[object, ...], status: int) -> None:
    assert bench.status(command, *params) == status
    assert bench.ok(C.GET_SYSTEM_STATUS).values[0] == status  # lastResultStatus


def test_unknown_command_and_undecodable_packet(bench: Bench) -> None:
    unknown = HEADER.pack(16, 0) + struct.pack("<ii", 4242, 7)
    (answer,) = [decode_reply(p) for p in bench.inst.handle(unknown, 0.0)]
    assert answer == Answer(4242, ResultStatus.NotImplemented)
    with pytest.raises(PacketError):
        bench.inst.handle(encode_command(C.SET_REFLECTOR, 1)[:-2], 0.0)
    with pytest.raises(PacketError):  # a reply is not a command
        bench.inst.handle(HEADER.pack(12, 8) + struct.pack("<i", 25), 0.0)


def test_settings_read_back(bench: Bench) -> None:
    bench.ok(C.SET_STATIONARY_MODE_PARAMS, 250, 0)
    assert bench.ok(C.GET_STATIONARY_MODE_PARAMS).values == (250, 0)
    bench.ok(C.SET_CONTINUOUS_TIME_MODE_PARAMS, 5, 100, 0, 0)
    assert bench.ok(C.GET_CONTINUOUS_TIME_MODE_PARAMS).values == (5, 100, 0, 0)
    bench.ok(C.SET_SEARCH_PARAMS, 0.2, 5000)
    bench.ok(C.SET_UNITS, 1, 1, 0, 0, 0)
    assert bench.ok(C.GET_SEARCH_PARAMS).values == (pytest.approx(200.0), 5000)
    for command, params in [(C.SET_STATISTIC_MODE, (1, 1)), (C.SWITCH_LASER, (1,)),
                            (C.CLEAR_COMMAND_QUEUE, (0,)), (C.SET_COORDINATE_SYSTEM_TYPE, (0,))]:
        bench.ok(command, *params)


def test_reflectors_and_tracker_info_follow_the_units(bench: Bench) -> None:
    rows = bench.send(C.GET_REFLECTORS)
    assert [r.values for r in rows if isinstance(r, Answer)] == [
        (3, 1, 5, 0.01905, "RRR 1.5in"), (3, 2, 6, 0.00635, "RRR 0.5in"), (3, 3, 9, 0.00635, "TBR 0.5in")]
    info = bench.ok(C.GET_TRACKER_INFO).values
    assert info[:2] == (13, "AT960-SIM") and info[8:12] == (20.0, 0.8, 1000, 2)
    assert info[12:14] == pytest.approx((2 * math.pi, math.radians(145.0)))
    bench.ok(C.SET_UNITS, 1, 1, 0, 0, 0)
    info = bench.ok(C.GET_TRACKER_INFO).values
    assert info[8:10] == (20_000.0, 800.0) and info[12:14] == pytest.approx((360.0, 145.0))
    assert bench.send(C.GET_REFLECTORS)[0].values[3] == pytest.approx(19.05)


def test_stationary_point_answer_then_result_after_the_measuring_time(bench: Bench) -> None:
    bench.ready()
    bench.ok(C.SET_STATIONARY_MODE_PARAMS, 500, 1)
    assert bench.send(C.START_MEASUREMENT) == [Answer(C.START_MEASUREMENT, OK)]
    assert bench.advance(0.25) == []
    assert bench.status(C.START_MEASUREMENT) == ResultStatus.ServerBusy
    (result,) = bench.advance(0.25)
    assert isinstance(result, SingleMeasResult)
    np.testing.assert_allclose(result.position, TRUE, atol=1e-12)
    assert result.status == 0 and result.mode == 0 and result.pointing_error == (0.0, 0.0, 0.0)
    assert (result.temperature, result.pressure, result.humidity) == (20.0, 1013.25, 50.0)
    assert bench.advance(1.0) == []
    bench.ok(C.SET_UNITS, 1, 0, 0, 0, 0)  # millimetres
    bench.ok(C.START_MEASUREMENT)
    (result,) = bench.advance(0.5)
    np.testing.assert_allclose(result.position, TRUE * 1000.0, atol=1e-9)


def test_stationary_noise_and_statistics() -> None:
    spec = NoiseSpec()
    bench = Bench(EmsconConfig(noise=spec, seed=3))
    bench.ready()
    bench.ok(C.START_MEASUREMENT)
    (result,) = bench.advance(1.0)  # default 1000 ms at 1000 Hz: the mean of 1000 readings
    assert isinstance(result, SingleMeasResult)
    apriori = np.array(result.apriori_std)
    # one reading's σ: distance σ along the line of sight, d·σ_V and d·sin(V)·σ_Hz across it
    across_v = np.linalg.norm(TRUE) * spec.angle_sigma_rad
    across_hz = math.hypot(*TRUE[:2]) * spec.angle_sigma_rad
    assert np.linalg.norm(apriori) == pytest.approx(math.hypot(spec.distance_sigma_m, across_v, across_hz))
    assert result.apriori_std_total == pytest.approx(np.linalg.norm(apriori))
    np.testing.assert_allclose(result.std, apriori, rtol=0.15)
    assert result.std_total == pytest.approx(np.linalg.norm(result.std))
    assert np.all(np.abs(np.array(result.position) - TRUE) < 5 * apriori / math.sqrt(1000))


def test_atmosphere_scales_the_distance() -> None:
    bench = Bench(EmsconConfig(noise=NOISELESS, true_temperature_c=20.0, true_pressure_mbar=1013.25))
    bench.ready()
    bench.ok(C.SET_ENVIRONMENT_PARAMS, 30.0, 950.0, 50.0)  # the client believes in other air
    bench.ok(C.START_MEASUREMENT)
    (result,) = bench.advance(1.0)
    ppm = atmospheric_ppm(30.0, 950.0) - atmospheric_ppm(20.0, 1013.25)
    np.testing.assert_allclose(result.position, TRUE * (1 + ppm * 1e-6), atol=1e-12)
    assert (result.temperature, result.pressure) == (30.0, 950.0)


def test_beam_lost_during_stationary_measurement(bench: Bench) -> None:
    bench.ready()
    bench.ok(C.START_MEASUREMENT)
    bench.advance(0.3)
    bench.target.set(TRUE, visible=False, reason="a person")
    no_result = ErrorResponse(C.START_MEASUREMENT, ResultStatus.NoStationaryResult)
    assert bench.advance(0.3) == [NOT_READY, no_result]
    assert bench.advance(1.0, watch=True) == []  # once per loss
    assert bench.status(C.START_MEASUREMENT) == ResultStatus.MeasurementStatusNotReady
    assert bench.ok(C.GET_TRACKER_STATUS).values == (0,)
    assert not bench.ok(C.GET_MEASUREMENT_STATUS_INFO).values[1] & MeasurementStatusInfo.REFLECTOR_FOUND
    assert bench.status(C.FIND_REFLECTOR, 2.3) == ResultStatus.ModuleTimedOut
    bench.target.set(TRUE, visible=True)
    assert bench.status(C.START_MEASUREMENT) == ResultStatus.MeasurementStatusNotReady  # no self re-lock
    assert bench.send(C.FIND_REFLECTOR, 2.3) == [Answer(C.FIND_REFLECTOR, OK), READY]
    bench.ok(C.START_MEASUREMENT)
    assert isinstance(bench.advance(1.0)[0], SingleMeasResult)


def test_loss_is_noticed_on_commands_and_when_watching(bench: Bench) -> None:
    bench.target.set(TRUE, visible=False)
    assert bench.advance(0.1) == []  # idle and not watching: nobody looked
    replies = bench.send(C.GET_TRACKER_STATUS)
    assert replies == [NOT_READY, Answer(C.GET_TRACKER_STATUS, OK, (0,))]
    bench.target.set(TRUE, visible=True)
    bench.ready()
    bench.send(C.FIND_REFLECTOR, 0.0)
    bench.target.set(TRUE, visible=False)
    assert bench.advance(0.1, watch=True) == [NOT_READY]


def test_go_bird_bath_leaves_the_beam_unlocked(bench: Bench) -> None:
    bench.ready()
    assert bench.send(C.GO_BIRD_BATH) == [Answer(C.GO_BIRD_BATH, OK), NOT_READY]
    assert bench.status(C.START_MEASUREMENT) == ResultStatus.MeasurementStatusNotReady


def test_initialize_takes_its_time_and_queues_later_commands() -> None:
    bench = Bench(EmsconConfig(noise=NOISELESS, initialize_s=20.0))
    assert bench.send(C.INITIALIZE) == []
    assert bench.send(C.GET_TRACKER_STATUS) == []
    assert bench.advance(19.0) == []
    assert bench.advance(1.0) == [Answer(C.INITIALIZE, OK), Answer(C.GET_TRACKER_STATUS, OK, (2,))]


def test_laser_warm_up_and_cold_fault() -> None:
    bench = Bench(EmsconConfig(noise=NOISELESS, warmup_s=60.0))
    bench.ready()
    assert bench.ok(C.GET_SYSTEM_STATUS).values[2] == 0
    assert bench.status(C.START_MEASUREMENT) == ResultStatus.SensorNotWarmedUp
    assert bench.ok(C.GET_TRACKER_STATUS).values == (0,)
    bench.advance(60.0)
    assert bench.ok(C.GET_SYSTEM_STATUS).values[2] == 3
    bench.inst.laser_cold(5.0, bench.now)
    assert bench.status(C.START_MEASUREMENT) == ResultStatus.SensorNotWarmedUp
    bench.advance(5.0)
    bench.ok(C.START_MEASUREMENT)


def test_continuous_time_mode_timestamps_and_limit(bench: Bench) -> None:
    bench.ready()
    bench.ok(C.SET_MEASUREMENT_MODE, 1)
    bench.ok(C.SET_CONTINUOUS_TIME_MODE_PARAMS, 4, 60, 0, 0)
    bench.now = 1.5
    bench.ok(C.START_MEASUREMENT)
    assert bench.advance(0.1, flush=False) == []  # collected, not yet sent
    packets = bench.advance(0.1) + bench.advance(1.0)
    assert all(isinstance(p, MultiMeasResult) and p.mode == 1 for p in packets)
    samples = [s for p in packets for s in p.samples]
    assert len(samples) == 60  # then the stream stops by itself
    times = np.array([s.seconds for s in samples])
    np.testing.assert_allclose(times, 1.5 + 0.004 * np.arange(60), atol=1e-6)
    assert all(0 <= s.time2 < 1_000_000 and s.status == 0 for s in samples)
    np.testing.assert_allclose([s.position for s in samples], np.tile(TRUE, (60, 1)), atol=1e-12)
    assert bench.advance(1.0) == []
    bench.ok(C.START_MEASUREMENT)  # finished: a new one may start


def test_continuous_stop_flushes_then_answers_and_resumes_after_relock(bench: Bench) -> None:
    bench.ready()
    bench.ok(C.SET_MEASUREMENT_MODE, 1)
    bench.ok(C.SET_CONTINUOUS_TIME_MODE_PARAMS, 10, 0, 0, 0)
    bench.ok(C.START_MEASUREMENT)
    first = [s for p in bench.advance(0.1) for s in p.samples]
    assert len(first) == 11  # t = 0, 0.01, ..., 0.1
    bench.target.set(TRUE, visible=False)
    assert bench.advance(0.05, flush=False) == [NOT_READY]  # (nothing was pending)
    assert bench.advance(0.25) == []
    bench.target.set(TRUE, visible=True)
    assert bench.send(C.FIND_REFLECTOR, 2.0) == [Answer(C.FIND_REFLECTOR, OK), READY]  # at t = 0.4
    bench.advance(0.05, flush=False)
    replies = bench.send(C.STOP_MEASUREMENT)
    assert isinstance(replies[0], MultiMeasResult) and replies[-1] == Answer(C.STOP_MEASUREMENT, OK)
    resumed = [s.seconds for s in replies[0].samples]
    # t = 0.4 was looked at while lost; the grid goes on from there
    np.testing.assert_allclose(resumed, [0.41, 0.42, 0.43, 0.44, 0.45], atol=1e-6)
    assert bench.advance(0.5) == []


def test_moving_target_is_interpolated_between_looks(bench: Bench) -> None:
    bench.ready()
    bench.ok(C.SET_MEASUREMENT_MODE, 1)
    bench.ok(C.SET_CONTINUOUS_TIME_MODE_PARAMS, 10, 0, 0, 0)
    bench.ok(C.START_MEASUREMENT)
    bench.advance(0.0)
    bench.target.set(TRUE + np.array([0.1, 0.0, 0.0]))
    samples = [s for p in bench.advance(0.1) for s in p.samples]
    np.testing.assert_allclose([s.position[0] for s in samples], 1.0 + np.arange(1, 11) * 0.01, atol=1e-9)


def test_disconnect_ends_the_measurement_and_forgets_pending_output(bench: Bench) -> None:
    bench.ready()
    bench.ok(C.START_MEASUREMENT)
    bench.inst.disconnect()
    assert bench.advance(2.0) == []
    bench.ok(C.START_MEASUREMENT)


def test_a_search_takes_time_and_commands_queue_behind_it() -> None:
    bench = Bench(EmsconConfig(noise=NOISELESS))  # find_s 0.5 s, a failed search its whole timeout
    bench.ready()
    bench.ok(C.SET_SEARCH_PARAMS, 0.05, 3000)
    bench.target.set(TRUE, visible=False)
    assert bench.send(C.FIND_REFLECTOR, 2.3) == [NOT_READY]  # the answer waits for the search
    assert bench.advance(2.9) == []
    assert bench.advance(0.2) == [Answer(C.FIND_REFLECTOR, ResultStatus.ModuleTimedOut)]
    bench.target.set(TRUE, visible=True)
    assert bench.send(C.FIND_REFLECTOR, 2.3) == []
    assert bench.send(C.GET_TRACKER_STATUS) == []  # queued behind the search
    assert bench.advance(0.6) == [Answer(C.FIND_REFLECTOR, OK), READY,
                                  Answer(C.GET_TRACKER_STATUS, OK, (2,))]


def test_continuous_stamps_follow_the_trackers_clock_and_leave_the_readings_alone() -> None:
    def stream(clock: InstrumentClock) -> list[MeasValue]:
        bench = Bench(EmsconConfig(noise=NoiseSpec(), seed=4, clock=clock))
        bench.ready()
        bench.ok(C.SET_MEASUREMENT_MODE, 1)
        bench.ok(C.SET_CONTINUOUS_TIME_MODE_PARAMS, 1, 2000, 0, 0)
        bench.now = 1.5
        bench.ok(C.START_MEASUREMENT)
        return [s for p in bench.advance(2.5) if isinstance(p, MultiMeasResult) for s in p.samples]

    perfect = stream(InstrumentClock())
    drifting = stream(InstrumentClock(offset_s=1234.5, drift_ppm=500.0, latency_s=0.002))
    jittery = stream(InstrumentClock(offset_s=1234.5, drift_ppm=500.0, latency_s=0.002, jitter_s=2e-5))
    tau = np.array([s.seconds for s in perfect])
    np.testing.assert_allclose(tau, 1.5 + 0.001 * np.arange(2000), atol=1e-6)
    want = 1234.5 + (1 + 500e-6) * (tau + 0.002)
    np.testing.assert_allclose([s.seconds for s in drifting], want, atol=1e-6)  # µs stamps
    assert np.std(np.array([s.seconds for s in jittery]) - want) == pytest.approx(2e-5, rel=0.1)
    # the clock draws nothing from the readings' noise: the same points with or without it
    assert [s.position for s in jittery] == [s.position for s in perfect]
