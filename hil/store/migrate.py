"""Creating and upgrading a store's schema with Alembic, on SQLite and PostgreSQL alike.

The revisions live in `hil.store.migrations` (hand-written, append-only, portable). `upgrade` runs
inside the caller's write transaction, so an upgrade interrupted by a crash leaves the old version
intact rather than a half-migrated database (SQLite's and PostgreSQL's DDL are both transactional).
Two processes opening an old database at once upgrade it exactly once: on SQLite the write
transaction (``BEGIN IMMEDIATE``) serialises them, on PostgreSQL a transaction-scoped advisory lock
does; each re-reads the version after taking it.

Stores written before Alembic (hil's own numbered steps, version in ``PRAGMA user_version``, 1 to 3)
are stamped with the matching revision and upgraded from there, in place. SQLite files keep
``user_version`` equal to `SCHEMA_VERSION`, so an older hil, which reads only that, still refuses a
store newer than it knows instead of writing into tables it does not understand.

Alembic is imported only to change a schema (or to ask the migrations on disk for their head): opening
a store that is already at `HEAD` — every read, and every write after the first — reads the revision
from ``alembic_version`` itself, so a listing does not pay Alembic's import (a fifth of
``hil history``'s start-up before; bench/cli_startup.py).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from sqlalchemy import Connection, inspect, text

from hil.errors import InputError
from hil.store.schema_version import HEAD, SCHEMA_VERSION

if TYPE_CHECKING:
    from alembic.config import Config

__all__ = ["HEAD", "SCHEMA_VERSION", "alembic_config", "found_version", "script_head", "upgrade"]

_LOCATION = Path(__file__).with_name("migrations")
_OUR_TABLES = frozenset({"stations", "robots", "campaigns", "poses", "measurements", "events"})
# pg_advisory_xact_lock key: "hil schema" in ASCII, any constant that no other lock of ours uses
_PG_LOCK = 0x68696C736368


def alembic_config(connection: Connection | None = None) -> Config:
    """An Alembic config without an ini file, pointing at hil's migrations (and `connection`)."""
    from alembic.config import Config

    cfg = Config()
    cfg.set_main_option("script_location", str(_LOCATION))
    if connection is not None:
        cfg.attributes["connection"] = connection
    return cfg


def script_head() -> str:
    """The head revision of the migrations on disk (what `HEAD` must equal)."""
    from alembic.script import ScriptDirectory

    return str(ScriptDirectory.from_config(alembic_config()).get_current_head())


def _revision(conn: Connection, where: str) -> str | None:
    """The revision ``alembic_version`` holds (None: none yet), read as Alembic's MigrationContext
    reads it, without importing Alembic. hil's revisions are one line, so one row at most."""
    found = conn.execute(text("SELECT version_num FROM alembic_version")).scalars().all()
    if len(found) > 1:
        raise InputError(f"{where}: alembic_version holds {len(found)} revisions ({', '.join(found)}); "
                         "hil's schema has one line of revisions: not a store this hil wrote")
    return str(found[0]) if found else None


def _sqlite_user_version(conn: Connection) -> int:
    return int(conn.exec_driver_sql("PRAGMA user_version").scalar() or 0)


def found_version(conn: Connection, where: str) -> int:
    """The schema version of the database on `conn` (0: empty), refusing what is not a hil store or
    is newer than this code. Reads only."""
    tables = set(inspect(conn).get_table_names())
    sqlite = conn.dialect.name == "sqlite"
    legacy = _sqlite_user_version(conn) if sqlite else 0
    if legacy > SCHEMA_VERSION:
        raise InputError(f"{where}: database schema version {legacy} is newer than this hil supports "
                         f"({SCHEMA_VERSION}); upgrade hil to read it")
    if "alembic_version" in tables:
        rev = _revision(conn, where)
        if rev is None:
            return 0
        try:
            version = int(rev)
        except ValueError:
            version = SCHEMA_VERSION + 1
        if version > SCHEMA_VERSION:
            raise InputError(f"{where}: database schema revision {rev} is newer than this hil supports "
                             f"({HEAD}); upgrade hil to read it")
        return version
    if legacy:
        return legacy
    if sqlite and tables:
        raise InputError(f"{where}: an SQLite database, but not a hil store")
    if tables & _OUR_TABLES:
        raise InputError(f"{where}: a database with tables named like hil's, but not a hil store")
    return 0


def upgrade(conn: Connection, where: str) -> int:
    """Bring the database on `conn` (inside a write transaction) to `HEAD`; returns the version found."""
    if conn.dialect.name == "postgresql":
        conn.execute(text("SELECT pg_advisory_xact_lock(:key)"), {"key": _PG_LOCK})
    found = found_version(conn, where)  # re-read under the lock
    if found >= SCHEMA_VERSION:
        return found
    from alembic import command

    cfg = alembic_config(conn)
    if found and "alembic_version" not in inspect(conn).get_table_names():
        command.stamp(cfg, f"{found:04d}")  # a store from before Alembic: its steps were these revisions
    command.upgrade(cfg, HEAD)
    if conn.dialect.name == "sqlite":
        conn.exec_driver_sql(f"PRAGMA user_version = {SCHEMA_VERSION}")
    return found
