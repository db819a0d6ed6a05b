"""`hil calibrate` on a PostgreSQL store (issue 18): the same guarantees as on SQLite.

- The database server stopped and restarted mid-campaign: the run waits (the arm stands at its pose,
  the command says why), then continues; every pose is measured once, nothing is lost or doubled.
- A database that stays away longer than the store waits: a station fault (exit 3), the campaign
  resumable once it is back, what was measured kept.
- ``kill -9`` of the real command on the simulated station, then the same command again: the same
  campaign continues from what PostgreSQL kept.

The in-process tests drive the real CLI on the engine's fake arm and tracker (`Cell`); the kill -9
test runs the real command in a subprocess on the simulated UR and tracker.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
from collections import Counter
from pathlib import Path

from hil.store import Store
from tests.hil.cli.test_calibrate_interrupt import Cell

ROOT = Path(__file__).resolve().parents[3]


def _stop_at(cell: Cell, measured: int, action) -> None:
    """Run `action` in the engine's thread as the `measured`-th point is taken (before it is recorded)."""
    measure = cell.tracker.measure_point

    def measure_point(*args, **kwargs):
        result = measure(*args, **kwargs)
        if cell.tracker.measurements == measured:
            action()
        return result

    cell.tracker.measure_point = measure_point


def test_the_database_restarted_mid_campaign_suspends_the_run_and_loses_nothing(
        tmp_path, monkeypatch, capsys, own_postgres):
    cell = Cell(tmp_path, monkeypatch)
    cell.db = own_postgres.create_database("cell")
    restarted = threading.Event()

    def outage() -> None:
        own_postgres.stop()
        timer = threading.Timer(2.0, lambda: (own_postgres.start(), restarted.set()))
        timer.daemon = True
        timer.start()

    _stop_at(cell, 5, outage)
    code = cell.calibrate()
    err = capsys.readouterr().err
    # the run needed the server back to finish; the timer thread may still be returning from start()
    assert restarted.wait(30)
    assert code in (0, 1), err  # accepted or rejected: the run finished
    assert "database link lost" in err and "the arm waits at its pose" in err, err
    assert "database link back" in err, err
    assert "Traceback" not in err
    kept = cell.measurements()
    assert set(kept.values()) == {1}, kept  # each pose once: the retried write was not doubled
    with Store.open(cell.db) as store:
        (summary,) = store.campaigns()
        assert summary.status in ("accepted", "rejected")
        assert summary.measured + summary.skipped == summary.planned == 16
        events = Counter(e["event"] for _, e in store.event_log(summary.id))
        assert events["PointMeasured"] == len(kept)  # one event per kept point
        seqs = [seq for seq, _ in store.event_log(summary.id)]
        assert seqs == list(range(1, len(seqs) + 1))  # no gap, no double


def test_a_database_that_stays_away_is_a_station_fault_and_the_campaign_resumes(
        tmp_path, monkeypatch, capsys, own_postgres):
    cell = Cell(tmp_path, monkeypatch)
    cell.db = own_postgres.create_database("cell")
    cell.config.write_text(cell.config.read_text() + "[timeouts]\ndatabase = 1.5\n")
    _stop_at(cell, 4, own_postgres.stop)
    code = cell.calibrate()
    err = capsys.readouterr().err
    assert code == 3, err
    assert "did not come back within 1.5 s" in err, err
    assert "Traceback" not in err
    own_postgres.start()
    kept = cell.measurements()
    assert len(kept) == 3 and set(kept.values()) == {1}  # the 4th point was never kept: re-measured
    with Store.open(cell.db) as store:
        assert store.campaigns()[0].status not in ("accepted", "rejected", "aborted")  # resumable
    code = cell.calibrate()
    err = capsys.readouterr().err
    assert code in (0, 1), err
    resumed = cell.measurements()
    assert set(resumed.values()) == {1}
    with Store.open(cell.db) as store:
        (summary,) = store.campaigns()
        assert summary.measured + summary.skipped == summary.planned == 16
    assert all(resumed[i] == 1 for i in kept)  # the three kept ones were not measured again


def test_kill_9_then_the_same_command_continues_the_campaign_on_postgresql(tmp_path, pg_url):
    command = [sys.executable, "-m", "hil", "calibrate", "--sim", "--ideal",
               "--speed", "200", "--poses", "12",
               "--validation", "4", "--candidates", "1000", "--db", pg_url, "--out", str(tmp_path / "r.json"),
               "--no-warmup"]
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.Popen(command, cwd=ROOT, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True, env=env)
    try:
        assert proc.stderr is not None
        seen: list[str] = []
        while sum("measured pose" in line for line in seen) < 6:
            line = proc.stderr.readline()
            assert line, f"hil calibrate ended early: {''.join(seen[-5:])}"
            seen.append(line)
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait(10)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(10)
    with Store.open(pg_url) as store:
        (first,) = store.campaigns()
        before = {i: m.t for i, m in store.measured_poses(first.id).items()}
        targets = {p.index: p.target for p in store.poses(first.id)}
    assert len(before) >= 6
    done = subprocess.run(command, cwd=ROOT, stdin=subprocess.DEVNULL, capture_output=True, text=True,
                          env=env, timeout=600)
    assert done.returncode in (0, 1), done.stderr[-2000:]
    with Store.open(pg_url) as store:
        (again,) = store.campaigns()
        assert again.id == first.id  # the same campaign continued
        after = store.measured_poses(first.id)
        rows = Counter(m.index for m in store.measurements(first.id))
        assert {p.index: p.target for p in store.poses(first.id) if p.index in targets} == targets
    assert all(after[i].t == t for i, t in before.items())  # nothing measured before was measured again
    assert set(rows.values()) == {1}
    assert again.measured + again.skipped == again.planned == 16

