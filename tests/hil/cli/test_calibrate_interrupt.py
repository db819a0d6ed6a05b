"""Ctrl-C, SIGTERM and SIGHUP during `hil calibrate`: the arm stops, the campaign stays resumable, the exit
is clean (128 + the signal number), and an earlier result file is left alone.

Most of it runs the real CLI in this process on the engine's fake arm and tracker (tests/hil/campaign/
fakes.py), a real signal raised from inside a move; one test drives the real command in a subprocess
on the simulated station, because only there do the ur_rtde client's child process and the simulator
share the terminal's process group with it.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections import Counter
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from hil.calibration.synthetic import random_truth
from hil.campaign.calibration_plan import Choice
from hil.campaign.engine import RunInterrupted
from hil.cli import main
from hil.cli.support.interrupts import interruptible
from hil.store import Store
from tests.hil.campaign.fakes import FakeArm, FakeTracker, visible_poses

ROOT = Path(__file__).resolve().parents[3]


class Devices:
    """`hil.station.devices.Devices` made of the fakes."""

    def __init__(self, arm: FakeArm, tracker: FakeTracker) -> None:
        self.robot, self.tracker = arm, tracker
        self.closed = 0

    def close(self) -> None:
        self.closed += 1


class Cell:
    """One fake station shared by successive `hil calibrate --config` runs (same arm, same store)."""

    def __init__(self, tmp_path: Path, monkeypatch) -> None:
        rng = np.random.default_rng(4)
        self.truth = random_truth("ur5e", rng, ideal=True)
        self.arm = FakeArm(visible_poses(self.truth, 1, rng)[0])
        self.arm.info = SimpleNamespace(serial="20235500042", model="UR5e", software_version="5.15")
        self.tracker = FakeTracker(self.arm, self.truth)
        self.signal_after: tuple[int, int] | None = None  # (points measured, signal)
        self.moves_when_signalled = -1
        self.opened: list[Devices] = []
        move = self.arm.move_to

        def move_to(q, **kw):
            if self.signal_after and self.tracker.measurements == self.signal_after[0]:
                sig, self.signal_after = self.signal_after[1], None
                self.moves_when_signalled = self.arm.moves
                signal.raise_signal(sig)  # as the terminal would, while the arm moves
            return move(q, **kw)

        self.arm.move_to = move_to
        self.config = tmp_path / "station.toml"
        tracker = ", ".join(map(str, self.truth.tracker.translation + 0.05))
        smr = ", ".join(map(str, self.truth.smr + 0.003))
        self.config.write_text(f'[station]\nname = "cell-9"\n[robot]\nsettle_time = 0.0\njoint_samples = 2\n'
                               # one tracker measurement per visit (the signals come after counted ones)
                               'settle = "fixed"\n'
                               f'[tracker]\nurl = "/dev/ttyFAKE"\nposition = [{tracker}]\n'
                               f"[smr]\noffset = [{smr}]\n"
                               "[keep_in]\nmin = [-2.0, -2.0, -0.5]\nmax = [2.0, 2.0, 2.0]\n"
                               "[campaign]\nsamples = 2\nacceptance = 0.01\n"
                               # a wall-clock run counting measurements: no warm-up, no reference visits
                               "[warmup]\nenabled = false\n[drift]\nevery = 0\n")
        self.db, self.out, self.report = tmp_path / "hil.db", tmp_path / "result.json", tmp_path / "r.html"

        def open_devices(config):
            self.opened.append(Devices(self.arm, self.tracker))
            return self.opened[-1]

        def chooser(config):  # random visible poses: the selector's seconds are not what is tested
            def choose(request):
                return Choice(visible_poses(request.model, request.count, rng), {"method": "test"})

            return choose

        monkeypatch.setattr("hil.station.devices.open_devices", open_devices)
        monkeypatch.setattr("hil.station.devices.ask_controller", lambda config: self.arm.info)
        monkeypatch.setattr("hil.campaign.chooser.campaign_chooser", chooser)

    def calibrate(self, *extra: str) -> int:
        return main(["calibrate", "--config", str(self.config), "--db", str(self.db), "--poses", "12",
                     "--validation", "4", "--out", str(self.out), *extra])

    def measurements(self) -> Counter:
        with Store.open(self.db) as store:
            (campaign,) = store.campaigns()
            return Counter(m.index for m in store.measurements(campaign.id))

    def status(self) -> str:
        with Store.open(self.db) as store:
            return store.campaigns()[0].status


def interrupted_run(cell: Cell, capsys, sig: int) -> Counter:
    """Raise `sig` in the move after the 3rd point; check the run ended as an interruption should;
    returns the points kept."""
    cell.out.write_text("an earlier result\n")
    cell.report.write_text("an earlier report\n")
    cell.signal_after = (3, sig)
    assert cell.calibrate("--report", str(cell.report)) == 128 + sig
    err = capsys.readouterr().err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err
    assert "interrupted" in err and "resumable" in err
    assert cell.arm.stops == 1 and cell.arm.moves == cell.moves_when_signalled  # stopped in that move
    assert cell.opened[-1].closed == 1
    assert cell.status() == "interrupted"
    # only a finished campaign writes the result and the report
    assert cell.out.read_text() == "an earlier result\n" and cell.report.read_text() == "an earlier report\n"
    with Store.open(cell.db) as store:
        record = store.campaign(store.resolve_id("last"))
    assert "KeyboardInterrupt" not in json.dumps(record.result) and record.detail.startswith("stopped by")
    kept = cell.measurements()
    assert len(kept) == 3
    return kept


def test_ctrl_c_mid_move_stops_the_arm_and_the_same_command_resumes(tmp_path, monkeypatch, capsys):
    cell = Cell(tmp_path, monkeypatch)
    kept = interrupted_run(cell, capsys, signal.SIGINT)
    # the same command again continues the campaign: nothing measured twice
    assert cell.calibrate() in (0, 1)
    assert "resuming campaign" in capsys.readouterr().err
    counts = cell.measurements()
    with Store.open(cell.db) as store:
        poses = store.poses(store.resolve_id("last"))
    assert len(poses) == 16 and all(p.status in ("measured", "skipped") for p in poses)  # all visited
    assert set(kept) < set(counts) == {p.index for p in poses if p.status == "measured"}
    assert max(counts.values()) == 1
    assert cell.status() in ("accepted", "rejected")
    assert json.loads(cell.out.read_text())["status"] in ("accepted", "rejected")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_are_interruptions_too(tmp_path, monkeypatch, capsys, sig):
    interrupted_run(Cell(tmp_path, monkeypatch), capsys, sig)


def test_interruptible_raises_once_and_restores_the_handlers():
    before = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)}
    with pytest.raises(RunInterrupted) as caught, interruptible() as received:
        signal.raise_signal(signal.SIGTERM)
    assert caught.value.signum == signal.SIGTERM and str(caught.value) == "stopped by SIGTERM"
    with interruptible() as received:  # later signals, while the first one unwinds, are ignored
        with pytest.raises(RunInterrupted):
            signal.raise_signal(signal.SIGINT)
        signal.raise_signal(signal.SIGINT)
    assert received == [signal.SIGINT, signal.SIGINT]
    assert {s: signal.getsignal(s) for s in before} == before


def test_ctrl_c_through_the_real_command_is_clean(tmp_path):
    """The real process group of a terminal: the CLI, ur_rtde's child process (which used to print a
    KeyboardInterrupt traceback of its own) and the simulator (which died with the CLI). About 15 s."""
    out = tmp_path / "result.json"
    out.write_text("an earlier result\n")
    cmd = [sys.executable, "-m", "hil", "calibrate", "--sim", "--ideal",
           "--speed", "40", "--seed", "5", "--poses", "14",
           "--validation", "4", "--candidates", "2000", "--db", str(tmp_path / "hil.db"), "--json",
           "--out", str(out), "--no-warmup"]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)  # its own group, as a shell's foreground job
    events = []
    try:
        for line in proc.stdout:
            events.append(json.loads(line))
            if events[-1]["event"] == "PointMeasured":  # the first (bootstrap) point: the arm moves on
                os.killpg(proc.pid, signal.SIGINT)  # what Ctrl-C does: the whole group
                break
        rest, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    events += [json.loads(line) for line in rest.splitlines()]
    assert proc.returncode == 130, err[-2000:]
    for noise in ("Traceback", "KeyboardInterrupt", "Reconnect", "econnect"):
        assert noise not in err, err[-2000:]
    assert events[-1]["event"] == "RunFinished" and events[-1]["status"] == "interrupted"
    assert out.read_text() == "an earlier result\n"
    with Store.open(tmp_path / "hil.db") as store:
        (summary,) = store.campaigns()
        assert summary.status == "interrupted"
        assert store.find_resumable(store.campaign(summary.id).config,
                                    robot_serial=store.campaign(summary.id).robot.serial) == summary.id
