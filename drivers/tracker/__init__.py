"""Laser trackers: one `Tracker` protocol (`device`), two implementations.

GeoCOM over a serial line (Leica's total stations and instruments that speak it), in three layers:

* `transport` — pyserial URL → lines with deadlines;
* `protocol` — GeoCOM framing, value codec, transaction ids, optional CRC-16, one request in flight;
* `commands` — one typed method per RPC; `measurement` — `GeoComTracker`: points, re-lock, continuous.

emScon TPI over TCP (Leica's absolute laser trackers, AT9xx/AT40x): `drivers.tracker.emscon`.

`geometry.polar_to_cartesian` is the single polar→Cartesian convention, shared with the simulator.
"""

from drivers.tracker.codes import ReturnCode
from drivers.tracker.device import Atmosphere, Identity, PointStatus, StreamSample, Tracker, TrackerPoint
from drivers.tracker.emscon import EmsconConfig, EmsconTracker, TcpConfig
from drivers.tracker.errors import (
    ChecksumError,
    ConnectionLost,
    EmsconError,
    GarbledReply,
    GeoComError,
    InstrumentError,
    LinkError,
    NotReady,
    ProtocolError,
    TargetLost,
    TrackerError,
    TrackerTimeout,
    UnstablePoint,
)
from drivers.tracker.geometry import cartesian_to_polar, polar_to_cartesian
from drivers.tracker.measurement import GeoComTracker, TrackerConfig
from drivers.tracker.transport import SerialConfig

__all__ = [
    "Atmosphere",
    "ChecksumError",
    "ConnectionLost",
    "EmsconConfig",
    "EmsconError",
    "EmsconTracker",
    "GarbledReply",
    "GeoComError",
    "GeoComTracker",
    "Identity",
    "InstrumentError",
    "LinkError",
    "NotReady",
    "PointStatus",
    "ProtocolError",
    "ReturnCode",
    "SerialConfig",
    "StreamSample",
    "TargetLost",
    "TcpConfig",
    "Tracker",
    "TrackerConfig",
    "TrackerError",
    "TrackerPoint",
    "TrackerTimeout",
    "UnstablePoint",
    "cartesian_to_polar",
    "polar_to_cartesian",
]
