"""Campaign ids: ``YYYYMMDD-HHMMSS-xxxx``, when the campaign started (UTC) and 16 random bits.

One function for the runner (a run given no id) and the store (a new campaign's row), so an id means
the same wherever it was made. UTC, not the station's local time: a fleet's stations in several time
zones share one PostgreSQL store, and its ids must sort by start time across them (local stamps would
put a Shanghai cell's morning before a Detroit cell's previous evening). The store sits above this
package and imports it; this package never imports the store.
"""

from __future__ import annotations

import secrets
import time

__all__ = ["new_campaign_id"]


def new_campaign_id(now: float | None = None) -> str:
    """``YYYYMMDD-HHMMSS-xxxx`` of `now` (seconds since the epoch; default: now) in UTC, with 16 random
    bits: sorts by start time, reads aloud, and unique enough that a collision (the store retries one)
    needs two campaigns started in the same second."""
    stamp = time.strftime("%Y%m%d-%H%M%S", time.gmtime(time.time() if now is None else now))
    return f"{stamp}-{secrets.token_hex(2)}"
