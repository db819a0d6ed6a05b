"""A full disk for the SQLite store, on cue: `FullDisk` makes every connection opened while it is
installed refuse writes as SQLite does when the disk is full (reads still work).

It wraps whatever connection class the store asks SQLite for (``factory=``), so the store's own
connection behaviour stays as it is; only ``execute`` is intercepted, which is how the store writes.
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

        class Refusing:
            def execute(self, sql: str, *args: Any) -> Any:
                disk._check(sql)
                return super().execute(sql, *args)  # type: ignore[misc]

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
