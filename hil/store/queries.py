"""The read side of the store: the campaign reads of `hil.store.listing` (the history, a campaign's
record, its poses and measurements: SQL text that SQLite's own driver runs too) on this store's
SQLAlchemy connections, and the reads only a running campaign, the TUI or a report make (raw samples,
the latest model, the event log), each read in one consistent snapshot (`TransactionalStore.reading`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from sqlalchemy import select

import hil.store.tables as tb
from hil.store.listing import ListingQueries, UnknownCampaignError
from hil.store.rows import row_json
from hil.store.transactions import TransactionalStore

if TYPE_CHECKING:
    from hil.campaign.events import Event

__all__ = ["StoreQueries", "UnknownCampaignError"]


class StoreQueries(ListingQueries, TransactionalStore):
    """The part of `hil.store.core.Store` that reads (the module docstring says how)."""

    def samples(self, measurement: int) -> dict[str, list[tuple[float, ...]]]:
        """The raw samples of one measurement: ``{"tracker": [...], "joints": [...]}``."""
        s = tb.samples
        out: dict[str, list[tuple[float, ...]]] = {"tracker": [], "joints": []}
        rows = self._query(lambda conn: conn.execute(
            select(s.c.kind, s.c.value).where(s.c.measurement == measurement)
            .order_by(s.c.kind, s.c.k)).all())
        for kind, value in rows:
            out[kind].append(tuple(row_json(value, table="samples", row=f"measurement {measurement}",
                                            column="value")))
        return out

    def stream_chunks(self, campaign: str, segment: int, take: str, stream: str
                      ) -> tuple[list[float], list[Any]]:
        """One recorded stream of a sweep segment's take, its chunks joined in order: (stamps, values)
        (`hil.store.tables.stream_chunks`)."""
        c = tb.stream_chunks
        rows = self._query(lambda conn: conn.execute(
            select(c.c.chunk, c.c.data).where(c.c.campaign == campaign, c.c.segment == segment,
                                              c.c.take == take, c.c.stream == stream)
            .order_by(c.c.chunk)).all())
        stamps: list[float] = []
        values: list[Any] = []
        for chunk, data in rows:
            doc = row_json(data, table="stream_chunks", row=f"{segment}/{take}/{stream}/{chunk}",
                           column="data", campaign=campaign)
            stamps.extend(doc["t"])
            values.extend(doc["v"])
        return stamps, values

    def model(self, campaign: str) -> dict[str, Any] | None:
        """The campaign's latest model document, or None if it has none yet."""
        m = tb.models
        doc = self._query(lambda conn: conn.execute(
            select(m.c.doc).where(m.c.campaign == campaign).order_by(m.c.id.desc()).limit(1)).scalar())
        return None if doc is None else dict(row_json(doc, table="models", row="latest", column="doc",
                                                      campaign=campaign))

    def event_log(self, campaign: str, *, after: int = 0,
                  types: Sequence[str] | None = None) -> list[tuple[int, dict[str, Any]]]:
        """``(seq, event dict)`` pairs with seq > `after`, in order: a reader polls with the last
        seq it saw (the TUI following a run from another process, a report). `types`: only events of
        these type names (``("ReferenceMeasured",)``: a campaign's reference measurements, which the
        log alone keeps — they are never campaign points; `hil.campaign.warmup`)."""
        e = tb.events
        q = select(e.c.seq, e.c.data).where(e.c.campaign == campaign, e.c.seq > after)
        if types is not None:
            q = q.where(e.c.type.in_(list(types)))
        rows = self._query(lambda conn: conn.execute(q.order_by(e.c.seq)).all())
        return [(seq, row_json(data, table="events", row=seq, column="data", campaign=campaign))
                for seq, data in rows]

    def events(self, campaign: str, *, after: int = 0, types: Sequence[str] | None = None) -> list[Event]:
        """The log as Event objects (types this version does not know are left out)."""
        from hil.campaign.events import Event

        return [Event.from_dict(d) for _, d in self.event_log(campaign, after=after, types=types)
                if d.get("event") in Event.registry]

