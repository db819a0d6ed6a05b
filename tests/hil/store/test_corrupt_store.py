"""A store with garbage written into it is bad input naming the file (exit 2), not an internal error.

Issue 19: ``hil history``, ``hil show`` and ``hil calibrate --db`` on a database corrupted mid-file
ended with exit 70 ("internal error: DatabaseError: database disk image is malformed"): SQLite opens
such a file happily and fails only when a query reaches the damaged page.
"""

from __future__ import annotations

import sqlite3
from pathlib import Path

import pytest

from hil.cli import main
from hil.errors import InputError
from hil.station.config import default_config
from hil.store import RobotIdentity, Store, StoreError


def make_store(path: Path) -> Path:
    """A store of three campaigns with plans and measurements, checkpointed into the one file."""
    config = default_config().as_dict()
    with Store.open(path) as store:
        for k in range(3):
            cid = store.create_campaign(config, RobotIdentity("ur5e", f"20235500{k}"), now=1.7e9 + k)
            store.save_plan(cid, [(i, "calibration", [0.01 * i] * 6) for i in range(40)])
            for i in range(40):
                store.record_measurement(cid, i, "calibration", [0.01 * i] * 6, [1.0, 2.0, 0.001 * i],
                                         t=1.7e9 + k + i)
    conn = sqlite3.connect(path)
    conn.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    conn.close()
    return path


def damage(path: Path, table: str | None = None) -> bytes:
    """Overwrite one page with garbage: the root page of `table`, else the page in the middle of the
    file (what the issue's sweep did). Returns the damaged file's bytes."""
    conn = sqlite3.connect(path)
    size = conn.execute("PRAGMA page_size").fetchone()[0]
    root = None if table is None else conn.execute(
        "SELECT rootpage FROM sqlite_master WHERE name = ?", (table,)).fetchone()[0]
    conn.close()
    raw = bytearray(path.read_bytes())
    start = (root - 1) * size if root else (len(raw) // 2) // size * size
    raw[start:start + size] = b"\xa5" * size
    path.write_bytes(bytes(raw))
    return bytes(raw)


@pytest.fixture
def no_hardware(monkeypatch: pytest.MonkeyPatch) -> None:
    import hil.station.devices

    def tripwire(config: object) -> None:
        raise AssertionError("connected to the station before refusing the damaged store")

    monkeypatch.setattr(hil.station.devices, "open_devices", tripwire)
    monkeypatch.setattr(hil.station.devices, "ask_controller", tripwire)  # asking it connects too


@pytest.mark.parametrize("argv", [["history"], ["history", "--json"], ["show", "last"],
                                  ["show", "last", "--json"]], ids=" ".join)
def test_readers_name_the_damaged_file(argv: list[str], tmp_path: Path,
                                       capsys: pytest.CaptureFixture[str]) -> None:
    db = make_store(tmp_path / "k.db")
    before = damage(db, "campaigns")
    assert main([*argv, "--db", str(db)]) == 2
    err = capsys.readouterr().err
    assert err == f"hil: error: {db} is not a readable hil store: database disk image is malformed\n"
    assert db.read_bytes() == before  # a reader never "repairs" (rewrites) the file


def test_garbage_in_the_middle_of_the_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    db = make_store(tmp_path / "k.db")
    damage(db)
    codes = [main(["history", "--db", str(db)]), main(["show", "last", "--db", str(db)])]
    err = capsys.readouterr().err
    assert 70 not in codes, err
    # the list may not read the damaged page; when it does, it is bad input naming the file
    for line in err.strip().splitlines():  # `hil history` names the store it read on stderr
        assert line.startswith((f"hil: error: {db}", f"database: {db}")), err


@pytest.mark.parametrize("table", ["measurements", "campaigns", None], ids=str)
def test_calibrate_refuses_a_damaged_store_before_connecting(
        table: str | None, tmp_path: Path, capsys: pytest.CaptureFixture[str], no_hardware: None) -> None:
    """A writer checks the whole file at open: damage anywhere, even in pages the first queries do
    not read, is refused before the arm is connected (and before anything is appended to it)."""
    db = make_store(tmp_path / "k.db")
    before = damage(db, table)
    config = tmp_path / "station.toml"
    config.write_text('[robot]\naddress = "127.0.0.77"\n[tracker]\nurl = "/dev/ttyFAKE"\n')
    assert main(["calibrate", "--config", str(config), "--db", str(db)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and f"{db}" in err and "not a readable hil store" in err, err
    assert db.read_bytes() == before


def test_the_store_error_is_both_bad_input_and_a_store_failure(tmp_path: Path) -> None:
    """Bad input for the command line (exit 2); a StoreError for a run that meets it mid-campaign."""
    db = make_store(tmp_path / "k.db")
    damage(db, "campaigns")
    with Store(db, readonly=True) as store, pytest.raises(InputError) as info:
        store.campaigns()
    assert isinstance(info.value, StoreError) and str(db) in str(info.value)


def test_a_sound_store_opens_and_reads(tmp_path: Path) -> None:
    """The check at open does not refuse a store that is merely full of data."""
    db = make_store(tmp_path / "k.db")
    with Store.open(db) as store:
        assert len(store.campaigns()) == 3
