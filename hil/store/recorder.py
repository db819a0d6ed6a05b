"""The event recorder: each campaign event appended to its campaign's log, and the rows it implies.

The engine subscribes `EventRecorder.record_event` (via `as_subscriber`) as a *critical* subscriber:
each event is appended to the log and its derived rows (a PointMeasured's measurement, a
RunFinished's status, ...) are written in the same transaction, and any failure raises `StoreError`,
which stops the run rather than let it measure what it cannot keep. The rows are written by
`hil.store.rows`, as the direct methods (`Store.record_measurement`, `save_model`,
`save_validation`) write them: recording a measurement with its raw samples and then emitting the
PointMeasured with the same ``t`` stores it once. An event is keyed by a ``uid`` drawn before its
transaction, so a retry after a lost link (`hil.store.transactions`) logs it once too.
"""

from __future__ import annotations

import json
import secrets
from collections.abc import Callable
from typing import TYPE_CHECKING

from sqlalchemy import Connection, func, select

import hil.store.rows as rows
import hil.store.tables as tb
from hil.store.owner import this_process
from hil.store.records import LIVE_STATES, ROLES
from hil.store.transactions import TransactionalStore

if TYPE_CHECKING:  # the event types are imported where events are recorded: a reader never needs them
    from hil.campaign.events import Event

__all__ = ["EventRecorder"]


class EventRecorder(TransactionalStore):
    """The part of `hil.store.core.Store` that records events (the module docstring says how)."""

    def record_event(self, event: Event) -> int:
        """Append `event` to its campaign's log and apply what it implies, in one transaction;
        returns the event's sequence number. Raises StoreError on any failure (critical).

        A `RunStarted` is logged with an ``owner`` key added (`hil.store.owner.this_process`): the
        process recording a run's start is the one running it, and readers use it to tell a live run
        from one whose process died (`campaigns` then says ``interrupted``)."""
        from hil.campaign.events import RunStarted

        data = event.to_dict()
        if isinstance(event, RunStarted):
            data["owner"] = this_process()
        uid = secrets.token_hex(12)
        e = tb.events

        def body(conn: Connection) -> int:
            rows.require_campaign(conn, event.campaign, self.location)
            done = conn.execute(select(e.c.seq).where(e.c.uid == uid)).scalar()
            if done is not None:  # this very event, committed before the link dropped
                return int(done)
            seq = conn.execute(select(func.coalesce(func.max(e.c.seq), 0) + 1)
                               .where(e.c.campaign == event.campaign)).scalar_one()
            conn.execute(e.insert().values(campaign=event.campaign, seq=seq, t=float(event.t),
                                           type=event.name, data=rows.dumps(data), uid=uid))
            self._apply(conn, event)
            rows.touch(conn, event.campaign, float(event.t))
            return int(seq)

        return self._write(f"record {event.name}", body)

    def as_subscriber(self) -> Callable[[Event], None]:
        """The callable to subscribe (critical) to the EventBus."""
        return self.record_event

    subscriber = record_event

    def _apply(self, conn: Connection, ev: Event) -> None:
        """Write the rows `ev` implies, in the transaction that logs it."""
        from hil.campaign.events import (
            ControllerModel,
            ModelIdentified,
            PointMeasured,
            PoseSkipped,
            PoseStarted,
            RunFinished,
            RunStarted,
            StateChanged,
            SweepChunk,
            ValidationDone,
        )

        cid, t, where = ev.campaign, float(ev.t), self.location
        if isinstance(ev, RunStarted):  # a new run: the last one's detail (e.g. why it stopped) is old
            rows.set_status(conn, cid, "running", "", None, t, where)
        elif isinstance(ev, StateChanged) and ev.state in LIVE_STATES:
            rows.set_status(conn, cid, ev.state, None, None, t, where)
        elif isinstance(ev, PoseStarted) and ev.role in ROLES:
            conn.execute(rows.dialect_insert(conn, tb.poses).values(
                campaign=cid, idx=int(ev.index), role=ev.role,
                target=rows.dumps(rows.vector(ev.target, 6, "target")))
                .on_conflict_do_nothing(index_elements=["campaign", "idx"]))
        elif isinstance(ev, PointMeasured):
            rows.insert_measurement(conn, cid, ev.index, ev.role, ev.q, ev.p,
                                    _reached_spread(conn, cid, ev.index), ev.p_spread,
                                    ev.samples, ev.deviation, t, None, None, where)
        elif isinstance(ev, PoseSkipped):
            rows.skip_pose(conn, cid, ev.index, ev.role, ev.reason, t, where)
        elif isinstance(ev, ModelIdentified) and ev.model:
            rows.insert_model(conn, cid, ev.model, t, where)
        elif isinstance(ev, ValidationDone):
            details = {"controller": ev.controller} if ev.controller else None
            rows.insert_validation(conn, cid, ev.before, ev.after, ev.passed, None, details, t, where)
        elif isinstance(ev, SweepChunk) and ev.stamps:
            rows.insert_stream_chunk(conn, cid, ev.segment, ev.take, ev.stream, ev.chunk, ev.session,
                                     ev.stamps, ev.values)
        elif isinstance(ev, ControllerModel):
            rows.keep_controller(conn, cid, ev.model)
        elif isinstance(ev, RunFinished):
            rows.set_status(conn, cid, ev.status, ev.detail, ev.result or None, t, where)


def _reached_spread(conn: Connection, campaign: str, index: int) -> list[float] | None:
    """The joint spread of the pose's PoseReached (PointMeasured does not carry it)."""
    e = tb.events
    data = conn.execute(select(e.c.data).where(e.c.campaign == campaign, e.c.type == "PoseReached")
                        .order_by(e.c.seq.desc()).limit(1)).scalar()
    if data is None:
        return None
    value = json.loads(data)
    spread = value.get("q_spread")
    return spread if value.get("index") == index and isinstance(spread, list) else None
