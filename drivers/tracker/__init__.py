"""Laser tracker over serial: GeoCOM in three layers.

* `transport` — pyserial URL → lines with deadlines;
* `protocol` — GeoCOM framing, value codec, transaction ids, optional CRC-16, one request in flight;
* `commands` — one typed method per RPC; `measurement` — points, re-lock, continuous mode.

`geometry.polar_to_cartesian` is the single polar→Cartesian convention, shared with the simulator.
"""

from drivers.tracker.codes import ReturnCode
from drivers.tracker.errors import (
    ChecksumError,
    ConnectionLost,
    GarbledReply,
    GeoComError,
    LinkError,
    ProtocolError,
    TargetLost,
    TrackerError,
    TrackerTimeout,
    UnstablePoint,
)
from drivers.tracker.geometry import cartesian_to_polar, polar_to_cartesian
from drivers.tracker.measurement import (
    Atmosphere,
    Identity,
    PointStatus,
    StreamSample,
    Tracker,
    TrackerConfig,
    TrackerPoint,
)
from drivers.tracker.transport import SerialConfig

__all__ = [
    "Atmosphere",
    "ChecksumError",
    "ConnectionLost",
    "GarbledReply",
    "GeoComError",
    "Identity",
    "LinkError",
    "PointStatus",
    "ProtocolError",
    "ReturnCode",
    "SerialConfig",
    "StreamSample",
    "TargetLost",
    "Tracker",
    "TrackerConfig",
    "TrackerError",
    "TrackerPoint",
    "TrackerTimeout",
    "UnstablePoint",
    "cartesian_to_polar",
    "polar_to_cartesian",
]
