"""The read side of the store: the history, a campaign's record, its poses, measurements, models and
events, each read in one consistent snapshot (`TransactionalStore.reading`).

Readers never write, not even to tidy up: a campaign left ``running`` by a process that is gone (kill
-9, a power cut) is *read* as ``interrupted`` (`_summary`), which is what it is — resumable — and the
database stays as it was (a reader may hold it read-only: ``hil history`` on another station's file).
The history's one row per campaign is a single query whatever the number of campaigns (`_SUMMARY`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from sqlalchemy import Connection, case, func, literal, select

import hil.store.tables as tb
from hil.errors import InputError
from hil.store.owner import is_gone
from hil.store.records import (
    INTERRUPTED,
    LIVE_STATES,
    CampaignRecord,
    CampaignSummary,
    Measurement,
    ModelRecord,
    PlannedPose,
    RobotIdentity,
    ValidationRecord,
)
from hil.store.rows import DamagedRowError, row_json
from hil.store.transactions import TransactionalStore

if TYPE_CHECKING:  # a listing needs neither: imported by the two readers that do (bench/cli_startup.py)
    import numpy as np

    from hil.campaign.events import Event

__all__ = ["StoreQueries", "UnknownCampaignError"]


class UnknownCampaignError(InputError):
    """No campaign with that id (or id prefix) in this database."""


_M = tb.measurements
_MEASUREMENT_COLUMNS = (_M.c.id, _M.c.campaign, _M.c.pose, _M.c.role, _M.c.q, _M.c.p, _M.c.q_spread,
                        _M.c.p_spread, _M.c.samples, _M.c.deviation, _M.c.t)


def _measurement(row: Sequence[Any]) -> Measurement:
    mid, cid, pose, role, q, p, qs, ps, samples, deviation, t = row

    def vector(text: str | None, column: str) -> tuple[float, ...] | None:
        value = row_json(text, table="measurements", row=mid, column=column, campaign=cid)
        if value is None:
            return None
        if not isinstance(value, list) or not all(isinstance(v, int | float) for v in value):
            raise DamagedRowError(f"damaged store row: campaign {cid}, table measurements, id {mid}: "
                                  f"{column} is not a list of numbers")
        return tuple(value)

    return Measurement(id=mid, campaign=cid, index=pose, role=role, q=vector(q, "q") or (),
                       p=vector(p, "p") or (), q_spread=vector(qs, "q_spread"),
                       p_spread=vector(ps, "p_spread"), samples=samples, deviation=deviation, t=t)


def _summary_query() -> Any:
    """One row per campaign for `CampaignSummary`. planned / measured / skipped count the campaign's
    calibration and validation poses: the count the progress bar, the Run screen and the history share
    (the bootstrap's points locate the tracker, and are counted apart: bootstrap_planned /
    bootstrap_measured)."""
    c, s, r, p = tb.campaigns, tb.stations, tb.robots, tb.poses
    m, v, e = tb.models, tb.validations, tb.events

    def pose_count(status: str | None, bootstrap: bool = False) -> Any:
        role = p.c.role == "bootstrap" if bootstrap else p.c.role != "bootstrap"
        q = select(func.count()).select_from(p).where(p.c.campaign == c.c.id, role)
        if status is not None:
            q = q.where(p.c.status == status)
        return q.correlate(c).scalar_subquery()

    def latest(column: Any, table: Any) -> Any:
        return (select(column).where(table.c.campaign == c.c.id).order_by(table.c.id.desc()).limit(1)
                .correlate(c).scalar_subquery())

    started = (select(e.c.data).where(e.c.campaign == c.c.id, e.c.type == "RunStarted")
               .order_by(e.c.seq.desc()).limit(1).correlate(c).scalar_subquery())
    return (select(c.c.id, c.c.created, c.c.updated, s.c.name, c.c.robot_type,
                   func.coalesce(r.c.serial, ""), c.c.status, pose_count(None), pose_count("measured"),
                   pose_count("skipped"), latest(m.c.rms, m), latest(v.c.rms, v), latest(v.c.passed, v),
                   c.c.kind, pose_count(None, bootstrap=True), pose_count("measured", bootstrap=True),
                   case((c.c.status.in_(sorted(LIVE_STATES)), started), else_=literal(None)))
            .select_from(c.join(s, s.c.id == c.c.station).outerjoin(r, r.c.id == c.c.robot)))


_SUMMARY = _summary_query()


def _summary(row: Sequence[Any]) -> CampaignSummary:
    """A summary row; a live status whose run's process is gone (kill -9, power cut) reads as
    ``interrupted``, which it is: resumable (the database itself is left as it is — a reader never
    writes)."""
    *head, passed, kind, boot_planned, boot_measured, started = row
    summary = CampaignSummary(*head, passed=None if passed is None else bool(passed), kind=str(kind),
                              bootstrap_planned=int(boot_planned or 0),
                              bootstrap_measured=int(boot_measured or 0))
    try:
        run = row_json(started, table="events", row="RunStarted", column="data", campaign=summary.id)
    except DamagedRowError:  # the listing reads the rest; `hil show` of this campaign names the row
        run = None
    if isinstance(run, dict) and is_gone(run.get("owner")):
        summary = dataclasses.replace(summary, status=INTERRUPTED)
    return summary


def _poses(conn: Connection, campaign: str, statuses: Sequence[str] | None = None) -> list[PlannedPose]:
    """The campaign's poses (only those of `statuses`, if given), by index."""
    p = tb.poses
    q = select(p.c.idx, p.c.role, p.c.target, p.c.status, p.c.reason).where(p.c.campaign == campaign)
    if statuses is not None:
        q = q.where(p.c.status.in_(statuses))
    return [PlannedPose(i, role, tuple(row_json(target, table="poses", row=i, column="target",
                                                campaign=campaign)), status, reason)
            for i, role, target, status, reason in conn.execute(q.order_by(p.c.idx))]


class StoreQueries(TransactionalStore):
    """The part of `hil.store.core.Store` that reads (the module docstring says how)."""

    def campaigns(self, limit: int | None = 20, *, station: str | None = None) -> list[CampaignSummary]:
        """Summaries, newest first (``limit=None`` for all)."""
        q = _SUMMARY
        if station:
            q = q.where(tb.stations.c.name == station)
        q = q.order_by(tb.campaigns.c.created.desc(), tb.campaigns.c.id.desc())
        if limit is not None:
            q = q.limit(int(limit))
        return [_summary(r) for r in self._query(lambda conn: conn.execute(q).all())]

    def resolve_id(self, text: str) -> str:
        """A full campaign id from what a user typed: the id, a unique prefix of it, or ``last``."""
        c = tb.campaigns

        def body(conn: Connection) -> str:
            if text in ("last", "latest"):
                row = conn.execute(select(c.c.id).order_by(c.c.created.desc(), c.c.id.desc())
                                   .limit(1)).first()
                if row is None:
                    raise UnknownCampaignError(f"{self.location}: no campaigns yet")
                return str(row[0])
            if conn.execute(select(c.c.id).where(c.c.id == text)).first():
                return text
            pattern = text.replace("\\", "\\\\").replace("%", "\\%").replace("_", "\\_") + "%"
            rows = [r[0] for r in conn.execute(
                select(c.c.id).where(c.c.id.like(pattern, escape="\\"))
                .order_by(c.c.created.desc()).limit(6))] if text else []
            if len(rows) == 1:
                return str(rows[0])
            if not rows:
                raise UnknownCampaignError(f"{self.location}: no campaign {text!r} (see `hil history`)")
            raise UnknownCampaignError(f"{self.location}: {text!r} matches several campaigns "
                                       f"({', '.join(rows[:5])}{', ...' if len(rows) > 5 else ''})")

        return self._query(body)

    def campaign(self, campaign: str) -> CampaignRecord:
        """Everything about one campaign (by exact id), read as one consistent snapshot."""
        c, r, v, e = tb.campaigns, tb.robots, tb.validations, tb.events
        with self.reading() as conn:
            row = conn.execute(_SUMMARY.where(c.c.id == campaign)).first()
            if row is None:
                raise UnknownCampaignError(f"{self.location}: no campaign {campaign!r}")
            summary = _summary(row)
            (config, chash, plan, detail, result, software, rtype, serial, model,
             rsoft, controller) = conn.execute(
                select(c.c.config, c.c.config_hash, c.c.plan, c.c.detail, c.c.result, c.c.software,
                       c.c.robot_type, r.c.serial, r.c.model, r.c.software, c.c.controller)
                .select_from(c.outerjoin(r, r.c.id == c.c.robot)).where(c.c.id == campaign)).one()
            poses = _poses(conn, campaign)
            measurements = [_measurement(m) for m in conn.execute(
                select(*_MEASUREMENT_COLUMNS).where(_M.c.campaign == campaign).order_by(_M.c.id))]
            models = [ModelRecord(i, when, rms, row_json(doc, table="models", row=i, column="doc",
                                                         campaign=campaign))
                      for i, when, rms, doc in conn.execute(
                select(tb.models.c.id, tb.models.c.created, tb.models.c.rms, tb.models.c.doc)
                .where(tb.models.c.campaign == campaign).order_by(tb.models.c.id))]
            validations = [
                ValidationRecord(i, when, m, *(row_json(x, table="validations", row=i, column=col,
                                                        campaign=campaign)
                                               for x, col in ((b, "before"), (a, "after"))),
                                 bool(ok), row_json(d, table="validations", row=i, column="details",
                                                    campaign=campaign))
                for i, when, m, b, a, ok, d in conn.execute(
                    select(v.c.id, v.c.created, v.c.model, v.c.before, v.c.after, v.c.passed, v.c.details)
                    .where(v.c.campaign == campaign).order_by(v.c.id))]
            counts = {t: int(n) for t, n in conn.execute(
                select(e.c.type, func.count()).where(e.c.campaign == campaign).group_by(e.c.type)
                .order_by(func.min(e.c.seq)))}
        def column(text: str | None, name: str) -> Any:
            return row_json(text, table="campaigns", row=campaign, column=name, campaign=campaign)

        if summary.status == INTERRUPTED and not detail:  # read so: its process is gone (`_summary`)
            detail = "its process ended before the run did (killed, or the machine went down)"
        return CampaignRecord(
            summary=summary,
            robot=RobotIdentity(type=rtype, serial=serial or "", model=model or "", software=rsoft or ""),
            config=column(config, "config"), config_hash=chash, plan=column(plan, "plan"), detail=detail,
            result=column(result, "result"), software=software, poses=poses, measurements=measurements,
            models=models, validations=validations, event_counts=counts,
            controller=column(controller, "controller"))

    def poses(self, campaign: str) -> list[PlannedPose]:
        """Every pose of the plan, by index."""
        return self._query(lambda conn: _poses(conn, campaign))

    def pending_poses(self, campaign: str, *, include_skipped: bool = False) -> list[PlannedPose]:
        """Poses still to measure, in plan order: what a resumed run visits."""
        statuses = ("planned", "skipped") if include_skipped else ("planned",)
        return self._query(lambda conn: _poses(conn, campaign, statuses))

    def measured_poses(self, campaign: str) -> dict[int, Measurement]:
        """The latest measurement of each measured pose, by pose index: what a resume keeps."""
        out: dict[int, Measurement] = {}
        for m in self.measurements(campaign):
            out[m.index] = m
        return dict(sorted(out.items()))

    def measurements(self, campaign: str, role: str | None = None) -> list[Measurement]:
        """Every measurement row (repeats included), in recording order."""
        q = select(*_MEASUREMENT_COLUMNS).where(_M.c.campaign == campaign)
        if role is not None:
            q = q.where(_M.c.role == role)
        return [_measurement(r) for r in self._query(lambda conn: conn.execute(q.order_by(_M.c.id)).all())]

    def arrays(self, campaign: str, role: str = "calibration") -> tuple[np.ndarray, np.ndarray]:
        """Joint angles (n×6) and points (n×3) of `role`'s poses, latest per pose, by pose index:
        the input identification (or validation) needs after a resume."""
        import numpy as np

        ms = [m for m in self.measured_poses(campaign).values() if m.role == role]
        q = np.array([m.q for m in ms], dtype=float).reshape(-1, 6)
        p = np.array([m.p for m in ms], dtype=float).reshape(-1, 3)
        return q, p

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

