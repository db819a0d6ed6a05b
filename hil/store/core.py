"""The `Store`: campaigns, poses, measurements, models, validations and events in one SQLite file.

Durability. The database runs in WAL mode with ``synchronous=FULL``: every write method is one
transaction, committed (and the WAL fsynced) before it returns. ``NORMAL`` would already survive
``kill -9`` (the WAL write reaches the OS before COMMIT returns) but could lose the last commits on
a power cut or kernel crash, which on a shop floor is not hypothetical. FULL costs one fsync per
commit, a few milliseconds against the seconds a pose takes to reach and measure, so the stronger
promise is nearly free. ``synchronous="NORMAL"`` is accepted for fast-time simulations.

Threads. A `Store` may be shared: each thread gets its own connection on first use (SQLite
connections must not be used by two threads at once), WAL lets readers (the TUI) run while the
engine writes, and writers — threads or other processes — queue on SQLite's lock for up to
``timeout`` seconds (the busy timeout). `close` closes every connection; call it when the other
threads are done with the store.

Recording. The engine subscribes `record_event` (via `as_subscriber`) as a *critical* subscriber:
each event is appended to the log and its derived rows (a PointMeasured's measurement, a
RunFinished's status, ...) are written in the same transaction, and any failure raises `StoreError`,
which stops the run rather than let it measure what it cannot keep. The direct methods
(`record_measurement`, `save_model`, `save_validation`) are idempotent with the event path: a
measurement is keyed by (campaign, pose, t), models and validations by their content hash, so
recording a measurement with its raw samples and then emitting the PointMeasured with the same
``t`` stores it once.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
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
from typing import Any

import numpy as np

from hil import __version__
from hil.campaign.events import (
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
from hil.errors import HilError, InputError
from hil.store.leases import LEASE_TTL, Lease, LeaseRefused, describe_holder, holder_gone
from hil.store.owner import is_gone, this_process
from hil.store.paths import resolve_path
from hil.store.records import (
    FINISHED,
    INTERRUPTED,
    ROLES,
    CampaignRecord,
    CampaignSummary,
    Measurement,
    ModelRecord,
    PlannedPose,
    RobotInfo,
    ValidationRecord,
)
from hil.store.schema import SCHEMA_VERSION, canonical_json, config_hash, measurement_hash, migrate

# Engine states that are also campaign statuses (the final status comes from RunFinished).
_LIVE_STATES = frozenset({"running", "paused", "suspended", "stopping"})


class StoreError(HilError):
    """The store could not record or read something (disk full, locked too long, unknown campaign)."""


class UnknownCampaignError(InputError):
    """No campaign with that id (or id prefix) in this database."""


class CorruptStoreError(StoreError, InputError):
    """The database file is damaged (garbage written into it, a torn copy): SQLite says "database disk
    image is malformed" only when a query reaches the damaged page, long after the file opened.

    Bad input naming the file (exit 2, ``k.db is not a readable hil store: ...``), not an internal
    error; still a `StoreError`, so a run that meets it mid-campaign stops as for any store failure.
    """


# SQLite's primary result codes for a damaged file: SQLITE_CORRUPT (11), SQLITE_NOTADB (26).
_DAMAGED = frozenset({11, 26})


def _damaged(exc: sqlite3.DatabaseError, conn: sqlite3.Connection) -> BaseException:
    """`exc` as a `CorruptStoreError` naming the file when it says the file is damaged, else itself."""
    code = getattr(exc, "sqlite_errorcode", None)
    if code is None or code & 0xFF not in _DAMAGED:
        return exc
    where = getattr(conn, "where", "the database")
    if code & 0xFF == 26:  # SQLITE_NOTADB: not SQLite at all (a text file, an image)
        return CorruptStoreError(f"{where}: not a hil database ({exc})")
    return CorruptStoreError(f"{where} is not a readable hil store: {exc}")


def _check_intact(conn: sqlite3.Connection) -> None:
    """CorruptStoreError unless SQLite's quick check finds every page sound. A writer runs it once, at
    open: a damaged page is otherwise met only by the query that reads it, which for ``hil calibrate``
    can be after it connected to the arm, or mid-campaign. It reads the file once (milliseconds for
    the megabytes a station's store holds)."""
    problems = [row[0] for row in conn.execute("PRAGMA quick_check(1)")]
    if problems != ["ok"]:
        where = getattr(conn, "where", "the database")
        # "*** in database main ***\nPage 16: btreeInitPage() returns error code 11": one line
        detail = " ".join(" ".join(problems).replace("*** in database main ***", "").split())
        raise CorruptStoreError(f"{where} is not a readable hil store: database disk image is malformed "
                                f"({detail[:200]})")


class _Cursor(sqlite3.Cursor):
    """A cursor whose damaged-file errors name the file (`CorruptStoreError`): every query and every
    fetch, since a row on a damaged page fails only when it is read."""

    def execute(self, *args: Any) -> _Cursor:
        try:
            return super().execute(*args)
        except sqlite3.DatabaseError as exc:
            raise _damaged(exc, self.connection) from None

    def executemany(self, *args: Any) -> _Cursor:
        try:
            return super().executemany(*args)
        except sqlite3.DatabaseError as exc:
            raise _damaged(exc, self.connection) from None

    def __next__(self) -> Any:
        try:
            return super().__next__()
        except sqlite3.DatabaseError as exc:
            raise _damaged(exc, self.connection) from None

    def fetchone(self) -> Any:
        try:
            return super().fetchone()
        except sqlite3.DatabaseError as exc:
            raise _damaged(exc, self.connection) from None

    def fetchmany(self, *args: Any) -> list[Any]:
        try:
            return super().fetchmany(*args)
        except sqlite3.DatabaseError as exc:
            raise _damaged(exc, self.connection) from None

    def fetchall(self) -> list[Any]:
        try:
            return super().fetchall()
        except sqlite3.DatabaseError as exc:
            raise _damaged(exc, self.connection) from None


class _Connection(sqlite3.Connection):
    """The store's connections: their queries go through `_Cursor` (``Connection.execute`` would
    bypass ``cursor()``); `where` is the file the errors name."""

    where = "the database"

    def cursor(self, factory: Any = _Cursor) -> Any:  # type: ignore[override]
        return super().cursor(factory)

    def execute(self, *args: Any) -> Any:  # type: ignore[override]
        return self.cursor().execute(*args)

    def executemany(self, *args: Any) -> Any:  # type: ignore[override]
        return self.cursor().executemany(*args)


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


def new_campaign_id(now: float | None = None) -> str:
    """``YYYYMMDD-HHMMSS-xxxx`` (local time, 16 random bits): sorts by date, reads aloud, unique
    enough that a collision (retried anyway) needs two campaigns started in the same second."""
    stamp = time.strftime("%Y%m%d-%H%M%S", time.localtime(time.time() if now is None else now))
    return f"{stamp}-{secrets.token_hex(2)}"


_MEASUREMENT_COLUMNS = "id, campaign, pose, role, q, p, q_spread, p_spread, samples, deviation, t"


def _measurement(row: Sequence[Any]) -> Measurement:
    mid, cid, pose, role, q, p, qs, ps, samples, deviation, t = row
    return Measurement(id=mid, campaign=cid, index=pose, role=role, q=tuple(json.loads(q)),
                       p=tuple(json.loads(p)), q_spread=_tuple(qs), p_spread=_tuple(ps),
                       samples=samples, deviation=deviation, t=t)


# planned / measured / skipped count the campaign's calibration and validation poses: the count the
# progress bar, the Run screen and the history share (the bootstrap's points only locate the tracker).
_SUMMARY_SQL = """
SELECT c.id, c.created, c.updated, s.name, c.robot_type, COALESCE(r.serial, ''), c.status,
       (SELECT count(*) FROM poses WHERE campaign = c.id AND role != 'bootstrap'),
       (SELECT count(*) FROM poses WHERE campaign = c.id AND role != 'bootstrap' AND status = 'measured'),
       (SELECT count(*) FROM poses WHERE campaign = c.id AND role != 'bootstrap' AND status = 'skipped'),
       (SELECT rms FROM models WHERE campaign = c.id ORDER BY id DESC LIMIT 1),
       (SELECT rms FROM validations WHERE campaign = c.id ORDER BY id DESC LIMIT 1),
       (SELECT passed FROM validations WHERE campaign = c.id ORDER BY id DESC LIMIT 1),
       CASE WHEN c.status IN ({live}) THEN (SELECT data FROM events WHERE campaign = c.id
                                            AND type = 'RunStarted' ORDER BY seq DESC LIMIT 1) END
FROM campaigns c JOIN stations s ON s.id = c.station LEFT JOIN robots r ON r.id = c.robot
""".format(live=", ".join(f"'{s}'" for s in sorted(_LIVE_STATES)))


def _summary(row: Sequence[Any]) -> CampaignSummary:
    """A summary row; a live status whose run's process is gone (kill -9, power cut) reads as
    ``interrupted``, which it is: resumable (the file itself is left as it is — a reader never writes)."""
    *head, passed, started = row
    summary = CampaignSummary(*head, passed=None if passed is None else bool(passed))
    if started is not None and is_gone(json.loads(started).get("owner")):
        summary = dataclasses.replace(summary, status=INTERRUPTED)
    return summary


class Store:
    """A hil database. ``Store(path)`` does no I/O; `connect` (or ``with``, or `Store.open`) does.

    Typical use::

        with Store.open(config=cfg) as store:
            cid = store.find_resumable(cfg, robot.serial) or store.create_campaign(cfg, robot, plan)
            bus.subscribe(store.as_subscriber(), critical=True)
    """

    def __init__(self, path: str | os.PathLike[str], *, create: bool = True,
                 synchronous: str = "FULL", timeout: float = 10.0, readonly: bool = False) -> None:
        if synchronous.upper() not in ("FULL", "NORMAL", "EXTRA"):
            raise ValueError(f"synchronous must be FULL, NORMAL or EXTRA, got {synchronous!r}")
        self.path = Path(path)
        self.create = create and not readonly
        self.readonly = readonly
        self.synchronous = synchronous.upper()
        self.timeout = timeout
        self._local = threading.local()
        self._lock = threading.Lock()
        self._connections: dict[threading.Thread, sqlite3.Connection] = {}
        self._ready = False
        self._closed = False

    def __repr__(self) -> str:
        return f"Store({str(self.path)!r})"

    # --- opening and closing ------------------------------------------------------------------
    @classmethod
    def open(cls, path: str | os.PathLike[str] | None = None, *, config: Any = None,
             create: bool = True, synchronous: str = "FULL", timeout: float = 10.0,
             readonly: bool = False) -> Store:
        """Open (creating or upgrading as needed) the database at `path`, or where `resolve_path`
        says from `config` and the environment. InputError if it is missing (with
        ``create=False`` or ``readonly=True``), empty (``readonly``), not a database, not a hil
        store, or newer than this code.

        ``readonly=True`` is for the commands that only read (history, show): they must work on a
        store they cannot write (read-only media, another user's station folder) and must never
        create or change a file — so no WAL switch, no schema upgrade (`_readonly_uri`)."""
        store = cls(resolve_path(path, config), create=create, synchronous=synchronous,
                    timeout=timeout, readonly=readonly)
        return store.connect()

    def connect(self) -> Store:
        """Open this thread's connection, upgrading the schema on the first call. Idempotent."""
        self._conn()
        return self

    def __enter__(self) -> Store:
        return self.connect()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        """Close every thread's connection. Further use raises StoreError."""
        with self._lock:
            self._closed = True
            conns, self._connections = list(self._connections.values()), {}
        for conn in conns:
            conn.close()
        self._local = threading.local()

    def _new_connection(self) -> sqlite3.Connection:
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
        try:
            # check_same_thread=False only so close() can close it from another thread; each
            # connection is still used by the one thread that created it.
            conn = sqlite3.connect(self._readonly_uri() if self.readonly else self.path,
                                   timeout=self.timeout, isolation_level=None,
                                   check_same_thread=False, uri=self.readonly, factory=_Connection)
        except sqlite3.Error as exc:
            raise InputError(f"{where}: cannot open: {exc}") from None
        conn.where = where  # what a damaged page, met later by any query, names (`CorruptStoreError`)
        try:
            conn.execute(f"PRAGMA busy_timeout = {int(self.timeout * 1000)}")
            if self.readonly:
                self._check_readable(conn, where)
                return conn
            mode = conn.execute("PRAGMA journal_mode = WAL").fetchone()[0]
            if str(mode).lower() != "wal":
                raise InputError(f"{where}: cannot use WAL journal mode (got {mode}); "
                                 "put the database on a local file system")
            conn.execute(f"PRAGMA synchronous = {self.synchronous}")
            conn.execute("PRAGMA foreign_keys = ON")
            if not self._ready:
                migrate(conn, where)
                _check_intact(conn)
        except sqlite3.DatabaseError as exc:
            conn.close()
            text = str(exc)
            if "locked" in text or "busy" in text:
                raise StoreError(f"{where}: {text}") from None
            if "not a database" in text or "malformed" in text:
                raise InputError(f"{where}: not a hil database ({text})") from None
            raise InputError(f"{where}: cannot open: {text}") from None
        except BaseException:
            conn.close()
            raise
        return conn

    def _readonly_uri(self) -> str:
        """The ``file:`` URI of a reading connection (never one that creates the file).

        A WAL database needs its ``-wal`` and ``-shm`` files beside it. Where the reader may write
        them (``mode=rw``, with ``query_only`` set by `_check_readable`), SQLite removes them again
        at close, leaving the folder as it was; ``mode=ro`` would leave them behind. In a directory
        we cannot write (read-only media, another user's folder) even ``mode=ro`` fails ("attempt
        to write a readonly database"): there, unless a ``-wal`` holds commits not yet folded into
        the file (hil closes cleanly, folding them in), ``immutable=1`` reads the file alone; with
        such a ``-wal`` it would hide them, so ``mode=ro`` reads through the existing files.
        """
        path = self.path.resolve()
        wal = path.with_name(path.name + "-wal")
        if os.access(path.parent, os.W_OK):
            query = "mode=rw" if os.access(path, os.W_OK) else "mode=ro"
        elif wal.exists() and wal.stat().st_size > 0:
            query = "mode=ro"
        else:
            query = "mode=ro&immutable=1"
        return f"file:{urllib.parse.quote(str(path))}?{query}"

    def _check_readable(self, conn: sqlite3.Connection, where: str) -> None:
        """What `migrate` checks, without writing: a hil store of a version this code reads.

        An older store is upgraded once, as any command did before readers opened read-only, when
        it can be written; on read-only media a reader says so rather than fail on a missing column
        later."""
        conn.execute("PRAGMA query_only = ON")
        found = conn.execute("PRAGMA user_version").fetchone()[0]
        if found > SCHEMA_VERSION:
            raise InputError(f"{where}: database schema version {found} is newer than this hil "
                             f"supports ({SCHEMA_VERSION}); upgrade hil to read it")
        if found == 0:
            raise InputError(f"{where}: an SQLite database, but not a hil store")
        if found < SCHEMA_VERSION and os.access(self.path, os.W_OK) and os.access(
                self.path.resolve().parent, os.W_OK):
            Store(self.path, create=False, timeout=self.timeout).connect().close()  # migrates
            found = conn.execute("PRAGMA user_version").fetchone()[0]
        if found < SCHEMA_VERSION:
            raise InputError(f"{where}: database schema version {found} is older than this hil's "
                             f"({SCHEMA_VERSION}) and the file is read-only: copy it somewhere "
                             "writable to upgrade it")

    def _conn(self) -> sqlite3.Connection:
        conn: sqlite3.Connection | None = getattr(self._local, "conn", None)
        if conn is not None:
            return conn
        with self._lock:
            if self._closed:
                raise StoreError(f"{self.path}: the store is closed")
            conn = self._new_connection()
            self._ready = True
            me = threading.current_thread()
            # Connections of threads that have ended are closed here rather than leaked.
            for thread in [t for t in self._connections if not t.is_alive()]:
                self._connections.pop(thread).close()
            self._connections[me] = conn
        self._local.conn = conn
        return conn

    @contextmanager
    def _write(self, what: str) -> Iterator[sqlite3.Connection]:
        """One write transaction, committed on exit; any SQLite failure becomes a StoreError."""
        conn = self._conn()
        try:
            # BEGIN inside the try: a Ctrl-C landing just after it must not leave the transaction open
            # (the run records its end on this connection next)
            try:
                conn.execute("BEGIN IMMEDIATE")
                yield conn
                conn.execute("COMMIT")
            except BaseException:
                if conn.in_transaction:  # the body failed, COMMIT did (busy, I/O), or an interrupt
                    conn.execute("ROLLBACK")
                raise
        except sqlite3.Error as exc:
            raise StoreError(f"{self.path}: cannot {what}: {exc}") from exc

    @contextmanager
    def _read(self) -> Iterator[sqlite3.Connection]:
        """A read transaction: the queries inside see one consistent snapshot."""
        conn = self._conn()
        try:
            conn.execute("BEGIN")
            yield conn
        finally:
            if conn.in_transaction:
                conn.execute("COMMIT")

    # --- campaigns ----------------------------------------------------------------------------
    def create_campaign(self, config: Any, robot: RobotInfo | Mapping[str, Any] | str | None = None,
                        plan: Mapping[str, Any] | None = None, *, now: float | None = None) -> str:
        """Start a campaign record (status ``created``) and return its id.

        `config` is a StationConfig or its ``as_dict()``; it is stored whole (the campaign must be
        reproducible from the database alone) with its `config_hash`, and the `measurement_hash`
        `find_resumable` matches.
        `robot` defaults to the config's robot type with an unknown serial.
        """
        now = time.time() if now is None else now
        with self._write("create a campaign") as conn:
            return self._create(conn, config, robot, plan, now)

    def _create(self, conn: sqlite3.Connection, config: Any,
                robot: RobotInfo | Mapping[str, Any] | str | None, plan: Mapping[str, Any] | None,
                now: float) -> str:
        values = config.as_dict() if hasattr(config, "as_dict") else dict(config)
        station = str((values.get("station") or {}).get("name") or "station")
        info = RobotInfo.coerce(robot if robot is not None
                                else str((values.get("robot") or {}).get("type") or ""))
        conn.execute("INSERT INTO stations (name, created) VALUES (?, ?) "
                     "ON CONFLICT (name) DO NOTHING", (station, now))
        station_id = conn.execute("SELECT id FROM stations WHERE name = ?", (station,)).fetchone()[0]
        robot_id = None
        if info.serial:
            conn.execute(
                "INSERT INTO robots (serial, type, model, software, first_seen, last_seen) "
                "VALUES (?, ?, ?, ?, ?, ?) ON CONFLICT (serial) DO UPDATE SET type = excluded.type, "
                "model = excluded.model, software = excluded.software, last_seen = excluded.last_seen",
                (info.serial, info.type, info.model, info.software, now, now))
            robot_id = conn.execute("SELECT id FROM robots WHERE serial = ?",
                                    (info.serial,)).fetchone()[0]
        for _ in range(20):
            cid = new_campaign_id(now)
            if conn.execute("SELECT 1 FROM campaigns WHERE id = ?", (cid,)).fetchone() is None:
                break
        conn.execute(
            "INSERT INTO campaigns (id, station, robot, robot_type, config, config_hash, "
            "measure_hash, plan, status, software, created, updated) "
            "VALUES (?, ?, ?, ?, ?, ?, ?, ?, 'created', ?, ?, ?)",
            (cid, station_id, robot_id, info.type, _dumps(values), config_hash(values),
             measurement_hash(values), _dumps_or_null(plan), __version__, now, now))
        return cid

    def set_status(self, campaign: str, status: str, detail: str | None = None,
                   result: Mapping[str, Any] | None = None) -> None:
        """Set a campaign's status (and optionally its detail text and result JSON)."""
        with self._write("set the status") as conn:
            self._set_status(conn, campaign, status, detail, result, time.time())

    def _set_status(self, conn: sqlite3.Connection, campaign: str, status: str, detail: str | None,
                    result: Mapping[str, Any] | None, now: float) -> None:
        cur = conn.execute(
            "UPDATE campaigns SET status = ?, detail = COALESCE(?, detail), "
            "result = COALESCE(?, result), updated = ? WHERE id = ?",
            (status, detail, _dumps_or_null(result), now, campaign))
        if cur.rowcount == 0:
            raise StoreError(f"{self.path}: no campaign {campaign!r}")

    def _touch(self, conn: sqlite3.Connection, campaign: str, now: float) -> None:
        conn.execute("UPDATE campaigns SET updated = max(updated, ?) WHERE id = ?", (now, campaign))

    def find_resumable(self, config: Any = None, robot_serial: str | None = None, *,
                       config_sha256: str | None = None) -> str | None:
        """The newest unfinished campaign that measures what `config` would, or None.

        Unfinished means a status outside `FINISHED` (so a killed run, and one ended by a hardware
        fault, are resumable; an accepted, rejected or aborted one is not). "Measures what `config`
        would" is the `measurement_hash`: a changed tracker URL, robot address, timeout or store path
        resumes the campaign, its poses already measured reused (`hil.store.schema.MEASUREMENT_IGNORED`
        says which keys and why). Give `robot_serial` whenever it is known: an end-of-line cell runs
        the same config on robot after robot, and resuming another arm's campaign would mix two
        robots' measurements. With a serial, only a campaign of that serial matches; without one,
        the robot address is what tells the arm, so it must match too. `config_sha256` instead of a
        config matches the exact configuration (`config_hash`).

        A campaign found here may be running in another process: `claim` it before resuming.
        """
        finished = sorted(FINISHED)
        if config_sha256 is not None:
            column, key, address = "c.config_hash", config_sha256, None
        elif config is None:
            raise ValueError("find_resumable needs a config or a config hash")
        else:
            values = config.as_dict() if hasattr(config, "as_dict") else config
            column, key = "c.measure_hash", measurement_hash(values)
            address = None if robot_serial else (values.get("robot") or {}).get("address")
        sql = (f"SELECT c.id, c.config FROM campaigns c LEFT JOIN robots r ON r.id = c.robot "
               f"WHERE {column} = ? AND c.status NOT IN ({', '.join('?' * len(finished))})")
        params: list[Any] = [key, *finished]
        if robot_serial:
            sql += " AND r.serial = ?"
            params.append(robot_serial)
        sql += " ORDER BY c.created DESC, c.rowid DESC"
        for cid, stored in self._conn().execute(sql, params):
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
        with self._write(f"claim campaign {campaign}") as conn:
            row = conn.execute("SELECT status FROM campaigns WHERE id = ?", (campaign,)).fetchone()
            if row is None:
                raise UnknownCampaignError(f"{self.path}: no campaign {campaign!r}")
            if row[0] in FINISHED:
                raise InputError(f"campaign {campaign} is already {row[0]}: there is nothing left to "
                                 "run (start a new one)")
            names = self._take_leases(conn, campaign, robot_serial, token, time.time(), ttl,
                                      f"campaign {campaign}")
        return Lease(self, campaign, token, names, ttl=ttl, heartbeat=heartbeat)

    def claim_new(self, config: Any, robot: RobotInfo | Mapping[str, Any] | str | None = None,
                  plan: Mapping[str, Any] | None = None, *, ttl: float = LEASE_TTL,
                  heartbeat: bool = True) -> Lease:
        """`create_campaign` and `claim` in one transaction: a robot driven by another live campaign
        refuses (LeaseRefused) and leaves no empty campaign behind. ``lease.campaign`` is the new id."""
        token, now = secrets.token_hex(16), time.time()
        serial = RobotInfo.coerce(robot).serial if robot is not None else ""
        with self._write("create a campaign") as conn:
            campaign = self._create(conn, config, robot, plan, now)
            names = self._take_leases(conn, campaign, serial, token, now, ttl, "")
        return Lease(self, campaign, token, names, ttl=ttl, heartbeat=heartbeat)

    def check_claim(self, campaign: str | None, robot_serial: str = "", *,
                    ttl: float = LEASE_TTL) -> None:
        """Raise LeaseRefused if `claim` (`claim_new` when `campaign` is None) would be refused now:
        a UI asks before offering a resume or starting a run. Writes nothing."""
        now = time.time()
        names = (([f"campaign:{campaign}"] if campaign else [])
                 + ([f"robot:{robot_serial}"] if robot_serial else []))
        for name in names:
            row = self._conn().execute("SELECT campaign, owner, since, heartbeat FROM leases "
                                       "WHERE name = ?", (name,)).fetchone()
            if row is not None and not holder_gone(json.loads(row[1]), row[3], now, ttl):
                raise LeaseRefused(self._refusal(name, campaign and f"campaign {campaign}", row[0],
                                                 json.loads(row[1]), row[2]))

    def _take_leases(self, conn: sqlite3.Connection, campaign: str, robot_serial: str, token: str,
                     now: float, ttl: float, mine: str) -> tuple[str, ...]:
        """Insert or take over (compare-and-set) each lease row, inside the caller's transaction;
        LeaseRefused (rolling the whole transaction back) at the first one a live process holds.
        `mine` names the campaign in that message ("" for a new one: its id is rolled back too)."""
        owner = _dumps(this_process())
        names = (f"campaign:{campaign}",) + ((f"robot:{robot_serial}",) if robot_serial else ())
        for name in names:
            for _ in range(3):  # PostgreSQL (read committed): a row may vanish between two statements
                if conn.execute(
                        "INSERT INTO leases (name, campaign, owner, token, since, heartbeat) "
                        "VALUES (?, ?, ?, ?, ?, ?) ON CONFLICT (name) DO NOTHING RETURNING name",
                        (name, campaign, owner, token, now, now)).fetchone() is not None:
                    break
                held = conn.execute("SELECT campaign, owner, token, since, heartbeat FROM leases "
                                    "WHERE name = ?", (name,)).fetchone()
                if held is None:
                    continue
                holder, held_owner, held_token, since, beat = held
                if not holder_gone(json.loads(held_owner), beat, now, ttl):
                    raise LeaseRefused(self._refusal(name, mine, holder, json.loads(held_owner), since))
                if conn.execute(  # the holder is gone: take it over, unless someone just did
                        "UPDATE leases SET campaign = ?, owner = ?, token = ?, since = ?, heartbeat = ? "
                        "WHERE name = ? AND token = ?",
                        (campaign, owner, token, now, now, name, held_token)).rowcount == 1:
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
        """The heartbeat: True while every row of `lease` still carries its token."""
        with self._write("renew a lease") as conn:
            count = conn.execute("UPDATE leases SET heartbeat = ? WHERE token = ?",
                                 (time.time(), lease.token)).rowcount
        return count == len(lease.names)

    def release_lease(self, lease: Lease) -> None:
        """Give up `lease` (rows taken over meanwhile carry another token and stay)."""
        with self._write("release a lease") as conn:
            conn.execute("DELETE FROM leases WHERE token = ?", (lease.token,))

    def campaigns(self, limit: int | None = 20, *, station: str | None = None) -> list[CampaignSummary]:
        """Summaries, newest first (``limit=None`` for all)."""
        sql = _SUMMARY_SQL + (" WHERE s.name = ?" if station else "")
        sql += " ORDER BY c.created DESC, c.rowid DESC"
        params: list[Any] = [station] if station else []
        if limit is not None:
            sql += " LIMIT ?"
            params.append(int(limit))
        return [_summary(r) for r in self._conn().execute(sql, params)]

    def resolve_id(self, text: str) -> str:
        """A full campaign id from what a user typed: the id, a unique prefix of it, or ``last``."""
        conn = self._conn()
        if text in ("last", "latest"):
            row = conn.execute("SELECT id FROM campaigns ORDER BY created DESC, rowid DESC "
                               "LIMIT 1").fetchone()
            if row is None:
                raise UnknownCampaignError(f"{self.path}: no campaigns yet")
            return str(row[0])
        if conn.execute("SELECT 1 FROM campaigns WHERE id = ?", (text,)).fetchone():
            return text
        pattern = text.replace("\\", "\\\\").replace("%", "\\%").replace("_", "\\_") + "%"
        rows = [r[0] for r in conn.execute(
            "SELECT id FROM campaigns WHERE id LIKE ? ESCAPE '\\' ORDER BY created DESC LIMIT 6",
            (pattern,))] if text else []
        if len(rows) == 1:
            return str(rows[0])
        if not rows:
            raise UnknownCampaignError(f"{self.path}: no campaign {text!r} (see `hil history`)")
        raise UnknownCampaignError(f"{self.path}: {text!r} matches several campaigns "
                                   f"({', '.join(rows[:5])}{', ...' if len(rows) > 5 else ''})")

    def campaign(self, campaign: str) -> CampaignRecord:
        """Everything about one campaign (by exact id), read as one consistent snapshot."""
        with self._read() as conn:
            row = conn.execute(_SUMMARY_SQL + " WHERE c.id = ?", (campaign,)).fetchone()
            if row is None:
                raise UnknownCampaignError(f"{self.path}: no campaign {campaign!r}")
            summary = _summary(row)
            (config, chash, plan, detail, result, software, rtype, serial, model,
             rsoft) = conn.execute(
                "SELECT c.config, c.config_hash, c.plan, c.detail, c.result, c.software, c.robot_type, "
                "r.serial, r.model, r.software FROM campaigns c LEFT JOIN robots r ON r.id = c.robot "
                "WHERE c.id = ?", (campaign,)).fetchone()
            poses = self._poses(conn, campaign)
            measurements = [_measurement(r) for r in conn.execute(
                f"SELECT {_MEASUREMENT_COLUMNS} FROM measurements WHERE campaign = ? ORDER BY id",
                (campaign,))]
            models = [ModelRecord(i, c, rms, json.loads(doc)) for i, c, rms, doc in conn.execute(
                "SELECT id, created, rms, doc FROM models WHERE campaign = ? ORDER BY id", (campaign,))]
            validations = [
                ValidationRecord(i, c, m, json.loads(b), json.loads(a), bool(ok), _loads(d))
                for i, c, m, b, a, ok, d in conn.execute(
                    "SELECT id, created, model, before, after, passed, details FROM validations "
                    "WHERE campaign = ? ORDER BY id", (campaign,))]
            counts = dict(conn.execute("SELECT type, count(*) FROM events WHERE campaign = ? "
                                       "GROUP BY type ORDER BY min(seq)", (campaign,)).fetchall())
        if summary.status == INTERRUPTED and not detail:  # read so: its process is gone (`_summary`)
            detail = "its process ended before the run did (killed, or the machine went down)"
        return CampaignRecord(
            summary=summary,
            robot=RobotInfo(type=rtype, serial=serial or "", model=model or "", software=rsoft or ""),
            config=json.loads(config), config_hash=chash, plan=_loads(plan), detail=detail,
            result=_loads(result), software=software, poses=poses, measurements=measurements,
            models=models, validations=validations, event_counts=counts)

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
        with self._write("save the plan") as conn:
            self._require_campaign(conn, campaign)
            for index, role, target in rows:
                old = conn.execute("SELECT role, target, status FROM poses WHERE campaign = ? "
                                   "AND idx = ?", (campaign, index)).fetchone()
                if old is None:
                    conn.execute("INSERT INTO poses (campaign, idx, role, target) VALUES (?, ?, ?, ?)",
                                 (campaign, index, role, target))
                elif old[2] == "planned":
                    conn.execute("UPDATE poses SET role = ?, target = ? WHERE campaign = ? AND idx = ?",
                                 (role, target, campaign, index))
                elif (old[0], json.loads(old[1])) != (role, json.loads(target)):
                    raise StoreError(f"campaign {campaign}: pose {index} is already {old[2]}; "
                                     "its target and role cannot change")
            if plan is not None:
                conn.execute("UPDATE campaigns SET plan = ? WHERE id = ?", (_dumps(plan), campaign))
            self._touch(conn, campaign, time.time())

    def _require_campaign(self, conn: sqlite3.Connection, campaign: str) -> None:
        if conn.execute("SELECT 1 FROM campaigns WHERE id = ?", (campaign,)).fetchone() is None:
            raise StoreError(f"{self.path}: no campaign {campaign!r}")

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
        with self._write(f"record the measurement of pose {index}") as conn:
            return self._insert_measurement(
                conn, campaign, index, role, q, p, q_spread, p_spread, samples, deviation,
                time.time() if t is None else t, tracker_samples, joint_samples)

    def _insert_measurement(self, conn: sqlite3.Connection, campaign: str, index: int, role: str,
                            q: Any, p: Any, q_spread: Any, p_spread: Any, samples: int,
                            deviation: float | None, t: float, tracker_samples: Any,
                            joint_samples: Any) -> int:
        if role not in ROLES:
            raise StoreError(f"pose {index}: role must be one of {', '.join(ROLES)}, got {role!r}")
        qv = _vector(q, 6, f"pose {index} q")
        self._require_campaign(conn, campaign)
        row = conn.execute(
            "INSERT INTO measurements (campaign, pose, role, q, q_spread, p, p_spread, samples, "
            "deviation, t) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?) "
            "ON CONFLICT (campaign, pose, t) DO NOTHING RETURNING id",
            (campaign, int(index), role, _dumps(qv),
             _dumps_or_null(_optional_vector(q_spread, 6, "q_spread")),
             _dumps(_vector(p, 3, f"pose {index} p")),
             _dumps_or_null(_optional_vector(p_spread, 3, "p_spread")),
             int(samples), _finite_or_none(deviation), float(t))).fetchone()
        if row is None:  # already recorded (the direct call and then its event)
            return int(conn.execute("SELECT id FROM measurements WHERE campaign = ? AND pose = ? "
                                    "AND t = ?", (campaign, int(index), float(t))).fetchone()[0])
        mid = int(row[0])
        for kind, values, n in (("tracker", tracker_samples, 3), ("joints", joint_samples, 6)):
            if values is not None:
                conn.executemany(
                    "INSERT INTO samples (measurement, kind, k, value) VALUES (?, ?, ?, ?)",
                    [(mid, kind, k, _dumps(_vector(v, n, f"{kind} sample {k}")))
                     for k, v in enumerate(values)])
        conn.execute(
            "INSERT INTO poses (campaign, idx, role, target, status) VALUES (?, ?, ?, ?, 'measured') "
            "ON CONFLICT (campaign, idx) DO UPDATE SET status = 'measured', reason = ''",
            (campaign, int(index), role, _dumps(qv)))
        self._touch(conn, campaign, float(t))
        return mid

    def record_skip(self, campaign: str, index: int, role: str, reason: str) -> None:
        """Mark a pose skipped (unreachable, no line of sight...), so a resume does not retry it."""
        with self._write(f"record the skip of pose {index}") as conn:
            self._skip(conn, campaign, index, role, reason, time.time())

    def _skip(self, conn: sqlite3.Connection, campaign: str, index: int, role: str, reason: str,
              now: float) -> None:
        self._require_campaign(conn, campaign)
        cur = conn.execute("UPDATE poses SET status = 'skipped', reason = ? WHERE campaign = ? "
                           "AND idx = ? AND status != 'measured'", (reason, campaign, int(index)))
        if cur.rowcount == 0 and conn.execute("SELECT 1 FROM poses WHERE campaign = ? AND idx = ?",
                                              (campaign, int(index))).fetchone() is None:
            raise StoreError(f"campaign {campaign}: cannot skip pose {index}: it is not in the plan")
        self._touch(conn, campaign, now)

    def _poses(self, conn: sqlite3.Connection, campaign: str, where: str = "") -> list[PlannedPose]:
        return [PlannedPose(i, role, tuple(json.loads(target)), status, reason)
                for i, role, target, status, reason in conn.execute(
                    f"SELECT idx, role, target, status, reason FROM poses WHERE campaign = ? {where} "
                    "ORDER BY idx", (campaign,))]

    def poses(self, campaign: str) -> list[PlannedPose]:
        """Every pose of the plan, by index."""
        return self._poses(self._conn(), campaign)

    def pending_poses(self, campaign: str, *, include_skipped: bool = False) -> list[PlannedPose]:
        """Poses still to measure, in plan order: what a resumed run visits."""
        statuses = "('planned', 'skipped')" if include_skipped else "('planned')"
        return self._poses(self._conn(), campaign, f"AND status IN {statuses}")

    def measured_poses(self, campaign: str) -> dict[int, Measurement]:
        """The latest measurement of each measured pose, by pose index: what a resume keeps."""
        out: dict[int, Measurement] = {}
        for row in self._conn().execute(
                f"SELECT {_MEASUREMENT_COLUMNS} FROM measurements WHERE campaign = ? ORDER BY id",
                (campaign,)):
            m = _measurement(row)
            out[m.index] = m
        return dict(sorted(out.items()))

    def measurements(self, campaign: str, role: str | None = None) -> list[Measurement]:
        """Every measurement row (repeats included), in recording order."""
        sql = f"SELECT {_MEASUREMENT_COLUMNS} FROM measurements WHERE campaign = ?"
        params: list[Any] = [campaign]
        if role is not None:
            sql += " AND role = ?"
            params.append(role)
        return [_measurement(r) for r in self._conn().execute(sql + " ORDER BY id", params)]

    def arrays(self, campaign: str, role: str = "calibration") -> tuple[np.ndarray, np.ndarray]:
        """Joint angles (n×6) and points (n×3) of `role`'s poses, latest per pose, by pose index:
        the input identification (or validation) needs after a resume."""
        ms = [m for m in self.measured_poses(campaign).values() if m.role == role]
        q = np.array([m.q for m in ms], dtype=float).reshape(-1, 6)
        p = np.array([m.p for m in ms], dtype=float).reshape(-1, 3)
        return q, p

    def samples(self, measurement: int) -> dict[str, list[tuple[float, ...]]]:
        """The raw samples of one measurement: ``{"tracker": [...], "joints": [...]}``."""
        out: dict[str, list[tuple[float, ...]]] = {"tracker": [], "joints": []}
        for kind, value in self._conn().execute(
                "SELECT kind, value FROM samples WHERE measurement = ? ORDER BY kind, k", (measurement,)):
            out[kind].append(tuple(json.loads(value)))
        return out

    # --- models and validation ----------------------------------------------------------------
    def save_model(self, campaign: str, doc: Mapping[str, Any]) -> int:
        """Keep a ``hil-model/1`` document; returns its id (the same id for the same document)."""
        with self._write("save the model") as conn:
            return self._insert_model(conn, campaign, doc, time.time())

    def _insert_model(self, conn: sqlite3.Connection, campaign: str, doc: Mapping[str, Any],
                      now: float) -> int:
        self._require_campaign(conn, campaign)
        text, sha = _dumps(doc), _sha(json.loads(_dumps(doc)))
        fit = doc.get("fit") if isinstance(doc.get("fit"), Mapping) else {}
        row = conn.execute("INSERT INTO models (campaign, doc, sha256, rms, created) VALUES (?, ?, ?, ?, ?) "
                           "ON CONFLICT (campaign, sha256) DO NOTHING RETURNING id",
                           (campaign, text, sha, _finite_or_none(fit.get("rms")), now)).fetchone()
        self._touch(conn, campaign, now)
        if row is None:
            return int(conn.execute("SELECT id FROM models WHERE campaign = ? AND sha256 = ?",
                                    (campaign, sha)).fetchone()[0])
        return int(row[0])

    def model(self, campaign: str) -> dict[str, Any] | None:
        """The campaign's latest model document, or None if it has none yet."""
        row = self._conn().execute("SELECT doc FROM models WHERE campaign = ? ORDER BY id DESC LIMIT 1",
                                   (campaign,)).fetchone()
        return None if row is None else dict(json.loads(row[0]))

    def save_validation(self, campaign: str, before: Mapping[str, Any], after: Mapping[str, Any],
                        passed: bool, *, model: int | None = None,
                        details: Mapping[str, Any] | None = None) -> int:
        """Keep a validation result (error stats of the nominal and the calibrated model on
        held-out poses: count, mean, rms, max; `details` for ISO 9283 AP/RP and the like).
        `model` defaults to the campaign's latest model. Returns its id (same result, same id)."""
        with self._write("save the validation") as conn:
            return self._insert_validation(conn, campaign, before, after, passed, model, details,
                                           time.time())

    def _insert_validation(self, conn: sqlite3.Connection, campaign: str, before: Mapping[str, Any],
                           after: Mapping[str, Any], passed: bool, model: int | None,
                           details: Mapping[str, Any] | None, now: float) -> int:
        self._require_campaign(conn, campaign)
        if model is None:
            row = conn.execute("SELECT max(id) FROM models WHERE campaign = ?", (campaign,)).fetchone()
            model = row[0]
        body = {"before": before, "after": after, "passed": bool(passed), "details": details,
                "model": model}
        sha = _sha(json.loads(_dumps(body)))
        row = conn.execute(
            "INSERT INTO validations (campaign, model, before, after, passed, rms, details, sha256, "
            "created) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?) ON CONFLICT (campaign, sha256) DO NOTHING "
            "RETURNING id",
            (campaign, model, _dumps(before), _dumps(after), int(bool(passed)),
             _finite_or_none(after.get("rms")), _dumps_or_null(details), sha,
             now)).fetchone()
        self._touch(conn, campaign, now)
        if row is None:
            return int(conn.execute("SELECT id FROM validations WHERE campaign = ? AND sha256 = ?",
                                    (campaign, sha)).fetchone()[0])
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
        with self._write(f"record {event.name}") as conn:
            self._require_campaign(conn, event.campaign)
            seq = conn.execute("SELECT COALESCE(max(seq), 0) + 1 FROM events WHERE campaign = ?",
                               (event.campaign,)).fetchone()[0]
            conn.execute("INSERT INTO events (campaign, seq, t, type, data) VALUES (?, ?, ?, ?, ?)",
                         (event.campaign, seq, float(event.t), event.name, _dumps(data)))
            self._apply(conn, event)
            self._touch(conn, event.campaign, float(event.t))
        return int(seq)

    def as_subscriber(self) -> Callable[[Event], None]:
        """The callable to subscribe (critical) to the EventBus."""
        return self.record_event

    subscriber = record_event

    def _apply(self, conn: sqlite3.Connection, ev: Event) -> None:
        cid, t = ev.campaign, float(ev.t)
        if isinstance(ev, RunStarted):  # a new run: the last one's detail (e.g. why it stopped) is old
            self._set_status(conn, cid, "running", "", None, t)
        elif isinstance(ev, StateChanged) and ev.state in _LIVE_STATES:
            self._set_status(conn, cid, ev.state, None, None, t)
        elif isinstance(ev, PoseStarted) and ev.role in ROLES:
            conn.execute("INSERT INTO poses (campaign, idx, role, target) VALUES (?, ?, ?, ?) "
                         "ON CONFLICT (campaign, idx) DO NOTHING",
                         (cid, int(ev.index), ev.role, _dumps(_vector(ev.target, 6, "target"))))
        elif isinstance(ev, PointMeasured):
            self._insert_measurement(conn, cid, ev.index, ev.role, ev.q, ev.p,
                                     self._reached_spread(conn, cid, ev.index), ev.p_spread,
                                     ev.samples, ev.deviation, t, None, None)
        elif isinstance(ev, PoseSkipped):
            self._skip(conn, cid, ev.index, ev.role, ev.reason, t)
        elif isinstance(ev, ModelIdentified) and ev.model:
            self._insert_model(conn, cid, ev.model, t)
        elif isinstance(ev, ValidationDone):
            self._insert_validation(conn, cid, ev.before, ev.after, ev.passed, None, None, t)
        elif isinstance(ev, RunFinished):
            self._set_status(conn, cid, ev.status, ev.detail, ev.result or None, t)

    @staticmethod
    def _reached_spread(conn: sqlite3.Connection, campaign: str, index: int) -> list[float] | None:
        """The joint spread of the pose's PoseReached (PointMeasured does not carry it)."""
        row = conn.execute("SELECT data FROM events WHERE campaign = ? AND type = 'PoseReached' "
                           "ORDER BY seq DESC LIMIT 1", (campaign,)).fetchone()
        if row is None:
            return None
        data = json.loads(row[0])
        spread = data.get("q_spread")
        return spread if data.get("index") == index and isinstance(spread, list) else None

    def event_log(self, campaign: str, *, after: int = 0) -> list[tuple[int, dict[str, Any]]]:
        """``(seq, event dict)`` pairs with seq > `after`, in order: a reader polls with the last
        seq it saw (the TUI following a run from another process, a report)."""
        return [(seq, json.loads(data)) for seq, data in self._conn().execute(
            "SELECT seq, data FROM events WHERE campaign = ? AND seq > ? ORDER BY seq",
            (campaign, after))]

    def events(self, campaign: str, *, after: int = 0) -> list[Event]:
        """The log as Event objects (types this version does not know are left out)."""
        return [Event.from_dict(d) for _, d in self.event_log(campaign, after=after)
                if d.get("event") in Event.registry]
