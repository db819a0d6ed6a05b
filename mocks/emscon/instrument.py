"""The instrument side of emScon TPI: request packet in, reply packets out, plus a clock-driven part.

No sockets here. `EmsconInstrument.handle(packet, now)` answers one command packet and
`EmsconInstrument.tick(now)` produces what the tracker sends by itself (measurement results, beam
events); both return the packets due at ``now`` (simulated seconds since the server started). All
wire formats come from `drivers.tracker.emscon.packets`, which follows Leica's ``ES_C_API_Def.h``.

Behaviour a plain TPI client can rely on
----------------------------------------
Units and frame: SetUnits accepts length METER(0) or MILLIMETER(1), angle RADIAN(0) or DEGREE(1),
temperature CELSIUS, pressure MBAR, humidity RH; anything else answers ``WrongParameter``.
Coordinates are right-handed Cartesian in the tracker frame (SetCoordinateSystemType accepts RHR
only, any other type answers ``NotImplemented``). Lengths the tracker reports (positions, their
standard deviations, reflector surface offsets, the distance range of GetTrackerInfo) are in the set
length unit; the angle ranges of GetTrackerInfo in the set angle unit; meteo values are always °C,
mbar and %RH. Defaults at start: metre, radian, RHR, stationary mode (1000 ms, ADM on), continuous
time mode 10 ms / unlimited points, reflector 1, environment 20 °C / 1013.25 mbar / 50 %.

Answers: every command gets exactly one answer packet (``encode_answer(command, status, ...)``),
with results only when the status is ``AllOK`` — except GetReflectors, which answers one packet per
reflector, as emScon does. A command this simulator does not implement (unknown or not tabled)
answers ``NotImplemented``. A packet that does not decode raises `PacketError` here; the server
closes the connection, because a TPI stream has no resynchronisation marker.

* GetSystemStatus → (lastResultStatus (the status of the previous answer), trackerProcessorStatus
  INITIALIZED(5) after Initialize else COMPENSATION_SET(4), laserStatus 3 when warm else 0,
  admStatus 2 (ADM ready), emScon version 3.6.0, weatherMonitorStatus 0, flags 0, serial number).
* GetTrackerStatus → READY(2) when initialized, warm and locked on the reflector, else NOT_READY(0).
* GetTrackerInfo → (trackerType 13 = ES_LTS_AT901_B: the header has no AT960 entry, the AT901-B is
  its closest predecessor; name, serial, compensation id, ADM/overview camera/nivel present, nivel
  offset 0, max distance 20 m (Leica's AT960 datasheet: 40 m measuring-volume diameter for the
  standard model), min distance 0.8 m, max data rate 1000 (the AT960's 1000 Hz output), 2 faces, Hz
  range ±360° and Vt range ±145°, accuracy model 0, firmware). The minimum distance and the angular
  ranges are the datasheet's figures as recalled when this was written: check them against the
  current datasheet before relying on them.
* GetSystemSoftwareVersion → "emScon 3.6.0 SIM". GetMeasurementStatusInfo → (lastResultStatus,
  TRACKER_FOUND | TRACKER_COMPENSATION_FOUND | ADM_FOUND | ADM_COMPENSATION_FOUND | IN_FACE1 always,
  INITIALIZED after Initialize, REFLECTOR_FOUND while the beam is locked).
* Initialize answers AllOK after ``initialize_s`` simulated seconds (default 0); commands that
  arrive meanwhile are queued and answered after it, in order. Before Initialize, StartMeasurement
  and FindReflector answer ``TrackerNotInitialized``. During a measurement it answers ``ServerBusy``.
* Laser: warm after ``warmup_s`` simulated seconds (default 0) and outside a `laser_cold` fault.
  While cold, laserStatus is 0 and StartMeasurement answers ``SensorNotWarmedUp``.

Beam lock: the tracker starts locked if the target is visible when the instrument is built. It looks
at the target on every command, on every tick of a running measurement and whenever the server asks
(``tick(..., watch=True)``). When it sees the target is not visible it drops the lock and sends
``SystemStatusChange MEAS_STATUS_NOT_READY`` once per loss (pending continuous samples are sent
first). It never re-acquires by itself: FindReflector(approximate distance) re-locks if the target
is visible, answering AllOK followed by ``MEAS_STATUS_READY`` (sent on every successful
FindReflector, so a client may wait for it), else answers ``ModuleTimedOut``. A search takes time:
a failed one its whole timeout (SetSearchParams lTimeOut), a successful one ``find_s`` at most;
commands that arrive meanwhile queue behind it, as behind Initialize. GoBirdBath answers
AllOK and leaves the beam unlocked (NOT_READY follows if it was locked): the SMR is on the robot.

Measurements: StartMeasurement while one runs answers ``ServerBusy``; not initialized →
``TrackerNotInitialized``; laser cold → ``SensorNotWarmedUp``; beam not locked →
``MeasurementStatusNotReady``; else AllOK and:

* stationary: readings at ``stationary_rate_hz`` (AT960: 1000 Hz) over lMeasTime ms of simulated
  time, each from the (linearly interpolated) true position with the GeoCOM simulator's physics;
  then one `SingleMeasResult`: their mean, per-axis standard deviation and its total (root sum of
  squares), the a-priori standard deviation of one reading from the `NoiseSpec` propagated to x, y, z,
  pointing errors 0, the set meteo values, status 0. Beam lost before the end: ``MEAS_STATUS_NOT_READY``
  then ``ErrorResponse(START_MEASUREMENT, NoStationaryResult)`` and no result.
* continuous time: a sample every lTimeSeparation ms of the tracker's clock from the start, each a
  `MeasValue` with status 0 and its time on the tracker's clock (lTime1 whole seconds, lTime2
  microseconds since the server started; see Clocks), the SMR where it was at that time, sent in
  `MultiMeasResult` packets of at most `packets.MAX_SAMPLES` whenever the server flushes (about
  every 100 ms of wall time, as emScon's TcpDataPacketRate of 3..10 packets/s), at the end of the
  stream, before a beam-loss event and before the answer to StopMeasurement. No samples while the
  beam is lost; after a FindReflector re-lock the stream resumes on the same time grid. It stops
  after lNumberOfPoints samples (0 = until StopMeasurement). Regions are not simulated (bUseRegion=1
  answers ``NotImplemented``).

Clocks: everything the instrument does runs on simulated seconds (``now``), except the tracker's own
clock, which stamps continuous samples and spaces their grid. A real tracker's clock is a quartz of its
own that runs at the rate of the host's (to tens of ppm) whatever the simulation's speed, and a client
maps its stamps onto the host's clock by an offset alone; a fast-time station (simulated seconds 20
times faster than the wall's) stamping samples in simulated seconds would make every sample's time
wrong by up to 95 % of its age. So the server passes that clock (``clock``: the simulated seconds since
it started over the station's nominal speed, `mocks.emscon.server`, which pass in wall seconds while
the station runs at that speed) beside ``now``, and a continuous sample stamped τ carries the SMR's
position at the simulated time that τ was. The stamp it carries is that clock's reading through
`EmsconConfig.clock` (`hil.calibration.stream_clocks.InstrumentClock`: offset + (1 + drift)·(τ +
latency) + jitter), perfect by default; the simulated station gives the tracker realistic ones, so its
stamps and the controller's RTDE timestamps disagree as two real instruments' do. The time grid stays
on τ (a drift of tens of ppm changes the spacing by nanoseconds).

Truth: a real tracker measures the SMR where it is at each sample's instant. This simulator's thread
runs when the machine lets it, so a source that keeps a record of its past (`positions_at(times)`, the
simulated station's `mocks.world.World`, from the arm's `mocks.ur.history`) is asked where the SMR was
at each sample's simulated time (the source's clock reads ``source_epoch`` when ``now`` is 0), and
samples later than the newest time it knows (`known_until()`) wait for the next tick; a stall of
this thread then delays samples but never moves them. Each reading is an instant (`READING_S`):
the source is asked with ``reading_time=0``. A stationary result is due when its measuring time
ends (`next_due`, which the server wakes for), so its answer does not wait for a polling period. A
source without a record (`StaticTarget`) is read linearly between the last two looks at it, which is exact
for a target that moves only between ticks.

StopMeasurement answers AllOK (also when idle) and ends the stream; a stationary measurement it
interrupts sends no result. Changing units, measurement mode, mode parameters, coordinate system
or reflector during a measurement answers ``ServerBusy``.

Settings: SetReflector(id) takes the ids GetReflectors lists (else ``WrongParameter``); GetReflector
answers the id. SetEnvironmentParams(T °C, p mbar, h %) outside −40..60 °C, 500..1200 mbar,
0..100 % answers ``MeteoDataOutOfRange``; the distance error is the atmospheric ppm of the true air
(config) against the set air, as in the GeoCOM simulator. SetStationaryModeParams(lMeasTime ≥ 1
ms, bUseADM 0/1), SetContinuousTimeModeParams(lTimeSeparation ≥ 1 ms, lNumberOfPoints ≥ 0,
bUseRegion 0/1), SetStatisticMode(0/1, 0/1), SetSearchParams(radius > 0, timeout > 0 ms),
SwitchLaser(0/1), ClearCommandQueue answer AllOK, or ``WrongParameter1/2/3`` naming the bad field.
The matching Get commands answer the stored values.
"""

from __future__ import annotations

import heapq
import logging
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from drivers.tracker.emscon.packets import (
    MAX_SAMPLES,
    AngleUnit,
    Command,
    CoordinateSystemType,
    HumidityUnit,
    LengthUnit,
    MeasMode,
    MeasurementStatusInfo,
    MeasValue,
    MultiMeasResult,
    PressureUnit,
    ResultStatus,
    SingleMeasResult,
    SystemStatusChange,
    TargetType,
    TemperatureUnit,
    TrackerProcessorStatus,
    TrackerStatus,
    decode_request,
    encode_answer,
    encode_error,
    encode_multi,
    encode_single,
    encode_status_change,
)
from drivers.tracker.geometry import cartesian_to_polar, polar_to_cartesian
from hil.calibration.stream_clocks import InstrumentClock
from mocks.geocom.noise import NoiseSpec, atmospheric_ppm
from mocks.geocom.target import TargetSource, TargetState

log = logging.getLogger(__name__)

#: Seconds one reading integrates the SMR's motion over: an AT960 outputs 1000 readings a second (Leica's
#: AT960 datasheet, the max data rate GetTrackerInfo answers below), so a reading spans at most
#: 1 ms, a hundredth of the 9 Hz ring's period (`mocks.ringing`): an instant. A stationary measurement
#: integrates by averaging its readings; a continuous stream's samples are such readings.
READING_S = 0.0
#: Seconds of the tracker's clock over which the simulation's rate (simulated seconds per tracker
#: second) is measured: long next to a tick's jitter of a millisecond or so (0.1 % of it at most).
RATE_BASELINE_S = 1.0
_AT901_B = 13  # ES_LTS_AT901_B: the header's closest sensor type to an AT960
_ADM_READY = 2  # ES_AS_ADMReady
_LASER_WARM = 3  # laserStatus reported when warm
_ALWAYS_FOUND = (MeasurementStatusInfo.TRACKER_FOUND | MeasurementStatusInfo.TRACKER_COMPENSATION_FOUND
                 | MeasurementStatusInfo.ADM_FOUND | MeasurementStatusInfo.ADM_COMPENSATION_FOUND
                 | MeasurementStatusInfo.IN_FACE1)


class _Answer(Exception):
    """Raised by a handler to answer with a non-OK status."""

    def __init__(self, status: ResultStatus) -> None:
        super().__init__(status.name)
        self.status = status


@dataclass(frozen=True)
class Reflector:
    """One entry of GetReflectors."""

    id: int
    name: str
    target_type: TargetType
    surface_offset_m: float


DEFAULT_REFLECTORS: tuple[Reflector, ...] = (
    Reflector(1, "RRR 1.5in", TargetType.RRR15, 0.01905),
    Reflector(2, "RRR 0.5in", TargetType.RRR05, 0.00635),
    Reflector(3, "TBR 0.5in", TargetType.TBR05, 0.00635),
)


@dataclass(frozen=True)
class TrackerIdentity:
    """What the identity commands answer."""

    name: str = "AT960-SIM"
    serial_number: int = 960_001
    compensation_id: int = 1
    firmware: tuple[int, int] = (1, 4)  # LCP firmware major, minor
    emscon_version: tuple[int, int, int] = (3, 6, 0)
    software_version: str = "emScon 3.6.0 SIM"


@dataclass(frozen=True)
class EmsconConfig:
    """Physics, identity and timing of the simulated tracker (times in simulated seconds)."""

    identity: TrackerIdentity = field(default_factory=TrackerIdentity)
    noise: NoiseSpec = field(default_factory=NoiseSpec)
    seed: int | None = 0
    true_temperature_c: float = 20.0
    true_pressure_mbar: float = 1013.25
    warmup_s: float = 0.0  # laser warm-up after the server starts
    initialize_s: float = 0.0  # how long Initialize takes (the real one: tens of seconds)
    # How long a FindReflector takes when the SMR is where the beam points: the search spirals out from
    # the last direction and a nearby SMR is caught early. An assumption (the TPI header gives no
    # figure), bounded by the search timeout of SetSearchParams, which a failed search takes whole
    # (``failed_search_s`` None) unless told otherwise.
    find_s: float = 0.5
    failed_search_s: float | None = None
    stationary_rate_hz: float = 1000.0  # readings averaged by a stationary measurement
    # how the tracker's stamps err against its reference clock (offset, drift, jitter, latency:
    # `hil.calibration.stream_clocks`); perfect by default, the simulated station gives it realistic ones
    clock: InstrumentClock = field(default_factory=InstrumentClock)
    reflectors: tuple[Reflector, ...] = DEFAULT_REFLECTORS
    max_distance_m: float = 20.0
    min_distance_m: float = 0.8
    max_data_rate_hz: int = 1000
    hz_range_deg: float = 360.0
    vt_range_deg: float = 145.0

    def __post_init__(self) -> None:
        if not (self.warmup_s >= 0 and self.initialize_s >= 0 and self.stationary_rate_hz > 0):
            raise ValueError("warmup_s and initialize_s must be >= 0, stationary_rate_hz > 0")
        if not self.reflectors or len({r.id for r in self.reflectors}) != len(self.reflectors):
            raise ValueError("reflector ids must be present and unique")


@dataclass
class _Stationary:
    start: float
    end: float
    count: int  # readings in total
    taken: list[NDArray[np.float64]] = field(default_factory=list)  # blocks of (n, 3) readings

    @property
    def count_taken(self) -> int:
        return sum(len(block) for block in self.taken)

    def time_of(self, i: int) -> float:
        return self.start + (i + 1) * (self.end - self.start) / self.count


@dataclass
class _Continuous:
    start: float  # on the tracker's clock, as the grid and the stamps
    separation: float  # seconds of the tracker's clock
    limit: int  # 0 = until stopped
    next_k: int = 0
    produced: int = 0
    pending: list[MeasValue] = field(default_factory=list)
    begun: float = 0.0  # the simulated time it started (when ticks may advance it)

    def time_of(self, k: int) -> float:
        return self.start + k * self.separation


class EmsconInstrument:
    """State and command handlers of the simulated tracker (not thread-safe: the server serialises)."""

    def __init__(self, source: TargetSource, config: EmsconConfig | None = None, now: float = 0.0) -> None:
        self.source = source
        self.config = config or EmsconConfig()
        self._rng = np.random.default_rng(self.config.seed)
        # the stamps' jitter draws from a generator of its own: the readings' noise stays as it was
        self._stamp_rng = np.random.default_rng(None if self.config.seed is None else (self.config.seed, 1))
        self._outbox: list[tuple[float, int, bytes]] = []
        self._seq = 0
        self._busy_until = 0.0
        self.last_status = ResultStatus.AllOK
        self.initialized = False
        self.cold_until = 0.0
        self.units = (LengthUnit.METER, AngleUnit.RADIAN, TemperatureUnit.CELSIUS, PressureUnit.MBAR,
                      HumidityUnit.RH)
        self.coordinate_system = CoordinateSystemType.RHR
        self.mode = MeasMode.STATIONARY
        self.stationary_params = (1000, 1)  # lMeasTime ms, bUseADM
        self.continuous_params = (10, 0, 0, 0)  # lTimeSeparation ms, lNumberOfPoints, bUseRegion, region
        self.statistic_mode = (0, 0)
        self.search_params = (0.05, 10_000)  # radius (m), timeout (ms)
        self.reflector_id = self.config.reflectors[0].id
        self.environment = (20.0, 1013.25, 50.0)
        self._measurement: _Stationary | _Continuous | None = None
        state = self.source.target()
        self._now = self._clock_now = now  # the last simulated time and tracker clock seen
        self._rate = 1.0  # simulated seconds per second of the tracker's clock, as last seen
        self._clock_start = now
        self._rate_ref = (now, now)  # (simulated time, tracker clock) the rate is measured from
        # the last two looks at the target: (simulated time, tracker clock, position)
        self._anchors = ((now, now, state.position), (now, now, state.position))
        self.locked = state.visible
        self._seen = state
        self.commands = 0
        # the instrument's own account of its stationary measuring (simulated seconds over lMeasTime,
        # for benches adding up robot time, as the GeoCOM instrument's `measuring_seconds`)
        self.stationary_seconds = 0.0
        self.stationary_measurements = 0
        # the source's time (`positions_at`, `known_until`) when this instrument's simulated time is 0:
        # the server's start on the clock both share
        self.source_epoch = 0.0
        self._handlers = {
            Command.GET_SYSTEM_STATUS: self._get_system_status,
            Command.GET_TRACKER_STATUS: self._get_tracker_status,
            Command.SET_UNITS: self._set_units,
            Command.GET_UNITS: lambda t, p: tuple(int(u) for u in self.units),
            Command.INITIALIZE: self._initialize,
            Command.SWITCH_LASER: self._switch_laser,
            Command.SET_ENVIRONMENT_PARAMS: self._set_environment,
            Command.GET_ENVIRONMENT_PARAMS: lambda t, p: self.environment,
            Command.SET_MEASUREMENT_MODE: self._set_measurement_mode,
            Command.GET_MEASUREMENT_MODE: lambda t, p: (int(self.mode),),
            Command.SET_COORDINATE_SYSTEM_TYPE: self._set_coordinate_system,
            Command.GET_COORDINATE_SYSTEM_TYPE: lambda t, p: (int(self.coordinate_system),),
            Command.SET_STATIONARY_MODE_PARAMS: self._set_stationary_params,
            Command.GET_STATIONARY_MODE_PARAMS: lambda t, p: self.stationary_params,
            Command.SET_CONTINUOUS_TIME_MODE_PARAMS: self._set_continuous_params,
            Command.GET_CONTINUOUS_TIME_MODE_PARAMS: lambda t, p: self.continuous_params,
            Command.SET_REFLECTOR: self._set_reflector,
            Command.GET_REFLECTOR: lambda t, p: (self.reflector_id,),
            Command.GET_REFLECTORS: lambda t, p: self._get_reflectors(),
            Command.SET_SEARCH_PARAMS: self._set_search_params,
            Command.GET_SEARCH_PARAMS: lambda t, p: (self.search_params[0] * self._length_scale,
                                                     self.search_params[1]),
            Command.START_MEASUREMENT: self._start_measurement,
            Command.STOP_MEASUREMENT: self._stop_measurement,
            Command.GO_BIRD_BATH: self._go_bird_bath,
            Command.FIND_REFLECTOR: self._find_reflector,
            Command.SET_STATISTIC_MODE: self._set_statistic_mode,
            Command.GET_MEASUREMENT_STATUS_INFO: self._get_measurement_status_info,
            Command.CLEAR_COMMAND_QUEUE: lambda t, p: (),
            Command.GET_TRACKER_INFO: self._get_tracker_info,
            Command.GET_SYSTEM_SOFTWARE_VERSION: lambda t, p: (self.config.identity.software_version,),
        }

    # ------------------------------------------------------------------------------ public
    def handle(self, packet: bytes, now: float, clock: float | None = None) -> list[bytes]:
        """Answer one client packet; the packets due at ``now`` (a `PacketError` if it does not decode).

        ``clock``: the tracker's own clock at ``now`` (module docstring, Clocks); ``now`` when None."""
        request = decode_request(packet)
        self._clocks(now, clock)
        self.commands += 1
        t = max(now, self._busy_until)  # commands queue behind a running Initialize
        self._seen = self._observe(now, t)
        try:
            command: Command | int = Command(request.command)
            handler = self._handlers.get(command)
        except ValueError:
            command, handler = request.command, None
        status, results = ResultStatus.AllOK, ()
        if handler is None:
            status = ResultStatus.NotImplemented
        else:
            try:
                results = handler(t, request.params)
            except _Answer as answer:
                status, results = answer.status, ()
        if command == Command.GET_REFLECTORS and status == ResultStatus.AllOK:
            for row in results:
                self._emit(t, encode_answer(command, status, *row))
        else:
            slow = command in (Command.INITIALIZE, Command.FIND_REFLECTOR)
            due = max(t, self._busy_until) if slow else t
            self._emit(due, encode_answer(command, status, *results))
            t = due
        self.last_status = status
        self._after_answer(t, command, status)
        return self._drain(now)

    def tick(self, now: float, flush: bool = True, watch: bool = False,
             clock: float | None = None) -> list[bytes]:
        """Advance a running measurement to ``now``; the packets due.

        ``flush`` sends the continuous samples collected so far; ``watch`` looks at the target even
        when no measurement runs (a real tracker notices a broken beam by itself). ``clock``: the
        tracker's own clock at ``now`` (module docstring, Clocks); ``now`` when None.
        """
        self._clocks(now, clock)
        m = self._measurement
        if m is not None and now >= (m.begun if isinstance(m, _Continuous) else m.start):
            self._observe(now, now)
            if isinstance(m, _Stationary):
                self._advance_stationary(m, now)
            else:
                self._advance_continuous(m, now, flush)
        elif watch:
            self._observe(now, now)
        return self._drain(now)

    def next_due(self) -> float | None:
        """The simulated time of the next thing this tracker does by itself (an answer queued behind a
        busy command, the end of a stationary measurement), None when nothing is pending: the server
        wakes for it then, so the instrument's own times, not a polling period, decide when a result
        leaves (a 10 ms poll is 0.4 s of simulated time at 40x)."""
        due = [self._outbox[0][0]] if self._outbox else []
        if isinstance(self._measurement, _Stationary):
            due.append(self._measurement.end)
        return min(due) if due else None

    def wall_seconds(self, simulated: float) -> float:
        """Seconds of the tracker's clock (the wall's) that `simulated` seconds take at the rate seen."""
        return simulated / self._rate

    def laser_cold(self, seconds: float, now: float) -> None:
        """Fault: the laser is not warm for ``seconds`` of simulated time from ``now``."""
        if not 0 <= seconds < 86_400:
            raise ValueError("laser cold seconds must be in [0, 86400)")
        self.cold_until = max(self.cold_until, now + seconds)

    def disconnect(self) -> None:
        """The client left: its measurement ends and whatever was not sent is forgotten."""
        self._measurement = None
        self._outbox.clear()

    def warm(self, now: float) -> bool:
        return now >= self.config.warmup_s and now >= self.cold_until

    @property
    def measuring(self) -> bool:
        return self._measurement is not None

    # ------------------------------------------------------------------------------ plumbing
    def _clocks(self, now: float, clock: float | None) -> None:
        """Note the simulated time and the tracker's clock at it (and the rate between the two)."""
        clock = now if clock is None else clock
        ref_now, ref_clock = self._rate_ref
        if now > ref_now and clock - ref_clock >= RATE_BASELINE_S:
            # over a long baseline: two reads a tick apart, each a little off, would make it jitter
            self._rate = (now - ref_now) / (clock - ref_clock)
            if clock - ref_clock >= 4 * RATE_BASELINE_S:  # follow a change of the simulation's speed
                self._rate_ref = (self._now, self._clock_now)
        elif now > self._now and clock > self._clock_now and ref_clock == self._clock_start:
            self._rate = (now - self._now) / (clock - self._clock_now)  # until the baseline is long
        self._now, self._clock_now = now, clock

    def _clock_at(self, t: float) -> float:
        """The tracker's clock at simulated time ``t`` (a command queued behind a busy one: later)."""
        return self._clock_now + (t - self._now) / self._rate

    def _emit(self, t: float, packet: bytes) -> None:
        self._seq += 1
        heapq.heappush(self._outbox, (t, self._seq, packet))

    def _drain(self, now: float) -> list[bytes]:
        out: list[bytes] = []
        while self._outbox and self._outbox[0][0] <= now:
            out.append(heapq.heappop(self._outbox)[2])
        return out

    @property
    def _length_scale(self) -> float:
        return 1000.0 if self.units[0] == LengthUnit.MILLIMETER else 1.0

    @property
    def _angle_scale(self) -> float:
        return 1.0 if self.units[1] == AngleUnit.DEGREE else math.pi / 180.0

    def _observe(self, now: float, t: float) -> TargetState:
        """Look at the target; drop the lock (and say so, once) when it is not visible."""
        state = self.source.target()
        clock = self._clock_at(now)
        if now > self._anchors[1][0]:
            self._anchors = (self._anchors[1], (now, clock, state.position))
        else:
            self._anchors = (self._anchors[0], (*self._anchors[1][:2], state.position))
        if self.locked and not state.visible:
            log.debug("beam lost: %s", state.reason)
            self._lose(t)
        return state

    def _lose(self, t: float) -> None:
        self.locked = False
        if isinstance(self._measurement, _Continuous):
            self._flush(self._measurement, t)
        self._emit(t, encode_status_change(SystemStatusChange.MEAS_STATUS_NOT_READY))

    def _truths(self, times: list[float], on_clock: bool = False) -> NDArray[np.float64]:
        """True positions (n, 3) at ``times`` (simulated, or on the tracker's clock with ``on_clock``).

        From the source's record of where the SMR was at each time (`positions_at`, module docstring:
        Truth) when it keeps one; else linear between the last two looks at the target."""
        recorded = getattr(self.source, "positions_at", None)
        if recorded is not None:
            t = np.asarray(times, dtype=float)
            if on_clock:
                t = self._now + (t - self._clock_now) * self._rate
            return np.asarray(recorded(t + self.source_epoch, reading_time=READING_S),
                              dtype=float).reshape(-1, 3)
        axis = 1 if on_clock else 0
        (t0, p0), (t1, p1) = ((a[axis], a[2]) for a in self._anchors)
        p0, p1 = np.asarray(p0, dtype=float), np.asarray(p1, dtype=float)
        if t1 <= t0 or np.array_equal(p0, p1):
            return np.tile(p1, (len(times), 1))
        a = np.clip((np.asarray(times, dtype=float) - t0) / (t1 - t0), 0.0, 1.0)[:, None]
        return (1.0 - a) * p0 + a * p1

    def _readings(self, times: list[float], on_clock: bool = False) -> NDArray[np.float64]:
        """Noisy tracker-frame readings (n, 3) in metres at ``times`` (`_truths`), as the GeoCOM
        simulator measures."""
        cfg = self.config
        t_set, p_set, _ = self.environment
        scale = 1.0 + 1e-6 * (atmospheric_ppm(t_set, p_set)
                              - atmospheric_ppm(cfg.true_temperature_c, cfg.true_pressure_mbar))
        truths = self._truths(times, on_clock)
        d = np.linalg.norm(truths, axis=1)
        hz = np.arctan2(truths[:, 0], truths[:, 1]) % (2 * np.pi)
        v = np.arctan2(np.hypot(truths[:, 0], truths[:, 1]), truths[:, 2])
        # the draws `NoiseSpec.perturb` makes reading by reading (hz, v, then d), all at once: the same
        # stream, so a seed gives the same readings
        z = self._rng.standard_normal((len(truths), 3))
        s = cfg.noise
        hz = (hz + s.angle_sigma_rad * z[:, 0]) % (2 * np.pi)
        v = v + s.angle_sigma_rad * z[:, 1]
        d = d * scale + s.distance_sigma_m * z[:, 2]
        return polar_to_cartesian(hz, v, d).reshape(-1, 3)

    def _apriori(self, position: NDArray[np.float64]) -> NDArray[np.float64]:
        """Per-axis σ (m) of one reading at ``position``: the `NoiseSpec` propagated to x, y, z."""
        hz, v, d = cartesian_to_polar(position)
        sv, cv, sh, ch = math.sin(v), math.cos(v), math.sin(hz), math.cos(hz)
        J = np.array([[d * sv * ch, d * cv * sh, sv * sh],
                      [-d * sv * sh, d * cv * ch, sv * ch],
                      [0.0, -d * sv, cv]])
        s = self.config.noise
        cov = J @ np.diag([s.angle_sigma_rad**2, s.angle_sigma_rad**2, s.distance_sigma_m**2]) @ J.T
        return np.sqrt(np.diag(cov))

    def _after_answer(self, t: float, command: Command | int, status: ResultStatus) -> None:
        if command == Command.FIND_REFLECTOR and status == ResultStatus.AllOK:
            self._emit(t, encode_status_change(SystemStatusChange.MEAS_STATUS_READY))
        elif command == Command.GO_BIRD_BATH and status == ResultStatus.AllOK and self.locked:
            self._lose(t)
        elif command == Command.STOP_MEASUREMENT:
            self._measurement = None

    # ------------------------------------------------------------------------------ measurements
    def _advance_stationary(self, m: _Stationary, now: float) -> None:
        if not self.locked:
            self._measurement = None
            self._emit(now, encode_error(Command.START_MEASUREMENT, ResultStatus.NoStationaryResult))
            return
        upto = min(now, m.end)
        first = m.count_taken
        last = first
        while last < m.count and m.time_of(last) <= upto + 1e-12:
            last += 1
        if last > first:
            m.taken.append(self._readings([m.time_of(i) for i in range(first, last)]))
        if now < m.end:
            return
        self._measurement = None
        self.stationary_seconds += m.end - m.start
        self.stationary_measurements += 1
        readings = np.vstack(m.taken)
        mean = readings.mean(axis=0)
        std = readings.std(axis=0, ddof=1) if len(readings) > 1 else np.zeros(3)
        apriori = self._apriori(mean)
        k = self._length_scale
        T, p, h = self.environment
        self._emit(now, encode_single(SingleMeasResult(
            status=0, mode=int(MeasMode.STATIONARY), try_mode=False,
            position=_triple(mean * k), std=_triple(std * k), std_total=float(np.linalg.norm(std)) * k,
            pointing_error=(0.0, 0.0, 0.0), apriori_std=_triple(apriori * k),
            apriori_std_total=float(np.linalg.norm(apriori)) * k, temperature=T, pressure=p, humidity=h)))

    def _advance_continuous(self, m: _Continuous, now: float, flush: bool) -> None:
        due: list[int] = []
        k = m.next_k
        upto = self._clock_at(now)
        known = getattr(self.source, "known_until", None)
        end = known() if known is not None else None
        if end is not None:  # a sample the source cannot tell the truth for yet waits for it
            upto = min(upto, self._clock_at(end - self.source_epoch))
        while m.time_of(k) <= upto + 1e-12 and not (m.limit and m.produced + len(due) >= m.limit):
            due.append(k)
            k += 1
        m.next_k = k
        if due and self.locked:
            times = [m.time_of(i) for i in due]
            readings = (self._readings(times, on_clock=True) * self._length_scale).tolist()
            stamps = self._stamps(times)
            for t, (x, y, z) in zip(stamps, readings, strict=True):
                t1, t2 = divmod(round(t * 1e6), 1_000_000)
                m.pending.append(MeasValue(0, t1, t2, (x, y, z)))
            m.produced += len(due)
        done = bool(m.limit and m.produced >= m.limit)
        if flush or done:
            self._flush(m, now)
        if done:
            self._measurement = None

    def _stamps(self, times: list[float]) -> list[float]:
        """The stamps of samples taken at ``times`` of the reference tracker clock: as they are with a
        perfect clock, else through `EmsconConfig.clock` (module docstring, Clocks)."""
        clock = self.config.clock
        if clock == InstrumentClock():
            return times
        return clock.stamps(np.asarray(times), self._stamp_rng).tolist()

    def _flush(self, m: _Continuous, t: float) -> None:
        T, p, h = self.environment
        for i in range(0, len(m.pending), MAX_SAMPLES):
            chunk = tuple(m.pending[i:i + MAX_SAMPLES])
            self._emit(t, encode_multi(MultiMeasResult(0, int(MeasMode.CONTINUOUS_TIME), False, T, p, h,
                                                       chunk)))
        m.pending.clear()

    # ------------------------------------------------------------------------------ handlers
    def _not_while_measuring(self) -> None:
        if self._measurement is not None:
            raise _Answer(ResultStatus.ServerBusy)

    def _get_system_status(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        tps = TrackerProcessorStatus.COMPENSATION_SET
        if self.initialized:
            tps = TrackerProcessorStatus.INITIALIZED
        major, minor, build = self.config.identity.emscon_version
        return (int(self.last_status), int(tps), _LASER_WARM if self.warm(t) else 0, _ADM_READY,
                major, minor, build, 0, 0, self.config.identity.serial_number)

    def _get_tracker_status(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        ready = self.initialized and self.warm(t) and self.locked
        return (int(TrackerStatus.READY if ready else TrackerStatus.NOT_READY),)

    def _get_measurement_status_info(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        flags = _ALWAYS_FOUND
        if self.initialized:
            flags |= MeasurementStatusInfo.INITIALIZED
        if self.locked:
            flags |= MeasurementStatusInfo.REFLECTOR_FOUND
        return (int(self.last_status), int(flags))

    def _get_tracker_info(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        cfg, ident = self.config, self.config.identity
        k, a = self._length_scale, self._angle_scale
        return (_AT901_B, ident.name, ident.serial_number, ident.compensation_id, 1, 1, 1, 0.0,
                cfg.max_distance_m * k, cfg.min_distance_m * k, cfg.max_data_rate_hz, 2,
                cfg.hz_range_deg * a, cfg.vt_range_deg * a, 0, *ident.firmware)

    def _set_units(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        self._not_while_measuring()
        length, angle, temperature, pressure, humidity = params
        if (length not in (LengthUnit.METER, LengthUnit.MILLIMETER)
                or angle not in (AngleUnit.RADIAN, AngleUnit.DEGREE)
                or temperature != TemperatureUnit.CELSIUS or pressure != PressureUnit.MBAR
                or humidity != HumidityUnit.RH):
            raise _Answer(ResultStatus.WrongParameter)
        self.units = (LengthUnit(length), AngleUnit(angle), TemperatureUnit(temperature),
                      PressureUnit(pressure), HumidityUnit(humidity))
        return ()

    def _initialize(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        self._not_while_measuring()
        self.initialized = True
        self._busy_until = t + self.config.initialize_s
        return ()

    def _switch_laser(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        (on,) = params
        if on not in (0, 1):
            raise _Answer(ResultStatus.WrongParameter)
        return ()

    def _set_environment(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        T, p, h = (float(x) for x in params)
        if not (-40.0 <= T <= 60.0 and 500.0 <= p <= 1200.0 and 0.0 <= h <= 100.0):
            raise _Answer(ResultStatus.MeteoDataOutOfRange)
        self.environment = (T, p, h)
        return ()

    def _set_measurement_mode(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        self._not_while_measuring()
        (mode,) = params
        if mode in (MeasMode.STATIONARY, MeasMode.CONTINUOUS_TIME):
            self.mode = MeasMode(mode)
            return ()
        if 0 <= mode <= 11:  # the other ES_MeasMode values (distance, grid, sphere, 6D...)
            raise _Answer(ResultStatus.NotImplemented)
        raise _Answer(ResultStatus.WrongParameter)

    def _set_coordinate_system(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        self._not_while_measuring()
        if params[0] != CoordinateSystemType.RHR:
            raise _Answer(ResultStatus.NotImplemented)
        return ()

    def _set_stationary_params(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        self._not_while_measuring()
        meas_time, use_adm = params
        if not 1 <= meas_time <= 3_600_000:
            raise _Answer(ResultStatus.WrongParameter1)
        if use_adm not in (0, 1):
            raise _Answer(ResultStatus.WrongParameter2)
        self.stationary_params = (meas_time, use_adm)
        return ()

    def _set_continuous_params(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        self._not_while_measuring()
        separation, points, use_region, region = params
        if not 1 <= separation <= 3_600_000:
            raise _Answer(ResultStatus.WrongParameter1)
        if points < 0:
            raise _Answer(ResultStatus.WrongParameter2)
        if use_region not in (0, 1):
            raise _Answer(ResultStatus.WrongParameter3)
        if use_region:
            raise _Answer(ResultStatus.NotImplemented)
        self.continuous_params = (separation, points, use_region, region)
        return ()

    def _set_statistic_mode(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        stationary, continuous = params
        if stationary not in (0, 1):
            raise _Answer(ResultStatus.WrongParameter1)
        if continuous not in (0, 1):
            raise _Answer(ResultStatus.WrongParameter2)
        self.statistic_mode = (stationary, continuous)
        return ()

    def _set_search_params(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        radius, timeout = params
        if not 0.0 < radius < math.inf:
            raise _Answer(ResultStatus.WrongParameter1)
        if timeout <= 0:
            raise _Answer(ResultStatus.WrongParameter2)
        self.search_params = (radius / self._length_scale, timeout)
        return ()

    def _set_reflector(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        self._not_while_measuring()
        if params[0] not in {r.id for r in self.config.reflectors}:
            raise _Answer(ResultStatus.WrongParameter)
        self.reflector_id = params[0]
        return ()

    def _get_reflectors(self) -> tuple[tuple[Any, ...], ...]:
        n = len(self.config.reflectors)
        return tuple((n, r.id, int(r.target_type), r.surface_offset_m * self._length_scale, r.name)
                     for r in self.config.reflectors)

    def _start_measurement(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        if self._measurement is not None:
            raise _Answer(ResultStatus.ServerBusy)
        if not self.initialized:
            raise _Answer(ResultStatus.TrackerNotInitialized)
        if not self.warm(t):
            raise _Answer(ResultStatus.SensorNotWarmedUp)
        if not self.locked:
            raise _Answer(ResultStatus.MeasurementStatusNotReady)
        if self.mode == MeasMode.STATIONARY:
            duration = self.stationary_params[0] / 1000.0
            count = max(1, round(duration * self.config.stationary_rate_hz))
            self._measurement = _Stationary(t, t + duration, count)
        else:
            separation, points, _, _ = self.continuous_params
            self._measurement = _Continuous(self._clock_at(t), separation / 1000.0, points, begun=t)
        return ()

    def _stop_measurement(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        m = self._measurement
        if isinstance(m, _Continuous) and t >= m.begun:
            self._advance_continuous(m, t, flush=True)
        return ()

    def _go_bird_bath(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        return ()

    def _find_reflector(self, t: float, params: tuple[Any, ...]) -> tuple[Any, ...]:
        (distance,) = params
        if not 0.0 <= distance < math.inf:
            raise _Answer(ResultStatus.WrongParameter1)
        if not self.initialized:
            raise _Answer(ResultStatus.TrackerNotInitialized)
        timeout = self.search_params[1] / 1000.0
        if not self._seen.visible:  # the search spirals until its timeout
            failed = self.config.failed_search_s
            self._busy_until = t + (timeout if failed is None else min(timeout, failed))
            raise _Answer(ResultStatus.ModuleTimedOut)
        self._busy_until = t + min(timeout, self.config.find_s)
        if not self.locked:
            self.locked = True
            m = self._measurement
            if isinstance(m, _Continuous):  # resume on the time grid, from now on
                m.next_k = max(m.next_k, math.ceil((self._clock_at(t) - m.start) / m.separation - 1e-9))
        return ()


def _triple(a: NDArray[np.float64]) -> tuple[float, float, float]:
    return float(a[0]), float(a[1]), float(a[2])
