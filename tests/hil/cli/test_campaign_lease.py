"""Issue 19, "two campaigns, one arm", through `hil calibrate`: a second command for the campaign (or the
arm) that a live process is running exits 2 with one line naming it and measures nothing; the first
finishes normally, no pose measured twice; after kill -9 a re-run resumes. And a changed tracker URL
resumes the campaign rather than measuring everything again.

In-process on the engine's fakes (the second command starts from inside a move of the first, so it
is certainly "while the first measures"), plus one real two-process run on the simulated station.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

from hil.cli import main
from hil.store import Store
from tests.hil.cli.test_calibrate_interrupt import Cell

ROOT = Path(__file__).resolve().parents[3]


def second_command_during(cell: Cell, after_points: int, *extra: str, lock_dir: Path | None = None) -> dict:
    """Run `hil calibrate` again from inside the first run's move after `after_points` points;
    returns what the second one did (exit code, arm moves and tracker measurements it made)."""
    seen: dict = {}
    move = cell.arm.move_to

    def move_to(q, **kw):
        if not seen and cell.tracker.measurements == after_points:
            moves, points = cell.arm.moves, cell.tracker.measurements
            locks = os.environ["HIL_LOCK_DIR"]
            if lock_dir is not None:  # past the host's address lock (another host, with a shared store)
                os.environ["HIL_LOCK_DIR"] = str(lock_dir)
            try:
                seen["code"] = main(["calibrate", "--config", str(cell.config), "--db", str(cell.db),
                                     "--poses", "12", "--validation", "4", "--out", str(cell.out) + ".b",
                                     *extra])
            finally:
                os.environ["HIL_LOCK_DIR"] = locks
            seen["moves"], seen["points"] = cell.arm.moves - moves, cell.tracker.measurements - points
        return move(q, **kw)

    cell.arm.move_to = move_to
    return seen


@pytest.fixture(params=["sqlite", "postgresql"])
def cell(request, tmp_path, monkeypatch) -> Cell:
    """The fake station on each engine: the store a file, or a PostgreSQL database (the leases must hold
    for a plant's shared store too)."""
    cell = Cell(tmp_path, monkeypatch)
    if request.param == "postgresql":
        cell.db = request.getfixturevalue("pg_url")
    return cell


def refusal(err: str) -> str:
    (line,) = [ln for ln in err.splitlines() if ln.startswith("hil: error:")]
    return line


def test_the_same_command_while_the_first_measures_is_refused_and_the_first_finishes(
        cell, tmp_path, capsys):
    second = second_command_during(cell, 5, lock_dir=tmp_path / "other-locks")
    assert cell.calibrate() in (0, 1)
    assert second["code"] == 2 and second["moves"] == 0 and second["points"] == 0
    with Store.open(cell.db) as store:
        (campaign,) = store.campaigns()
    line = refusal(capsys.readouterr().err)
    assert re.fullmatch(rf"hil: error: campaign {campaign.id} is being run by pid {os.getpid()} on host "
                        r"\S+ since \d{4}-\d\d-\d\d \d\d:\d\d:\d\d: wait for that run to end, or stop it "
                        r"\(a campaign whose process has ended is resumed\)", line), line
    assert campaign.status in ("accepted", "rejected")
    assert max(cell.measurements().values()) == 1  # no pose measured twice
    assert not Path(str(cell.out) + ".b").exists()
    assert cell.opened[1].closed == 1  # the refused command closed the devices it had opened


def test_the_hosts_address_lock_refuses_before_connecting(tmp_path, monkeypatch, capsys):
    cell = Cell(tmp_path, monkeypatch)
    second = second_command_during(cell, 5)
    assert cell.calibrate() in (0, 1)
    assert second == {"code": 2, "moves": 0, "points": 0}
    assert len(cell.opened) == 1  # the second never connected
    line = refusal(capsys.readouterr().err)
    assert line.startswith("hil: error: the robot at 127.0.0.1 is in use by hil calibrate "
                           f"(pid {os.getpid()} ")


def test_a_new_campaign_on_a_driven_arm_is_refused_and_leaves_no_campaign(cell, tmp_path, capsys):
    second = second_command_during(cell, 5, "--new", lock_dir=tmp_path / "other-locks")
    assert cell.calibrate() in (0, 1)
    assert second == {"code": 2, "moves": 0, "points": 0}
    with Store.open(cell.db) as store:
        (campaign,) = store.campaigns()  # the refused --new created nothing
    line = refusal(capsys.readouterr().err)
    assert line.startswith(f"hil: error: robot 20235500042 is being driven by campaign {campaign.id} "
                           f"(pid {os.getpid()} on host ")
    assert line.endswith("a new campaign cannot use it until that run ends")


def test_a_changed_tracker_url_resumes_the_campaign(tmp_path, monkeypatch, capsys):
    cell = Cell(tmp_path, monkeypatch)
    cell.signal_after = (3, signal.SIGINT)
    text = re.sub(r"(?m)^url = .*\n", "", cell.config.read_text())
    cell.config.write_text(text.replace("[tracker]\n", '[tracker]\nurl = "/dev/ttyUSB0"\n'))
    assert cell.calibrate() == 130
    kept = cell.measurements()
    assert len(kept) == 3
    capsys.readouterr()
    # the tracker moved to another port (the same instrument): the campaign continues
    cell.config.write_text(text.replace("[tracker]\n", '[tracker]\nurl = "socket://127.0.0.1:4001"\n'))
    assert cell.calibrate() in (0, 1)
    assert "resuming campaign" in capsys.readouterr().err
    counts = cell.measurements()  # one campaign only (Cell.measurements unpacks one)
    assert set(kept) < set(counts) and max(counts.values()) == 1


def _store_writable(db) -> bool:
    """Whether a write transaction on the SQLite store can start now (nobody holds its write lock)."""
    import sqlite3

    conn = sqlite3.connect(db, timeout=0.2)
    try:
        conn.execute("BEGIN IMMEDIATE")
        conn.rollback()
        return True
    except sqlite3.OperationalError:
        return False
    finally:
        conn.close()


def test_two_real_processes_on_the_simulator(tmp_path):
    """The issue's scenario with real processes: the second `hil calibrate --sim` exits 2 while the
    first measures; after a kill -9 of the first a re-run takes the campaign over and resumes it.
    Three starts of the simulated station: about 30 s on an idle machine."""
    db = tmp_path / "k.db"

    def command(out: str) -> list[str]:
        return [sys.executable, "-m", "hil", "calibrate", "--sim", "--ideal",
                "--speed", "100", "--seed", "5", "--poses",
                "12", "--validation", "3", "--candidates", "500", "--db", str(db), "--json",
                "--out", str(tmp_path / out), "--no-warmup"]

    log = (tmp_path / "first.err").open("w")
    first = subprocess.Popen(command("ra.json"), cwd=ROOT, stdout=subprocess.PIPE, stderr=log, text=True,
                             start_new_session=True)
    try:
        for line in first.stdout:
            event = json.loads(line)
            if event["event"] == "PointMeasured" and event["role"] == "calibration":
                # the first is measuring (the bootstrap is behind it); hold it there, alive, however
                # long the second takes to start on a loaded machine
                os.kill(first.pid, signal.SIGSTOP)
                if _store_writable(db):
                    break
                # stopped in the middle of its next commit (a write lock no live process would keep
                # for long): let it finish that and stop it at a later point instead
                os.kill(first.pid, signal.SIGCONT)
        else:
            raise AssertionError(f"the first ended early:\n{(tmp_path / 'first.err').read_text()[-2000:]}")
        second = subprocess.run(command("rb.json"), cwd=ROOT, capture_output=True, text=True, timeout=120)
        assert second.returncode == 2, second.stderr[-2000:]
        assert re.fullmatch(rf"hil: error: campaign \S+ is being run by pid {first.pid} on host .*\n",
                            second.stderr), second.stderr
        assert second.stdout == ""  # no event: it measured nothing
        assert first.poll() is None  # the first runs on
    finally:
        os.killpg(first.pid, signal.SIGKILL)  # kill -9, its simulator with it
        first.wait()
        first.stdout.close()
        log.close()
    with Store.open(db) as store:
        (killed,) = store.campaigns()
        before = Counter(m.index for m in store.measurements(killed.id))
    assert killed.status == "interrupted" and before
    third = subprocess.run(command("rc.json"), cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert third.returncode in (0, 1), third.stderr[-2000:]
    with Store.open(db) as store:
        (campaign,) = store.campaigns()
        after = Counter(m.index for m in store.measurements(campaign.id))
    assert campaign.id == killed.id and campaign.status in ("accepted", "rejected")
    assert set(before) < set(after) and max(after.values()) == 1  # resumed: nothing measured twice
    assert not (tmp_path / "ra.json").exists() and not (tmp_path / "rb.json").exists()
    assert json.loads((tmp_path / "rc.json").read_text())["status"] == campaign.status
