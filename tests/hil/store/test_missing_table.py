"""A table or column missing from a store that opened is damage, named as such (exit 2), not a failed
job: the schema is migrated to this hil's version at open, so only a hand's DROP or ALTER removes one
(issue 31, second pass: ``hil show`` with the events table dropped was exit 1)."""

from __future__ import annotations

import sqlite3

import pytest

from hil.store.sqlite_errors import CorruptStoreError, damaged


def _error(sql: str) -> sqlite3.DatabaseError:
    conn = sqlite3.connect(":memory:")
    conn.execute("CREATE TABLE t (a)")
    with pytest.raises(sqlite3.DatabaseError) as info:
        conn.execute(sql)
    return info.value


@pytest.mark.parametrize("sql", ["SELECT * FROM events", "SELECT b FROM t"], ids=["table", "column"])
def test_a_missing_table_or_column_is_a_damaged_store_naming_the_file(sql: str) -> None:
    problem = damaged(_error(sql), "s.db")
    assert isinstance(problem, CorruptStoreError)
    assert str(problem).startswith("s.db is not a readable hil store: no such ")


def test_other_errors_stay_what_they_are() -> None:
    exc = _error("SELEC 1")  # a syntax error is hil's, not the file's
    assert damaged(exc, "s.db") is exc
