"""The `Store`: campaigns, poses, measurements, models, validations and events, on SQLite or PostgreSQL.

One schema, two engines (`hil.store.tables`, migrated by Alembic: `hil.store.migrate`), and every
query written once with SQLAlchemy Core, so both run the same statements.

Durability. Every write method is one transaction, committed before it returns. On SQLite the file
runs in WAL mode with ``synchronous=FULL`` (the WAL fsynced at each commit): ``NORMAL`` would already
survive ``kill -9`` (the WAL write reaches the OS before COMMIT returns) but could lose the last
commits on a power cut or kernel crash, which on a shop floor is not hypothetical. FULL costs one fsync
per commit, a few milliseconds against the seconds a pose takes to reach and measure, so the stronger
promise is nearly free (``synchronous="NORMAL"`` is accepted for fast-time simulations). On
PostgreSQL a COMMIT returns once the server has flushed its WAL (the server's own setting).

Threads. A `Store` may be shared between threads: each transaction takes a connection from the
engine's pool for its duration. SQLite's WAL lets readers (the TUI) run while the engine writes, and
writers — threads or other processes — queue on SQLite's lock for up to ``timeout`` seconds; on
PostgreSQL many stations write at once, each campaign's rows its own. `close` disposes of the pool.

A lost database link (PostgreSQL restarted, a network cut). A write whose connection fails is
retried on a new connection until ``outage_timeout`` seconds have passed, and the caller — the engine,
between a measurement and the next move — waits meanwhile, as for a lost tracker beam: nothing is
measured that cannot be kept, and nothing kept is lost. ``on_outage`` is told when the link goes and
comes back (the CLI and TUI say so). Every write is idempotent, so one whose COMMIT may or may not
have landed before the link dropped is safe to repeat: a measurement is keyed by (campaign, pose, t),
models and validations by their content hash, an event by its ``uid``, a new campaign by its id.

Recording. The engine subscribes `record_event` (via `as_subscriber`) as a *critical* subscriber:
each event is appended to the log and its derived rows (a PointMeasured's measurement, a
RunFinished's status, ...) are written in the same transaction, and any failure raises `StoreError`,
which stops the run rather than let it measure what it cannot keep. The direct methods
(`record_measurement`, `save_model`, `save_validation`) are idempotent with the event path: recording
a measurement with its raw samples and then emitting the PointMeasured with the same ``t`` stores it
once.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import math
import os
import secrets
import sqlite3
import threading
import time
import urllib.parse
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
from sqlalchemy import Connection, Engine, case, func, literal, select
from sqlalchemy.dialects import postgresql as pg_dialect
from sqlalchemy.dialects import sqlite as sqlite_dialect
from sqlalchemy.exc import DBAPIError

import hil.store.tables as tb
from hil import __version__
from hil.campaign.events import (
    ControllerModel,
    Event,
    ModelIdentified,
    PointMeasured,
    PoseSkipped,
    PoseStarted,
    RunFinished,
    RunStarted,
    StateChanged,
    ValidationDone,
)
from hil.campaign.ids import new_campaign_id
from hil.errors import InputError
from hil.store.database import display_url, is_postgres, postgres_engine, sqlite_engine
from hil.store.hashing import canonical_json, config_hash, measurement_hash
from hil.store.leases import LEASE_TTL, Lease, LeaseRefused, describe_holder, holder_gone
from hil.store.migrate import SCHEMA_VERSION, found_version, upgrade
from hil.store.owner import is_gone, this_process
from hil.store.paths import resolve_location
from hil.store.records import (
    CALIBRATION,
    FINISHED,
    INTERRUPTED,
    ROLES,
    CampaignRecord,
    CampaignSummary,
    Measurement,
    ModelRecord,
    PlannedPose,
    RobotIdentity,
    ValidationRecord,
)
from hil.store.sqlite_errors import CorruptStoreError, StoreError, StoreUnavailable, check_intact

log = logging.getLogger(__name__)

R = TypeVar("R")

# Engine states that are also campaign statuses (the final status comes from RunFinished).
_LIVE_STATES = frozenset({"running", "paused", "suspended", "stopping"})

#: Seconds a write waits for a lost PostgreSQL link to come back before the run stops (resumable).
OUTAGE_TIMEOUT = 600.0

__all__ = ["CorruptStoreError", "Store", "StoreError", "StoreUnavailable", "UnknownCampaignError",
           "new_campaign_id"]


class UnknownCampaignError(InputError):
    """No campaign with that id (or id prefix) in this database."""


def _dumps(value: Any) -> str:
    """Compact JSON of plain values, numpy arrays and scalars included."""

    def default(obj: Any) -> Any:
        if isinstance(obj, np.ndarray | np.generic):
            return obj.tolist()
        if isinstance(obj, tuple | set | frozenset):
            return list(obj)
        if hasattr(obj, "as_dict"):
            return obj.as_dict()
        raise TypeError(f"cannot store a {type(obj).__name__} as JSON")

    return json.dumps(value, separators=(",", ":"), default=default)


def _dumps_or_null(value: Any) -> str | None:
    """JSON text, or SQL NULL for None (so "absent" is queryable as IS NULL)."""
    return None if value is None else _dumps(value)


def _loads(text: str | None) -> Any:
    return None if text is None else json.loads(text)


def _vector(value: Any, n: int, what: str) -> tuple[float, ...]:
    try:
        v = tuple(float(x) for x in np.asarray(value, dtype=float).reshape(-1))
    except (TypeError, ValueError):
        raise StoreError(f"{what}: expected {n} numbers, got {value!r}") from None
    if len(v) != n:
        raise StoreError(f"{what}: expected {n} numbers, got {len(v)}")
    return v


def _optional_vector(value: Any, n: int, what: str) -> tuple[float, ...] | None:
    return None if value is None else _vector(value, n, what)


def _tuple(text: str | None) -> tuple[float, ...] | None:
    value = _loads(text)
    return None if value is None else tuple(value)


def _sha(value: Any) -> str:
    return hashlib.sha256(canonical_json(value).encode()).hexdigest()


def _finite_or_none(value: Any) -> float | None:
    try:
        f = float(value)
    except (TypeError, ValueError):
        return None
    return f if math.isfinite(f) else None


def _insert(conn: Connection, table: Any) -> Any:
    """INSERT with this engine's ``ON CONFLICT`` support (both dialects spell it the same in SQL)."""
    return (pg_dialect.insert if conn.dialect.name == "postgresql" else sqlite_dialect.insert)(table)


_M = tb.measurements
_MEASUREMENT_COLUMNS = (_M.c.id, _M.c.campaign, _M.c.pose, _M.c.role, _M.c.q, _M.c.p, _M.c.q_spread,
                        _M.c.p_spread, _M.c.samples, _M.c.deviation, _M.c.t)


def _measurement(row: Sequence[Any]) -> Measurement:
    mid, cid, pose, role, q, p, qs, ps, samples, deviation, t = row
    return Measurement(id=mid, campaign=cid, index=pose, role=role, q=tuple(json.loads(q)),
                       p=tuple(json.loads(p)), q_spread=_tuple(qs), p_spread=_tuple(ps),
                       samples=samples, deviation=deviation, t=t)


def _summary_query() -> Any:
    """One row per campaign for `CampaignSummary`. planned / measured / skipped count the campaign's
    calibration and validation poses: the count the progress bar, the Run screen and the history share
    (the bootstrap's points only locate the tracker)."""
    c, s, r, p = tb.campaigns, tb.stations, tb.robots, tb.poses
    m, v, e = tb.models, tb.validations, tb.events

    def pose_count(status: str | None) -> Any:
        q = select(func.count()).select_from(p).where(p.c.campaign == c.c.id, p.c.role != "bootstrap")
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
                   c.c.kind,
                   case((c.c.status.in_(sorted(_LIVE_STATES)), started), else_=literal(None)))
            .select_from(c.join(s, s.c.id == c.c.station).outerjoin(r, r.c.id == c.c.robot)))


_SUMMARY = _summary_query()


def _summary(row: Sequence[Any]) -> CampaignSummary:
    """A summary row; a live status whose run's process is gone (kill -9, power cut) reads as
    ``interrupted``, which it is: resumable (the database itself is left as it is — a reader never
    writes)."""
    *head, passed, kind, started = row
    summary = CampaignSummary(*head, passed=None if passed is None else bool(passed), kind=str(kind))
    if started is not None and is_gone(json.loads(started).get("owner")):
        summary = dataclasses.replace(summary, status=INTERRUPTED)
    return summary


def _lost_link(exc: DBAPIError) -> bool:
    """True when `exc` says the connection to the server is gone, not that the statement failed."""
    if exc.connection_invalidated:
        return True
    orig = exc.orig
    module = type(orig).__module__
    if not module.startswith("psycopg"):
        return False
    try:
        import psycopg
    except ImportError:  # pragma: no cover - psycopg is a dependency
        return False
    return isinstance(orig, psycopg.OperationalError) and not isinstance(
        orig, psycopg.errors.QueryCanceled | psycopg.errors.LockNotAvailable)


class Store:
    """A hil database. ``Store(location)`` does no I/O; `connect` (or ``with``, or `Store.open`) does.

    `location` is a file path (SQLite) or a ``postgresql://`` URL. Typical use::

        with Store.open(config=cfg) as store:
            cid = store.find_resumable(cfg, robot.serial) or store.create_campaign(cfg, robot, plan)
            bus.subscribe(store.as_subscriber(), critical=True)
    """

    def __init__(self, path: str | os.PathLike[str], *, create: bool = True,
                 synchronous: str = "FULL", timeout: float = 10.0, readonly: bool = False,
                 outage_timeout: float = OUTAGE_TIMEOUT) -> None:
        if synchronous.upper() not in ("FULL", "NORMAL", "EXTRA"):
            raise ValueError(f"synchronous must be FULL, NORMAL or EXTRA, got {synchronous!r}")
        self.postgres = is_postgres(path)
        self.url = str(path) if self.postgres else ""
        #: the SQLite file (None for a PostgreSQL store)
        self.path: Path | None = None if self.postgres else Path(path)
        #: what messages name: the file, or the URL without its password
        self.location = display_url(self.url) if self.postgres else str(self.path)
        self.create = create and not readonly
        self.readonly = readonly
        self.synchronous = synchronous.upper()
        self.timeout = timeout
        self.outage_timeout = outage_timeout
        #: called with a reason when a write finds the database link lost, and with None when it is back
        self.on_outage: Callable[[str | None], None] | None = None
        self._lock = threading.Lock()
        self._engine: Engine | None = None
        self._closed = False

    def __repr__(self) -> str:
        return f"Store({self.location!r})"

    @property
    def dialect(self) -> str:
        """``sqlite`` or ``postgresql``."""
        return "postgresql" if self.postgres else "sqlite"

    # --- opening and closing ------------------------------------------------------------------
    @classmethod
    def open(cls, path: str | os.PathLike[str] | None = None, *, config: Any = None,
             create: bool = True, synchronous: str = "FULL", timeout: float = 10.0,
             readonly: bool = False, outage_timeout: float | None = None) -> Store:
        """Open (creating or upgrading as needed) the database at `path`, or where `resolve_location`
        says from `config` and the environment. InputError if it is missing (with ``create=False`` or
        ``readonly=True``), empty (``readonly``), not a database, not a hil store, or newer than this
        code; StoreError if a PostgreSQL server cannot be reached.

        ``readonly=True`` is for the commands that only read (history, show, robots): they must work
        on a store they cannot write (read-only media, another user's station folder, a read-only
        database role) and must never create or change anything — so no WAL switch, no schema
        upgrade (`_readonly_uri`). `outage_timeout` defaults to the config's ``timeouts.database``."""
        if outage_timeout is None:
            values = config.as_dict() if hasattr(config, "as_dict") else (config or {})
            outage_timeout = float((values.get("timeouts") or {}).get("database") or OUTAGE_TIMEOUT)
        store = cls(resolve_location(path, config), create=create, synchronous=synchronous,
                    timeout=timeout, readonly=readonly, outage_timeout=outage_timeout)
        return store.connect()

    def connect(self) -> Store:
        """Open the database, creating or upgrading its schema on the first call. Idempotent."""
        self._get_engine()
        return self

    def __enter__(self) -> Store:
        return self.connect()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close every pooled connection. Further use raises StoreError."""
        with self._lock:
            self._closed = True
            engine, self._engine = self._engine, None
        if engine is not None:
            engine.dispose()

    def _get_engine(self) -> Engine:
        engine = self._engine
        if engine is not None:
            return engine
        with self._lock:
            if self._closed:
                raise StoreError(f"{self.location}: the store is closed")
            if self._engine is None:
                self._engine = self._open_postgres() if self.postgres else self._open_sqlite()
            return self._engine

    def _open_postgres(self) -> Engine:
        engine = postgres_engine(self.url, timeout=self.timeout, readonly=self.readonly)
        try:
            with engine.connect() as conn:
                if self.readonly:
                    self._check_version(conn, writable=False)
                else:
                    with conn.begin():
                        upgrade(conn, self.location)
        except DBAPIError as exc:
            engine.dispose()
            # no such database (3D000), no such role or a refused password (28000, 28P01): what was
            # typed is wrong (exit 2); a server that does not answer is a station fault (exit 3)
            text = str(exc.orig)
            if getattr(exc.orig, "sqlstate", None) in ("3D000", "28000", "28P01") or (
                    "does not exist" in text and ('database "' in text or 'role "' in text)) or (
                    "password authentication failed" in text):
                raise InputError(f"{self.location}: {_first_line(exc.orig)}") from None
            raise StoreUnavailable(f"{self.location}: cannot open: {_first_line(exc.orig)}") from exc
        except BaseException:
            engine.dispose()
            raise
        return engine

    def _open_sqlite(self) -> Engine:
        assert self.path is not None
        where = str(self.path)
        if not self.path.exists():
            if not self.create:
                raise InputError(f"{where}: no such database")
            try:
                self.path.parent.mkdir(parents=True, exist_ok=True)
            except OSError as exc:
                raise InputError(f"{where}: cannot create: {exc.strerror or exc}") from None
        elif self.path.is_dir():
            raise InputError(f"{where}: is a directory, not a database")
        elif self.readonly and self.path.stat().st_size == 0:
            # SQLite takes a 0-byte file for a new database; a reader must not turn it into a store
            raise InputError(f"{where} is empty: not a hil store")
        engine = sqlite_engine(self.path, uri=self._readonly_uri() if self.readonly else None,
                               timeout=self.timeout, synchronous=self.synchronous,
                               readonly=self.readonly)
        try:
            with engine.connect() as conn:
                raw = conn.connection.dbapi_connection
                if self.readonly:
                    self._check_version(conn, writable=os.access(self.path, os.W_OK)
                                        and os.access(self.path.resolve().parent, os.W_OK))
                else:
                    mode = raw.execute("PRAGMA journal_mode = WAL").fetchone()[0]
                    if str(mode).lower() != "wal":
                        raise InputError(f"{where}: cannot use WAL journal mode (got {mode}); "
                                         "put the database on a local file system")
                    if found_version(conn, where) < SCHEMA_VERSION:
                        conn.rollback()
                        with conn.execution_options(hil_write=True).begin():
                            upgrade(conn, where)
                    conn.rollback()
                    check_intact(raw, where)
        except DBAPIError as exc:
            engine.dispose()
            text = str(exc.orig)
            if "locked" in text or "busy" in text:
                raise StoreError(f"{where}: {text}") from None
            if "not a database" in text or "malformed" in text:
                raise InputError(f"{where}: not a hil database ({text})") from None
            raise InputError(f"{where}: cannot open: {text}") from None
        except sqlite3.DatabaseError as exc:
            engine.dispose()
            raise InputError(f"{where}: cannot open: {exc}") from None
        except BaseException:
            engine.dispose()
            raise
        return engine

    def _readonly_uri(self) -> str:
        """The ``file:`` URI of a reading connection (never one that creates the file).

        A WAL database needs its ``-wal`` and ``-shm`` files beside it. Where the reader may write
        them (``mode=rw``, with ``query_only`` set on every connection), SQLite removes them again at
        close, leaving the folder as it was; ``mode=ro`` would leave them behind. In a directory we
        cannot write (read-only media, another user's folder) even ``mode=ro`` fails ("attempt to
        write a readonly database"): there, unless a ``-wal`` holds commits not yet folded into the
        file (hil closes cleanly, folding them in), ``immutable=1`` reads the file alone; with such a
        ``-wal`` it would hide them, so ``mode=ro`` reads through the existing files.
        """
        assert self.path is not None
        path = self.path.resolve()
        wal = path.with_name(path.name + "-wal")
        if os.access(path.parent, os.W_OK):
            query = "mode=rw" if os.access(path, os.W_OK) else "mode=ro"
        elif wal.exists() and wal.stat().st_size > 0:
            query = "mode=ro"
        else:
            query = "mode=ro&immutable=1"
        return f"file:{urllib.parse.quote(str(path))}?{query}"

    def _check_version(self, conn: Connection, *, writable: bool) -> None:
        """What `upgrade` checks, without writing: a hil store of a version this code reads.

        An older store is upgraded once, as any command did before readers opened read-only, when it
        can be written; on read-only media a reader says so rather than fail on a missing column
        later."""
        found = found_version(conn, self.location)
        if found == 0:
            kind = "a PostgreSQL" if self.postgres else "an SQLite"
            raise InputError(f"{self.location}: {kind} database, but not a hil store")
        conn.rollback()
        if found < SCHEMA_VERSION and writable:
            Store(self.url or str(self.path), create=False, timeout=self.timeout).connect().close()
            found = found_version(conn, self.location)
            conn.rollback()
        if found < SCHEMA_VERSION:
            raise InputError(f"{self.location}: database schema version {found} is older than this "
                             f"hil's ({SCHEMA_VERSION}) and it is read-only here: copy it somewhere "
                             "writable to upgrade it")

    # --- transactions -------------------------------------------------------------------------
    def _transact(self, what: str, body: Callable[[Connection], R]) -> R:
        """Run `body` in one write transaction and commit it; any database failure becomes a
        StoreError naming `what`. A lost link is retried (the body again, on a new connection) until
        ``outage_timeout``: every body is idempotent (see the module docstring)."""
        waited_since: float | None = None
        delay = 0.2
        while True:
            engine = self._get_engine()
            try:
                with engine.connect() as conn, conn.execution_options(hil_write=True).begin():
                    result = body(conn)
                if waited_since is not None:
                    self._outage(None)
                return result
            except DBAPIError as exc:
                if not (self.postgres and _lost_link(exc)):
                    raise StoreError(f"{self.location}: cannot {what}: {_first_line(exc.orig)}") \
                        from exc.orig
                now = time.monotonic()
                if waited_since is None:
                    waited_since = now
                    self._outage(f"database link lost ({_first_line(exc.orig)}); waiting up to "
                                 f"{self.outage_timeout:g} s for it to come back")
                if now - waited_since >= self.outage_timeout:
                    raise StoreUnavailable(f"{self.location}: cannot {what}: the database did not come back "
                                     f"within {self.outage_timeout:g} s ({_first_line(exc.orig)})") \
                        from exc.orig
                time.sleep(min(delay, max(0.0, self.outage_timeout - (now - waited_since))))
                delay = min(delay * 2, 5.0)

    def _outage(self, reason: str | None) -> None:
        if reason is None:
            log.warning("%s: database link back; continuing", self.location)
        else:
            log.warning("%s: %s", self.location, reason)
        callback = self.on_outage
        if callback is not None:
            try:
                callback(reason)
            except Exception:  # a UI's trouble must not stop the store
                log.exception("on_outage callback failed")

    @contextmanager
    def writing(self, what: str) -> Iterator[Connection]:
        """One write transaction (no retry on a lost link: the body is the caller's), committed on
        exit; a database failure becomes a StoreError naming `what`."""
        if self.readonly:
            raise StoreError(f"{self.location}: opened read-only: cannot {what}")
        engine = self._get_engine()
        try:
            with engine.connect() as conn, conn.execution_options(hil_write=True).begin():
                yield conn
        except DBAPIError as exc:
            raise StoreError(f"{self.location}: cannot {what}: {_first_line(exc.orig)}") from exc.orig

    @contextmanager
    def reading(self) -> Iterator[Connection]:
        """A read transaction: the queries inside see one consistent snapshot. It ends by a rollback: a
        reader has nothing to commit (and a COMMIT on a full disk may fail where a rollback does not)."""
        engine = self._get_engine()
        try:
            with engine.connect() as conn:
                transaction = conn.begin()
                try:
                    yield conn
                finally:
                    transaction.rollback()
        except DBAPIError as exc:
            raise StoreError(f"{self.location}: cannot read: {_first_line(exc.orig)}") from exc.orig

    def _query(self, fn: Callable[[Connection], R]) -> R:
        with self.reading() as conn:
            return fn(conn)

    def _write(self, what: str, fn: Callable[[Connection], R]) -> R:
        if self.readonly:
            raise StoreError(f"{self.location}: opened read-only: cannot {what}")
        return self._transact(what, fn)

    # --- campaigns ----------------------------------------------------------------------------
    def create_campaign(self, config: Any, robot: RobotIdentity | Mapping[str, Any] | str | None = None,
                        plan: Mapping[str, Any] | None = None, *, now: float | None = None) -> str:
        """Start a campaign record (status ``created``) and return its id.

        `config` is a StationConfig or its ``as_dict()``; it is stored whole (the campaign must be
        reproducible from the database alone) with its `config_hash`, and the `measurement_hash`
        `find_resumable` matches.
        `robot` defaults to the config's robot type with an unknown serial.
        """
        now = time.time() if now is None else now
        cid = new_campaign_id(now)
        return self._write("create a campaign",
                           lambda conn: self._create(conn, config, robot, plan, now, cid))

    def _create(self, conn: Connection, config: Any,
                robot: RobotIdentity | Mapping[str, Any] | str | None, plan: Mapping[str, Any] | None,
                now: float, cid: str) -> str:
        """Insert the campaign `cid` (a retry after a lost link finds it there and returns it)."""
        values = config.as_dict() if hasattr(config, "as_dict") else dict(config)
        station = str((values.get("station") or {}).get("name") or "station")
        info = RobotIdentity.coerce(robot if robot is not None
                                else str((values.get("robot") or {}).get("type") or ""))
        c = tb.campaigns
        if conn.execute(select(c.c.config_hash).where(c.c.id == cid)).first() is not None:
            return cid  # this very campaign, committed before the link dropped
        conn.execute(_insert(conn, tb.stations).values(name=station, created=now)
                     .on_conflict_do_nothing(index_elements=["name"]))
        station_id = conn.execute(select(tb.stations.c.id).where(tb.stations.c.name == station)).scalar_one()
        robot_id = None
        if info.serial:
            stmt = _insert(conn, tb.robots).values(serial=info.serial, type=info.type, model=info.model,
                                                  software=info.software, first_seen=now, last_seen=now)
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
            id=cid, station=station_id, robot=robot_id, robot_type=info.type, config=_dumps(values),
            config_hash=config_hash(values), measure_hash=measurement_hash(values),
            plan=_dumps_or_null(plan), status="created", software=__version__, created=now, updated=now,
            kind=str((plan or {}).get("kind") or CALIBRATION)))
        return cid

    def set_status(self, campaign: str, status: str, detail: str | None = None,
                   result: Mapping[str, Any] | None = None) -> None:
        """Set a campaign's status (and optionally its detail text and result JSON)."""
        now = time.time()
        self._write("set the status",
                    lambda conn: self._set_status(conn, campaign, status, detail, result, now))

    def _set_status(self, conn: Connection, campaign: str, status: str, detail: str | None,
                    result: Mapping[str, Any] | None, now: float) -> None:
        c = tb.campaigns
        values: dict[str, Any] = {"status": status, "updated": now}
        if detail is not None:
            values["detail"] = detail
        if result is not None:
            values["result"] = _dumps(result)
        if conn.execute(c.update().where(c.c.id == campaign).values(**values)).rowcount == 0:
            raise StoreError(f"{self.location}: no campaign {campaign!r}")

    @staticmethod
    def _touch(conn: Connection, campaign: str, now: float) -> None:
        c = tb.campaigns
        conn.execute(c.update().where(c.c.id == campaign, c.c.updated < now).values(updated=now))

    def set_controller(self, serial: str, controller: Mapping[str, Any]) -> None:
        """Keep what a robot's controller says about its own (factory) calibration."""
        r = tb.robots

        def body(conn: Connection) -> None:
            if conn.execute(r.update().where(r.c.serial == serial)
                            .values(controller=_dumps(controller))).rowcount == 0:
                raise StoreError(f"{self.location}: no robot {serial!r}")

        self._write("record the controller's calibration", body)

    @staticmethod
    def _keep_controller(conn: Connection, campaign: str, model: Mapping[str, Any]) -> None:
        """The controller's model a campaign runs with, kept with the campaign and, when the robot
        is known by its serial, as that robot's latest (what `set_controller` keeps)."""
        c, r = tb.campaigns, tb.robots
        text = _dumps(model)
        conn.execute(c.update().where(c.c.id == campaign).values(controller=text))
        robot = conn.execute(select(c.c.robot).where(c.c.id == campaign)).scalar()
        if robot is not None:
            conn.execute(r.update().where(r.c.id == robot).values(controller=text))

    def find_resumable(self, config: Any = None, robot_serial: str | None = None, *,
                       config_sha256: str | None = None) -> str | None:
        """The newest unfinished campaign that measures what `config` would, or None.

        Unfinished means a status outside `FINISHED` (so a killed run, and one ended by a hardware
        fault, are resumable; an accepted, rejected or aborted one is not). "Measures what `config`
        would" is the `measurement_hash`: a changed tracker URL, robot address, timeout or store path
        resumes the campaign, its poses already measured reused (`hil.store.hashing.MEASUREMENT_IGNORED`
        says which keys and why). Give `robot_serial` whenever it is known: an end-of-line cell runs
        the same config on robot after robot, and resuming another arm's campaign would mix two
        robots' measurements. With a serial, only a campaign of that serial matches; without one,
        the robot address is what tells the arm, so it must match too. `config_sha256` instead of a
        config matches the exact configuration (`config_hash`).

        A campaign found here may be running in another process: `claim` it before resuming.
        """
        c, r = tb.campaigns, tb.robots
        if config_sha256 is not None:
            column, key, address = c.c.config_hash, config_sha256, None
        elif config is None:
            raise ValueError("find_resumable needs a config or a config hash")
        else:
            values = config.as_dict() if hasattr(config, "as_dict") else config
            column, key = c.c.measure_hash, measurement_hash(values)
            address = None if robot_serial else (values.get("robot") or {}).get("address")
        q = (select(c.c.id, c.c.config).select_from(c.outerjoin(r, r.c.id == c.c.robot))
             .where(column == key, c.c.status.not_in(sorted(FINISHED))))
        if robot_serial:
            q = q.where(r.c.serial == robot_serial)
        q = q.order_by(c.c.created.desc(), c.c.id.desc())
        for cid, stored in self._query(lambda conn: conn.execute(q).all()):
            if address is None or (json.loads(stored).get("robot") or {}).get("address") == address:
                return str(cid)
        return None

    # --- leases (hil.store.leases: one process per campaign, one campaign per robot) ----------------
    def claim(self, campaign: str, robot_serial: str = "", *, ttl: float = LEASE_TTL,
              heartbeat: bool = True) -> Lease:
        """Take the leases of `campaign` and of the robot `robot_serial` ("" = unknown: none) for this
        process, in one transaction, or raise LeaseRefused naming the live process that holds either.

        A lease whose holder is gone (killed, a power cut; `holder_gone`) is taken over: its campaign
        is resumable. InputError if the campaign is finished (accepted, rejected, aborted: nothing
        left to run), UnknownCampaignError if there is none. Release the lease when the run ends.
        """
        token = secrets.token_hex(16)

        def body(conn: Connection) -> tuple[str, ...]:
            c = tb.campaigns
            status = conn.execute(select(c.c.status).where(c.c.id == campaign)).scalar()
            if status is None:
                raise UnknownCampaignError(f"{self.location}: no campaign {campaign!r}")
            mine = self._mine(conn, token)
            if mine:
                return mine  # committed before the link dropped
            if status in FINISHED:
                raise InputError(f"campaign {campaign} is already {status}: there is nothing left to "
                                 "run (start a new one)")
            return self._take_leases(conn, campaign, robot_serial, token, time.time(), ttl,
                                     f"campaign {campaign}")

        names = self._write(f"claim campaign {campaign}", body)
        return Lease(self, campaign, token, names, ttl=ttl, heartbeat=heartbeat)

    def claim_new(self, config: Any, robot: RobotIdentity | Mapping[str, Any] | str | None = None,
                  plan: Mapping[str, Any] | None = None, *, ttl: float = LEASE_TTL,
                  heartbeat: bool = True) -> Lease:
        """`create_campaign` and `claim` in one transaction: a robot driven by another live campaign
        refuses (LeaseRefused) and leaves no empty campaign behind. ``lease.campaign`` is the new id."""
        token, now = secrets.token_hex(16), time.time()
        serial = RobotIdentity.coerce(robot).serial if robot is not None else ""
        cid = new_campaign_id(now)
        made: dict[str, str] = {}

        def body(conn: Connection) -> tuple[str, ...]:
            mine = self._mine(conn, token)
            if mine:
                return mine
            made["id"] = self._create(conn, config, robot, plan, now, cid)
            return self._take_leases(conn, made["id"], serial, token, now, ttl, "")

        names = self._write("create a campaign", body)
        return Lease(self, made["id"], token, names, ttl=ttl, heartbeat=heartbeat)

    @staticmethod
    def _mine(conn: Connection, token: str) -> tuple[str, ...]:
        """The lease rows carrying `token` (a claim whose COMMIT landed before the link dropped)."""
        le = tb.leases
        return tuple(sorted(conn.execute(select(le.c.name).where(le.c.token == token)).scalars(),
                            key=lambda n: not n.startswith("campaign:")))

    def check_claim(self, campaign: str | None, robot_serial: str = "", *,
                    ttl: float = LEASE_TTL) -> None:
        """Raise LeaseRefused if `claim` (`claim_new` when `campaign` is None) would be refused now:
        a UI asks before offering a resume or starting a run. Writes nothing."""
        now = time.time()
        le = tb.leases
        names = (([f"campaign:{campaign}"] if campaign else [])
                 + ([f"robot:{robot_serial}"] if robot_serial else []))
        for name in names:
            row = self._query(lambda conn, name=name: conn.execute(
                select(le.c.campaign, le.c.owner, le.c.since, le.c.heartbeat, le.c.token)
                .where(le.c.name == name)).first())
            if row is not None and not holder_gone(json.loads(row[1]), row[3], now, ttl, row[4]):
                raise LeaseRefused(self._refusal(name, campaign and f"campaign {campaign}", row[0],
                                                 json.loads(row[1]), row[2]))

    def _take_leases(self, conn: Connection, campaign: str, robot_serial: str, token: str,
                     now: float, ttl: float, mine: str) -> tuple[str, ...]:
        """Insert or take over (compare-and-set) each lease row, inside the caller's transaction;
        LeaseRefused (rolling the whole transaction back) at the first one a live process holds.
        `mine` names the campaign in that message ("" for a new one: its id is rolled back too)."""
        le = tb.leases
        owner = _dumps(this_process())
        names = (f"campaign:{campaign}",) + ((f"robot:{robot_serial}",) if robot_serial else ())
        for name in names:
            for _ in range(3):  # PostgreSQL (read committed): a row may vanish between two statements
                if conn.execute(_insert(conn, le).values(
                        name=name, campaign=campaign, owner=owner, token=token, since=now, heartbeat=now)
                        .on_conflict_do_nothing(index_elements=["name"])
                        .returning(le.c.name)).first() is not None:
                    break
                held = conn.execute(select(le.c.campaign, le.c.owner, le.c.token, le.c.since,
                                           le.c.heartbeat).where(le.c.name == name)).first()
                if held is None:
                    continue
                holder, held_owner, held_token, since, beat = held
                if not holder_gone(json.loads(held_owner), beat, now, ttl, held_token):
                    raise LeaseRefused(self._refusal(name, mine, holder, json.loads(held_owner), since))
                if conn.execute(  # the holder is gone: take it over, unless someone just did
                        le.update().where(le.c.name == name, le.c.token == held_token)
                        .values(campaign=campaign, owner=owner, token=token, since=now,
                                heartbeat=now)).rowcount == 1:
                    break
            else:
                raise LeaseRefused(f"{mine or 'a new campaign'}: {name} keeps changing hands; try again")
        return names

    @staticmethod
    def _refusal(name: str, mine: str, holder: str, owner: Any, since: float) -> str:
        """The one line a refused claim says: what is held, by which campaign and process, since when."""
        who = describe_holder(owner, since)
        if name.startswith("robot:"):
            return (f"robot {name[len('robot:'):]} is being driven by campaign {holder} ({who}): "
                    f"{mine or 'a new campaign'} cannot use it until that run ends")
        return (f"campaign {holder} is being run by {who}: wait for that run to end, or stop it "
                "(a campaign whose process has ended is resumed)")

    def renew_lease(self, lease: Lease) -> bool:
        """The heartbeat: True while every row of `lease` still carries its token. One try (no wait on
        a lost link: the next beat tries again)."""
        le = tb.leases
        with self.writing("renew a lease") as conn:
            count = conn.execute(le.update().where(le.c.token == lease.token)
                                 .values(heartbeat=time.time())).rowcount
        return count == len(lease.names)

    def release_lease(self, lease: Lease) -> None:
        """Give up `lease` (rows taken over meanwhile carry another token and stay)."""
        le = tb.leases
        with self.writing("release a lease") as conn:
            conn.execute(le.delete().where(le.c.token == lease.token))

    def leases(self) -> list[dict[str, Any]]:
        """Every lease row (name, campaign, owner, since, heartbeat): who holds what, for tests and UIs."""
        le = tb.leases
        rows = self._query(lambda conn: conn.execute(
            select(le.c.name, le.c.campaign, le.c.owner, le.c.since, le.c.heartbeat)
            .order_by(le.c.name)).all())
        return [{"name": n, "campaign": c, "owner": json.loads(o), "since": s, "heartbeat": h}
                for n, c, o, s, h in rows]

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
            poses = self._poses(conn, campaign)
            measurements = [_measurement(m) for m in conn.execute(
                select(*_MEASUREMENT_COLUMNS).where(_M.c.campaign == campaign).order_by(_M.c.id))]
            models = [ModelRecord(i, when, rms, json.loads(doc)) for i, when, rms, doc in conn.execute(
                select(tb.models.c.id, tb.models.c.created, tb.models.c.rms, tb.models.c.doc)
                .where(tb.models.c.campaign == campaign).order_by(tb.models.c.id))]
            validations = [
                ValidationRecord(i, when, m, json.loads(b), json.loads(a), bool(ok), _loads(d))
                for i, when, m, b, a, ok, d in conn.execute(
                    select(v.c.id, v.c.created, v.c.model, v.c.before, v.c.after, v.c.passed, v.c.details)
                    .where(v.c.campaign == campaign).order_by(v.c.id))]
            counts = {t: int(n) for t, n in conn.execute(
                select(e.c.type, func.count()).where(e.c.campaign == campaign).group_by(e.c.type)
                .order_by(func.min(e.c.seq)))}
        if summary.status == INTERRUPTED and not detail:  # read so: its process is gone (`_summary`)
            detail = "its process ended before the run did (killed, or the machine went down)"
        return CampaignRecord(
            summary=summary,
            robot=RobotIdentity(type=rtype, serial=serial or "", model=model or "", software=rsoft or ""),
            config=json.loads(config), config_hash=chash, plan=_loads(plan), detail=detail,
            result=_loads(result), software=software, poses=poses, measurements=measurements,
            models=models, validations=validations, event_counts=counts, controller=_loads(controller))

    # --- poses and measurements ---------------------------------------------------------------
    def save_plan(self, campaign: str,
                  poses: Iterable[PlannedPose | tuple[int, str, Sequence[float]]],
                  plan: Mapping[str, Any] | None = None) -> None:
        """Record the poses to visit (index, role, target q), and optionally the plan summary.

        May be called again (bootstrap poses first, the selected ones later; or a new selection):
        a pose still ``planned`` is replaced, one already measured or skipped must not change, as
        its measurement was taken at that target (StoreError).
        """
        rows = []
        for pose in poses:
            index, role, target = ((pose.index, pose.role, pose.target)
                                   if isinstance(pose, PlannedPose) else pose)
            if role not in ROLES:
                raise StoreError(f"pose {index}: role must be one of {', '.join(ROLES)}, got {role!r}")
            rows.append((int(index), role, _dumps(_vector(target, 6, f"pose {index} target"))))
        p = tb.poses

        def body(conn: Connection) -> None:
            self._require_campaign(conn, campaign)
            old = {i: (role, target, status) for i, role, target, status in conn.execute(
                select(p.c.idx, p.c.role, p.c.target, p.c.status).where(p.c.campaign == campaign))}
            new: dict[int, dict[str, Any]] = {}
            for index, role, target in rows:
                was = old.get(index)
                if was is None or index in new:
                    new[index] = {"campaign": campaign, "idx": index, "role": role, "target": target}
                elif was[2] == "planned":
                    if (was[0], was[1]) != (role, target):
                        conn.execute(p.update().where(p.c.campaign == campaign, p.c.idx == index)
                                     .values(role=role, target=target))
                elif (was[0], json.loads(was[1])) != (role, json.loads(target)):
                    raise StoreError(f"campaign {campaign}: pose {index} is already {was[2]}; "
                                     "its target and role cannot change")
            if new:
                conn.execute(p.insert(), list(new.values()))
            if plan is not None:
                conn.execute(tb.campaigns.update().where(tb.campaigns.c.id == campaign)
                             .values(plan=_dumps(plan)))
            self._touch(conn, campaign, time.time())

        self._write("save the plan", body)

    def _require_campaign(self, conn: Connection, campaign: str) -> None:
        """StoreError unless `campaign` exists; it also locks the campaign's row for the rest of the
        transaction (PostgreSQL; SQLite's BEGIN IMMEDIATE already serialises writers), so two writers of
        one campaign — threads of one process — number its events one after the other."""
        if conn.execute(select(tb.campaigns.c.id).where(tb.campaigns.c.id == campaign)
                        .with_for_update()).first() is None:
            raise StoreError(f"{self.location}: no campaign {campaign!r}")

    def record_measurement(self, campaign: str, index: int, role: str, q: Sequence[float],
                           p: Sequence[float], *, q_spread: Sequence[float] | None = None,
                           p_spread: Sequence[float] | None = None, samples: int = 1,
                           deviation: float | None = None, t: float | None = None,
                           tracker_samples: Sequence[Sequence[float]] | None = None,
                           joint_samples: Sequence[Sequence[float]] | None = None) -> int:
        """Record one measured point and return its id; committed (and synced) before returning.

        The pose is marked measured (and created if it was not planned). Raw tracker points
        (n×3) and joint readings (n×6), when given, are kept with it. Recording the same
        (campaign, index, t) again stores nothing and returns the existing id.
        """
        when = time.time() if t is None else t
        return self._write(f"record the measurement of pose {index}", lambda conn: self._insert_measurement(
            conn, campaign, index, role, q, p, q_spread, p_spread, samples, deviation, when,
            tracker_samples, joint_samples))

    def _insert_measurement(self, conn: Connection, campaign: str, index: int, role: str,
                            q: Any, p: Any, q_spread: Any, p_spread: Any, samples: int,
                            deviation: float | None, t: float, tracker_samples: Any,
                            joint_samples: Any) -> int:
        if role not in ROLES:
            raise StoreError(f"pose {index}: role must be one of {', '.join(ROLES)}, got {role!r}")
        qv = _vector(q, 6, f"pose {index} q")
        self._require_campaign(conn, campaign)
        row = conn.execute(_insert(conn, _M).values(
            campaign=campaign, pose=int(index), role=role, q=_dumps(qv),
            q_spread=_dumps_or_null(_optional_vector(q_spread, 6, "q_spread")),
            p=_dumps(_vector(p, 3, f"pose {index} p")),
            p_spread=_dumps_or_null(_optional_vector(p_spread, 3, "p_spread")),
            samples=int(samples), deviation=_finite_or_none(deviation), t=float(t))
            .on_conflict_do_nothing(index_elements=["campaign", "pose", "t"])
            .returning(_M.c.id)).first()
        if row is None:  # already recorded (the direct call and then its event)
            return int(conn.execute(select(_M.c.id).where(
                _M.c.campaign == campaign, _M.c.pose == int(index), _M.c.t == float(t))).scalar_one())
        mid = int(row[0])
        for kind, values, n in (("tracker", tracker_samples, 3), ("joints", joint_samples, 6)):
            if values is not None and len(values):
                conn.execute(tb.samples.insert(), [
                    {"measurement": mid, "kind": kind, "k": k,
                     "value": _dumps(_vector(v, n, f"{kind} sample {k}"))} for k, v in enumerate(values)])
        stmt = _insert(conn, tb.poses).values(campaign=campaign, idx=int(index), role=role,
                                             target=_dumps(qv), status="measured")
        conn.execute(stmt.on_conflict_do_update(index_elements=["campaign", "idx"],
                                                set_={"status": "measured", "reason": ""}))
        self._touch(conn, campaign, float(t))
        return mid

    def record_skip(self, campaign: str, index: int, role: str, reason: str) -> None:
        """Mark a pose skipped (unreachable, no line of sight...), so a resume does not retry it."""
        now = time.time()
        self._write(f"record the skip of pose {index}",
                    lambda conn: self._skip(conn, campaign, index, role, reason, now))

    def _skip(self, conn: Connection, campaign: str, index: int, role: str, reason: str,
              now: float) -> None:
        p = tb.poses
        self._require_campaign(conn, campaign)
        count = conn.execute(p.update().where(p.c.campaign == campaign, p.c.idx == int(index),
                                              p.c.status != "measured")
                             .values(status="skipped", reason=reason)).rowcount
        if count == 0 and conn.execute(select(p.c.idx).where(
                p.c.campaign == campaign, p.c.idx == int(index))).first() is None:
            raise StoreError(f"campaign {campaign}: cannot skip pose {index}: it is not in the plan")
        self._touch(conn, campaign, now)

    @staticmethod
    def _poses(conn: Connection, campaign: str, statuses: Sequence[str] | None = None) -> list[PlannedPose]:
        p = tb.poses
        q = select(p.c.idx, p.c.role, p.c.target, p.c.status, p.c.reason).where(p.c.campaign == campaign)
        if statuses is not None:
            q = q.where(p.c.status.in_(statuses))
        return [PlannedPose(i, role, tuple(json.loads(target)), status, reason)
                for i, role, target, status, reason in conn.execute(q.order_by(p.c.idx))]

    def poses(self, campaign: str) -> list[PlannedPose]:
        """Every pose of the plan, by index."""
        return self._query(lambda conn: self._poses(conn, campaign))

    def pending_poses(self, campaign: str, *, include_skipped: bool = False) -> list[PlannedPose]:
        """Poses still to measure, in plan order: what a resumed run visits."""
        statuses = ("planned", "skipped") if include_skipped else ("planned",)
        return self._query(lambda conn: self._poses(conn, campaign, statuses))

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
            out[kind].append(tuple(json.loads(value)))
        return out

    # --- models and validation ----------------------------------------------------------------
    def save_model(self, campaign: str, doc: Mapping[str, Any]) -> int:
        """Keep a ``hil-model/1`` document; returns its id (the same id for the same document)."""
        now = time.time()
        return self._write("save the model", lambda conn: self._insert_model(conn, campaign, doc, now))

    def _insert_model(self, conn: Connection, campaign: str, doc: Mapping[str, Any], now: float) -> int:
        m = tb.models
        self._require_campaign(conn, campaign)
        text, sha = _dumps(doc), _sha(json.loads(_dumps(doc)))
        fit = doc.get("fit") if isinstance(doc.get("fit"), Mapping) else {}
        row = conn.execute(_insert(conn, m).values(campaign=campaign, doc=text, sha256=sha,
                                                   rms=_finite_or_none(fit.get("rms")), created=now)
                           .on_conflict_do_nothing(index_elements=["campaign", "sha256"])
                           .returning(m.c.id)).first()
        self._touch(conn, campaign, now)
        if row is None:
            return int(conn.execute(select(m.c.id).where(m.c.campaign == campaign,
                                                         m.c.sha256 == sha)).scalar_one())
        return int(row[0])

    def model(self, campaign: str) -> dict[str, Any] | None:
        """The campaign's latest model document, or None if it has none yet."""
        m = tb.models
        doc = self._query(lambda conn: conn.execute(
            select(m.c.doc).where(m.c.campaign == campaign).order_by(m.c.id.desc()).limit(1)).scalar())
        return None if doc is None else dict(json.loads(doc))

    def save_validation(self, campaign: str, before: Mapping[str, Any], after: Mapping[str, Any],
                        passed: bool, *, model: int | None = None,
                        details: Mapping[str, Any] | None = None) -> int:
        """Keep a validation result (error stats of the nominal and the calibrated model on
        held-out poses: count, mean, rms, max; `details` for ISO 9283 AP/RP and the like).
        `model` defaults to the campaign's latest model. Returns its id (same result, same id)."""
        now = time.time()
        return self._write("save the validation", lambda conn: self._insert_validation(
            conn, campaign, before, after, passed, model, details, now))

    def _insert_validation(self, conn: Connection, campaign: str, before: Mapping[str, Any],
                           after: Mapping[str, Any], passed: bool, model: int | None,
                           details: Mapping[str, Any] | None, now: float) -> int:
        v = tb.validations
        self._require_campaign(conn, campaign)
        if model is None:
            model = conn.execute(select(func.max(tb.models.c.id))
                                 .where(tb.models.c.campaign == campaign)).scalar()
        body = {"before": before, "after": after, "passed": bool(passed), "details": details,
                "model": model}
        sha = _sha(json.loads(_dumps(body)))
        row = conn.execute(_insert(conn, v).values(
            campaign=campaign, model=model, before=_dumps(before), after=_dumps(after),
            passed=int(bool(passed)), rms=_finite_or_none(after.get("rms")),
            details=_dumps_or_null(details), sha256=sha, created=now)
            .on_conflict_do_nothing(index_elements=["campaign", "sha256"]).returning(v.c.id)).first()
        self._touch(conn, campaign, now)
        if row is None:
            return int(conn.execute(select(v.c.id).where(v.c.campaign == campaign,
                                                         v.c.sha256 == sha)).scalar_one())
        return int(row[0])

    # --- events -------------------------------------------------------------------------------
    def record_event(self, event: Event) -> int:
        """Append `event` to its campaign's log and apply what it implies, in one transaction;
        returns the event's sequence number. Raises StoreError on any failure (critical).

        A `RunStarted` is logged with an ``owner`` key added (`hil.store.owner.this_process`): the
        process recording a run's start is the one running it, and readers use it to tell a live run
        from one whose process died (`campaigns` then says ``interrupted``)."""
        data = event.to_dict()
        if isinstance(event, RunStarted):
            data["owner"] = this_process()
        uid = secrets.token_hex(12)
        e = tb.events

        def body(conn: Connection) -> int:
            self._require_campaign(conn, event.campaign)
            done = conn.execute(select(e.c.seq).where(e.c.uid == uid)).scalar()
            if done is not None:  # this very event, committed before the link dropped
                return int(done)
            seq = conn.execute(select(func.coalesce(func.max(e.c.seq), 0) + 1)
                               .where(e.c.campaign == event.campaign)).scalar_one()
            conn.execute(e.insert().values(campaign=event.campaign, seq=seq, t=float(event.t),
                                           type=event.name, data=_dumps(data), uid=uid))
            self._apply(conn, event)
            self._touch(conn, event.campaign, float(event.t))
            return int(seq)

        return self._write(f"record {event.name}", body)

    def as_subscriber(self) -> Callable[[Event], None]:
        """The callable to subscribe (critical) to the EventBus."""
        return self.record_event

    subscriber = record_event

    def _apply(self, conn: Connection, ev: Event) -> None:
        cid, t = ev.campaign, float(ev.t)
        if isinstance(ev, RunStarted):  # a new run: the last one's detail (e.g. why it stopped) is old
            self._set_status(conn, cid, "running", "", None, t)
        elif isinstance(ev, StateChanged) and ev.state in _LIVE_STATES:
            self._set_status(conn, cid, ev.state, None, None, t)
        elif isinstance(ev, PoseStarted) and ev.role in ROLES:
            conn.execute(_insert(conn, tb.poses).values(
                campaign=cid, idx=int(ev.index), role=ev.role,
                target=_dumps(_vector(ev.target, 6, "target")))
                .on_conflict_do_nothing(index_elements=["campaign", "idx"]))
        elif isinstance(ev, PointMeasured):
            self._insert_measurement(conn, cid, ev.index, ev.role, ev.q, ev.p,
                                     self._reached_spread(conn, cid, ev.index), ev.p_spread,
                                     ev.samples, ev.deviation, t, None, None)
        elif isinstance(ev, PoseSkipped):
            self._skip(conn, cid, ev.index, ev.role, ev.reason, t)
        elif isinstance(ev, ModelIdentified) and ev.model:
            self._insert_model(conn, cid, ev.model, t)
        elif isinstance(ev, ValidationDone):
            details = {"controller": ev.controller} if ev.controller else None
            self._insert_validation(conn, cid, ev.before, ev.after, ev.passed, None, details, t)
        elif isinstance(ev, ControllerModel):
            self._keep_controller(conn, cid, ev.model)
        elif isinstance(ev, RunFinished):
            self._set_status(conn, cid, ev.status, ev.detail, ev.result or None, t)

    @staticmethod
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
        return [(seq, json.loads(data)) for seq, data in rows]

    def events(self, campaign: str, *, after: int = 0, types: Sequence[str] | None = None) -> list[Event]:
        """The log as Event objects (types this version does not know are left out)."""
        return [Event.from_dict(d) for _, d in self.event_log(campaign, after=after, types=types)
                if d.get("event") in Event.registry]


def _first_line(exc: BaseException | None) -> str:
    """A driver's message on one line (psycopg's carry a DETAIL and a HINT on lines of their own)."""
    text = str(exc) if exc is not None else "unknown error"
    return " ".join(text.split()) if "\n" not in text.strip() else text.strip().splitlines()[0].strip()

