"""`hil.cli.support.store_options.open_location`: what the listing commands open — a station's SQLite
file at this hil's schema through sqlite3 alone, everything else (a write, an older store, a missing
file) through the Store, exactly as before."""

from __future__ import annotations

from pathlib import Path

import pytest

from hil.cli.support.store_options import open_location
from hil.errors import InputError
from hil.store import Store
from hil.store.sqlite_reader import SqliteReader
from tests.hil.store.legacy_schema import make_legacy


def test_a_current_store_is_read_with_sqlite3_and_written_with_the_store(tmp_path: Path) -> None:
    db = tmp_path / "hil.db"
    Store.open(db).close()
    with open_location(str(db)) as reader:
        assert isinstance(reader, SqliteReader) and reader.campaigns() == []
    with open_location(str(db), readonly=False) as store:
        assert isinstance(store, Store) and not store.readonly


def test_an_older_store_goes_to_the_store_which_upgrades_it(tmp_path: Path) -> None:
    older = make_legacy(tmp_path / "older.db", 2)
    with open_location(str(older)) as store:
        assert isinstance(store, Store)
    with open_location(str(older)) as reader:  # upgraded by the first open: now at the head
        assert isinstance(reader, SqliteReader)


def test_a_missing_store_is_bad_input_as_before(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such database"):
        open_location(str(tmp_path / "missing.db"))
    assert not (tmp_path / "missing.db").exists()
