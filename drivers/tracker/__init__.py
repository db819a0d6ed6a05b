"""Laser trackers: one `Tracker` protocol (`device`), two implementations.

* GeoCOM over a serial line (Leica's total stations and instruments that speak it):
  `drivers.tracker.geocom`;
* emScon TPI over TCP (Leica's absolute laser trackers, AT9xx/AT40x): `drivers.tracker.emscon`.

`errors` holds the typed errors of both; `geometry.polar_to_cartesian` is the single polar→Cartesian
convention, shared with the simulator.
"""

from typing import TYPE_CHECKING

if TYPE_CHECKING:
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

#: Each public name by the module that defines it, imported when first asked for: a user of one part
#: (`hil identify` needs only `geometry`'s polar convention) does not load both protocols' clients,
#: which cost about a fifth of `hil identify`'s start-up (bench/cli_startup.py).
_LAZY = {
    **dict.fromkeys(("Atmosphere", "Identity", "PointStatus", "StreamSample", "Tracker", "TrackerPoint"),
                    "drivers.tracker.device"),
    **dict.fromkeys(("EmsconConfig", "EmsconTracker", "TcpConfig"), "drivers.tracker.emscon"),
    **dict.fromkeys(("ChecksumError", "ConnectionLost", "EmsconError", "GarbledReply", "GeoComError",
                     "InstrumentError", "LinkError", "NotReady", "ProtocolError", "TargetLost",
                     "TrackerError", "TrackerTimeout", "UnstablePoint"), "drivers.tracker.errors"),
    **dict.fromkeys(("GeoComTracker", "ReturnCode", "SerialConfig", "TrackerConfig"),
                    "drivers.tracker.geocom"),
    **dict.fromkeys(("cartesian_to_polar", "polar_to_cartesian"), "drivers.tracker.geometry"),
}


def __getattr__(name: str) -> object:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


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
