"""A first open that SQLite refuses at once ("database is locked" without waiting) is tried again."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

import hil.store.transactions as transactions
from hil.store import Store
from hil.store.sqlite_errors import StoreError


def _locked_for(monkeypatch: pytest.MonkeyPatch, times: int) -> list[int]:
    """`check_intact` refuses the first `times` opens as SQLite does where its busy handler could
    deadlock (sqlite3_busy_handler: SQLITE_BUSY returned at once): four threads racing a new file's
    first open met it under load (test_engines' first-opens race)."""
    calls: list[int] = []
    real = transactions.check_intact

    def check(raw: sqlite3.Connection, where: str) -> None:
        calls.append(1)
        if len(calls) <= times:
            raise sqlite3.OperationalError("database is locked")
        real(raw, where)

    monkeypatch.setattr(transactions, "check_intact", check)
    return calls


def test_a_first_open_refused_at_once_is_tried_again(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    calls = _locked_for(monkeypatch, 2)
    with Store.open(tmp_path / "hil.db") as store:
        assert store.campaigns() == []
    assert len(calls) == 3


def test_a_store_locked_past_the_timeout_is_a_store_error_naming_it(tmp_path: Path,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    _locked_for(monkeypatch, 10**6)
    with pytest.raises(StoreError, match=r"hil\.db: database is locked .*0\.3 s"):
        Store.open(tmp_path / "hil.db", timeout=0.3)
