"""A calibration campaign as a job (`hil.jobs.calibration`): claimed, run and its result stored, on the
terminal app's in-process fake station (tests/hil/tui/fake_station.py: a real engine, store and plan,
fake devices and a quick pose chooser; a small campaign takes about a second)."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from drivers.robot.errors import RobotUnreachable
from hil.campaign.events import Event, PointMeasured, RunFinished
from hil.errors import InputError
from hil.jobs.calibration import (
    CalibrationOutcome,
    CalibrationRequest,
    Resume,
    StoreGate,
    calibrate,
    check_pose_count,
    run_calibration,
)
from hil.jobs.outcome import EXIT_FAILED, EXIT_FAULT, EXIT_INTERRUPTED, EXIT_OK
from hil.jobs.station import StationSetup, StationSource, take_station
from hil.station.config import minimum_calibration_poses
from hil.store import FINISHED, RobotIdentity, StoreError, address_lock
from tests.hil.tui.fake_station import SERIAL, FakeStation

EXIT_OF = {"accepted": EXIT_OK, "rejected": EXIT_FAILED}


@pytest.fixture
def station(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, address: str) -> Iterator[FakeStation]:
    st = FakeStation(tmp_path, monkeypatch)
    st.config = st.config.with_overrides(robot__address=address)
    yield st
    st.store.close()


def run(st: FakeStation, *, resume: Resume = "find", **kwargs: Any) -> CalibrationOutcome:
    """One `run_calibration` on the fake station, taken as every job takes it."""
    request = CalibrationRequest(StationSource(config=st.config), resume=resume)
    with take_station(st.config, what="test", store=st.store) as taken:
        return run_calibration(request, StationSetup(st.config, st.config.as_dict(), None), taken, **kwargs)


def test_a_run_claims_a_campaign_and_stores_its_result(station: FakeStation) -> None:
    st = station
    claimed: list[tuple[str, int]] = []
    stored: list[int] = []  # points in the store as each PointMeasured is heard

    def hear(event: Event) -> None:
        if isinstance(event, PointMeasured):
            stored.append(len(st.store.measurements(claimed[0][0])))

    out = run(st, subscribers=[hear], on_claimed=lambda c: claimed.append((c, st.arm.moves)))
    assert claimed == [(out.campaign, 0)]  # claimed before the first motion
    assert out.status in EXIT_OF and out.exit_code == EXIT_OF[out.status] and out.recorded and out.finished
    rec = st.store.campaign(out.campaign)
    assert rec.summary.status == out.status
    assert rec.result is not None and rec.result["status"] == out.status == out.document["status"]
    assert rec.robot.serial == SERIAL
    # every point committed before anyone else hears of it (the store's subscriber is critical)
    assert len(stored) > 1 and stored == list(range(1, len(stored) + 1))
    assert len(rec.measurements) == len(stored) == sum(isinstance(e, PointMeasured) for e in out.events)
    assert isinstance(out.events[-1], RunFinished)
    assert st.store.leases() == []  # the campaign's lease let go


def test_resume_only_without_an_unfinished_campaign_is_bad_input_before_anything_moves(
        station: FakeStation) -> None:
    st = station
    identity = st.config.as_dict()
    done = st.store.create_campaign(identity, RobotIdentity(type="ur5e", serial=SERIAL))
    st.store.set_status(done, "accepted")  # finished: nothing to resume
    other_arm = st.store.create_campaign(identity, RobotIdentity(type="ur5e", serial="20235599999"))
    st.store.set_status(other_arm, "interrupted")  # unfinished, but of another robot
    with pytest.raises(InputError, match="^--resume: no unfinished campaign of this station, robot"):
        run(st, resume="only")
    assert st.arm.moves == 0
    assert {c.id: c.status for c in st.store.campaigns()} == {done: "accepted", other_arm: "interrupted"}


def test_an_abandoned_gate_writes_nothing_more_and_the_campaign_stays_resumable(station: FakeStation) -> None:
    st = station
    gate = StoreGate()
    campaign: list[str] = []
    stored: list[int] = []

    def give_up(event: Event) -> None:  # the app's quit outwaiting the run, after the first point
        if isinstance(event, PointMeasured):
            stored.append(len(st.store.measurements(campaign[0])))
            gate.abandon(lambda: st.store.set_status(campaign[0], "interrupted", detail="given up"))

    out = run(st, subscribers=[give_up], gate=gate, on_claimed=campaign.append)
    assert gate.abandoned and gate.abandon(lambda: None) is False  # closed once
    assert len(stored) > 1 and set(stored) == {1}  # the stored points stopped at the first
    rec = st.store.campaign(out.campaign)
    assert len(rec.measurements) == 1
    assert (rec.summary.status, rec.detail, rec.result) == ("interrupted", "given up", None)  # not the run's
    assert "RunFinished" not in rec.event_counts

    again = run(st, resume="only")  # the campaign given up is continued, not started afresh
    assert again.campaign == out.campaign and again.status in EXIT_OF
    assert len(st.store.measurements(out.campaign)) == len(stored)
    assert st.store.campaign(out.campaign).summary.status == again.status


def test_status_of_decides_the_stored_status_and_its_words(station: FakeStation) -> None:
    st = station
    heard: list[tuple[Any, list[Event]]] = []

    def judged(outcome: Any, events: list[Event]) -> tuple[str, str]:
        heard.append((outcome, events))
        return "rejected", "judged by the caller"

    out = run(st, status_of=judged)
    ((outcome, events),) = heard
    assert outcome is out.run and outcome.status in EXIT_OF and events is out.events
    assert isinstance(events[-1], RunFinished)  # the whole run, its end included
    assert out.document is not None
    assert (out.status, out.detail, out.document["status"]) == (
        "rejected", "judged by the caller", "rejected")
    rec = st.store.campaign(out.campaign)
    assert (rec.summary.status, rec.detail, rec.result["status"]) == (
        "rejected", "judged by the caller", "rejected")


def test_a_store_that_refuses_the_result_is_a_fault_said(
        station: FakeStation, monkeypatch: pytest.MonkeyPatch) -> None:
    st = station
    said: list[tuple[str, str]] = []

    def full(*_args: Any, **_kw: Any) -> None:
        raise StoreError("database or disk is full")

    monkeypatch.setattr(st.store, "set_status", full)
    out = run(st, say=lambda text, severity: said.append((text, severity)))
    assert (out.exit_code, out.recorded) == (EXIT_FAULT, False)
    assert out.status in EXIT_OF  # how the run ended, even though the store did not take it
    assert len(said) == 1 and said[0][1] == "error"
    assert said[0][0].startswith(f"fault: campaign {out.campaign} ended {out.status}, but could not record "
                                 f"its result in {st.store.location}: database or disk is full")


def test_check_pose_count_refuses_too_few_poses_naming_the_option() -> None:
    need, n = minimum_calibration_poses("ur10e", True)
    check_pose_count(need, None, "ur10e")  # enough
    check_pose_count(None, None, "ur10e")  # not given
    check_pose_count(0, None, "ur10e")  # refused elsewhere as not positive
    with pytest.raises(InputError) as exc:
        check_pose_count(need - 1, None, "ur10e")
    assert str(exc.value) == (f"--poses {need - 1}: too few calibration poses: identifying the {n} "
                              f"parameters of a ur10e from 3 coordinates per pose needs at least {need}")
    with pytest.raises(InputError, match=r"^--poses \d+: .* of a ur5e "):  # the default robot
        check_pose_count(minimum_calibration_poses("ur5e", True)[0] - 1, None, None)


def _source(st: FakeStation) -> StationSource:
    return StationSource.of(config=st.config.with_overrides(tracker__url="socket://127.0.0.1:1"), sim=False)


def test_calibrate_runs_the_whole_job_into_the_store_it_names(station: FakeStation, tmp_path: Path) -> None:
    from hil.store import Store

    db = tmp_path / "calibrate.db"
    said: list[str] = []
    out = calibrate(CalibrationRequest(_source(station), db=str(db)),
                    say=lambda text, severity: said.append(text))
    assert out.status in FINISHED and out.exit_code == EXIT_OF[out.status] and said == []
    with Store.open(db) as store:
        assert [(c.id, c.status) for c in store.campaigns()] == [(out.campaign, out.status)]
    assert station.store.campaigns() == []  # not the fake station's own store
    with address_lock(station.config.robot["address"]):  # the arm let go
        pass


def test_calibrate_on_an_arm_that_does_not_answer_is_a_fault_said_leaving_no_store(
        station: FakeStation, tmp_path: Path) -> None:
    station.reconnects.append(RobotUnreachable("nothing answers at the robot's address"))
    db = tmp_path / "never.db"
    said: list[tuple[str, str]] = []
    out = calibrate(CalibrationRequest(_source(station), db=str(db)),
                    say=lambda text, severity: said.append((text, severity)))
    assert (out.exit_code, out.status, out.document) == (EXIT_FAULT, "failed", None)
    assert said == [("hardware fault: cannot connect: RobotUnreachable: nothing answers at the robot's "
                     "address", "error")]
    assert not db.exists() and station.arm.moves == 0


def test_calibrate_interrupted_says_the_campaign_is_resumable(
        station: FakeStation, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    move = station.arm.move_to

    def interrupted_at_the_third_move(q: Any, **kw: Any) -> Any:
        if station.arm.moves == 2:
            raise KeyboardInterrupt  # Ctrl-C while the arm travels
        return move(q, **kw)

    monkeypatch.setattr(station.arm, "move_to", interrupted_at_the_third_move)
    said: list[tuple[str, str]] = []
    out = calibrate(CalibrationRequest(_source(station), db=str(tmp_path / "c.db")),
                    say=lambda text, severity: said.append((text, severity)))  # a Say as words.py types it
    assert (out.status, out.exit_code, out.recorded) == ("interrupted", EXIT_INTERRUPTED, True)
    assert said[-1] == (f"campaign {out.campaign} is resumable: re-run the same command to continue it",
                        "information")
