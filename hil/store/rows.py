"""A campaign's rows, written inside the caller's transaction, and the column text they are kept as.

The store writes a measurement (a model, a validation, a skipped pose, a status) two ways: directly
(`hil.store.core.Store.record_measurement`, ...) and from the event that reports it
(`hil.store.recorder`). Both go through these functions, so both write the same rows, and recording a
measurement directly and then by its event stores it once. Each function is idempotent for the same
reason: a transaction whose COMMIT may or may not have landed before the link dropped is run again
whole (`hil.store.transactions`).

Values are kept as compact JSON text (`dumps`; numpy arrays and records included) that both SQLite
and PostgreSQL store alike (`hil.store.json_columns`, re-exported here); `row_json` reads them back.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping
from typing import Any

from sqlalchemy import Connection, func, select

import hil
import hil.store.tables as tb
from hil.campaign.ids import new_campaign_id
from hil.store.hashing import canonical_json, config_hash, measurement_hash
from hil.store.json_columns import (  # re-exported: the store's modules and tests import them from here
    DamagedRowError,  # noqa: F401
    dumps,
    dumps_or_null,
    floats,  # noqa: F401
    loads,  # noqa: F401
    row_json,  # noqa: F401
)
from hil.store.records import CALIBRATION, ROLES, RobotIdentity
from hil.store.sqlite_errors import StoreError


def vector(value: Any, n: int, what: str) -> tuple[float, ...]:
    """`value` as `n` floats; StoreError naming `what` if it is not that."""
    import numpy as np

    try:
        v = tuple(float(x) for x in np.asarray(value, dtype=float).reshape(-1))
    except (TypeError, ValueError):
        raise StoreError(f"{what}: expected {n} numbers, got {value!r}") from None
    if len(v) != n:
        raise StoreError(f"{what}: expected {n} numbers, got {len(v)}")
    return v


def optional_vector(value: Any, n: int, what: str) -> tuple[float, ...] | None:
    """`vector`, or None for None."""
    return None if value is None else vector(value, n, what)


def sha(value: Any) -> str:
    """The SHA-256 of `value`'s canonical JSON: the content key of a model or a validation."""
    return hashlib.sha256(canonical_json(value).encode()).hexdigest()


def finite_or_none(value: Any) -> float | None:
    """`value` as a float if it is a finite number, else None (NaN and inf are not kept as numbers)."""
    try:
        f = float(value)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def dialect_insert(conn: Connection, table: Any) -> Any:
    """INSERT with this engine's ``ON CONFLICT`` support (both dialects spell it the same in SQL).
    The dialect is imported here, by the writes: a reader of an SQLite store never loads PostgreSQL's."""
    if conn.dialect.name == "postgresql":
        from sqlalchemy.dialects.postgresql import insert
    else:
        from sqlalchemy.dialects.sqlite import insert
    return insert(table)


# --- campaigns --------------------------------------------------------------------------------------
def require_campaign(conn: Connection, campaign: str, location: str) -> None:
    """StoreError unless `campaign` exists; it also locks the campaign's row for the rest of the
    transaction (PostgreSQL; SQLite's BEGIN IMMEDIATE already serialises writers), so two writers of
    one campaign — threads of one process — number its events one after the other."""
    if conn.execute(select(tb.campaigns.c.id).where(tb.campaigns.c.id == campaign)
                    .with_for_update()).first() is None:
        raise StoreError(f"{location}: no campaign {campaign!r}")


def insert_campaign(conn: Connection, config: Any,
                    robot: RobotIdentity | Mapping[str, Any] | str | None, plan: Mapping[str, Any] | None,
                    now: float, cid: str) -> str:
    """Insert the campaign `cid` (a retry after a lost link finds it there and returns it), its
    station and its robot; another id if `cid` is taken by another campaign. Returns the id."""
    values = config.as_dict() if hasattr(config, "as_dict") else dict(config)
    station = str((values.get("station") or {}).get("name") or "station")
    info = RobotIdentity.coerce(robot if robot is not None
                                else str((values.get("robot") or {}).get("type") or ""))
    c = tb.campaigns
    if conn.execute(select(c.c.config_hash).where(c.c.id == cid)).first() is not None:
        return cid  # this very campaign, committed before the link dropped
    conn.execute(dialect_insert(conn, tb.stations).values(name=station, created=now)
                 .on_conflict_do_nothing(index_elements=["name"]))
    station_id = conn.execute(select(tb.stations.c.id).where(tb.stations.c.name == station)).scalar_one()
    robot_id = None
    if info.serial:
        stmt = dialect_insert(conn, tb.robots).values(serial=info.serial, type=info.type, model=info.model,
                                                      software=info.software, first_seen=now,
                                                      last_seen=now)
        conn.execute(stmt.on_conflict_do_update(
            index_elements=["serial"],
            set_={"type": stmt.excluded.type, "model": stmt.excluded.model,
                  "software": stmt.excluded.software, "last_seen": stmt.excluded.last_seen}))
        robot_id = conn.execute(select(tb.robots.c.id)
                                .where(tb.robots.c.serial == info.serial)).scalar_one()
    for _ in range(20):
        if conn.execute(select(c.c.id).where(c.c.id == cid)).first() is None:
            break
        cid = new_campaign_id(now)
    conn.execute(c.insert().values(
        id=cid, station=station_id, robot=robot_id, robot_type=info.type, config=dumps(values),
        config_hash=config_hash(values), measure_hash=measurement_hash(values),
        # hil.__version__ looked up here, not on import: a listing never pays for importlib.metadata
        plan=dumps_or_null(plan), status="created", software=hil.__version__, created=now, updated=now,
        kind=str((plan or {}).get("kind") or CALIBRATION)))
    return cid


def set_status(conn: Connection, campaign: str, status: str, detail: str | None,
               result: Mapping[str, Any] | None, now: float, location: str) -> None:
    """Set a campaign's status (and its detail text and result JSON, unless None)."""
    c = tb.campaigns
    values: dict[str, Any] = {"status": status, "updated": now}
    if detail is not None:
        values["detail"] = detail
    if result is not None:
        values["result"] = dumps(result)
    if conn.execute(c.update().where(c.c.id == campaign).values(**values)).rowcount == 0:
        raise StoreError(f"{location}: no campaign {campaign!r}")


def touch(conn: Connection, campaign: str, now: float) -> None:
    """Move a campaign's ``updated`` time forward to `now` (never back)."""
    c = tb.campaigns
    conn.execute(c.update().where(c.c.id == campaign, c.c.updated < now).values(updated=now))


def keep_controller(conn: Connection, campaign: str, model: Mapping[str, Any]) -> None:
    """The controller's model a campaign runs with, kept with the campaign and, when the robot
    is known by its serial, as that robot's latest (what `Store.set_controller` keeps)."""
    c, r = tb.campaigns, tb.robots
    text = dumps(model)
    conn.execute(c.update().where(c.c.id == campaign).values(controller=text))
    robot = conn.execute(select(c.c.robot).where(c.c.id == campaign)).scalar()
    if robot is not None:
        conn.execute(r.update().where(r.c.id == robot).values(controller=text))


# --- poses and measurements -------------------------------------------------------------------------
def insert_measurement(conn: Connection, campaign: str, index: int, role: str, q: Any, p: Any,
                       q_spread: Any, p_spread: Any, samples: int, deviation: float | None, t: float,
                       tracker_samples: Any, joint_samples: Any, location: str) -> int:
    """Insert one measured point (and its raw samples), mark its pose measured; the id of the row,
    the existing one if (campaign, index, t) is already recorded."""
    m = tb.measurements
    if role not in ROLES:
        raise StoreError(f"pose {index}: role must be one of {', '.join(ROLES)}, got {role!r}")
    qv = vector(q, 6, f"pose {index} q")
    require_campaign(conn, campaign, location)
    row = conn.execute(dialect_insert(conn, m).values(
        campaign=campaign, pose=int(index), role=role, q=dumps(qv),
        q_spread=dumps_or_null(optional_vector(q_spread, 6, "q_spread")),
        p=dumps(vector(p, 3, f"pose {index} p")),
        p_spread=dumps_or_null(optional_vector(p_spread, 3, "p_spread")),
        samples=int(samples), deviation=finite_or_none(deviation), t=float(t))
        .on_conflict_do_nothing(index_elements=["campaign", "pose", "t"])
        .returning(m.c.id)).first()
    if row is None:  # already recorded (the direct call and then its event)
        return int(conn.execute(select(m.c.id).where(
            m.c.campaign == campaign, m.c.pose == int(index), m.c.t == float(t))).scalar_one())
    mid = int(row[0])
    for kind, values, n in (("tracker", tracker_samples, 3), ("joints", joint_samples, 6)):
        if values is not None and len(values):
            conn.execute(tb.samples.insert(), [
                {"measurement": mid, "kind": kind, "k": k,
                 "value": dumps(vector(v, n, f"{kind} sample {k}"))} for k, v in enumerate(values)])
    stmt = dialect_insert(conn, tb.poses).values(campaign=campaign, idx=int(index), role=role,
                                                 target=dumps(qv), status="measured")
    conn.execute(stmt.on_conflict_do_update(index_elements=["campaign", "idx"],
                                            set_={"status": "measured", "reason": ""}))
    touch(conn, campaign, float(t))
    return mid


def skip_pose(conn: Connection, campaign: str, index: int, role: str, reason: str, now: float,
              location: str) -> None:
    """Mark a planned pose skipped (a measured one stays measured); StoreError if it is not planned."""
    p = tb.poses
    require_campaign(conn, campaign, location)
    count = conn.execute(p.update().where(p.c.campaign == campaign, p.c.idx == int(index),
                                          p.c.status != "measured")
                         .values(status="skipped", reason=reason)).rowcount
    if count == 0 and conn.execute(select(p.c.idx).where(
            p.c.campaign == campaign, p.c.idx == int(index))).first() is None:
        raise StoreError(f"campaign {campaign}: cannot skip pose {index}: it is not in the plan")
    touch(conn, campaign, now)


# --- models and validations -------------------------------------------------------------------------
def insert_model(conn: Connection, campaign: str, doc: Mapping[str, Any], now: float,
                 location: str) -> int:
    """Insert a ``hil-model/1`` document; its id (the existing one for the same document)."""
    m = tb.models
    require_campaign(conn, campaign, location)
    text, key = dumps(doc), sha(json.loads(dumps(doc)))
    fit = doc.get("fit") if isinstance(doc.get("fit"), Mapping) else {}
    row = conn.execute(dialect_insert(conn, m).values(campaign=campaign, doc=text, sha256=key,
                                                      rms=finite_or_none(fit.get("rms")), created=now)
                       .on_conflict_do_nothing(index_elements=["campaign", "sha256"])
                       .returning(m.c.id)).first()
    touch(conn, campaign, now)
    if row is None:
        return int(conn.execute(select(m.c.id).where(m.c.campaign == campaign,
                                                     m.c.sha256 == key)).scalar_one())
    return int(row[0])


def insert_validation(conn: Connection, campaign: str, before: Mapping[str, Any],
                      after: Mapping[str, Any], passed: bool, model: int | None,
                      details: Mapping[str, Any] | None, now: float, location: str) -> int:
    """Insert a validation result (`model` None: the campaign's latest); its id (the existing one
    for the same result)."""
    v = tb.validations
    require_campaign(conn, campaign, location)
    if model is None:
        model = conn.execute(select(func.max(tb.models.c.id))
                             .where(tb.models.c.campaign == campaign)).scalar()
    body = {"before": before, "after": after, "passed": bool(passed), "details": details,
            "model": model}
    key = sha(json.loads(dumps(body)))
    row = conn.execute(dialect_insert(conn, v).values(
        campaign=campaign, model=model, before=dumps(before), after=dumps(after),
        passed=int(bool(passed)), rms=finite_or_none(after.get("rms")),
        details=dumps_or_null(details), sha256=key, created=now)
        .on_conflict_do_nothing(index_elements=["campaign", "sha256"]).returning(v.c.id)).first()
    touch(conn, campaign, now)
    if row is None:
        return int(conn.execute(select(v.c.id).where(v.c.campaign == campaign,
                                                     v.c.sha256 == key)).scalar_one())
    return int(row[0])


def insert_stream_chunk(conn: Connection, campaign: str, segment: int, take: str, stream: str, chunk: int,
                        session: str, stamps: Any, values: Any) -> None:
    """One chunk of a sweep's stream (`hil.store.tables.stream_chunks`); again for the same key (a
    retried transaction) it is kept once."""
    t = [float(v) for v in stamps]
    if not t:
        raise StoreError(f"stream chunk {stream} {segment}/{chunk}: no samples")
    data = {"t": t, "v": [None if v is None else [float(x) for x in v] for v in values]}
    if len(data["v"]) != len(t):
        raise StoreError(f"stream chunk {stream} {segment}/{chunk}: {len(t)} stamps, {len(data['v'])} values")
    conn.execute(dialect_insert(conn, tb.stream_chunks).values(
        campaign=campaign, segment=int(segment), take=str(take), stream=str(stream), chunk=int(chunk),
        session=str(session), count=len(t), t0=t[0], t1=t[-1], data=dumps(data))
        .on_conflict_do_nothing(index_elements=["campaign", "segment", "take", "stream", "chunk"]))
