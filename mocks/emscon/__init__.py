"""Simulated Leica emScon server (AT960 over TPI/TCP): instrument logic and a one-client TCP server.

It measures the same world as the GeoCOM simulator (`mocks.geocom`): give it any `TargetSource`.
"""

from mocks.emscon.instrument import (
    DEFAULT_REFLECTORS,
    EmsconConfig,
    EmsconInstrument,
    Reflector,
    TrackerIdentity,
)
from mocks.emscon.server import EmsconSimulator, ServerConfig

__all__ = [
    "DEFAULT_REFLECTORS",
    "EmsconConfig",
    "EmsconInstrument",
    "EmsconSimulator",
    "Reflector",
    "ServerConfig",
    "TrackerIdentity",
]
