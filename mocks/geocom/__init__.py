"""Simulated GeoCOM laser tracker: instrument logic, a breakable beam, pty and TCP links.

Wiring into a shared world: implement `TargetSource.target() -> TargetState` (true SMR centre in
the tracker frame, visibility and reason) and pass it to `GeoComSimulator`.
"""

from mocks.geocom.faults import FaultInjector, ReplyFault
from mocks.geocom.instrument import GeoComInstrument, InstrumentConfig, InstrumentIdentity
from mocks.geocom.noise import NOISELESS, NoiseSpec, atmospheric_ppm, mpe_m
from mocks.geocom.server import GeoComSimulator, LinkConfig, SimulatorConfig
from mocks.geocom.target import StaticTarget, TargetSource, TargetState

__all__ = [
    "NOISELESS",
    "FaultInjector",
    "GeoComInstrument",
    "GeoComSimulator",
    "InstrumentConfig",
    "InstrumentIdentity",
    "LinkConfig",
    "NoiseSpec",
    "ReplyFault",
    "SimulatorConfig",
    "StaticTarget",
    "TargetSource",
    "TargetState",
    "atmospheric_ppm",
    "mpe_m",
]
