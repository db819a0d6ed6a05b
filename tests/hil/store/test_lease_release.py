"""Issue 19 follow-up: `Lease.release` is best-effort. A run ends, often because the disk filled up, and
its lease cannot be deleted then: release logs a warning and returns (the run's own failure stays the
news: `hil calibrate` exits 3 naming the write that failed), and the row left behind lapses on its
own once its process is gone — the next claim takes it over.

The full disk is tests/hil/campaign/full_disk.py (SQLite writes refused on cue); the "process gone"
case runs the owner as a real child process that exits after its failed release.
"""

from __future__ import annotations

import json
import logging
import os
import subprocess
import sys
import textwrap
from pathlib import Path

from hil.station.config import default_config
from hil.store import RobotIdentity, Store
from tests.hil.campaign.full_disk import FullDisk
from tests.hil.store.raw import raw

ROOT = Path(__file__).resolve().parents[3]
ROBOT = RobotIdentity(type="ur5e", serial="20235500777", model="UR5e", software="5.15.0")


def held(db: Path) -> dict[str, int]:
    """The lease rows: name -> the pid holding it."""
    with Store.open(db) as s:
        return {name: json.loads(owner)["pid"] for name, owner in
                raw(s).execute("SELECT name, owner FROM leases")}


def test_release_on_a_full_disk_warns_and_does_not_raise(tmp_path, monkeypatch, caplog):
    db = tmp_path / "hil.db"
    disk = FullDisk(monkeypatch)
    with Store.open(db) as store:
        lease = store.claim_new(default_config().as_dict(), ROBOT)
        disk.full = True
        with caplog.at_level(logging.WARNING, logger="hil.store.leases"):
            lease.release()  # must not raise
            lease.release()  # a second release does nothing (no second attempt, no second warning)
        (record,) = [r for r in caplog.records if r.name == "hil.store.leases"]
        assert record.levelno == logging.WARNING
        assert record.getMessage().startswith(f"could not release the lease of campaign {lease.campaign}: ")
        assert "database or disk is full" in record.getMessage()
        assert lease.lost.is_set()  # the heartbeat has stopped: it renews nothing any more
    disk.make_room()
    # the row stayed (the disk was full); it is this live process's, so it still holds
    assert set(held(db)) == {f"campaign:{lease.campaign}", f"robot:{ROBOT.serial}"}


OWNER = textwrap.dedent("""
    import os
    import sys

    import pytest
    from hil.station.config import default_config
    from hil.store import RobotIdentity, Store
    from tests.hil.campaign.full_disk import FullDisk

    disk = FullDisk(pytest.MonkeyPatch())
    store = Store.open(sys.argv[1])
    lease = store.claim_new(default_config().as_dict(), RobotIdentity(type="ur5e", serial=sys.argv[2]))
    print(lease.campaign, os.getpid(), flush=True)
    disk.full = True
    lease.release()
    print("released", flush=True)
""")


def test_a_lease_its_owner_could_not_release_lapses_when_the_owner_has_ended(tmp_path):
    db = tmp_path / "hil.db"
    Store.open(db).close()
    child = subprocess.run([sys.executable, "-c", OWNER, str(db), ROBOT.serial], cwd=ROOT,
                           capture_output=True, text=True, timeout=60)
    assert child.returncode == 0, child.stderr  # no traceback out of release
    campaign, pid, done = child.stdout.split()
    assert done == "released"
    assert "Traceback" not in child.stderr
    assert f"could not release the lease of campaign {campaign}: " in child.stderr  # the warning
    rows = held(db)  # the disk was full: the rows stayed, naming the (now ended) owner
    assert rows == {f"campaign:{campaign}": int(pid), f"robot:{ROBOT.serial}": int(pid)}
    # its process has ended: the campaign is resumable and the arm free, without waiting for any ttl
    with Store.open(db) as store, store.claim(campaign, ROBOT.serial, heartbeat=False):
        assert held(db) == dict.fromkeys(rows, os.getpid())
