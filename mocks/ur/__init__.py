"""Simulated Universal Robots e-series controller, protocol-level, driven by the real ur_rtde client.

Entry points: `SimController` (in-process object), `SimProcess` (own process + control channel),
`serve` (blocking, composable with other services), `SimConfig` (plain-data configuration).
"""

from mocks.ur.clock import SimClock
from mocks.ur.controller import SimConfig, SimController
from mocks.ur.process import SimProcess, SimStartError, serve

__all__ = ["SimClock", "SimConfig", "SimController", "SimProcess", "SimStartError", "serve"]
