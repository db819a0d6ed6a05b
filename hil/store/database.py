"""SQLAlchemy engines for the two places a store can live: an SQLite file or a PostgreSQL server.

Named for the database it opens, not "engine": `hil.campaign.engine` is the campaign engine.

SQLite (one station). The file runs in WAL mode with ``synchronous=FULL`` (see
`hil.store.transactions` for why), foreign keys on, and a busy timeout so writers of several threads
or processes queue on SQLite's lock instead of failing. Python's sqlite3 driver opens transactions
implicitly and never with ``BEGIN IMMEDIATE``; SQLAlchemy's documented recipe for pysqlite turns
that off and emits BEGIN itself, which here becomes ``BEGIN IMMEDIATE`` for a write (execution
option ``hil_write``): a writer takes the lock when it starts, so two writers never deadlock
upgrading a read lock. The store's own connection class (`hil.store.sqlite_errors`) names the file
in the error a damaged page raises.

PostgreSQL (a plant's fleet). ``postgresql://`` URLs are driven through psycopg 3. Connections are
checked before use (``pool_pre_ping``) so a server restarted between two writes costs a reconnect,
not a failed write; every blocking step has a timeout (connect, statement, lock wait), since an
end-of-line cell must never hang on a database.
"""

from __future__ import annotations

import sqlite3
from pathlib import Path
from typing import Any

from sqlalchemy import Engine, create_engine, event
from sqlalchemy.engine import make_url
from sqlalchemy.pool import QueuePool

from hil.store.paths import POSTGRES_SCHEMES, is_postgres, is_url
from hil.store.sqlite_errors import StoreConnection

__all__ = ["POSTGRES_SCHEMES", "display_url", "is_postgres", "is_url", "postgres_engine", "sqlite_engine"]

def display_url(url: str) -> str:
    """The URL with its password hidden: what messages, logs and the history header print."""
    try:
        return make_url(url).render_as_string(hide_password=True)
    except Exception:  # not parseable: say it without anything after the scheme's user part
        return url.split("@")[-1]


def sqlite_engine(path: Path, *, uri: str | None, timeout: float, synchronous: str,
                  readonly: bool) -> Engine:
    """An engine on the SQLite file `path` (`uri`: the ``file:`` URI a reader opens instead)."""
    where = str(path)

    def connect() -> sqlite3.Connection:
        # check_same_thread=False: the pool hands a connection to one thread at a time, not always the
        # thread that opened it. ``sqlite3.connect`` is looked up at call time (tests replace it).
        conn = sqlite3.connect(uri if uri else str(path), timeout=timeout, isolation_level=None,
                               check_same_thread=False, uri=uri is not None, factory=StoreConnection)
        conn.where = where  # type: ignore[attr-defined]
        return conn

    # a pool, so a thread reuses a connection (and its page cache) from one transaction to the next
    engine = create_engine("sqlite+pysqlite://", creator=connect, poolclass=QueuePool, pool_size=4,
                           max_overflow=28, pool_timeout=timeout)

    @event.listens_for(engine, "connect")
    def _on_connect(dbapi: Any, _record: Any) -> None:
        dbapi.isolation_level = None  # the recipe: no implicit BEGIN from the driver
        dbapi.execute(f"PRAGMA busy_timeout = {int(timeout * 1000)}")
        if readonly:
            dbapi.execute("PRAGMA query_only = ON")
            return
        dbapi.execute(f"PRAGMA synchronous = {synchronous}")
        dbapi.execute("PRAGMA foreign_keys = ON")

    @event.listens_for(engine, "begin")
    def _on_begin(conn: Any) -> None:
        write = conn.get_execution_options().get("hil_write", False)
        conn.exec_driver_sql("BEGIN IMMEDIATE" if write else "BEGIN")

    return engine


def postgres_engine(url: str, *, timeout: float, readonly: bool) -> Engine:
    """An engine on a PostgreSQL database, through psycopg 3, with timeouts on every wait."""
    parsed = make_url(url)
    parsed = parsed.set(drivername="postgresql+psycopg")
    ms = int(timeout * 1000)
    connect_args = {
        "connect_timeout": max(1, round(timeout)),
        "application_name": "hil",
        # a statement (or a lock wait) longer than this fails instead of hanging the station; the
        # lease heartbeat and every write are far shorter
        "options": f"-c statement_timeout={ms} -c lock_timeout={ms} "
                   f"-c idle_in_transaction_session_timeout={max(ms * 6, 60_000)}",
    }
    engine = create_engine(parsed, pool_pre_ping=True, pool_size=4, max_overflow=16,
                           pool_timeout=timeout, connect_args=connect_args)
    if readonly:
        engine = engine.execution_options(postgresql_readonly=True)
    return engine
