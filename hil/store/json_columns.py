"""The store's JSON columns as text: `dumps` writes them, `row_json` reads one back naming the row when
it does not parse. SQLite and PostgreSQL keep the same compact text. A module of its own, free of
SQLAlchemy: the listings that read a station's file with sqlite3 (`hil.store.sqlite_reader`) parse
these columns exactly as every other reader does.
"""

from __future__ import annotations

import json
import math
import sys
from typing import Any

from hil.store.sqlite_errors import CorruptStoreError

__all__ = ["DamagedRowError", "dumps", "dumps_or_null", "floats", "loads", "row_json"]


def dumps(value: Any) -> str:
    """Compact JSON of plain values, numpy arrays and scalars included."""

    def default(obj: Any) -> Any:
        # numpy is not imported for it: a value can hold an array only once someone imported numpy
        # (a listing that writes, `hil robot --mark-bad`, never does)
        np = sys.modules.get("numpy")
        if np is not None and isinstance(obj, np.ndarray | np.generic):
            return obj.tolist()
        if isinstance(obj, tuple | set | frozenset):
            return list(obj)
        if hasattr(obj, "as_dict"):
            return obj.as_dict()
        raise TypeError(f"cannot store a {type(obj).__name__} as JSON")

    return json.dumps(value, separators=(",", ":"), default=default)


def dumps_or_null(value: Any) -> str | None:
    """JSON text, or SQL NULL for None (so "absent" is queryable as IS NULL)."""
    return None if value is None else dumps(value)


def loads(text: str | None) -> Any:
    """The value of a JSON column (None for SQL NULL)."""
    return None if text is None else json.loads(text)


class DamagedRowError(CorruptStoreError):
    """One row of the store holds a JSON column that does not parse (a disk error, a hand edit, a
    tool that wrote into the database): bad input naming the row — campaign, table, id, column — so
    it can be found and mended, not an internal error."""


def row_json(text: str | None, *, table: str, row: Any, column: str, campaign: str | None = None) -> Any:
    """The value of JSON column `column` of `table`'s row `row` (None for SQL NULL); `DamagedRowError`
    naming the row when it does not parse. Every reader of the store's JSON columns goes through it."""
    if text is None:
        return None
    try:
        return json.loads(text)
    except (ValueError, TypeError, RecursionError) as exc:
        where = f"campaign {campaign}, " if campaign else ""
        reason = exc.msg if isinstance(exc, json.JSONDecodeError) else type(exc).__name__
        raise DamagedRowError(f"damaged store row: {where}table {table}, id {row}: {column} is not valid "
                              f"JSON ({reason})") from None


def row_number(value: Any, *, table: str, row: Any, column: str, campaign: str | None = None,
               optional: bool = False) -> float | None:
    """The value of number column `column` of `table`'s row `row` as a float (None for SQL NULL when
    `optional`); `DamagedRowError` naming the row when it is not a finite number. SQLite keeps whatever
    was written into a column (text in a REAL column, from a hand edit or another tool), so a reader
    checks the number columns it reads as it checks the JSON ones."""
    if value is None and optional:
        return None
    if isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value):
        return float(value)
    where = f"campaign {campaign}, " if campaign else ""
    raise DamagedRowError(f"damaged store row: {where}table {table}, id {row}: {column} is not a number "
                          f"({str(value)[:40]!r})")


def floats(text: str | None) -> tuple[float, ...] | None:
    """A JSON column holding a vector, as a tuple (None for SQL NULL)."""
    value = loads(text)
    return None if value is None else tuple(value)
