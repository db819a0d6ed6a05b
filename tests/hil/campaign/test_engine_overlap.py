"""Issue 17, "overlap what can overlap": a measured point is committed while the arm travels to the
next pose, never after the next measurement; a failed commit stops the arm and fails the run; the
events reach subscribers in the same order as without the overlap; an interruption during the
overlapped commit loses at most that point, and the resumed campaign measures it again.

The real plan, engine, runner and SQLite store run here on the fake arm and tracker
(tests/hil/campaign/fakes.py); the arm gains `start_move` / `wait_move`, as `drivers.robot.URRobot`
has, and knows whether it is travelling when a subscriber is called.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.calibration.synthetic import random_truth
from hil.campaign.calibration_plan import Choice, calibration_plan
from hil.campaign.engine import FAILED, Engine, RealClock, RunInterrupted, Suspender
from hil.campaign.events import (
    EventBus,
    PointMeasured,
    PoseReached,
    PoseStarted,
    StateChanged,
)
from hil.campaign.runner import plan_saver, resume_state, run_campaign, store_recorder
from hil.station.config import default_config
from hil.store import Store
from tests.hil.campaign.fakes import FakeArm, FakeTracker, visible_poses


class TravellingArm(FakeArm):
    """The fake arm with the driver's start/wait split: `start_move` sets off (the arm is
    `travelling` towards `heading` until `wait_move`), `stop` ends a move where it is."""

    def __post_init__(self) -> None:
        super().__post_init__()
        self.travelling = False
        self.heading: np.ndarray | None = None
        self.stopped_travelling = 0  # stops that caught the arm on its way
        self.interrupt_on_start: int | None = None  # Ctrl-C at this start_move (1-based)
        self.starts = 0

    def start_move(self, q, *, speed=None, acceleration=None):
        self.starts += 1
        if self.interrupt_on_start == self.starts:
            raise RunInterrupted(2)
        self.travelling, self.heading = True, np.asarray(q, float)
        return self.heading

    def wait_move(self, samples: int = 1):
        assert self.travelling, "wait_move without a move on its way"
        self.travelling = False
        return self.move_to(self.heading)

    def stop(self):
        super().stop()
        if self.travelling:
            self.stopped_travelling += 1
            self.travelling = False


class Cell:
    """A station on fakes with a known tracker position, fixed settling and no warm-up or drift
    watch: one tracker measurement per pose, so the tracker's count says what was measured when."""

    def __init__(self, seed: int = 3, overlap: bool = True, tmp_path: Path | None = None) -> None:
        self.rng = np.random.default_rng(seed)
        self.truth = random_truth("ur5e", self.rng, rigid=True)
        self.arm = TravellingArm(visible_poses(self.truth, 1, self.rng)[0])
        self.tracker = FakeTracker(self.arm, self.truth)
        self.config = default_config().with_overrides(
            campaign__calibration_poses=12, campaign__validation_poses=4, robot__settle_time=0.0,
            robot__settle="fixed", smr__offset=tuple(self.truth.smr + 0.003),
            tracker__position=tuple(self.truth.tracker.translation + 0.05), campaign__compliance=False,
            warmup__enabled=False, drift__every=0)
        self.overlap = overlap
        self.events: list = []
        # (event, arm travelling?, where to, tracker measurements so far) at each delivery
        self.seen: list[tuple] = []
        self.store = Store.open(tmp_path / "hil.db") if tmp_path is not None else None
        self.campaign = self.store.create_campaign(self.config, "ur5e") if self.store else "c1"

    def watch(self, event) -> None:
        self.events.append(event)
        heading = None if self.arm.heading is None else self.arm.heading.copy()
        self.seen.append((event, self.arm.travelling, heading, self.tracker.measurements))

    def choose(self, request):
        return Choice(visible_poses(request.model, request.count, self.rng), {"method": "test"})

    def engine(self, *subscribers) -> Engine:
        bus = EventBus()
        for fn in (*subscribers, self.watch):
            bus.subscribe(fn, critical=True)
        return Engine(self.arm, self.tracker, self.campaign, get_robot("ur5e"), bus=bus, clock=RealClock(),
                      overlap=self.overlap)

    def run(self, *subscribers):
        return self.engine(*subscribers).run(calibration_plan(self.config, self.choose, self.campaign))

    def run_stored(self, *subscribers):
        """One run of the runner on the SQLite store, resuming what it holds (as `hil calibrate`)."""
        assert self.store is not None
        bus = EventBus()
        bus.subscribe(store_recorder(self.store), critical=True)
        bus.subscribe(plan_saver(self.store, self.campaign), critical=True)
        for fn in (*subscribers, self.watch):
            bus.subscribe(fn, critical=True)
        resume = resume_state(self.store, self.campaign) if self.store.measured_poses(self.campaign) else None
        return run_campaign(self.config, self.choose, bus=bus, campaign=self.campaign, resume=resume,
                            devices=_Devices(self.arm, self.tracker), clock=RealClock())


class _Devices:
    def __init__(self, arm, tracker) -> None:
        self.robot, self.tracker = arm, tracker

    def close(self) -> None:
        pass


def test_each_point_is_committed_while_the_arm_travels_to_the_next_pose():
    cell = Cell()
    result = cell.run()
    assert result.passed
    measured = [(e, moving, heading, count) for e, moving, heading, count in cell.seen
                if isinstance(e, PointMeasured)]
    assert len(measured) == 16
    starts = [e for e in cell.events if isinstance(e, PoseStarted)]
    for k, (event, moving, heading, count) in enumerate(measured):
        # committed before anything else was measured: the tracker has measured this point and the
        # ones before it, not the next
        assert count == k + 1 and event.index == starts[k].index
        if k + 1 < len(measured):  # on its way to the next pose (or its approach), not standing at this one
            lead = np.asarray(starts[k + 1].target) - cell.config.campaign["approach"]
            assert moving and (np.allclose(heading, starts[k + 1].target) or np.allclose(heading, lead))
    # the last point has no next move: it is committed before the identification, arm standing
    assert not measured[-1][1]


def test_the_commit_time_is_counted_inside_the_motion():
    cell = Cell()
    engine = cell.engine()
    engine.run(calibration_plan(cell.config, cell.choose, cell.campaign))
    assert engine.stats.events_in_motion > 0
    assert engine.stats.motion >= engine.stats.events_in_motion
    # a record joins `records` once its point is committed, in the order they were measured
    assert [r.index for r in engine.records] == [e.index for e in cell.events if isinstance(e, PointMeasured)]
    assert len(engine.records) == 16


def _shape(events):
    """What a subscriber can rely on: which events, in which order, about which pose and state."""
    return [(type(e).__name__, getattr(e, "index", None), getattr(e, "state", None)) for e in events]


def test_subscribers_see_the_events_in_the_same_order_with_and_without_the_overlap():
    with_overlap, without = Cell(overlap=True), Cell(overlap=False)
    with_overlap.run()
    without.run()
    assert _shape(with_overlap.events) == _shape(without.events)
    # without the overlap nothing is delivered while the arm travels
    assert not any(moving for _, moving, *_ in without.seen)
    assert sum(moving for _, moving, *_ in with_overlap.seen) >= 3 * 15  # PoseReached, PointMeasured,
    # PoseStarted of the next pose: delivered on the way there
    order = [type(e).__name__ for e in with_overlap.events
             if isinstance(e, PoseStarted | PoseReached | PointMeasured)]
    assert order == ["PoseStarted", "PoseReached", "PointMeasured"] * 16


class DiskFull(Exception):
    pass


def test_a_failed_commit_stops_the_arm_and_fails_the_run_before_the_next_measurement():
    cell = Cell()

    def store(event):
        if isinstance(event, PointMeasured) and event.index == 4:
            raise DiskFull("database or disk is full")

    engine = cell.engine(store)
    # a suspender that would claim anything: a commit that failed must still never be retried
    engine.suspenders = [Suspender("anything", lambda e: True, lambda: True, "(none)", poll=0.01)]
    with pytest.raises(DiskFull):
        engine.run(calibration_plan(cell.config, cell.choose, cell.campaign))
    assert engine.state == FAILED
    assert cell.arm.stopped_travelling == 1  # stopped on its way to the next pose
    assert cell.tracker.measurements == 5  # poses 0..4: nothing measured after the failed commit
    assert [e.index for e in cell.events if isinstance(e, PointMeasured)] == [0, 1, 2, 3]
    assert len(engine.records) == 4  # the point that was not kept is not a record either
    assert [e.state for e in cell.events if isinstance(e, StateChanged)][-1] == FAILED


def test_a_point_held_when_ctrl_c_lands_is_committed_after_the_arm_stops(tmp_path):
    cell = Cell(tmp_path=tmp_path)
    # Ctrl-C as the move after the 5th point is sent (the first move, with nothing held, is a move_to)
    cell.arm.interrupt_on_start = 5
    assert cell.run_stored().status == "interrupted"
    kept = sorted(cell.store.measured_poses(cell.campaign))
    assert kept == [0, 1, 2, 3, 4] and cell.tracker.measurements == 5  # the held point is in the store
    # it was delivered as the run ended, after the arm was told to stop
    assert _shape(cell.events)[-6:] == [
        ("PoseReached", 4, None), ("PointMeasured", 4, None), ("PoseStarted", 5, None),
        ("StateChanged", None, "stopping"), ("StateChanged", None, "interrupted"),
        ("RunFinished", None, None)]
    assert cell.arm.stops >= 1
    assert cell.run_stored().status == "accepted"
    measured = [e.index for e in cell.events if isinstance(e, PointMeasured)]
    assert len(measured) == len(set(measured)) >= 14  # nothing measured twice
    assert cell.tracker.measurements == len(measured)
    assert sorted(cell.store.measured_poses(cell.campaign)) == sorted(measured)


class Killed(BaseException):
    """``kill -9``: the process ends where it is; nothing after it runs, nothing more is stored."""


def test_killed_during_the_overlapped_commit_loses_only_that_point_and_the_resume_measures_it(tmp_path):
    cell = Cell(tmp_path=tmp_path)
    dead = []
    recorder = store_recorder(cell.store)

    def store_or_die(event):
        if dead:
            return  # a dead process stores nothing more
        if isinstance(event, PointMeasured) and event.index == 6:
            dead.append(cell.arm.travelling)
            raise Killed  # before its commit finished
        recorder(event)

    engine = cell.engine(store_or_die, plan_saver(cell.store, cell.campaign))
    with pytest.raises(Killed):
        engine.run(calibration_plan(cell.config, cell.choose, cell.campaign))
    assert dead == [True]  # it died while the arm was travelling to the next pose
    kept = set(cell.store.measured_poses(cell.campaign))
    assert kept == set(range(6))  # every point before it is kept; that one is lost

    before = len(cell.events)
    assert cell.run_stored().status == "accepted"
    resumed = [e.index for e in cell.events[before:] if isinstance(e, PointMeasured)]
    assert resumed[0] == 6  # the resumed run measures the lost pose first
    measured = [e.index for e in cell.events if isinstance(e, PointMeasured)]  # (the lost one never
    assert len(measured) == len(set(measured))  # reached a subscriber): each delivered once
    assert cell.tracker.measurements == len(measured) + 1  # the lost pose measured twice, only it
    assert sorted(cell.store.measured_poses(cell.campaign)) == sorted(set(measured))
