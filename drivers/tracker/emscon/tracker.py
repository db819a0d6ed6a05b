"""A Leica absolute tracker (AT9xx, AT40x) over emScon TPI: `drivers.tracker.device.Tracker` over TCP.

Start-up (`open`), as Leica's TPI manual orders it: connect; read the system status (the server
answers, its version, the laser and the tracker processor's state); coordinate system RHR and units
metre / radian / °C / mbar / %RH, so every value the server sends is SI; the environment (air
temperature, pressure, humidity) for the refraction correction; Initialize when the tracker processor
is not initialized yet; stationary measurement mode with the configured measuring time; the reflector
(by name or id; none keeps the tracker's current one); the search parameters for FindReflector; the
tracker's name, serial number and software version for the record. A laser that is still warming up
is waited for up to ``warmup_timeout`` and is otherwise `NotReady` (the campaign pauses on it).

A lost beam is searched for with ES_C_FindReflector; with ``bird_bath_on_loss`` a failed search
sends the beam to the bird bath (ES_C_GoBirdBath), where an operator can catch it and carry it back.

Points: `measure_point(samples)` runs ``samples`` stationary measurements (each one averaged inside
the tracker over the measuring time; ES_C_StartMeasurement answers, then a SingleMeasResultT follows)
and reports their mean and spread. ES_RS_MeasurementStatusNotReady to a start is "not ready yet"
and is waited on, bounded, with a FindReflector when the beam is not known to be locked
(`_start_measurement`); a beam lost while measuring (an ES_RS_NoStationaryResult error packet, or the
MeasStatus_NotReady event) and a search that finds nothing are `TargetLost`; the driver re-locks with
ES_C_FindReflector at the last measured distance a bounded number of times first.

Paths: `stream` switches to continuous-time mode (ES_C_SetContinuousTimeModeParams: the sample
separation in ms, no point limit), starts, yields the samples of each MultiMeasResultT and stops and
returns to stationary mode when the caller stops iterating. The tracker stamps each sample on its own
clock (``lTime1`` s, ``lTime2`` µs); the driver maps that clock onto the caller's by one offset, the
smallest (arrival − tracker time of its newest sample) of the packets so far: the least-delayed
packet bounds the true offset best (the minimum-delay filter of NTP-style clock estimation), a packet
that waited behind a stalled reader never sets it. The samples of a packet keep the tracker's exact
spacing; the offset can only fall, so a gap between packets is at most one separation, and no sample
is mapped later than the packet that carried it arrived.

Links: every command waits at most ``timeout``. A timeout or an undecodable packet leaves the
connection out of step (no transaction ids in TPI), so the next command reconnects and repeats the
settings before it is sent; a closed connection is `ConnectionLost`.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from types import TracebackType

import numpy as np

from drivers.tracker.device import (
    Atmosphere,
    Identity,
    PointStatus,
    StreamSample,
    TrackerPoint,
    measure_with_retries,
)
from drivers.tracker.emscon.client import EmsconClient
from drivers.tracker.emscon.packets import (
    AngleUnit,
    Answer,
    Command,
    CoordinateSystemType,
    HumidityUnit,
    LengthUnit,
    MeasMode,
    MeasurementStatus,
    MeasurementStatusInfo,
    PressureUnit,
    ResultStatus,
    SingleMeasResult,
    TemperatureUnit,
    TrackerProcessorStatus,
    status_name,
)
from drivers.tracker.emscon.transport import TcpConfig, TcpTransport
from drivers.tracker.errors import (
    ConnectionLost,
    EmsconError,
    NotReady,
    TargetLost,
    TrackerError,
    TrackerTimeout,
    UnstablePoint,
)

log = logging.getLogger(__name__)

LASER_READY = 3  # ES_LPS_LaserReady
_BEAM_LOST = {ResultStatus.MeasurementStatusNotReady, ResultStatus.NoStationaryResult}
_NOT_READY = {ResultStatus.SensorNotWarmedUp, ResultStatus.TrackerNotInitialized,
              ResultStatus.ADMStartUpBusy, ResultStatus.SensorNotStable,
              ResultStatus.SystemNotReadyForMeasurement}


@dataclass(frozen=True)
class EmsconConfig:
    """Everything the emScon driver needs; times are seconds unless the name says ms."""

    tcp: TcpConfig
    timeout: float = 3.0  # per command answer
    atmosphere: Atmosphere | None = field(default_factory=Atmosphere)
    initialize: bool = True  # run ES_C_Initialize when the tracker processor is not initialized
    initialize_timeout: float = 120.0
    warmup_timeout: float = 0.0  # wait this long at open for a cold laser (0: NotReady at once)
    reflector: str | int | None = None  # name (as GetReflectors lists it) or id; None keeps the current
    measure_time_ms: int = 500  # stationary measuring time (the tracker averages over it)
    stability_threshold_m: float = 50e-6
    max_relocks: int = 2
    link_retries: int = 1
    search_radius_m: float = 0.05  # ES_C_SetSearchParams
    search_timeout_ms: int = 5000
    ready_timeout: float = 2.0  # wait this long for MeasStatus_Ready after a "not ready yet" answer
    bird_bath_on_loss: bool = False  # after a failed search, park the beam in the bird bath for an operator

    def __post_init__(self) -> None:
        for name in ("timeout", "initialize_timeout", "ready_timeout"):
            if not 0 < getattr(self, name) < math.inf:
                raise ValueError(f"{name} must be positive and finite")
        if not 0 <= self.warmup_timeout < math.inf:
            raise ValueError("warmup_timeout must be >= 0 and finite")
        if not 1 <= self.measure_time_ms <= 60_000:
            raise ValueError("measure_time_ms must be within 1..60000")
        if not self.stability_threshold_m > 0:
            raise ValueError("stability_threshold_m must be positive")
        if self.max_relocks < 0 or self.link_retries < 0:
            raise ValueError("retry counts must be >= 0")


@dataclass(frozen=True)
class EmsconStatus:
    """What the tracker says of itself (ES_C_GetSystemStatus + ES_C_GetMeasurementStatusInfo)."""

    laser_ready: bool
    initialized: bool
    reflector_found: bool
    server_version: tuple[int, int, int]


class EmsconTracker:
    """A laser tracker over emScon TPI. No I/O until `open()` (or ``with EmsconTracker(cfg) as t:``)."""

    def __init__(self, config: EmsconConfig) -> None:
        self.config = config
        self.transport = TcpTransport(config.tcp)
        self.client = EmsconClient(self.transport, timeout=config.timeout)
        self.identity: Identity | None = None
        self._distance: float | None = None  # last measured distance, for FindReflector
        self._reflector_id: int | None = None

    # --- lifecycle -------------------------------------------------------------------------------
    def open(self) -> EmsconTracker:
        """Connect and run the start-up sequence (module docstring)."""
        self._connect(first=True)
        return self

    def close(self) -> None:
        """Stop any measurement (best effort) and disconnect."""
        if self.transport.is_open and not self.client.dirty:
            try:
                self.client.request(Command.STOP_MEASUREMENT, timeout=min(self.config.timeout, 1.0))
            except TrackerError:
                log.debug("could not stop the measurement on close", exc_info=True)
        self.transport.close()

    def __enter__(self) -> EmsconTracker:
        return self.open()

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()

    def _connect(self, first: bool) -> None:
        """Connect and set up. A reconnect the server refuses as a second client is retried until the
        connect timeout: it is our own previous connection, which the server has not let go of yet."""
        deadline = time.monotonic() + self.config.tcp.connect_timeout
        while True:
            self.transport.close()
            self.client.reset()
            self.transport.open()
            try:
                self._start_up(first)
                return
            except ConnectionLost as exc:
                self.transport.close()
                if first or "MultiConnectionsNotAllowed" not in str(exc) or time.monotonic() > deadline:
                    raise
                time.sleep(0.1)
            except BaseException:
                self.transport.close()
                raise

    def _start_up(self, first: bool) -> None:
        cfg = self.config
        status = self.status()
        self._check(Command.SET_COORDINATE_SYSTEM_TYPE, CoordinateSystemType.RHR)
        self._check(Command.SET_UNITS, LengthUnit.METER, AngleUnit.RADIAN, TemperatureUnit.CELSIUS,
                    PressureUnit.MBAR, HumidityUnit.RH)
        if cfg.atmosphere is not None:
            atm = cfg.atmosphere
            self._check(Command.SET_ENVIRONMENT_PARAMS, atm.temperature_c, atm.pressure_mbar,
                        atm.humidity_percent)
        if not status.initialized:
            if not cfg.initialize:
                raise NotReady("the tracker is not initialized (emScon ES_C_Initialize not allowed by the "
                               "configuration)")
            log.info("initializing the tracker")
            self._check(Command.INITIALIZE, timeout=cfg.initialize_timeout)
        self._wait_warm(cfg.warmup_timeout)
        self._stationary()
        self._check(Command.SET_SEARCH_PARAMS, cfg.search_radius_m, cfg.search_timeout_ms)
        if cfg.reflector is not None or self._reflector_id is not None:
            self._select_reflector()
        if first or self.identity is None:
            info = self._check(Command.GET_TRACKER_INFO).values
            software = self._check(Command.GET_SYSTEM_SOFTWARE_VERSION).values[0]
            version = ".".join(map(str, status.server_version))
            self.identity = Identity(str(info[1]) or "emScon tracker", int(info[2]),
                                     _version_tuple(software, status.server_version),
                                     f"emScon TPI {version}")
            log.info("tracker %s (%s)", self.identity, software)

    def _stationary(self) -> None:
        self._check(Command.SET_MEASUREMENT_MODE, MeasMode.STATIONARY)
        self._check(Command.SET_STATIONARY_MODE_PARAMS, self.config.measure_time_ms, 1)

    def _select_reflector(self) -> None:
        wanted = self.config.reflector if self._reflector_id is None else self._reflector_id
        answers = self.client.request_many(Command.GET_REFLECTORS)
        known = {int(a.values[1]): str(a.values[4]) for a in answers if a.ok and a.values}
        if isinstance(wanted, int):
            rid = wanted if wanted in known else None
        else:
            key = str(wanted).strip().lower()
            rid = next((i for i, name in known.items() if name.strip().lower() == key), None)
        if rid is None:
            names = ", ".join(f"{i}: {n}" for i, n in sorted(known.items())) or "none"
            raise EmsconError(f"reflector {wanted!r} is not one the tracker knows ({names})",
                              int(ResultStatus.WrongParameter), int(Command.SET_REFLECTOR))
        self._check(Command.SET_REFLECTOR, rid)
        self._reflector_id = rid

    def _wait_warm(self, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while True:
            status = self.status()
            if status.laser_ready:
                return
            if time.monotonic() >= deadline:
                raise NotReady("the tracker's laser is still warming up (emScon laser status not ready); "
                               "wait for it, the run goes on by itself")
            time.sleep(min(1.0, max(0.05, deadline - time.monotonic())))

    def _ensure(self) -> None:
        """Reconnect (and repeat the settings) if the last exchange left the connection out of step."""
        if self.client.dirty or not self.transport.is_open:
            log.info("emScon: reconnecting")
            self._connect(first=False)

    # --- status ----------------------------------------------------------------------------------
    def status(self) -> EmsconStatus:
        """Laser, initialization and reflector state as the tracker reports them."""
        sys_status = self._check(Command.GET_SYSTEM_STATUS).values
        info = self._check(Command.GET_MEASUREMENT_STATUS_INFO).values
        flags = MeasurementStatusInfo(int(info[1]) & sum(int(f) for f in MeasurementStatusInfo))
        return EmsconStatus(
            laser_ready=int(sys_status[2]) == LASER_READY,
            initialized=int(sys_status[1]) == TrackerProcessorStatus.INITIALIZED,
            reflector_found=bool(flags & MeasurementStatusInfo.REFLECTOR_FOUND),
            server_version=(int(sys_status[4]), int(sys_status[5]), int(sys_status[6])))

    def lock_status(self) -> str:
        self._ensure()
        return "locked in" if self.status().reflector_found else "locked out"

    def ready(self) -> bool:
        """True when the tracker could measure now (initialized, laser warm), reconnecting if needed."""
        self._ensure()
        st = self.status()
        return st.initialized and st.laser_ready

    def go_bird_bath(self) -> None:
        """Point the beam at the bird bath, where an operator can pick it up with the SMR."""
        self._ensure()
        self._check(Command.GO_BIRD_BATH, timeout=max(self.config.timeout, 30.0))

    # --- points ----------------------------------------------------------------------------------
    def relock(self) -> bool:
        """ES_C_FindReflector around the last measured distance; True when the beam is locked again."""
        self._ensure()
        distance = self._distance if self._distance is not None else 2.0
        answer = self.client.request(Command.FIND_REFLECTOR, float(distance),
                                     timeout=self.config.timeout + self.config.search_timeout_ms / 1000.0)
        if answer.ok:
            self.client.beam_locked = True
            return True
        log.info("FindReflector failed: %s", status_name(answer.status))
        if self.config.bird_bath_on_loss:
            # an operator catches the beam there with a hand-held SMR and carries it back to the robot
            self.go_bird_bath()
        return False

    def measure_point(self, samples: int = 1) -> TrackerPoint:
        """Mean of ``samples`` stationary measurements (see the module docstring for the errors)."""
        if samples < 1:
            raise ValueError("samples must be >= 1")
        return measure_with_retries(lambda: self._measure_once(samples), self.relock,
                                    self.config.max_relocks, self.config.link_retries)

    def sample(self) -> TrackerPoint:
        """One stationary measurement now (averaged inside the tracker over its measuring time), without
        the spread check of `measure_point`: the building block of settling on evidence. Its spread is
        the tracker's own standard deviation of that measurement's readings."""
        def once() -> TrackerPoint:
            self._ensure()
            result = self._single()
            xyz = np.array(result.position, dtype=float)
            if not np.all(np.isfinite(xyz)):
                raise TrackerError("non-finite coordinate from the tracker")
            self._distance = float(np.linalg.norm(xyz))
            std = tuple(abs(float(v)) for v in result.std)
            return TrackerPoint((float(xyz[0]), float(xyz[1]), float(xyz[2])), (std[0], std[1], std[2]), 1,
                                PointStatus.OK)

        return measure_with_retries(once, self.relock, self.config.max_relocks, self.config.link_retries)

    def _measure_once(self, samples: int) -> TrackerPoint:
        self._ensure()
        positions, stds = [], []
        for _ in range(samples):
            result = self._single()
            positions.append(result.position)
            stds.append(result.std)
        xyz = np.array(positions, dtype=float)
        if not np.all(np.isfinite(xyz)):
            raise TrackerError("non-finite coordinate from the tracker")
        self._distance = float(np.linalg.norm(xyz.mean(axis=0)))
        mean = xyz.mean(axis=0)
        spread = xyz.std(axis=0, ddof=1) if samples > 1 else np.abs(np.array(stds[0], dtype=float))
        spread_t = (float(spread[0]), float(spread[1]), float(spread[2]))
        if float(spread.max()) > self.config.stability_threshold_m:
            raise UnstablePoint(f"point unstable: spread {max(spread_t) * 1e6:.1f} µm > "
                                f"{self.config.stability_threshold_m * 1e6:.1f} µm over {samples} "
                                "measurements", spread_t)
        return TrackerPoint((float(mean[0]), float(mean[1]), float(mean[2])), spread_t, samples,
                            PointStatus.OK)

    def _single(self) -> SingleMeasResult:
        client = self.client
        client.singles.clear()
        client.errors.clear()
        self._start_measurement(search=False)  # measure_with_retries re-locks, a bounded number of times
        deadline = time.monotonic() + self.config.timeout + self.config.measure_time_ms / 1000.0
        client.wait(lambda: bool(client.singles or client.errors), deadline, "the stationary measurement")
        if client.errors:
            self._raise(Command.START_MEASUREMENT, client.errors.popleft().status, "error packet")
        return client.singles.popleft()

    # --- paths -----------------------------------------------------------------------------------
    def stream(self, rate_hz: float, *, duration: float | None = None, max_samples: int | None = None,
               stop: threading.Event | None = None, clock: Callable[[], float] = time.monotonic,
               sleep: Callable[[float], None] = time.sleep) -> Iterator[StreamSample]:
        """Continuous-time samples at about ``rate_hz`` (module docstring). While the beam is lost the
        stream yields a sample without a position every period, as the GeoCOM stream does; no re-lock
        is tried mid-path (the caller decides)."""
        if not 0 < rate_hz < math.inf:
            raise ValueError("rate_hz must be positive and finite")
        if duration is None and max_samples is None and stop is None:
            raise ValueError("give duration, max_samples or stop so the stream ends")
        self._ensure()
        separation_ms = max(1, round(1000.0 / rate_hz))
        client = self.client
        self._check(Command.SET_MEASUREMENT_MODE, MeasMode.CONTINUOUS_TIME)
        self._check(Command.SET_CONTINUOUS_TIME_MODE_PARAMS, separation_ms, 0, 0, 0)
        client.multis.clear()
        client.errors.clear()
        losses = client.beam_changes
        try:
            self._start_measurement()
            t0 = clock()
            count = 0
            offset: float | None = None
            heard = time.monotonic()  # when the tracker last sent anything
            lost_at: float | None = None  # when the beam was lost (no re-lock mid-path)
            lost_slots = 0
            while True:
                if stop is not None and stop.is_set():
                    return
                if duration is not None and clock() - t0 >= duration:
                    return
                if max_samples is not None and count >= max_samples:
                    return
                if client.pump(time.monotonic() + 0.05):
                    heard = time.monotonic()
                elif client.beam_locked is not False and time.monotonic() - heard > self.config.timeout:
                    # silence is expected while the beam is lost; otherwise the link is gone
                    client.dirty = True
                    raise TrackerTimeout("emScon: no continuous samples within the timeout")
                if client.beam_changes != losses:
                    losses = client.beam_changes
                    lost_at = clock()
                    lost_slots = -1
                if client.beam_locked is False and lost_at is not None:
                    # one lost sample per period while the beam is gone, as the GeoCOM stream yields them
                    while lost_slots < (clock() - lost_at) * rate_hz and (max_samples is None or
                                                                           count < max_samples):
                        lost_slots += 1
                        yield StreamSample(lost_at + lost_slots / rate_hz, None, None,
                                           "beam lost (emScon MeasStatus_NotReady)")
                        count += 1
                if client.errors:
                    self._raise(Command.START_MEASUREMENT, client.errors.popleft().status, "error packet")
                while client.multis:
                    batch = client.multis.popleft()
                    arrival = clock()
                    if batch.samples:  # the least-delayed packet so far (module docstring)
                        delay = arrival - max(s.seconds for s in batch.samples)
                        offset = delay if offset is None else min(offset, delay)
                    for s in batch.samples:
                        if max_samples is not None and count >= max_samples:
                            break
                        status = (PointStatus.OK if s.status == MeasurementStatus.ALL_OK
                                  else PointStatus.WARNING)
                        p = s.position
                        yield StreamSample(s.seconds + (offset or 0.0),
                                           (float(p[0]), float(p[1]), float(p[2])), status,
                                           stamp=float(s.seconds))
                        count += 1
        finally:
            self._end_stream()

    def _end_stream(self) -> None:
        if not self.transport.is_open or self.client.dirty:
            return
        try:
            self.client.request(Command.STOP_MEASUREMENT)
            self._stationary()
            self.client.multis.clear()
        except TrackerError as exc:  # one line: the stream's own failure is what the user is told
            log.warning("could not return the tracker to stationary mode: %s", exc)

    def _start_measurement(self, search: bool = True) -> None:
        """ES_C_StartMeasurement once the tracker can measure.

        ES_RS_MeasurementStatusNotReady says the tracker's measurement status (the one its
        MeasStatus_NotReady / _Busy / _Ready events report, ES_C_API_Def.h) is not Ready *yet*: no
        reflector locked — the SMR turned away while the arm moved to a path's start and faces the
        tracker again — or one just caught whose distance is still being set. That is waited on,
        bounded: a FindReflector at the last distance when the beam is not known to be locked (its
        own search timeout), then the MeasStatus_Ready event for up to ``ready_timeout``, then the
        start again. Only a search that finds nothing, or a status still not Ready at the deadline,
        is `TargetLost`. Without ``search`` a beam not known to be locked is `TargetLost` at once, for
        a caller that re-locks itself (`measure_point`: its bounded re-locks, not one more search).
        """
        client = self.client
        deadline = time.monotonic() + self.config.ready_timeout
        searched = False
        while True:
            answer = client.request(Command.START_MEASUREMENT)
            if answer.ok or answer.status != ResultStatus.MeasurementStatusNotReady:
                self._judge(answer)
                return
            if client.beam_locked is not True and not searched:
                if not search:
                    self._judge(answer)
                searched = True
                if not self.relock():
                    self._raise(Command.START_MEASUREMENT, answer.status,
                                "answer, and FindReflector found no reflector")
                deadline = time.monotonic() + self.config.ready_timeout
            while client.beam_locked is not True and time.monotonic() < deadline:
                client.pump(min(deadline, time.monotonic() + 0.05))
            if client.beam_locked is not True:
                self._raise(Command.START_MEASUREMENT, answer.status,
                            f"answer, still not ready after {self.config.ready_timeout:g} s")
            if time.monotonic() >= deadline:
                self._raise(Command.START_MEASUREMENT, answer.status,
                            f"answer, still not ready after {self.config.ready_timeout:g} s")
            time.sleep(0.01)  # Ready announced: ask again (bounded by the deadline above)

    # --- answers ---------------------------------------------------------------------------------
    def _check(self, command: Command, *params: object, timeout: float | None = None) -> Answer:
        answer = self.client.request(command, *params, timeout=timeout)
        self._judge(answer)
        return answer

    def _judge(self, answer: Answer) -> None:
        if not answer.ok:
            self._raise(Command(answer.command), answer.status, "answer")

    @staticmethod
    def _raise(command: Command, status: int, how: str) -> None:
        text = f"emScon ES_C_{command.name} {how}: {status_name(status)} ({status})"
        if status in _BEAM_LOST:
            raise TargetLost(text, status, int(command))
        if status in _NOT_READY:
            raise NotReady(text)
        raise EmsconError(text, status, int(command))


def _version_tuple(software: str, fallback: tuple[int, int, int]) -> tuple[int, int, int]:
    """The first a.b.c in the software version string (the server's version otherwise)."""
    import re

    m = re.search(r"(\d+)\.(\d+)(?:\.(\d+))?", software)
    return (int(m[1]), int(m[2]), int(m[3] or 0)) if m else fallback
