"""Laser trackers: one `Tracker` protocol (`device`), two implementations.

* GeoCOM over a serial line (Leica's total stations and instruments that speak it):
  `drivers.tracker.geocom`;
* emScon TPI over TCP (Leica's absolute laser trackers, AT9xx/AT40x): `drivers.tracker.emscon`.

`errors` holds the typed errors of both; `geometry.polar_to_cartesian` is the single polar→Cartesian
convention, shared with the simulator.
"""

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
from drivers.tracker.geocom import GeoComTracker, ReturnCode, SerialConfig, TrackerConfig
from drivers.tracker.geometry import cartesian_to_polar, polar_to_cartesian

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
