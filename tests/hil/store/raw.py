"""Plain SQL against a `Store`'s own connections, for tests that look under the hood (pragmas, row
counts, a lease row edited to fake another host). Parameters are ``?``, on either engine."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from hil.store import Store


class Rows:
    """What a query returned, read like an sqlite3 cursor (fetchone, fetchall, iteration)."""

    def __init__(self, rows: Sequence[Any], rowcount: int = -1) -> None:
        self.rows, self.rowcount = [tuple(r) for r in rows], rowcount

    def fetchone(self) -> Any:
        return self.rows[0] if self.rows else None

    def fetchall(self) -> list[Any]:
        return list(self.rows)

    def __iter__(self) -> Iterator[Any]:
        return iter(self.rows)


class Raw:
    """``raw(store).execute(sql, params)``: one statement in its own transaction (committed)."""

    def __init__(self, conn: Any) -> None:
        self.conn = conn

    def execute(self, sql: str, params: Sequence[Any] = ()) -> Rows:
        if self.conn.dialect.name == "postgresql":  # psycopg's parameter style
            sql = sql.replace("%", "%%").replace("?", "%s")
        result = self.conn.exec_driver_sql(sql, tuple(params))
        return Rows(result.all() if result.returns_rows else [], result.rowcount)


class _OneShot:
    def __init__(self, store: Store) -> None:
        self.store = store

    def execute(self, sql: str, params: Sequence[Any] = ()) -> Rows:
        with self.store.writing("test") as conn:
            return Raw(conn).execute(sql, params)


def raw(store: Store) -> _OneShot:
    return _OneShot(store)


@contextmanager
def raw_write(store: Store) -> Iterator[Raw]:
    """Several statements in one write transaction."""
    with store.writing("test") as conn:
        yield Raw(conn)
