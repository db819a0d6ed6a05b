"""The store's campaign reads — the history, a campaign's record, its poses and measurements — written
once over any connection that runs SQL text (`Rows`): SQLAlchemy's (`hil.store.core.Store`, both
engines) or Python's own sqlite3 (`hil.store.sqlite_reader.SqliteReader`, a listing that must not pay
SQLAlchemy's import). The SQL is `hil.store.listing_sql`'s; this module maps its rows to records.

Readers never write, not even to tidy up: a campaign left ``running`` by a process that is gone (kill
-9, a power cut) is *read* as ``interrupted`` (`summary`), which is what it is — resumable — and the
database stays as it was (a reader may hold it read-only: ``hil history`` on another station's file).
The history's one row per campaign is a single query whatever the number of campaigns.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from contextlib import AbstractContextManager
from typing import TYPE_CHECKING, Any, Protocol

import hil.store.listing_sql as sql
from hil.errors import InputError
from hil.store.json_columns import DamagedRowError, row_json, row_number
from hil.store.owner import is_gone
from hil.store.records import (
    INTERRUPTED,
    CampaignRecord,
    CampaignSummary,
    Measurement,
    ModelRecord,
    PlannedPose,
    RobotIdentity,
    ValidationRecord,
)

if TYPE_CHECKING:
    import numpy as np

__all__ = ["ListingQueries", "Reader", "Rows", "UnknownCampaignError"]


class UnknownCampaignError(InputError):
    """No campaign with that id (or id prefix) in this database."""


class Rows(Protocol):
    """Runs one SQL text of `hil.store.listing_sql` with its named parameters; every row, as tuples."""

    def __call__(self, text: str, params: dict[str, Any] | None = None, /) -> Sequence[Sequence[Any]]: ...


class Reader(Protocol):
    """What the reads need of a store: what to call it in messages, and a consistent snapshot."""

    location: str

    def snapshot(self) -> AbstractContextManager[Rows]: ...


def measurement(row: Sequence[Any]) -> Measurement:
    """A `sql.MEASUREMENTS` row; DamagedRowError naming the row when a vector column is not one."""
    mid, cid, pose, role, q, p, qs, ps, samples, deviation, t = row

    def vector(text: str | None, column: str) -> tuple[float, ...] | None:
        value = row_json(text, table="measurements", row=mid, column=column, campaign=cid)
        if value is None:
            return None
        if not isinstance(value, list) or not all(isinstance(v, int | float) for v in value):
            raise DamagedRowError(f"damaged store row: campaign {cid}, table measurements, id {mid}: "
                                  f"{column} is not a list of numbers")
        return tuple(value)

    deviation = row_number(deviation, table="measurements", row=mid, column="deviation", campaign=cid,
                           optional=True)
    t = row_number(t, table="measurements", row=mid, column="t", campaign=cid)
    return Measurement(id=mid, campaign=cid, index=pose, role=role, q=vector(q, "q") or (),
                       p=vector(p, "p") or (), q_spread=vector(qs, "q_spread"),
                       p_spread=vector(ps, "p_spread"), samples=samples, deviation=deviation, t=t)


def summary(row: Sequence[Any]) -> CampaignSummary:
    """A `sql.SUMMARY` row; a live status whose run's process is gone (kill -9, power cut) reads as
    ``interrupted``, which it is: resumable (the database itself is left as it is — a reader never
    writes)."""
    *head, passed, kind, boot_planned, boot_measured, started = row
    cid = head[0]
    for i, column, optional in ((1, "created", False), (2, "updated", False), (10, "models.rms", True),
                                (11, "validations.rms", True)):
        head[i] = row_number(head[i], table="campaigns", row=cid, column=column, campaign=cid,
                             optional=optional)
    out = CampaignSummary(*head, passed=None if passed is None else bool(passed), kind=str(kind),
                          bootstrap_planned=int(boot_planned or 0),
                          bootstrap_measured=int(boot_measured or 0))
    try:
        run = row_json(started, table="events", row="RunStarted", column="data", campaign=out.id)
    except DamagedRowError:  # the listing reads the rest; `hil show` of this campaign names the row
        run = None
    if isinstance(run, dict) and is_gone(run.get("owner")):
        out = dataclasses.replace(out, status=INTERRUPTED)
    return out


def poses(rows: Rows, campaign: str, statuses: Sequence[str] | None = None) -> list[PlannedPose]:
    """The campaign's poses (only those of `statuses`, if given), by index."""
    text, params = sql.POSES, {"campaign": campaign}
    if statuses is not None:
        names, more = sql.in_list("status", statuses)
        text, params = f"{text} AND status IN ({names})", params | more
    return [PlannedPose(i, role, tuple(row_json(target, table="poses", row=i, column="target",
                                                campaign=campaign)), status, reason)
            for i, role, target, status, reason in rows(text + sql.BY_INDEX, params)]


class ListingQueries:
    """The campaign reads of a store (the module docstring says how), for any class that has a
    `location` and a `snapshot` (`Reader`)."""

    location: str

    if TYPE_CHECKING:  # each store has its own (a class below this one in the MRO)
        def snapshot(self) -> AbstractContextManager[Rows]: ...

    def _read(self, text: str, params: dict[str, Any] | None = None) -> Sequence[Sequence[Any]]:
        """`text`'s rows, read in a snapshot of their own."""
        with self.snapshot() as rows:
            return rows(text, params)

    def campaigns(self, limit: int | None = 20, *, station: str | None = None) -> list[CampaignSummary]:
        """Summaries, newest first (``limit=None`` for all)."""
        text, params = sql.SUMMARY, {}
        if station:
            text, params = text + sql.HISTORY_AT_STATION, {"station": station}
        text += sql.NEWEST_FIRST
        if limit is not None:
            text, params = text + " LIMIT :limit", params | {"limit": int(limit)}
        return [summary(r) for r in self._read(text, params)]

    def resolve_id(self, text: str) -> str:
        """A full campaign id from what a user typed: the id, a unique prefix of it, or ``last``."""
        with self.snapshot() as rows:
            if text in ("last", "latest"):
                found = rows(sql.LAST_ID)
                if not found:
                    raise UnknownCampaignError(f"{self.location}: no campaigns yet")
                return str(found[0][0])
            if rows(sql.ID, {"id": text}):
                return text
            pattern = text.replace("\\", "\\\\").replace("%", "\\%").replace("_", "\\_") + "%"
            ids = [r[0] for r in rows(sql.IDS_LIKE, {"pattern": pattern})] if text else []
        if len(ids) == 1:
            return str(ids[0])
        if not ids:
            raise UnknownCampaignError(f"{self.location}: no campaign {text!r} (see `hil history`)")
        raise UnknownCampaignError(f"{self.location}: {text!r} matches several campaigns "
                                   f"({', '.join(ids[:5])}{', ...' if len(ids) > 5 else ''})")

    def campaign(self, campaign: str) -> CampaignRecord:
        """Everything about one campaign (by exact id), read as one consistent snapshot."""
        one = {"campaign": campaign}
        with self.snapshot() as rows:
            found = rows(sql.SUMMARY + sql.ONE_CAMPAIGN, one)
            if not found:
                raise UnknownCampaignError(f"{self.location}: no campaign {campaign!r}")
            head = summary(found[0])
            (config, chash, plan, detail, result, software, rtype, serial, model, rsoft,
             controller) = rows(sql.DETAIL, one)[0]
            planned = poses(rows, campaign)
            measured = [measurement(m) for m in rows(sql.MEASUREMENTS + sql.BY_ID, one)]
            models = [ModelRecord(i, when, rms, row_json(doc, table="models", row=i, column="doc",
                                                         campaign=campaign))
                      for i, when, rms, doc in rows(sql.MODELS, one)]
            validations = [
                ValidationRecord(i, when, m, *(row_json(x, table="validations", row=i, column=col,
                                                        campaign=campaign)
                                               for x, col in ((b, "before"), (a, "after"))),
                                 bool(ok), row_json(d, table="validations", row=i, column="details",
                                                    campaign=campaign))
                for i, when, m, b, a, ok, d in rows(sql.VALIDATIONS, one)]
            counts = {t: int(n) for t, n in rows(sql.EVENT_COUNTS, one)}

        def column(text: str | None, name: str) -> Any:
            return row_json(text, table="campaigns", row=campaign, column=name, campaign=campaign)

        if head.status == INTERRUPTED and not detail:  # read so: its process is gone (`summary`)
            detail = "its process ended before the run did (killed, or the machine went down)"
        return CampaignRecord(
            summary=head,
            robot=RobotIdentity(type=rtype, serial=serial or "", model=model or "", software=rsoft or ""),
            config=column(config, "config"), config_hash=chash, plan=column(plan, "plan"), detail=detail,
            result=column(result, "result"), software=software, poses=planned, measurements=measured,
            models=models, validations=validations, event_counts=counts,
            controller=column(controller, "controller"))

    def poses(self, campaign: str) -> list[PlannedPose]:
        """Every pose of the plan, by index."""
        with self.snapshot() as rows:
            return poses(rows, campaign)

    def pending_poses(self, campaign: str, *, include_skipped: bool = False) -> list[PlannedPose]:
        """Poses still to measure, in plan order: what a resumed run visits."""
        statuses = ("planned", "skipped") if include_skipped else ("planned",)
        with self.snapshot() as rows:
            return poses(rows, campaign, statuses)

    def measured_poses(self, campaign: str) -> dict[int, Measurement]:
        """The latest measurement of each measured pose, by pose index: what a resume keeps."""
        out: dict[int, Measurement] = {}
        for m in self.measurements(campaign):
            out[m.index] = m
        return dict(sorted(out.items()))

    def measurements(self, campaign: str, role: str | None = None) -> list[Measurement]:
        """Every measurement row (repeats included), in recording order."""
        text, params = sql.MEASUREMENTS, {"campaign": campaign}
        if role is not None:
            text, params = text + sql.OF_ROLE, params | {"role": role}
        return [measurement(r) for r in self._read(text + sql.BY_ID, params)]

    def arrays(self, campaign: str, role: str = "calibration") -> tuple[np.ndarray, np.ndarray]:
        """Joint angles (n×6) and points (n×3) of `role`'s poses, latest per pose, by pose index:
        the input identification (or validation) needs after a resume."""
        import numpy as np

        ms = [m for m in self.measured_poses(campaign).values() if m.role == role]
        q = np.array([m.q for m in ms], dtype=float).reshape(-1, 6)
        p = np.array([m.p for m in ms], dtype=float).reshape(-1, 3)
        return q, p
