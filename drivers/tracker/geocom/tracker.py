"""The GeoCOM tracker: connect, correct for the atmosphere, measure points and paths.

`GeoComTracker` implements `drivers.tracker.device.Tracker`. `measure_point` averages N samples in
tracking mode, re-locks on a lost target (AUT_LockIn, then AUT_Search + AUT_LockIn) a bounded number
of times, retries once after a transient link fault, and refuses an unstable point. `stream` samples at
a fixed rate with timestamps for path measurements.
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
from drivers.tracker.errors import GeoComError, TargetLost, TrackerError, UnstablePoint
from drivers.tracker.geocom.commands import (
    AtmosphericCorrection,
    LockStatus,
    MeasureProgram,
    PolarReading,
    TrackerCommands,
)
from drivers.tracker.geocom.protocol import GeoComClient
from drivers.tracker.geocom.transport import SerialConfig, SerialTransport
from drivers.tracker.geometry import polar_to_cartesian

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class TrackerConfig:
    """Everything the driver needs; all times are seconds and finite."""

    serial: SerialConfig
    timeout: float = 2.0  # per RPC
    crc: bool = False
    atmosphere: Atmosphere | None = field(default_factory=Atmosphere)
    stability_threshold_m: float = 50e-6  # max per-axis sample standard deviation of one point
    max_relocks: int = 2
    link_retries: int = 1
    search_window_rad: tuple[float, float] = (0.05, 0.05)
    wait_ms: int = 100  # TMC_GetSimpleMea wait for a distance

    def __post_init__(self) -> None:
        if not 0 < self.timeout < math.inf:
            raise ValueError("timeout must be positive and finite")
        if not self.stability_threshold_m > 0:
            raise ValueError("stability_threshold_m must be positive")
        if self.max_relocks < 0 or self.link_retries < 0:
            raise ValueError("retry counts must be >= 0")


class GeoComTracker:
    """A GeoCOM laser tracker (`drivers.tracker.device.Tracker`). No I/O until `open()`."""

    def __init__(self, config: TrackerConfig) -> None:
        self.config = config
        self.transport = SerialTransport(config.serial)
        self.client = GeoComClient(self.transport, timeout=config.timeout, crc=config.crc)
        self.commands = TrackerCommands(self.client)
        self.identity: Identity | None = None
        self._tracking = False

    # --- lifecycle
    def open(self) -> GeoComTracker:
        """Connect, identify the instrument and apply the atmospheric correction."""
        self.transport.open()
        try:
            cmd = self.commands
            cmd.null_proc()
            self.identity = Identity(
                cmd.get_instrument_name(), cmd.get_instrument_number(), cmd.get_firmware_version(),
                "GeoCOM " + ".".join(map(str, cmd.get_geocom_version())),
            )
            log.info("tracker %s", self.identity)
            if self.config.atmosphere is not None:
                self.apply_atmosphere(self.config.atmosphere)
        except BaseException:
            self.transport.close()
            raise
        return self

    def close(self) -> None:
        """Stop tracking (best effort) and close the port."""
        if self._tracking and self.transport.is_open:
            try:
                self.commands.do_measure(MeasureProgram.STOP)
            except TrackerError:
                log.debug("could not stop tracking on close", exc_info=True)
        self._tracking = False
        self.transport.close()

    def __enter__(self) -> GeoComTracker:
        return self.open()

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def apply_atmosphere(self, atm: Atmosphere) -> AtmosphericCorrection:
        """Send temperature and pressure (keeping the instrument's wavelength unless given)."""
        wavelength = atm.wavelength_m
        if wavelength is None:
            wavelength = self.commands.get_atmospheric_correction().wavelength_m
        corr = AtmosphericCorrection(
            wavelength, atm.pressure_mbar, atm.temperature_c,
            atm.temperature_c if atm.wet_temperature_c is None else atm.wet_temperature_c,
        )
        self.commands.set_atmospheric_correction(corr)
        return corr

    # --- points
    def relock(self) -> bool:
        """Try AUT_LockIn, then AUT_Search + AUT_LockIn. True when locked; link errors propagate."""
        cmd = self.commands
        try:
            cmd.lock_in()
            return True
        except GeoComError as exc:
            log.info("lock-in failed (%s); searching", exc)
        try:
            cmd.search(*self.config.search_window_rad)
            cmd.lock_in()
            return True
        except GeoComError as exc:
            log.info("search failed (%s)", exc)
            return False

    def ready(self) -> bool:
        """GeoCOM's RPCs used here expose no warm-up state, and this driver never raises NotReady."""
        return True

    def lock_status(self) -> str:
        """MOT_ReadLockStatus in words ("locked in", "locked out", "prediction")."""
        return self.commands.read_lock_status().name.lower().replace("_", " ")

    def _start_tracking(self) -> None:
        self.commands.do_measure(MeasureProgram.RTRK_DIST)
        self._tracking = True

    def _sample(self) -> PolarReading:
        return self.commands.get_simple_measurement(self.config.wait_ms)

    def _measure_once(self, samples: int) -> TrackerPoint:
        cmd = self.commands
        if cmd.read_lock_status() == LockStatus.LOCKED_OUT:
            raise TargetLost("MOT_ReadLockStatus: locked out", 0, 6021)
        self._start_tracking()
        readings = [self._sample() for _ in range(samples)]
        xyz = polar_to_cartesian(
            [r.hz for r in readings], [r.v for r in readings], [r.distance for r in readings]
        )
        if not np.all(np.isfinite(xyz)):
            raise TrackerError("non-finite coordinate from the instrument")
        mean = xyz.mean(axis=0)
        spread = xyz.std(axis=0, ddof=1) if samples > 1 else np.zeros(3)
        spread_t = (float(spread[0]), float(spread[1]), float(spread[2]))
        if float(spread.max()) > self.config.stability_threshold_m:
            raise UnstablePoint(
                f"point unstable: spread {max(spread_t) * 1e6:.1f} µm > "
                f"{self.config.stability_threshold_m * 1e6:.1f} µm over {samples} samples",
                spread_t,
            )
        status = PointStatus.WARNING if any(r.warning for r in readings) else PointStatus.OK
        return TrackerPoint((float(mean[0]), float(mean[1]), float(mean[2])), spread_t, samples, status)

    def measure_point(self, samples: int = 1) -> TrackerPoint:
        """Average ``samples`` readings of the SMR into one point in the tracker frame.

        Raises TargetLost after ``max_relocks`` failed re-locks, UnstablePoint if the spread
        exceeds the threshold, LinkError after ``link_retries`` retries, ConnectionLost at once.
        """
        if samples < 1:
            raise ValueError("samples must be >= 1")

        def relock() -> bool:
            self._tracking = False
            return self.relock()

        return measure_with_retries(lambda: self._measure_once(samples), relock,
                                    self.config.max_relocks, self.config.link_retries)

    def sample(self) -> TrackerPoint:
        """One reading of the SMR now (one TMC_GetSimpleMea; tracking started once, not per reading),
        without averaging or a stability check: the building block of settling on evidence. A lost
        target is re-locked as in `measure_point`; its spread is 0 (one reading)."""
        def once() -> TrackerPoint:
            if not self._tracking:
                if self.commands.read_lock_status() == LockStatus.LOCKED_OUT:
                    raise TargetLost("MOT_ReadLockStatus: locked out", 0, 6021)
                self._start_tracking()
            try:
                r = self._sample()
            except TargetLost:
                self._tracking = False
                raise
            xyz = polar_to_cartesian(r.hz, r.v, r.distance).reshape(-1)
            if not np.all(np.isfinite(xyz)):
                raise TrackerError("non-finite coordinate from the instrument")
            status = PointStatus.WARNING if r.warning else PointStatus.OK
            return TrackerPoint((float(xyz[0]), float(xyz[1]), float(xyz[2])), (0.0, 0.0, 0.0), 1, status)

        def relock() -> bool:
            self._tracking = False
            return self.relock()

        return measure_with_retries(once, relock, self.config.max_relocks, self.config.link_retries)

    # --- paths
    def stream(
        self,
        rate_hz: float,
        *,
        duration: float | None = None,
        max_samples: int | None = None,
        stop: threading.Event | None = None,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
    ) -> Iterator[StreamSample]:
        """Sample the SMR at ``rate_hz`` (one reading each) until duration / count / ``stop``.

        Slots are on a fixed grid from the start; a slot missed because the link was slower is
        skipped, never bunched. A lost target yields a sample with ``position=None`` (no re-lock
        mid-path: the caller decides). At least one of ``duration``, ``max_samples``, ``stop``
        must bound the loop.
        """
        if not 0 < rate_hz < math.inf:
            raise ValueError("rate_hz must be positive and finite")
        if duration is None and max_samples is None and stop is None:
            raise ValueError("give duration, max_samples or stop so the stream ends")
        period = 1.0 / rate_hz
        self._start_tracking()
        t0 = clock()
        count = 0
        slot = 0
        while True:
            if stop is not None and stop.is_set():
                return
            if max_samples is not None and count >= max_samples:
                return
            now = clock()
            if duration is not None and now - t0 >= duration:
                return
            target_t = t0 + slot * period
            if target_t > now:
                sleep(target_t - now)
            t = clock()
            # a reading integrates over the instrument's measuring time between request and reply, so
            # it is stamped at the middle of that (a moving SMR is where the reading says half-way)
            try:
                reading = self._sample()
                xyz = polar_to_cartesian(reading.hz, reading.v, reading.distance)
                status = PointStatus.WARNING if reading.warning else PointStatus.OK
                yield StreamSample(0.5 * (t + clock()), (float(xyz[0]), float(xyz[1]), float(xyz[2])), status)
            except TargetLost as exc:
                yield StreamSample(0.5 * (t + clock()), None, None, str(exc))
            count += 1
            slot = max(slot + 1, math.floor((clock() - t0) / period) + 1)
