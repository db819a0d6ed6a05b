"""Opening a store's database and running its transactions: durability, threads, a lost link.

Every other part of the store (`hil.store.core`, `hil.store.queries`, `hil.store.recorder`,
`hil.store.fleet`) reaches the database through `TransactionalStore`, so these rules hold for all of
them.

Durability. Every write method is one transaction, committed before it returns. On SQLite the file
runs in WAL mode with ``synchronous=FULL`` (the WAL fsynced at each commit): ``NORMAL`` would already
survive ``kill -9`` (the WAL write reaches the OS before COMMIT returns) but could lose the last
commits on a power cut or kernel crash, which on a shop floor is not hypothetical. FULL costs one fsync
per commit, a few milliseconds against the seconds a pose takes to reach and measure, so the stronger
promise is nearly free (``synchronous="NORMAL"`` is accepted for fast-time simulations). On
PostgreSQL a COMMIT returns once the server has flushed its WAL (the server's own setting).

Threads. A store may be shared between threads: each transaction takes a connection from the
engine's pool for its duration. SQLite's WAL lets readers (the TUI) run while the engine writes, and
writers — threads or other processes — queue on SQLite's lock for up to ``timeout`` seconds; on
PostgreSQL many stations write at once, each campaign's rows its own. `close` disposes of the pool.

A lost database link (PostgreSQL restarted, a network cut). A write whose connection fails is
retried on a new connection until ``outage_timeout`` seconds have passed, and the caller — the engine,
between a measurement and the next move — waits meanwhile, as for a lost tracker beam: nothing is
measured that cannot be kept, and nothing kept is lost. ``on_outage`` is told when the link goes and
comes back (the CLI and TUI say so). Every write is idempotent, so one whose COMMIT may or may not
have landed before the link dropped is safe to repeat: a measurement is keyed by (campaign, pose, t),
models and validations by their content hash, an event by its ``uid``, a new campaign by its id
(`hil.store.rows`).
"""

from __future__ import annotations

import logging
import os
import sqlite3
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any, Self, TypeVar

from sqlalchemy import Connection, Engine, text
from sqlalchemy.exc import DBAPIError

from hil.errors import InputError
from hil.store.database import display_url, is_postgres, postgres_engine, sqlite_engine
from hil.store.migrate import SCHEMA_VERSION, found_version, upgrade
from hil.store.paths import check_store, locate
from hil.store.sqlite_errors import CorruptStoreError, StoreError, StoreUnavailable, check_intact, damaged
from hil.store.sqlite_reader import readonly_uri

if TYPE_CHECKING:
    from hil.store.listing import Rows

log = logging.getLogger(__name__)


class _LockedAtOpen(Exception):
    """SQLite refused a lock at once while a store was being opened (`_open_sqlite` retries)."""

R = TypeVar("R")

#: Seconds a write waits for a lost PostgreSQL link to come back before the run stops (resumable).
OUTAGE_TIMEOUT = 600.0

__all__ = ["OUTAGE_TIMEOUT", "TransactionalStore"]


class TransactionalStore:
    """A hil database, opened on first use, and its transactions (the module docstring says how).

    `location` is a file path (SQLite) or a ``postgresql://`` URL. `hil.store.core.Store` adds what
    is kept in it; this class knows only how to open it and run a transaction.
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
        return f"{type(self).__name__}({self.location!r})"

    @property
    def dialect(self) -> str:
        """``sqlite`` or ``postgresql``."""
        return "postgresql" if self.postgres else "sqlite"

    # --- opening and closing ------------------------------------------------------------------
    @classmethod
    def open(cls, path: str | os.PathLike[str] | None = None, *, config: Any = None,
             create: bool = True, synchronous: str = "FULL", timeout: float = 10.0,
             readonly: bool = False, outage_timeout: float | None = None) -> Self:
        """Open (creating or upgrading as needed) the database at `path`, or where `locate`
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
        located = locate(path, config)
        if readonly or not create:  # a missing file named as it was given (--db, $HIL_DB, store.url)
            check_store(located, create=False)
        store = cls(located.location, create=create, synchronous=synchronous,
                    timeout=timeout, readonly=readonly, outage_timeout=outage_timeout)
        return store.connect()

    def connect(self) -> Self:
        """Open the database, creating or upgrading its schema on the first call. Idempotent."""
        self._get_engine()
        return self

    def __enter__(self) -> Self:
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
        deadline = time.monotonic() + self.timeout
        while True:
            try:
                return self._first_open_sqlite(where)
            except _LockedAtOpen:
                # SQLite answers SQLITE_BUSY at once, without its busy handler, where waiting could
                # deadlock (sqlite3_busy_handler's documentation): a first open racing another one
                # that is upgrading the file (switching it to WAL, migrating). Rolled back: try again.
                if time.monotonic() > deadline:
                    raise StoreError(f"{where}: database is locked (another process kept it for "
                                     f"{self.timeout:g} s while it was opened)") from None
                time.sleep(0.05)

    def _first_open_sqlite(self, where: str) -> Engine:
        """One attempt of `_open_sqlite` (_LockedAtOpen when SQLite said busy without waiting)."""
        assert self.path is not None
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
                raise _LockedAtOpen from None
            if "not a database" in text or "malformed" in text:
                raise InputError(f"{where}: not a hil database ({text})") from None
            raise InputError(f"{where}: cannot open: {text}") from None
        except sqlite3.DatabaseError as exc:
            engine.dispose()
            if isinstance(exc, sqlite3.OperationalError) and ("locked" in str(exc) or "busy" in str(exc)):
                raise _LockedAtOpen from None
            raise InputError(f"{where}: cannot open: {exc}") from None
        except BaseException:
            engine.dispose()
            raise
        return engine

    def _readonly_uri(self) -> str:
        """The ``file:`` URI of a reading connection (`hil.store.sqlite_reader.readonly_uri` says why)."""
        assert self.path is not None
        return readonly_uri(self.path)

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
            upgrader = TransactionalStore(self.url or str(self.path), create=False, timeout=self.timeout)
            upgrader.connect().close()
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
            if isinstance(exc.orig, sqlite3.DatabaseError):
                problem = damaged(exc.orig, str(self.location))
                if isinstance(problem, CorruptStoreError):
                    raise problem from None
            raise StoreError(f"{self.location}: cannot read: {_first_line(exc.orig)}") from exc.orig

    @contextmanager
    def snapshot(self) -> Iterator[Rows]:
        """A `reading` snapshot as the `hil.store.listing` reads take it: a function running one SQL text
        of `hil.store.listing_sql` (its ``:name`` parameters bound by SQLAlchemy's ``text()``) and
        returning its rows. `hil.store.sqlite_reader` runs the same texts through sqlite3."""
        with self.reading() as conn:
            def rows(sql: str, params: dict[str, Any] | None = None, /) -> Sequence[Sequence[Any]]:
                return conn.execute(text(sql), params or {}).all()  # DBAPIError: `reading` says it

            yield rows

    def _query(self, fn: Callable[[Connection], R]) -> R:
        """`fn`'s answer, read in one `reading` snapshot."""
        with self.reading() as conn:
            return fn(conn)

    def _write(self, what: str, fn: Callable[[Connection], R]) -> R:
        """`fn` in one write transaction (`_transact`: retried on a lost link); StoreError if this
        store was opened read-only."""
        if self.readonly:
            raise StoreError(f"{self.location}: opened read-only: cannot {what}")
        return self._transact(what, fn)


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


def _first_line(exc: BaseException | None) -> str:
    """A driver's message on one line (psycopg's carry a DETAIL and a HINT on lines of their own)."""
    text = str(exc) if exc is not None else "unknown error"
    return " ".join(text.split()) if "\n" not in text.strip() else text.strip().splitlines()[0].strip()
