"""Issue 17, "Stopping rule" in a running campaign: ``campaign.stop_early`` stops visiting calibration
poses once the fit predicts the acceptance with margin, says why (`AcquisitionStopped`, the result's
``stopping`` block), still measures every validation pose, and keeps the decision across a resume.

The in-process tests run the real plan, engine, runner and SQLite store on the fake arm and tracker
(tests/hil/campaign/fakes.py); the last one runs ``hil calibrate --sim --stop-early`` on the simulated
station, interrupted after the stop and run again.
"""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.arm.geometry import look_at_tracker
from hil.calibration.model_file import truth_document, write_json
from hil.calibration.synthetic import Noise, random_truth
from hil.campaign.calibration_plan import CALIBRATION, VALIDATION, Choice, ResumeState, calibration_plan
from hil.campaign.engine import Engine, RealClock, RunInterrupted
from hil.campaign.events import (
    AcquisitionStopped,
    EventBus,
    PointMeasured,
    PoseSkipped,
    PoseStarted,
    RunFinished,
)
from hil.campaign.runner import plan_saver, resume_state, run_campaign, store_recorder
from hil.cli.support.progress import Progress
from hil.errors import InputError
from hil.report import render_html
from hil.report.data import report_data_from_result
from hil.report.result import result_document
from hil.station.config import default_config
from hil.store import Store
from hil.tui.state import RunState
from tests.hil.campaign.fakes import FakeArm, FakeTracker, visible_poses

ROOT = Path(__file__).resolve().parents[3]


class Devices:
    def __init__(self, arm: FakeArm, tracker: FakeTracker) -> None:
        self.robot, self.tracker = arm, tracker

    def close(self) -> None:
        pass


def fake_config(truth, **overrides):
    """The fake station with its tracker position configured (no bootstrap), the rigid arm's geometry
    alone fitted, 30 calibration and 8 validation poses, the stopping rule on."""
    return default_config().with_overrides(**{
        "campaign__calibration_poses": 30, "campaign__validation_poses": 8, "campaign__samples": 2,
        "robot__settle_time": 0.0, "robot__joint_samples": 2, "smr__offset": tuple(truth.smr + 0.003),
        "tracker__position": tuple(truth.tracker.translation + 0.05), "warmup__enabled": False,
        "drift__every": 0, "campaign__compliance": False, "campaign__stop_early": True,
        "campaign__acceptance": 0.1e-3, **overrides})  # a threshold the rule works to (the old default)


class StopCell:
    """Runs of `run_campaign` on one fake arm and one store, as re-runs of ``hil calibrate`` are."""

    def __init__(self, tmp_path: Path, seed: int = 5, **overrides) -> None:
        rng = np.random.default_rng(seed)
        self.truth = random_truth("ur5e", rng, rigid=True)
        self.arm = FakeArm(visible_poses(self.truth, 1, rng)[0])
        self.tracker = FakeTracker(self.arm, self.truth)
        self.config = fake_config(self.truth, **overrides)
        self.rng = rng
        self.store = Store.open(tmp_path / "hil.db")
        self.campaign = self.store.create_campaign(self.config, "ur5e")
        self.events: list = []
        self.runs: list[list] = []

    def choose(self, request):
        return Choice(visible_poses(request.model, request.count, self.rng), {"method": "test"})

    def run(self, interrupt=None):
        """One run, resuming what the store holds; `interrupt(event)` True stops it as SIGTERM would,
        after the store has recorded that event."""
        mine: list = []

        def interrupter(event):
            if interrupt is not None and interrupt(event):
                raise RunInterrupted(15)

        bus = EventBus()
        bus.subscribe(store_recorder(self.store), critical=True)
        bus.subscribe(plan_saver(self.store, self.campaign), critical=True)
        bus.subscribe(self.events.append, critical=True)
        bus.subscribe(mine.append, critical=True)
        bus.subscribe(interrupter, critical=True)
        self.runs.append(mine)
        resume = resume_state(self.store, self.campaign) if self.store.measured_poses(self.campaign) else None
        return run_campaign(self.config, self.choose, bus=bus, campaign=self.campaign, resume=resume,
                            devices=Devices(self.arm, self.tracker), clock=RealClock())


def of(events, kind, role=None):
    return [e for e in events if isinstance(e, kind) and (role is None or e.role == role)]


def visited(events, role):
    """Poses of `role` measured or passed over by the sight check (the fake chooser's poses face the
    tracker as the plan had it, 5 cm off, so now and then one is predicted hidden, rule or not)."""
    return len(of(events, PointMeasured, role)) + len(of(events, PoseSkipped, role))


def test_the_rule_stops_the_calibration_poses_and_the_campaign_still_validates(tmp_path):
    cell = StopCell(tmp_path)
    outcome = cell.run()
    assert outcome.status == "accepted", outcome.error
    (stop,) = of(cell.events, AcquisitionStopped)
    measured = of(cell.events, PointMeasured, CALIBRATION)
    # (a pose the sight check predicts hidden is passed over, neither measured nor saved)
    assert stop.poses_used == len(measured) and stop.poses_left == len(stop.skipped) > 0
    assert stop.poses_used + stop.poses_left <= 30
    assert stop.predicted_rms <= stop.target == pytest.approx(0.7 * cell.config.campaign["acceptance"])
    assert not {e.index for e in of(cell.events, PoseStarted, CALIBRATION)} & set(stop.skipped)
    # every validation pose
    assert visited(cell.events, VALIDATION) == 8
    result = outcome.result
    assert result.stopping["stopped"] and result.stopping["poses_left"] == stop.poses_left
    assert result.stopping["reason"] == stop.reason and "<=" in stop.reason
    assert result.after.rms <= cell.config.campaign["acceptance"]
    assert "stopped early after" in of(cell.events, RunFinished)[-1].detail  # the summary line
    # the store kept the event, and a reader of the log gets it back whole
    (kept,) = cell.store.events(cell.campaign, types=("AcquisitionStopped",))
    assert kept.figures == stop.figures and kept.skipped == stop.skipped


def test_the_result_file_the_report_and_the_progress_say_why_it_stopped(tmp_path):
    cell = StopCell(tmp_path)
    outcome = cell.run()
    (stop,) = of(cell.events, AcquisitionStopped)
    doc = result_document(outcome, cell.config, cell.events, 0.0, None)
    assert doc["stopping"]["stopped"] and doc["stopping"]["poses_left"] == stop.poses_left
    assert doc["stopping"]["predicted_rms"] == stop.predicted_rms
    assert {"validation", "model", "passed"} <= doc.keys()  # the existing contract stays
    back = report_data_from_result(json.loads(json.dumps(doc)))  # ``hil report --result``
    assert back.stopping == doc["stopping"]
    html = render_html(back, generated="2026-01-01T00:00:00+00:00")
    assert f"Acquisition stopped early: after {stop.poses_used} of" in html
    with pytest.raises(InputError, match="stopping"):
        report_data_from_result({**doc, "stopping": {"stopped": "yes"}}, "r.json")
    with pytest.raises(InputError, match="stopping.poses_left"):
        report_data_from_result({**doc, "stopping": {**doc["stopping"], "poses_left": -1}}, "r.json")
    # the progress lines (CLI) and the run state (TUI): the count shrinks by the poses not needed
    stream = io.StringIO()
    progress, state = Progress(stream, bar=False), RunState()
    for event in cell.events:
        progress(event)
        state.apply(event)
    said = f"stopping early: {stop.reason}; {stop.poses_left} calibration poses not needed"
    assert said in stream.getvalue()
    assert state.planned == 38 - stop.poses_left
    assert progress.total == 38 - stop.poses_left


def test_off_by_default_and_recorded_as_not_stopped_when_every_pose_was_needed(tmp_path):
    off = StopCell(tmp_path / "off", campaign__stop_early=False)
    outcome = off.run()
    assert outcome.result.stopping is None and not of(off.events, AcquisitionStopped)
    assert visited(off.events, CALIBRATION) == 30
    # an acceptance no 30 poses can promise (below the noise): every pose visited, and said why
    strict = StopCell(tmp_path / "strict", campaign__acceptance=20e-6)
    outcome = strict.run()
    assert not of(strict.events, AcquisitionStopped)
    assert visited(strict.events, CALIBRATION) == 30
    assert outcome.result.stopping["stopped"] is False and ">" in outcome.result.stopping["reason"]


def test_a_resume_after_the_stop_keeps_the_decision(tmp_path):
    """Interrupted while measuring the validation poses after the stop: the resumed run visits no
    calibration pose, emits no second stop, and ends with the same record of why it stopped."""
    cell = StopCell(tmp_path)
    stopped = []

    def after_the_stop(event):
        stopped.extend(of([event], AcquisitionStopped))
        return bool(stopped) and isinstance(event, PointMeasured) and event.role == VALIDATION

    assert cell.run(interrupt=after_the_stop).status == "interrupted"
    (stop,) = stopped
    outcome = cell.run()
    assert outcome.status == "accepted", outcome.error
    second = cell.runs[1]
    assert not of(second, PoseStarted, CALIBRATION) and not of(second, AcquisitionStopped)
    assert len(of(second, PointMeasured, VALIDATION)) + len(of(cell.events, PoseSkipped, VALIDATION)) == 7
    assert outcome.result.stopping == stop.figures
    assert sum(1 for p in cell.store.measured_poses(cell.campaign).values()
               if p.role == CALIBRATION) == stop.poses_used


def test_interrupted_before_the_stop_was_recorded_the_same_records_give_the_same_verdict(tmp_path):
    """A run killed right after the pose that satisfies the rule was recorded, before the stop was:
    the resumed run checks those same records first and stops with the same verdict, visiting no
    further calibration pose."""
    reference = StopCell(tmp_path / "a")
    reference.run()
    (expected,) = of(reference.events, AcquisitionStopped)
    last = of(reference.events, PointMeasured, CALIBRATION)[-1].index

    cell = StopCell(tmp_path / "b")  # the same station, poses and noise
    outcome = cell.run(interrupt=lambda e: isinstance(e, PointMeasured) and e.index == last)
    assert outcome.status == "interrupted" and not of(cell.events, AcquisitionStopped)
    assert cell.run().status == "accepted"
    (stop,) = of(cell.events, AcquisitionStopped)
    assert stop.predicted_rms == expected.predicted_rms and stop.reason == expected.reason
    # the same poses saved, and any the first run had passed over as hidden (this run had not yet)
    hidden = {e.index for e in of(cell.runs[0], PoseSkipped, CALIBRATION)}
    assert set(expected.skipped) <= set(stop.skipped) <= set(expected.skipped) | hidden
    assert not of(cell.runs[1], PoseStarted, CALIBRATION)


def test_roles_interleaved_in_the_visiting_order_each_keep_their_part(tmp_path):
    """One tour mixing calibration and validation poses (the time-aware selection's): after the stop,
    the calibration poses are passed over and the validation poses after them are still measured."""
    rng = np.random.default_rng(5)
    truth = random_truth("ur5e", rng, rigid=True)
    arm = FakeArm(visible_poses(truth, 1, rng)[0])
    config = fake_config(truth)
    model_tracker = look_at_tracker(config.tracker["position"])
    cal, val = visible_poses(truth, 30, rng), visible_poses(truth, 8, rng)
    tour, c, v = [], 0, 0
    for k in range(38):  # a validation pose after every fourth calibration pose
        if (k % 5 == 4 and v < 8) or c == 30:
            tour.append((k, VALIDATION, val[v]))
            v += 1
        else:
            tour.append((k, CALIBRATION, cal[c]))
            c += 1
    events: list = []
    bus = EventBus()
    bus.subscribe(events.append, critical=True)
    engine = Engine(arm, FakeTracker(arm, truth), "c1", get_robot("ur5e"), bus=bus, clock=RealClock())
    result = engine.run(calibration_plan(config, lambda r: None, "c1",
                                         ResumeState(poses=tour, tracker=model_tracker)))
    (stop,) = of(events, AcquisitionStopped)
    visited = [(e.role, e.index) for e in of(events, PoseStarted)]
    stop_at = visited.index((CALIBRATION, max(e.index for e in of(events, PointMeasured, CALIBRATION))))
    assert all(role == VALIDATION for role, _ in visited[stop_at + 1:])
    assert len(visited) - stop_at - 1 > 0  # validation poses after the stop were still visited
    hidden = len(of(events, PoseSkipped, VALIDATION))
    assert len(of(events, PointMeasured, VALIDATION)) == result.after.count == 8 - hidden
    assert set(stop.skipped) == {i for i, r, _ in tour if r == CALIBRATION} - {
        e.index for e in of(events, PointMeasured, CALIBRATION)}


@pytest.fixture
def truth_file(tmp_path):
    truth = random_truth("ur5e", np.random.default_rng(11), rigid=True)
    write_json(tmp_path / "truth.json", truth_document(truth, Noise()))
    return truth


def test_simulated_campaign_stops_early_validates_and_resumes_after_an_interruption(tmp_path, truth_file):
    """``hil calibrate --sim --stop-early`` in fast time: interrupted (SIGINT) at the first validation
    point after the stop, then run again: the resumed run keeps the stop, measures the remaining
    validation poses only, is accepted, and its result and report say why it stopped."""
    out, report = tmp_path / "result.json", tmp_path / "report.html"
    cmd = [sys.executable, "-m", "hil", "calibrate", "--sim", "--speed", "40", "--seed", "11",
           "--truth", str(tmp_path / "truth.json"), "--poses", "30", "--validation", "4",
           "--candidates", "3000", "--db", str(tmp_path / "hil.db"), "--no-warmup", "--stop-early",
           "--json", "--out", str(out), "--report", str(report)]
    proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    first: list[dict] = []
    try:
        for line in proc.stdout:
            first.append(json.loads(line))
            if first[-1]["event"] == "PointMeasured" and first[-1]["role"] == VALIDATION and \
                    any(e["event"] == "AcquisitionStopped" for e in first):
                os.killpg(proc.pid, signal.SIGINT)
                break
    finally:
        _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, ([e["event"] for e in first][-5:], err[-2000:])
    (stop,) = [e for e in first if e["event"] == "AcquisitionStopped"]
    assert stop["poses_left"] > 0 and stop["poses_used"] + stop["poses_left"] == 30

    again = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=240)
    assert again.returncode == 0, again.stderr[-2000:]
    second = [json.loads(line) for line in again.stdout.splitlines()]
    assert second[0]["event"] == "RunStarted" and second[0]["resumed"]
    assert not [e for e in second if e["event"] in ("AcquisitionStopped",) or
                (e["event"] == "PoseStarted" and e["role"] == CALIBRATION)]
    measured = [e for e in first + second if e["event"] == "PointMeasured"]
    assert sum(1 for e in measured if e["role"] == VALIDATION) == 4
    assert sum(1 for e in measured if e["role"] == CALIBRATION) == stop["poses_used"]
    result = json.loads(out.read_text())
    assert result["status"] == "accepted" and result["passed"]
    assert result["stopping"]["stopped"] and result["stopping"]["poses_left"] == stop["poses_left"]
    assert result["stopping"]["predicted_rms"] == pytest.approx(stop["predicted_rms"])
    assert "stopped early after" in again.stderr
    assert "Acquisition stopped early" in report.read_text()
