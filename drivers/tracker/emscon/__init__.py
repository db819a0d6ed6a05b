"""Leica's emScon TPI over TCP, for absolute laser trackers (AT9xx, AT40x), in four layers.

* `packets` — the C structs of ES_C_API_Def.h as bytes, both ways, and framing;
* `transport` — ``tcp://host:700``: whole packets with deadlines;
* `client` — command/answer pairing, asynchronous results, errors and status events;
* `tracker` — `EmsconTracker`: start-up sequence, points, re-lock, continuous paths.
"""

from drivers.tracker.emscon.tracker import EmsconConfig, EmsconStatus, EmsconTracker
from drivers.tracker.emscon.transport import TcpConfig

__all__ = ["EmsconConfig", "EmsconStatus", "EmsconTracker", "TcpConfig"]
