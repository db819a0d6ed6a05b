"""Reading a station's SQLite store with sqlite3 alone (`hil.store.sqlite_reader`): it answers exactly
as the SQLAlchemy `Store` does on the same file — records, fleet views and every listing command's
output, a damaged row and an empty store included — it takes only a store at this code's schema
(anything else goes to the Store, which accepts, upgrades or refuses it as before), and it writes
nothing."""

from __future__ import annotations

import json
import re
import socket
import sqlite3
import subprocess
from pathlib import Path

import pytest

import hil.store.sqlite_reader as sqlite_reader
from hil.cli import main
from hil.station.config import default_config
from hil.store import RobotIdentity, Store
from hil.store.fleet import calibrations, current_model, fleet, geometry_changes, mark, robot_history
from hil.store.migrate import script_head
from hil.store.schema_version import HEAD
from hil.store.sqlite_errors import StoreError
from hil.store.sqlite_reader import SqliteReader, open_reader
from tests.hil.fleet_data import DAY, HIT_ROBOT, REJECTING, STATIONS, STEADY, T0, Fleet
from tests.hil.store.legacy_schema import make_legacy

NOW = T0 + 100 * DAY


def test_the_schema_revision_the_reader_takes_is_the_migrations_head() -> None:
    assert script_head() == HEAD


def _sql(path: Path, *statements: str) -> None:
    conn = sqlite3.connect(path)
    for s in statements:
        conn.execute(s)
    conn.commit()
    conn.close()


@pytest.fixture
def store_path(_sqlite_fleet: Fleet, tmp_path: Path) -> Path:
    """The realistic fleet (tests/hil/fleet_data.py) and more of what listings show: a calibration
    marked bad, a verification, a run whose process is gone (reads as interrupted), a campaign still in
    its bootstrap, and one of an arm whose serial was not read."""
    path = Path(_sqlite_fleet.copy_to(tmp_path))
    gone = subprocess.Popen(["true"])
    gone.wait()
    owner = {"host": socket.gethostname(), "pid": gone.pid, "boot": "", "started": None}
    with Store.open(path) as s:
        last = [c for c in calibrations(s) if c.serial == STEADY][-1]
        mark(s, last.id, bad=True, reason="hit by a forklift", who="qa@cell")
        config = default_config().as_dict()
        config["station"]["name"] = STATIONS[1]
        check = s.create_campaign(config, RobotIdentity("ur5e", HIT_ROBOT), {"kind": "verification"},
                                  now=T0 + 60 * DAY)
        s.set_status(check, "accepted", result={"cycles": 30, "results": {
            "uncompensated": {"AP_max": 1.2e-3, "RP_max": 30e-6},
            "compensated": {"AP_max": 0.2e-3, "RP_max": 28e-6}}})
        dead = s.create_campaign(config, RobotIdentity("ur10e", REJECTING), now=T0 + 70 * DAY)
        s.save_plan(dead, [(0, "bootstrap", [0.0] * 6), (1, "bootstrap", [0.1] * 6),
                           (2, "calibration", [0.2] * 6)])
        s.record_measurement(dead, 0, "bootstrap", [0.0] * 6, [1, 2, 3], t=T0 + 70 * DAY + 1)
        s.set_status(dead, "running")
        unknown = s.create_campaign(config, None, now=T0 + 80 * DAY)
        s.set_status(unknown, "created")
    _sql(path, "INSERT INTO events (campaign, seq, t, type, data) VALUES "
               f"('{dead}', 1, {T0 + 70 * DAY}, 'RunStarted', '{json.dumps({'owner': owner})}')")
    return path


def both(path: Path):
    """(the SQLAlchemy Store, the sqlite3 reader) on `path`, both read-only."""
    reader = open_reader(path)
    assert isinstance(reader, SqliteReader)
    return Store.open(path, readonly=True, create=False), reader


def test_both_read_the_same_records_and_fleet_views(store_path: Path) -> None:
    store, reader = both(store_path)
    with store, reader:
        history = store.campaigns(None)
        assert reader.campaigns(None) == history and len(history) == 13
        assert {c.status for c in history} >= {"accepted", "rejected", "interrupted", "created"}
        assert reader.campaigns(3, station=STATIONS[1]) == store.campaigns(3, station=STATIONS[1])
        for c in history:
            assert reader.campaign(c.id) == store.campaign(c.id)
            assert reader.measurements(c.id, "calibration") == store.measurements(c.id, "calibration")
            assert reader.pending_poses(c.id, include_skipped=True) == store.pending_poses(
                c.id, include_skipped=True)
            assert reader.resolve_id(c.id) == store.resolve_id(c.id) == c.id
        for text in ("last", history[0].id[:4], "%", "2023_"):
            outcomes = []
            for r in (store, reader):
                try:
                    outcomes.append(r.resolve_id(text))
                except Exception as exc:
                    outcomes.append(f"{type(exc).__name__}: {exc}")
            assert outcomes[0] == outcomes[1]
        assert fleet(reader, now=NOW) == fleet(store, now=NOW)
        assert fleet(reader, station=STATIONS[0], now=NOW) == fleet(store, station=STATIONS[0], now=NOW)
        for serial in (STEADY, HIT_ROBOT, REJECTING):
            history_ = robot_history(reader, serial)
            assert history_ == robot_history(store, serial)
            assert current_model(reader, serial) == current_model(store, serial)
        assert robot_history(reader, HIT_ROBOT).verifications  # the verification is read
        assert calibrations(reader, since=T0 + 10 * DAY) == calibrations(store, since=T0 + 10 * DAY)
        moved = geometry_changes(reader)
        assert moved == geometry_changes(store) and [s for s, _ in moved] == [HIT_ROBOT]


LISTINGS = (["history"], ["history", "--json"], ["history", "--limit", "2", "--station", STATIONS[0]],
            ["show", "last"], ["show", "last", "--json"], ["show", "2023"], ["show", "nope"],
            ["robots"], ["robots", "--json"], ["robots", "--station", "cell-9"],
            ["robot", STEADY], ["robot", HIT_ROBOT, "--json"], ["robot", "999"])


def outputs(argv: list[str], db: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch,
            *, fast: bool) -> tuple[int, str, str]:
    """(exit code, stdout, stderr) of ``hil ARGV --db DB``, read by sqlite3 (`fast`) or the Store."""
    used: list[bool] = []

    def spy(location, **kwargs):
        reader = real(location, **kwargs) if fast else None
        used.append(reader is not None)
        return reader

    real = sqlite_reader.open_reader
    with monkeypatch.context() as m:
        m.setattr(sqlite_reader, "open_reader", spy)
        m.setattr("time.time", lambda: NOW)  # the fleet's ages
        rc = main([*argv, "--db", str(db)])
    out, err = capsys.readouterr()
    assert used == [fast], argv
    return rc, out, err


@pytest.mark.parametrize("argv", LISTINGS, ids=" ".join)
def test_every_listing_prints_the_same_on_both_paths(store_path: Path, argv: list[str], capsys,
                                                     monkeypatch) -> None:
    fast = outputs(argv, store_path, capsys, monkeypatch, fast=True)
    assert fast == outputs(argv, store_path, capsys, monkeypatch, fast=False)
    assert fast[0] in (0, 2) and (fast[1] or fast[2])


@pytest.mark.parametrize(("sql", "argv", "error"), [
    ("UPDATE campaigns SET config = '{broken' WHERE id = (SELECT max(id) FROM campaigns)",
     ["show", "last"], "table campaigns, id .*: config is not valid JSON"),
    ("UPDATE measurements SET p = '[1, \"x\"]' WHERE id = 1", ["show", "{first}"],
     "table measurements, id 1: p is not a list of numbers"),
    ("UPDATE events SET data = 'nope' WHERE type = 'RunStarted'", ["history"], None),
])
def test_a_damaged_row_is_named_alike_on_both_paths(store_path: Path, sql: str, argv: list[str],
                                                    error: str | None, capsys, monkeypatch) -> None:
    _sql(store_path, sql)
    conn = sqlite3.connect(store_path)
    first = conn.execute("SELECT campaign FROM measurements WHERE id = 1").fetchone()[0]
    conn.close()
    argv = [a.format(first=first) for a in argv]
    rc, out, err = outputs(argv, store_path, capsys, monkeypatch, fast=True)
    assert (rc, out, err) == outputs(argv, store_path, capsys, monkeypatch, fast=False)
    if error is None:
        assert rc == 0 and "interrupted" not in out  # its RunStarted unreadable: read as running
    else:
        assert rc == 2 and not out
        assert len(err.splitlines()) == 1
        assert re.search(f"^hil: error: damaged store row: campaign .*{error}", err), err


@pytest.mark.parametrize("argv", [["history"], ["history", "--json"], ["show", "last"], ["robots"],
                                  ["robots", "--json"], ["robot", STEADY]], ids=" ".join)
def test_an_empty_store_lists_alike_on_both_paths(tmp_path: Path, argv: list[str], capsys,
                                                  monkeypatch) -> None:
    db = tmp_path / "empty.db"
    Store.open(db).close()
    fast = outputs(argv, db, capsys, monkeypatch, fast=True)
    assert fast == outputs(argv, db, capsys, monkeypatch, fast=False)


def test_the_reader_takes_only_a_store_at_this_schema(tmp_path: Path) -> None:
    """Everything else is the Store's to accept, upgrade or refuse, with today's messages."""
    (tmp_path / "empty.db").write_bytes(b"")
    (tmp_path / "text.db").write_text("not a database\n")
    (tmp_path / "folder.db").mkdir()
    foreign = tmp_path / "foreign.db"
    _sql(foreign, "CREATE TABLE t (x)")
    newer = tmp_path / "newer.db"
    Store.open(newer).close()
    _sql(newer, "UPDATE alembic_version SET version_num = '0099'")
    newer_number = tmp_path / "newer-number.db"
    Store.open(newer_number).close()
    _sql(newer_number, "PRAGMA user_version = 99")
    older = make_legacy(tmp_path / "older.db", 3)
    for location in ("postgresql://hil@localhost/hil", tmp_path / "missing.db", tmp_path / "empty.db",
                     tmp_path / "text.db", tmp_path / "folder.db", foreign, newer, newer_number, older):
        assert open_reader(location) is None, location
    current = tmp_path / "current.db"
    Store.open(current).close()
    reader = open_reader(current)
    assert isinstance(reader, SqliteReader)
    reader.close()


@pytest.mark.parametrize("name", ["missing.db", "text.db", "newer.db"])
def test_a_store_the_reader_leaves_is_refused_as_before(tmp_path: Path, name: str, capsys) -> None:
    (tmp_path / "text.db").write_text("not a database\n")
    Store.open(tmp_path / "newer.db").close()
    _sql(tmp_path / "newer.db", "UPDATE alembic_version SET version_num = '0099'")
    assert main(["history", "--db", str(tmp_path / name)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("hil: error: ") and len(err.splitlines()) == 1
    assert {"missing.db": "no such database", "text.db": "not a hil database",
            "newer.db": "newer than this hil supports"}[name] in err


def test_an_older_store_is_listed_after_the_store_upgrades_it(tmp_path: Path, capsys) -> None:
    older = make_legacy(tmp_path / "older.db", 3)
    assert main(["history", "--db", str(older)]) == 0
    reader = open_reader(older)  # the Store upgraded it (as every read-only open did): now at head
    assert isinstance(reader, SqliteReader)
    reader.close()


def test_the_reader_writes_nothing(store_path: Path, capsys) -> None:
    before = sorted(p.name for p in store_path.parent.iterdir()), store_path.read_bytes()
    for argv in (["history"], ["show", "last"], ["robots"], ["robot", STEADY]):
        assert main([*argv, "--db", str(store_path)]) == 0
    assert (sorted(p.name for p in store_path.parent.iterdir()), store_path.read_bytes()) == before
    reader = open_reader(store_path)
    assert reader is not None
    with reader, pytest.raises(StoreError, match="cannot read: attempt to write a readonly database"), \
            reader.snapshot() as rows:
        rows("DELETE FROM marks")
