"""Issue 19 (smaller): the reading commands (`hil history`, `hil show`) open the store read-only.

They must read a store on read-only media or in a folder the user cannot write (where SQLite cannot
create the WAL's ``-shm`` index), and must never create or change a file: no store made out of a
missing or an empty (0-byte) file, no ``-wal``/``-shm`` left behind, no write accepted.
"""

from __future__ import annotations

import os
import sqlite3
import stat
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from hil.campaign.events import RunStarted
from hil.cli import main
from hil.errors import InputError
from hil.station.config import default_config
from hil.store import SCHEMA_VERSION, RobotIdentity, Store, StoreError
from tests.hil.store.legacy_schema import make_legacy

ROOT = Path(__file__).resolve().parents[3]
NOBODY = 65534


def _store_with_a_campaign(path: Path) -> str:
    with Store.open(path) as s:
        cid = s.create_campaign(default_config().as_dict(), RobotIdentity("ur5e", "2023550001"))
        s.save_plan(cid, [(i, "calibration", [0.1 * i] * 6) for i in range(3)])
        s.record_event(RunStarted(campaign=cid, robot="ur5e", station="cell", poses=3))
        s.record_measurement(cid, 0, "calibration", [0.0] * 6, [1.0, 2.0, 3.0], t=1.7e9)
    return cid


@pytest.fixture
def shared_dir() -> Iterator[Path]:
    """A folder another user can enter (pytest's tmp_path is private to its owner)."""
    path = Path(tempfile.mkdtemp(prefix="hil-ro-"))
    path.chmod(0o755)
    try:
        yield path
    finally:
        path.chmod(0o755)
        for child in path.iterdir():
            child.unlink()
        path.rmdir()


def _run_unprivileged(args: list[str]) -> subprocess.CompletedProcess[str]:
    """`hil ARGS` as a user who cannot write the store's folder.

    As root, permissions do not bind, so the command runs as ``nobody`` (util-linux ``setpriv``);
    as anyone else, the chmod of the folder is enough."""
    drop = (["setpriv", f"--reuid={NOBODY}", f"--regid={NOBODY}", "--clear-groups"]
            if os.geteuid() == 0 else [])
    return subprocess.run([*drop, sys.executable, "-m", "hil", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=60,
                          env={**os.environ, "PYTHONPATH": str(ROOT)})


def test_history_and_show_read_a_store_in_a_read_only_folder(shared_dir):
    db = shared_dir / "s.db"
    cid = _store_with_a_campaign(db)
    db.chmod(0o444)
    shared_dir.chmod(0o555)
    before = sorted(os.listdir(shared_dir))
    history = _run_unprivileged(["history", "--db", str(db)])
    assert history.returncode == 0, history.stderr
    assert cid in history.stdout
    show = _run_unprivileged(["show", "last", "--db", str(db)])
    assert show.returncode == 0, show.stderr
    assert f"campaign {cid}" in show.stdout and "1 measured" in show.stdout
    assert sorted(os.listdir(shared_dir)) == before == ["s.db"]


def test_read_only_folder_with_uncheckpointed_wal_reads_the_wal(shared_dir):
    """A copy taken while a writer held the file has its commits in ``-wal``: they are read, not
    hidden (``immutable`` would hide them)."""
    db = shared_dir / "s.db"
    _store_with_a_campaign(db)
    writer = sqlite3.connect(db, isolation_level=None)
    writer.execute("PRAGMA wal_autocheckpoint = 0")
    writer.execute("UPDATE stations SET name = 'renamed-in-the-wal'")
    for suffix in ("", "-wal", "-shm"):  # the files as a crash (or a copy of a live store) leaves them
        (shared_dir / f"c.db{suffix}").write_bytes((shared_dir / f"s.db{suffix}").read_bytes())
    writer.close()
    (shared_dir / "s.db").unlink()
    assert sorted(os.listdir(shared_dir)) == ["c.db", "c.db-shm", "c.db-wal"]
    assert (shared_dir / "c.db-wal").stat().st_size > 0
    for name in os.listdir(shared_dir):
        (shared_dir / name).chmod(stat.S_IRUSR | stat.S_IRGRP | stat.S_IROTH)
    shared_dir.chmod(0o555)
    history = _run_unprivileged(["history", "--db", str(shared_dir / "c.db")])
    assert history.returncode == 0, history.stderr
    assert "renamed-in" in history.stdout


@pytest.mark.parametrize("command", [["history"], ["show", "last"]])
def test_empty_file_is_not_turned_into_a_store(tmp_path, capsys, command):
    empty = tmp_path / "x.db"
    empty.touch()
    assert main([*command, "--db", str(empty)]) == 2
    assert capsys.readouterr().err == f"hil: error: {empty} is empty: not a hil store\n"
    assert empty.stat().st_size == 0
    assert sorted(os.listdir(tmp_path)) == ["x.db"]


def test_missing_file_is_not_created(tmp_path, capsys):
    missing = tmp_path / "sub" / "x.db"
    assert main(["history", "--db", str(missing)]) == 2
    assert "no such database" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_reading_leaves_the_folder_as_it_was_and_refuses_writes(tmp_path):
    db = tmp_path / "s.db"
    cid = _store_with_a_campaign(db)
    assert os.listdir(tmp_path) == ["s.db"]
    with Store.open(db, readonly=True) as s:
        assert [c.id for c in s.campaigns()] == [cid]
        with pytest.raises(StoreError, match="read-only"):
            s.set_status(cid, "aborted")
    assert os.listdir(tmp_path) == ["s.db"]
    with Store.open(db) as s:
        assert s.campaign(cid).summary.status == "running"


def test_a_plain_sqlite_file_is_not_a_store(tmp_path):
    other = tmp_path / "other.db"
    conn = sqlite3.connect(other)
    conn.executescript("CREATE TABLE t (a); DROP TABLE t;")  # a valid database with no tables
    conn.close()
    size = other.stat().st_size
    with pytest.raises(InputError, match="not a hil store"):
        Store.open(other, readonly=True)
    assert other.stat().st_size == size
    conn = sqlite3.connect(other)
    assert conn.execute("SELECT count(*) FROM sqlite_master").fetchone()[0] == 0
    conn.close()


def test_an_older_store_is_upgraded_when_writable(tmp_path):
    db = tmp_path / "old.db"
    make_legacy(db, 1)
    with Store.open(db, readonly=True) as s:
        assert s.campaigns() == []
    conn = sqlite3.connect(db)
    assert conn.execute("PRAGMA user_version").fetchone()[0] == SCHEMA_VERSION
    conn.close()
