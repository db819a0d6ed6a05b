"""A campaign's validation RMS comes with its standard error under the validation design: the plan maps
each validation entry to its validation pose (``pose_of_index``, stored with the plan, so a resumed run
maps alike), the result's ``validation`` block carries ``precision``, the report shows it."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from hil.calibration.synthetic import random_truth
from hil.calibration.validation_precision import validation_precision
from hil.campaign.calibration_plan import CALIBRATION, VALIDATION, Choice, SelectionRequest
from hil.campaign.chooser import campaign_chooser
from hil.campaign.engine import RealClock, RunInterrupted
from hil.campaign.events import EventBus, PlanReady, PointMeasured
from hil.campaign.runner import plan_saver, resume_state, run_campaign, store_recorder
from hil.report import report_data_from_result
from hil.report.render import render_html
from hil.report.result import result_document
from hil.station.config import default_config
from hil.store import Store
from tests.hil.campaign.fakes import FakeArm, FakeTracker, visible_poses

CANDIDATES = 3000  # the clustered chooser's candidates (as tests/hil/campaign/test_clustered_validation.py)


class _Station:
    """A fake arm and tracker over a rigid random truth, a store and one campaign in it."""

    def __init__(self, tmp_path: Path, seed: int, **overrides: Any) -> None:
        self.rng = np.random.default_rng(seed)
        truth = random_truth("ur5e", self.rng, rigid=True)
        self.arm = FakeArm(visible_poses(truth, 1, self.rng)[0])
        self.tracker = FakeTracker(self.arm, truth)
        settings: dict[str, Any] = dict(
            campaign__calibration_poses=14, campaign__validation_poses=4, campaign__compliance=False,
            campaign__candidates=CANDIDATES, campaign__samples=2, robot__settle_time=0.0,
            robot__joint_samples=2, tracker__position=tuple(truth.tracker.translation),
            smr__offset=tuple(truth.smr), warmup__enabled=False, drift__every=0)
        self.config = default_config().with_overrides(**{**settings, **overrides})
        self.store = Store.open(tmp_path / "hil.db")
        self.campaign = self.store.create_campaign(self.config, "ur5e")

    def chooser(self, real_validation: bool) -> Any:
        """Calibration poses at random among the visible ones; validation poses by the campaign chooser
        (`real_validation`: the clustered draw) or at random too."""
        real = campaign_chooser(self.config)

        def choose(request: SelectionRequest) -> Choice:
            if request.role == VALIDATION and real_validation:
                return real(request)
            return Choice(visible_poses(request.model, request.count, self.rng), {"method": "test"})

        return choose

    def run(self, chooser: Any, stop_after: int | None = None, cycles: int = 1) -> tuple[Any, list[Any]]:
        events: list[Any] = []

        def interrupter(event: Any) -> None:
            if isinstance(event, PointMeasured) and stop_after is not None and \
                    sum(isinstance(e, PointMeasured) for e in events) >= stop_after:
                raise RunInterrupted(15)

        bus = EventBus()
        bus.subscribe(store_recorder(self.store), critical=True)
        bus.subscribe(plan_saver(self.store, self.campaign), critical=True)
        bus.subscribe(events.append, critical=True)
        bus.subscribe(interrupter, critical=True)
        resume = resume_state(self.store, self.campaign) if self.store.measured_poses(self.campaign) else None
        outcome = run_campaign(self.config, chooser, bus=bus, campaign=self.campaign, resume=resume,
                               devices=_Devices(self.arm, self.tracker), clock=RealClock(),
                               validation_cycles=cycles)
        return outcome, events

    def result(self, outcome: Any, events: list[Any]) -> dict[str, Any]:
        assert outcome.status in ("accepted", "rejected"), outcome.error  # ran to its verdict
        return result_document(outcome, self.config, events, time.time(), None)


def _independently(doc: dict[str, Any]) -> dict[str, Any]:
    """The precision recomputed from the result file alone: its per-pose validation errors, their pose
    numbers and the plan's selection (map and labels)."""
    per_pose = doc["per_pose"]["validation"]
    errors = np.linalg.norm(np.array(per_pose["after"]), axis=1)
    info = doc["selection"]["validation"]
    poses = [info["pose_of_index"][str(i)] for i in per_pose["lines"]]
    return validation_precision(errors, poses, info.get("labels"))


def _assert_same(got: dict[str, Any], expected: dict[str, Any]) -> None:
    """The same precision block (numbers to rounding: the file's per-pose errors are its own sums)."""
    assert got.keys() == expected.keys()
    for key, value in expected.items():
        assert got[key] == (pytest.approx(value, rel=1e-9) if isinstance(value, float) else value), key


def test_a_clustered_campaign_reports_its_standard_error_with_its_clusters(tmp_path: Path) -> None:
    station = _Station(tmp_path, 11, campaign__validation_clusters=2)
    outcome, events = station.run(station.chooser(real_validation=True))
    doc = station.result(outcome, events)
    validation = doc["validation"]
    assert set(validation) == {"before", "after", "iso9283", "precision"}  # the old keys, plus one
    precision = validation["precision"]
    assert precision["design"] == "clustered" and (precision["clusters"], precision["poses"]) == (2, 4)
    assert precision["rms_standard_error"] > 0
    _assert_same(precision, _independently(doc))
    assert outcome.result.validation_precision == precision
    # the plan mapped every validation entry to the pose it visits
    (ready,) = [e for e in events if isinstance(e, PlanReady)]
    pose_of = ready.selection["validation"]["pose_of_index"]
    validation_entries = [p["index"] for p in ready.poses if p["role"] == VALIDATION]
    assert sorted(map(int, pose_of)) == validation_entries and sorted(pose_of.values()) == [0, 1, 2, 3]
    # the report rebuilt from the result file shows it beside the validation RMS
    data = report_data_from_result(doc)
    assert data.validation_precision == precision
    page = render_html(data)
    assert "1 s.e., 2 clusters" in page and f"± {precision['rms_standard_error'] * 1e6:.1f} µm" in page


def test_a_resumed_clustered_campaign_still_gets_it(tmp_path: Path) -> None:
    station = _Station(tmp_path, 12, campaign__validation_clusters=2)
    first, _ = station.run(station.chooser(real_validation=True), stop_after=3)
    assert first.status == "interrupted"
    stored = resume_state(station.store, station.campaign).selection["validation"]
    assert len(stored["pose_of_index"]) == 4 and stored["method"] == "clustered"

    def refuse(request: SelectionRequest) -> Choice:
        raise AssertionError("a resumed campaign chose poses again")

    second, events = station.run(refuse)
    (ready,) = [e for e in events if isinstance(e, PlanReady)]
    assert ready.selection["validation"] == stored  # the stored plan's, map included
    doc = station.result(second, events)
    precision = doc["validation"]["precision"]
    assert precision["design"] == "clustered" and (precision["clusters"], precision["poses"]) == (2, 4)
    assert precision["rms_standard_error"] is not None
    _assert_same(precision, _independently(doc))


def test_repeated_cycles_count_each_validation_pose_once(tmp_path: Path) -> None:
    station = _Station(tmp_path, 13)
    outcome, events = station.run(station.chooser(real_validation=False), cycles=2)
    doc = station.result(outcome, events)
    (ready,) = [e for e in events if isinstance(e, PlanReady)]
    pose_of = ready.selection["validation"]["pose_of_index"]
    targets = {p["index"]: p["q"] for p in ready.poses if p["role"] == VALIDATION}
    assert len(targets) == 8 and sorted(pose_of.values()) == [0, 0, 1, 1, 2, 2, 3, 3]
    for k in range(4):  # each cycle's entry of pose k goes to the same target
        same = [targets[int(i)] for i, v in pose_of.items() if v == k]
        assert len(same) == 2 and np.array_equal(same[0], same[1])
    # poses measured (the fake poses may leave one out of the keep-in box's safe paths), once each
    measured = [e.index for e in events if isinstance(e, PointMeasured) and e.role == VALIDATION]
    poses = len({pose_of[str(i)] for i in measured})
    assert len(measured) == 2 * poses  # both cycles of each pose
    precision = doc["validation"]["precision"]
    assert (precision["design"], precision["poses"], precision["clusters"]) == ("simple random", poses, None)
    _assert_same(precision, _independently(doc))


def test_a_tour_maps_its_validation_stops_by_their_pose_index(tmp_path: Path) -> None:
    """Time-aware selection: the calibration Choice's tour interleaves the validation poses, each stop
    naming its pose k in the validation Choice; the map follows the tour, not the visiting order."""
    station = _Station(tmp_path, 14, campaign__selection="time-aware")
    rng = station.rng
    picked: dict[str, np.ndarray] = {}

    def choose(request: SelectionRequest) -> Choice:
        poses = visible_poses(request.model, request.count, rng)
        picked[request.role] = poses
        if request.role != CALIBRATION:
            return Choice(poses, {"method": "test"})
        fixed = [{"role": "fixed", "index": k} for k in (2, 0, 3, 1)]  # not in pose order
        selected = [{"role": "selected", "index": i} for i in range(request.count)]
        tour = selected[:5] + fixed[:2] + selected[5:9] + fixed[2:] + selected[9:]
        return Choice(poses, {"method": "test", "tour": tour})

    outcome, events = station.run(choose)
    (ready,) = [e for e in events if isinstance(e, PlanReady)]
    pose_of = ready.selection["validation"]["pose_of_index"]
    visited = [p for p in ready.poses if p["role"] == VALIDATION]
    assert [pose_of[str(p["index"])] for p in visited] == [2, 0, 3, 1]
    for p in visited:
        assert np.array_equal(p["q"], picked[VALIDATION][pose_of[str(p["index"])]])
    measured = {e.index for e in events if isinstance(e, PointMeasured) and e.role == VALIDATION}
    precision = station.result(outcome, events)["validation"]["precision"]
    assert precision["design"] == "simple random" and precision["poses"] == len(measured) >= 2


class _Devices:
    """`hil.station.devices.Devices` made of the fakes."""

    def __init__(self, arm: FakeArm, tracker: FakeTracker) -> None:
        self.robot, self.tracker = arm, tracker

    def close(self) -> None:
        pass
