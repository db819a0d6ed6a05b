"""Issue 19, "Resume and fail-fast", through `hil calibrate`: too few calibration poses are refused before
anything starts or moves (exit 2), and a store whose disk fills up mid-run stops the arm and ends the run
as a fault (exit 3) naming the write that failed, the campaign resumable from what was committed
(re-running it is not done here: this process, which still holds the campaign's lease, is the one
that would have ended).

The real CLI runs in this process on the engine's fake arm and tracker (`Cell`, shared with
test_calibrate_interrupt.py); the full disk is a SQLite connection whose writes fail on cue.
"""

from __future__ import annotations

from collections import Counter

import numpy as np

from hil.cli import main
from hil.store import Store
from tests.hil.campaign.full_disk import FullDisk
from tests.hil.cli.test_calibrate_interrupt import Cell


def _nothing_may_start(monkeypatch) -> None:
    def refuse(*args, **kwargs):
        raise AssertionError("the station was started")

    monkeypatch.setattr("mocks.station.start_station", refuse)


def test_poses_too_few_to_identify_are_refused_before_the_simulated_station_starts(tmp_path, monkeypatch,
                                                                                   capsys):
    _nothing_may_start(monkeypatch)
    db = tmp_path / "hil.db"
    assert main(["calibrate", "--sim", "--speed", "40", "--poses", "3", "--db", str(db)]) == 2
    err = capsys.readouterr().err
    # 27 geometric parameters and the compliance of joints 2, 3 and 4 (the campaign identifies it by default)
    assert err.count("\n") == 1 and "--poses 3" in err and "at least 11" in err and "30 parameters" in err
    assert not db.exists()


def test_poses_too_few_are_refused_before_the_configured_station_is_connected(tmp_path, monkeypatch, capsys):
    cell = Cell(tmp_path, monkeypatch)
    assert main(["calibrate", "--config", str(cell.config), "--db", str(cell.db), "--poses", "10"]) == 2
    assert "--poses 10" in capsys.readouterr().err
    assert cell.opened == [] and cell.arm.moves == 0 and not cell.db.exists()
    assert main(["calibrate", "--config", str(cell.config), "--db", str(cell.db), "--poses", "11",
                 "--validation", "4"]) in (0, 1)  # the least that identifies is accepted


def test_a_configured_count_too_few_to_identify_is_refused_naming_the_key(tmp_path, monkeypatch, capsys):
    cell = Cell(tmp_path, monkeypatch)
    text = cell.config.read_text()
    cell.config.write_text(text.replace("[campaign]\n", "[campaign]\ncalibration_poses = 5\n"))
    assert main(["calibrate", "--config", str(cell.config), "--db", str(cell.db)]) == 2
    err = capsys.readouterr().err
    assert f"{cell.config}: campaign.calibration_poses: 5 is too few" in err and "at least 11" in err
    assert cell.opened == [] and not cell.db.exists()


def test_a_full_disk_mid_run_is_a_fault_naming_the_write_and_the_campaign_resumes(tmp_path, monkeypatch,
                                                                                 capsys):
    disk = FullDisk(monkeypatch, room=5)  # the 6th measurement does not fit
    cell = Cell(tmp_path, monkeypatch)
    cell.out.write_text("an earlier result\n")
    assert cell.calibrate() == 3
    err = capsys.readouterr().err
    assert f"could not record the measurement of pose 5 in {cell.db}: database or disk is full" in err
    for noise in ("RunFinished", "Traceback", "StoreError"):
        assert noise not in err, err
    assert cell.arm.stops >= 1
    with Store.open(cell.db) as store:
        (pose,) = [p for p in store.poses(store.resolve_id("last")) if p.index == 5]
    assert np.allclose(cell.arm.targets[-1], pose.target)  # no move after the write that failed
    assert cell.out.read_text() == "an earlier result\n"

    disk.make_room()
    assert cell.measurements() == Counter(range(5))  # what was committed stays
    with Store.open(cell.db) as store:  # and the campaign is the one the same command continues
        record = store.campaign(store.resolve_id("last"))
        assert record.summary.status not in ("accepted", "rejected", "aborted")
        assert store.find_resumable(record.config, robot_serial=record.robot.serial) == record.summary.id
