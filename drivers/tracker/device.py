"""One laser tracker for the campaign, the TUI and MOVEB, whatever protocol it speaks.

`Tracker` is the protocol the orchestrator holds; `drivers.tracker.geocom.tracker.GeoComTracker` (GeoCOM
over a serial line) and `drivers.tracker.emscon.EmsconTracker` (Leica's emScon TPI over TCP) implement
it. Both report points in the tracker's own right-handed Cartesian frame in metres, raise the typed
errors of `drivers.tracker.errors`, and bound every wait with a timeout.
"""

from __future__ import annotations

import enum
import logging
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from types import TracebackType
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from drivers.tracker.errors import LinkError, TargetLost

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Atmosphere:
    """Air at the station, applied to the instrument at connect.

    GeoCOM sends temperature and pressure (TMC_SetAtmCorr; ``wet_temperature_c`` defaults to the dry
    temperature, ``wavelength_m`` None keeps the instrument's own, as Leica recommends); emScon sends
    temperature, pressure and humidity (ES_C_SetEnvironmentParams).
    """

    temperature_c: float = 20.0
    pressure_mbar: float = 1013.25
    wet_temperature_c: float | None = None
    wavelength_m: float | None = None
    humidity_percent: float = 50.0


class PointStatus(enum.Enum):
    """How trustworthy a point is."""

    OK = "ok"
    WARNING = "warning"  # instrument flagged accuracy / correction (GeoCOM rc 1283/1284)


@dataclass(frozen=True)
class TrackerPoint:
    """The SMR centre in the tracker frame (metres, see `drivers.tracker.geometry`)."""

    position: tuple[float, float, float]
    spread: tuple[float, float, float]  # per-axis sample standard deviation (ddof=1; 0 for one sample)
    samples: int
    status: PointStatus
    relocks: int = 0

    @property
    def xyz(self) -> NDArray[np.float64]:
        """Position as a numpy array."""
        return np.array(self.position)


@dataclass(frozen=True)
class StreamSample:
    """One sample of continuous mode: monotonic timestamp (the middle of the reading when the instrument
    gives none of its own), position or None if the target was lost."""

    t: float
    position: tuple[float, float, float] | None
    status: PointStatus | None  # None when lost
    reason: str = ""
    # the instrument's own stamp on its own clock (s; emScon's lTime1 + lTime2 µs), None when it gives
    # none (GeoCOM, a lost sample): what a sweep joins with the controller's clock
    stamp: float | None = None


@dataclass(frozen=True)
class Identity:
    """Who answered: model name, serial number, firmware version and the interface it speaks."""

    name: str
    serial_number: int
    firmware: tuple[int, int, int]
    interface: str  # "GeoCOM 1.50.0", "emScon TPI 3.6.0"


@runtime_checkable
class Tracker(Protocol):
    """What the campaign, the TUI and MOVEB use of a laser tracker. No I/O before `open()`."""

    identity: Identity | None

    def open(self) -> Tracker:
        """Connect and run the instrument's start-up sequence; typed errors, nothing left open."""
        ...

    def close(self) -> None:
        """Stop measuring (best effort) and disconnect."""
        ...

    def __enter__(self) -> Tracker: ...

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None: ...

    def measure_point(self, samples: int = 1) -> TrackerPoint:
        """One averaged point (TargetLost after bounded re-locks, UnstablePoint above the threshold)."""
        ...

    def sample(self) -> TrackerPoint:
        """One reading of the SMR now, no averaging and no stability check (TargetLost after bounded
        re-locks): what `hil.campaign` settles on evidence with, reading until the last few agree."""
        ...

    def relock(self) -> bool:
        """Try to find the SMR again; True when the beam is locked on it."""
        ...

    def ready(self) -> bool:
        """True when the instrument could measure now (after a `NotReady`: laser warm, initialized)."""
        ...

    def lock_status(self) -> str:
        """The beam's state in plain words ("locked in", "locked out", ...), for the operator."""
        ...

    def stream(self, rate_hz: float, *, duration: float | None = None, max_samples: int | None = None,
               stop: threading.Event | None = None, clock: Callable[[], float] = ...,
               sleep: Callable[[float], None] = ...) -> Iterator[StreamSample]:
        """Time-stamped samples of the SMR at about `rate_hz` until duration, count or `stop`."""
        ...


def measure_with_retries(measure_once: Callable[[], TrackerPoint], relock: Callable[[], object],
                         max_relocks: int, link_retries: int) -> TrackerPoint:
    """One point, the way every driver takes it: a lost target is re-locked (`relock`) up to
    `max_relocks` times and the point taken again; a transient link fault is retried `link_retries`
    times; everything else propagates. The point carries how many re-locks it needed."""
    relocks = link_failures = 0
    while True:
        try:
            point = measure_once()
            return TrackerPoint(point.position, point.spread, point.samples, point.status, relocks)
        except TargetLost as exc:
            if relocks >= max_relocks:
                raise TargetLost(f"target lost after {relocks} re-lock attempts: {exc}", exc.rc,
                                 exc.rpc) from exc
            relocks += 1
            log.info("target lost (%s); re-lock attempt %d", exc, relocks)
            relock()
        except LinkError as exc:
            if link_failures >= link_retries:
                raise
            link_failures += 1
            log.warning("link fault (%s); retrying the point", exc)
