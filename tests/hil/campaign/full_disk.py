"""A full disk for the SQLite store, on cue: `FullDisk` makes every connection opened while it is
installed refuse writes as SQLite does when the disk is full (reads still work).

It wraps whatever connection class the store asks SQLite for (``factory=``), so the store's own
connection behaviour stays as it is; only the statements (on the connection and on its cursors, which
is how SQLAlchemy runs them) and ``commit`` are intercepted, which is how the store writes.
"""

from __future__ import annotations

import sqlite3
from typing import Any

WRITES = ("INSERT", "UPDATE", "DELETE", "COMMIT")


class FullDisk:
    """`room`: measurements that still fit (None: unlimited); once one does not, nothing more does.
    `full` can also be set directly."""

    def __init__(self, monkeypatch: Any, room: int | None = None) -> None:
        self.room, self.full = room, False
        disk = self
        connect = sqlite3.connect
        classes: dict[type, type] = {}

        class Cursor:
            def __init__(self, cursor: Any) -> None:
                self._cursor = cursor

            def execute(self, sql: str, *args: Any) -> Any:
                disk._check(sql)
                self._cursor.execute(sql, *args)
                return self

            def executemany(self, sql: str, *args: Any) -> Any:
                disk._check(sql)
                self._cursor.executemany(sql, *args)
                return self

            def __iter__(self) -> Any:
                return iter(self._cursor)

            def __getattr__(self, name: str) -> Any:
                return getattr(self._cursor, name)

        class Refusing:
            def execute(self, sql: str, *args: Any) -> Any:
                disk._check(sql)
                return super().execute(sql, *args)  # type: ignore[misc]

            def cursor(self, *args: Any, **kwargs: Any) -> Any:
                return Cursor(super().cursor(*args, **kwargs))  # type: ignore[misc]

            def commit(self) -> None:
                if self.in_transaction:  # type: ignore[attr-defined]
                    disk._check("COMMIT")
                super().commit()  # type: ignore[misc]

        def connect_here(*args: Any, **kwargs: Any) -> sqlite3.Connection:
            base = kwargs.pop("factory", sqlite3.Connection)
            if base not in classes:
                classes[base] = type(f"FullDisk{base.__name__}", (Refusing, base), {})
            kwargs["factory"] = classes[base]
            return connect(*args, **kwargs)

        monkeypatch.setattr(sqlite3, "connect", connect_here)

    def _check(self, sql: str) -> None:
        words = sql.split()
        if self.room is not None and words[:3] == ["INSERT", "INTO", "measurements"]:
            self.full = self.full or self.room == 0
            self.room -= 1
        if self.full and words and words[0].upper() in WRITES:
            raise sqlite3.OperationalError("database or disk is full")

    def make_room(self) -> None:
        self.room, self.full = None, False
