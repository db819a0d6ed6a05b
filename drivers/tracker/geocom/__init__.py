"""GeoCOM over a serial line (Leica's total stations and instruments that speak it), in four layers.

* `transport` — pyserial URL → lines with deadlines;
* `protocol` — GeoCOM framing, value codec, transaction ids, optional CRC-16, one request in flight;
* `commands` — one typed method per RPC (return codes in `codes`);
* `tracker` — `GeoComTracker`: points, re-lock, continuous.
"""

from drivers.tracker.geocom.codes import ReturnCode
from drivers.tracker.geocom.tracker import GeoComTracker, TrackerConfig
from drivers.tracker.geocom.transport import SerialConfig

__all__ = ["GeoComTracker", "ReturnCode", "SerialConfig", "TrackerConfig"]
