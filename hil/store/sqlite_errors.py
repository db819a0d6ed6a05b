"""A damaged SQLite file, named: the store's sqlite3 connection and cursor classes.

SQLite says "database disk image is malformed" only when a query reaches the damaged page, long after
the file opened, and the message does not say which file. Every query and every fetch of the store's
SQLite connections goes through `StoreCursor`, which turns that into `CorruptStoreError` naming the
file: bad input (exit 2, ``k.db is not a readable hil store: ...``), and still a `StoreError`, so a run
that meets it mid-campaign stops as for any store failure. SQLAlchemy passes it through unchanged (it
wraps only the driver's own exception classes).
"""

from __future__ import annotations

import sqlite3
from typing import Any

from hil.errors import FaultError, HilError, InputError


class StoreError(HilError):
    """The store could not record or read something (disk full, locked too long, unknown campaign)."""


class StoreUnavailable(StoreError, FaultError):
    """The database server cannot be reached (at open, or for longer than a write waits for it)."""


class CorruptStoreError(StoreError, InputError):
    """The database file is damaged (garbage written into it, a torn copy)."""


# SQLite's primary result codes for a damaged file: SQLITE_CORRUPT (11), SQLITE_NOTADB (26).
_DAMAGED = frozenset({11, 26})


#: What SQLite says (SQLITE_ERROR, 1) when a query names a table or column the file lacks. The schema
#: is migrated to this hil's version at open, so in a store that opened it means a table was dropped
#: or altered by hand: damage, which ``hil show`` reported as a failed job (exit 1).
_MISSING_SCHEMA = ("no such table", "no such column")


def damaged(exc: sqlite3.DatabaseError, where: str) -> BaseException:
    """`exc` as a `CorruptStoreError` naming the file when it says the file is damaged (a damaged
    page, not SQLite at all, or a table or column of its schema missing), else itself."""
    code = getattr(exc, "sqlite_errorcode", None)
    if code is not None and code & 0xFF == 1 and str(exc).startswith(_MISSING_SCHEMA):
        return CorruptStoreError(f"{where} is not a readable hil store: {exc} (its schema was altered)")
    if code is None or code & 0xFF not in _DAMAGED:
        return exc
    if code & 0xFF == 26:  # SQLITE_NOTADB: not SQLite at all (a text file, an image)
        return CorruptStoreError(f"{where}: not a hil database ({exc})")
    return CorruptStoreError(f"{where} is not a readable hil store: {exc}")


def check_intact(conn: Any, where: str) -> None:
    """CorruptStoreError unless SQLite's quick check finds every page sound. A writer runs it once, at
    open: a damaged page is otherwise met only by the query that reads it, which for ``hil calibrate``
    can be after it connected to the arm, or mid-campaign. It reads the file once (milliseconds for
    the megabytes a station's store holds). `conn` is an sqlite3 connection."""
    problems = [row[0] for row in conn.execute("PRAGMA quick_check(1)")]
    if problems != ["ok"]:
        # "*** in database main ***\nPage 16: btreeInitPage() returns error code 11": one line
        detail = " ".join(" ".join(problems).replace("*** in database main ***", "").split())
        raise CorruptStoreError(f"{where} is not a readable hil store: database disk image is malformed "
                                f"({detail[:200]})")


class StoreCursor(sqlite3.Cursor):
    """A cursor whose damaged-file errors name the file: every query and every fetch, since a row on a
    damaged page fails only when it is read."""

    def _where(self) -> str:
        return getattr(self.connection, "where", "the database")

    def execute(self, *args: Any) -> StoreCursor:
        try:
            return super().execute(*args)
        except sqlite3.DatabaseError as exc:
            raise damaged(exc, self._where()) from None

    def executemany(self, *args: Any) -> StoreCursor:
        try:
            return super().executemany(*args)
        except sqlite3.DatabaseError as exc:
            raise damaged(exc, self._where()) from None

    def __next__(self) -> Any:
        try:
            return super().__next__()
        except sqlite3.DatabaseError as exc:
            raise damaged(exc, self._where()) from None

    def fetchone(self) -> Any:
        try:
            return super().fetchone()
        except sqlite3.DatabaseError as exc:
            raise damaged(exc, self._where()) from None

    def fetchmany(self, *args: Any) -> list[Any]:
        try:
            return super().fetchmany(*args)
        except sqlite3.DatabaseError as exc:
            raise damaged(exc, self._where()) from None

    def fetchall(self) -> list[Any]:
        try:
            return super().fetchall()
        except sqlite3.DatabaseError as exc:
            raise damaged(exc, self._where()) from None


class StoreConnection(sqlite3.Connection):
    """The store's SQLite connections: their queries go through `StoreCursor` (``Connection.execute``
    would bypass ``cursor()``); `where` is the file the errors name."""

    where = "the database"

    def cursor(self, factory: Any = StoreCursor) -> Any:  # type: ignore[override]
        return super().cursor(factory)

    def execute(self, *args: Any) -> Any:  # type: ignore[override]
        return self.cursor().execute(*args)

    def executemany(self, *args: Any) -> Any:  # type: ignore[override]
        return self.cursor().executemany(*args)
