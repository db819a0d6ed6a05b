"""Reading a station's SQLite store with Python's own sqlite3: the listings (``hil history``, ``hil
show``, ``hil robots``, ``hil robot``) without SQLAlchemy or Alembic, whose import alone took most of
their start-up (0.3–0.45 s of ``import sqlalchemy``; bench/cli_startup.py).

`SqliteReader` runs the very SQL texts the `hil.store.core.Store` runs through SQLAlchemy
(`hil.store.listing_sql`, mapped to records by `hil.store.listing`), so both answer alike
(tests/hil/store/test_sqlite_reader.py). It takes only what it can read exactly as the Store would: a
plain, non-empty SQLite file whose schema is this code's (`HEAD` in ``alembic_version``, and no newer
``user_version``). Anything else — a PostgreSQL URL, a missing, empty or foreign file, an older store
(which the Store upgrades when it can write it), a newer one — gets ``None`` from `open_reader`, and
the caller opens the `Store` instead, which accepts, upgrades or refuses it as before, with the same
messages.

Read-only as the Store's readers: the same ``file:`` URI (`readonly_uri`), ``query_only`` on, a busy
timeout, one transaction per snapshot ended by a rollback, and the store's own connection class
(`hil.store.sqlite_errors.StoreConnection`), which names the file when a page is damaged.
"""

from __future__ import annotations

import os
import sqlite3
import urllib.parse
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Self

from hil.store.listing import ListingQueries, Rows
from hil.store.paths import is_url
from hil.store.schema_version import HEAD, SCHEMA_VERSION
from hil.store.sqlite_errors import CorruptStoreError, StoreConnection, StoreError, damaged

__all__ = ["SqliteReader", "open_reader", "readonly_uri"]


def readonly_uri(path: Path) -> str:
    """The ``file:`` URI of a reading connection (never one that creates the file).

    A WAL database needs its ``-wal`` and ``-shm`` files beside it. Where the reader may write
    them (``mode=rw``, with ``query_only`` set on every connection), SQLite removes them again at
    close, leaving the folder as it was; ``mode=ro`` would leave them behind. In a directory we
    cannot write (read-only media, another user's folder) even ``mode=ro`` fails ("attempt to
    write a readonly database"): there, unless a ``-wal`` holds commits not yet folded into the
    file (hil closes cleanly, folding them in), ``immutable=1`` reads the file alone; with such a
    ``-wal`` it would hide them, so ``mode=ro`` reads through the existing files.
    """
    path = path.resolve()
    wal = path.with_name(path.name + "-wal")
    if os.access(path.parent, os.W_OK):
        query = "mode=rw" if os.access(path, os.W_OK) else "mode=ro"
    elif wal.exists() and wal.stat().st_size > 0:
        query = "mode=ro"
    else:
        query = "mode=ro&immutable=1"
    return f"file:{urllib.parse.quote(str(path))}?{query}"


def _first_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())


class SqliteReader(ListingQueries):
    """A read-only sqlite3 connection to a store at this code's schema, with the Store's campaign reads
    (`ListingQueries`) and what the fleet reads need (`location`, `snapshot`). Open it with
    `open_reader`."""

    postgres = False
    dialect = "sqlite"
    readonly = True

    def __init__(self, path: Path, conn: sqlite3.Connection) -> None:
        #: the SQLite file, and what messages name (as `hil.store.core.Store`'s)
        self.path: Path | None = path
        self.location = str(path)
        self._conn = conn

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._conn.close()

    @contextmanager
    def snapshot(self) -> Iterator[Rows]:
        """One read transaction: the queries inside see one consistent snapshot; a rollback ends it.
        A failing query is a StoreError naming the file (as the Store's ``cannot read: …``); a damaged
        page, a CorruptStoreError (`StoreConnection`)."""
        conn = self._conn

        def rows(text: str, params: dict[str, Any] | None = None, /) -> Sequence[Sequence[Any]]:
            return conn.execute(text, params or {}).fetchall()

        try:
            conn.execute("BEGIN")
            try:
                yield rows
            finally:
                if conn.in_transaction:
                    conn.execute("ROLLBACK")
        except sqlite3.Error as exc:
            problem = damaged(exc, str(self.location)) if isinstance(exc, sqlite3.DatabaseError) else exc
            if isinstance(problem, CorruptStoreError):
                raise problem from None
            raise StoreError(f"{self.location}: cannot read: {_first_line(exc)}") from exc


def _at_head(conn: sqlite3.Connection) -> bool:
    """Whether the open file is a hil store at this code's schema (what the Store would read as is)."""
    if int(conn.execute("PRAGMA user_version").fetchone()[0] or 0) > SCHEMA_VERSION:
        return False  # newer than this code: the Store refuses it, saying so
    if conn.execute("SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'alembic_version'"
                    ).fetchone() is None:
        return False
    return [r[0] for r in conn.execute("SELECT version_num FROM alembic_version")] == [HEAD]


def open_reader(location: str | os.PathLike[str], *, timeout: float = 10.0) -> SqliteReader | None:
    """A `SqliteReader` on the SQLite store at `location`, or None when the `hil.store.core.Store`
    must open it instead (the module docstring says when). Never creates or changes a file."""
    if is_url(location):
        return None
    path = Path(location)
    try:
        if not path.is_file() or path.stat().st_size == 0:
            return None
    except OSError:
        return None
    conn: sqlite3.Connection | None = None
    try:
        conn = sqlite3.connect(readonly_uri(path), uri=True, timeout=timeout, isolation_level=None,
                               factory=StoreConnection)
        conn.where = str(path)  # type: ignore[attr-defined]
        conn.execute(f"PRAGMA busy_timeout = {int(timeout * 1000)}")
        conn.execute("PRAGMA query_only = ON")
        if _at_head(conn):
            return SqliteReader(path, conn)
    except (sqlite3.Error, StoreError):  # not a database, damaged, locked...: the Store says what
        pass
    if conn is not None:
        conn.close()
    return None
