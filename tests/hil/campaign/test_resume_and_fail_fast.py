"""Issue 19, "Resume and fail-fast": a bootstrap interrupted and resumed visits the same targets and
measures each pose once; several poses in a row that lose the beam stop the run, saying the tracker
position looks wrong; a store that cannot write stops the arm and names the write.

Most of it runs the real plan, engine, runner and SQLite store in this process on the fake arm and
tracker (tests/hil/campaign/fakes.py); one test runs the simulated station with a wrong tracker
position, through the real ur_rtde and GeoCOM clients.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.calibration.synthetic import random_truth
from hil.campaign.calibration_plan import (
    BOOTSTRAP,
    VALIDATION,
    Choice,
    TrackerLooksWrong,
    bootstrap_targets,
    calibration_plan,
)
from hil.campaign.chooser import campaign_chooser
from hil.campaign.engine import FAILED, Engine, RealClock, RunInterrupted, Suspender
from hil.campaign.events import (
    BootstrapPlanned,
    EventBus,
    PointMeasured,
    PoseReached,
    PoseSkipped,
    PoseStarted,
    RunFinished,
    Suspended,
)
from hil.campaign.runner import RecordFailed, plan_saver, resume_state, run_campaign, store_recorder
from hil.station.config import default_config
from hil.station.devices import open_devices
from hil.store import Store
from tests.hil.campaign.fakes import FakeArm, FakeBeamLost, FakeTracker, visible_poses
from tests.hil.campaign.full_disk import FullDisk


class Devices:
    """`hil.station.devices.Devices` made of the fakes (the same arm across runs: it stays where it
    stopped, as a real one does)."""

    def __init__(self, arm: FakeArm, tracker: FakeTracker) -> None:
        self.robot, self.tracker = arm, tracker

    def close(self) -> None:
        pass


class BootCell:
    """A station whose tracker position is not configured, so every campaign starts with a bootstrap;
    runs of `run_campaign` share the arm and the SQLite store, as re-runs of ``hil calibrate`` do."""

    def __init__(self, tmp_path: Path) -> None:
        rng = np.random.default_rng(7)
        self.truth = random_truth("ur5e", rng, ideal=True)
        self.arm = FakeArm(visible_poses(self.truth, 1, rng)[0])
        self.tracker = FakeTracker(self.arm, self.truth)
        self.config = default_config().with_overrides(
            campaign__calibration_poses=12, campaign__validation_poses=4, campaign__samples=2,
            robot__settle_time=0.0, robot__joint_samples=2, smr__offset=tuple(self.truth.smr + 0.003),
            warmup__enabled=False,  # a wall-clock run on fakes (test_warmup.py resumes warm-ups)
            campaign__approach=0.0)  # one move a pose: the tests count them (test_approach.py: the approach)
        self.rng = rng
        self.store = Store.open(tmp_path / "hil.db")
        self.campaign = self.store.create_campaign(self.config, "ur5e")
        self.events: list = []

    def choose(self, request):
        return Choice(visible_poses(request.model, request.count, self.rng), {"method": "test"})

    def run(self, interrupt_after: int | None = None):
        """One run (resuming whatever the store holds), interrupted as SIGTERM would be after
        `interrupt_after` bootstrap points of this run were recorded."""
        seen = []

        def interrupter(event):
            if isinstance(event, PointMeasured) and event.role == BOOTSTRAP:
                seen.append(event.index)
                if len(seen) == interrupt_after:
                    raise RunInterrupted(15)

        bus = EventBus()
        bus.subscribe(store_recorder(self.store), critical=True)
        bus.subscribe(plan_saver(self.store, self.campaign), critical=True)
        bus.subscribe(self.events.append, critical=True)
        bus.subscribe(interrupter, critical=True)  # after the store: the point is kept
        first = not self.store.measured_poses(self.campaign)
        resume = None if first else resume_state(self.store, self.campaign)
        return run_campaign(self.config, self.choose, bus=bus, campaign=self.campaign, resume=resume,
                            devices=Devices(self.arm, self.tracker), clock=RealClock())

    def of(self, kind):
        return [e for e in self.events if isinstance(e, kind)]


def test_a_bootstrap_interrupted_twice_resumes_at_the_same_targets_measuring_each_pose_once(tmp_path):
    cell = BootCell(tmp_path)
    n_boot = len(bootstrap_targets(np.zeros(6), cell.config.campaign["bootstrap_poses"]))
    assert cell.run(interrupt_after=3).status == "interrupted"
    (planned,) = cell.of(BootstrapPlanned)  # stored before the first bootstrap move
    targets = {p["index"]: np.array(p["q"]) for p in planned.poses}
    assert len(targets) == n_boot
    stopped_at = cell.arm.q.copy()
    assert not np.allclose(stopped_at, planned.start)  # the arm is no longer where the bootstrap began

    assert cell.run(interrupt_after=4).status == "interrupted"
    outcome = cell.run()
    assert outcome.status == "accepted", outcome.error

    assert len(cell.of(BootstrapPlanned)) == 1  # the resumed runs planned no bootstrap of their own
    visited = [e for e in cell.of(PoseStarted) if e.role == BOOTSTRAP]
    for e in visited:  # every bootstrap visit, in all three runs, went to a target of the stored plan
        assert np.allclose(e.target, targets[e.index], atol=1e-12), (e.index, e.target)
    stored = {p.index: np.array(p.target) for p in cell.store.poses(cell.campaign) if p.role == BOOTSTRAP}
    assert stored.keys() == targets.keys()
    assert all(np.allclose(stored[i], targets[i], atol=1e-12) for i in targets)
    # each bootstrap pose measured exactly once over the three runs: 3, then 4, then the rest
    measured = [m.index for m in cell.store.measurements(cell.campaign, role=BOOTSTRAP)]
    assert sorted(measured) == sorted(targets) and len(measured) == n_boot
    assert [e.index for e in cell.of(PointMeasured) if e.role == BOOTSTRAP] == measured
    # the calibration poses are numbered after every bootstrap pose
    assert min(p.index for p in cell.store.poses(cell.campaign) if p.role != BOOTSTRAP) == n_boot


class LostCell:
    """The fake station with its tracker position configured, and a beam that is lost at chosen
    measure-phase poses: a lost pose is given up at once (the re-lock wait is not what is tested)."""

    def __init__(self, lost_at: set[int], cal: int = 14, val: int = 6, **overrides) -> None:
        rng = np.random.default_rng(3)
        self.truth = random_truth("ur5e", rng, ideal=True)
        self.arm = FakeArm(visible_poses(self.truth, 1, rng)[0])
        self.tracker = FakeTracker(self.arm, self.truth)
        self.rng = rng
        self.config = default_config().with_overrides(
            # one tracker measurement per visit (the fixed settle): the fake loses the beam by visit
            campaign__calibration_poses=cal, campaign__validation_poses=val, robot__settle_time=0.0,
            robot__settle="fixed",
            smr__offset=tuple(self.truth.smr + 0.003),
            tracker__position=tuple(self.truth.tracker.translation + 0.05),
            # counts lost poses in a row; the fake arm is rigid: the geometry alone is fitted, so the
            # fewest poses that identify it stay the 10 these tests lose down to
            warmup__enabled=False, drift__every=0, campaign__compliance=False, **overrides)
        visits = []
        measure = self.tracker.measure_point

        def measure_point(samples: int = 1):
            visits.append(1)
            if len(visits) - 1 in lost_at:  # the k-th visit (0-based) never sees the beam
                raise FakeBeamLost("target lost")
            return measure(samples)

        self.tracker.measure_point = measure_point
        self.events: list = []
        bus = EventBus()
        bus.subscribe(self.events.append, critical=True)
        self.engine = Engine(self.arm, self.tracker, "c1", get_robot("ur5e"), bus=bus, clock=RealClock(),
                             suspenders=[Suspender("beam_lost", lambda e: isinstance(e, FakeBeamLost),
                                                   lambda: False, "bring the SMR back into the beam",
                                                   poll=0.01, timeout=0.02, on_timeout="skip")])

    def choose(self, request):
        return Choice(visible_poses(request.model, request.count, self.rng), {"method": "test"})

    def run(self):
        return self.engine.run(calibration_plan(self.config, self.choose, "c1"))

    def of(self, kind):
        return [e for e in self.events if isinstance(e, kind)]


def test_three_poses_in_a_row_losing_the_beam_stop_the_run_naming_the_tracker_position():
    cell = LostCell(lost_at=set(range(6, 100)))  # the first 6 poses are seen, then none
    with pytest.raises(TrackerLooksWrong) as caught:
        cell.run()
    assert cell.engine.state == FAILED and cell.arm.stops >= 1
    skipped = cell.of(PoseSkipped)
    assert len(skipped) == 3 and len(cell.of(PointMeasured)) == 6  # stopped at the third, not the 14th
    text = str(caught.value)
    given = [round(float(v), 3) for v in cell.config.tracker["position"]]
    assert f"tracker.position {given} looks wrong" in text
    assert f"poses {', '.join(str(e.index) for e in skipped)}" in text
    # the 6 points measured before say where the tracker is (the nominal arm: to a few centimetres)
    where = np.array([float(v) for v in text.split("put the tracker at about [")[1].split("]")[0].split(",")])
    assert np.linalg.norm(where - cell.truth.tracker.translation) < 0.03
    assert "\n" not in text


def test_losses_that_are_not_in_a_row_do_not_stop_the_run():
    cell = LostCell(lost_at={2, 3, 8, 9, 16, 17})  # two at a time, with measured poses between
    result = cell.run()
    assert len(cell.of(PoseSkipped)) == 6 and result.passed


def test_the_number_of_losses_in_a_row_is_the_configured_one():
    cell = LostCell(lost_at=set(range(4, 100)), campaign__max_consecutive_lost=5)
    with pytest.raises(TrackerLooksWrong, match="5 poses in a row lost the beam"):
        cell.run()
    assert len(cell.of(PoseSkipped)) == 5


def test_a_store_that_cannot_write_stops_the_arm_and_the_run_fails_naming_the_write(tmp_path, monkeypatch):
    disk = FullDisk(monkeypatch)
    cell = BootCell(tmp_path)

    def fill_the_disk(event):  # 5 points committed, the 6th pose reached: nothing more fits
        if isinstance(event, PoseReached) and len(cell.store.measurements(cell.campaign)) == 5:
            disk.full = True

    bus = EventBus()
    bus.subscribe(store_recorder(cell.store), critical=True)
    bus.subscribe(plan_saver(cell.store, cell.campaign), critical=True)
    bus.subscribe(fill_the_disk, critical=True)
    bus.subscribe(cell.events.append)
    outcome = run_campaign(cell.config, cell.choose, bus=bus, campaign=cell.campaign,
                           devices=Devices(cell.arm, cell.tracker), clock=RealClock())
    assert outcome.status == "failed" and outcome.exit_code == 3
    assert isinstance(outcome.error, RecordFailed)
    assert str(outcome.error) == (f"could not record the measurement of pose 5 in {cell.store.path}: "
                                  "database or disk is full")
    assert outcome.unrecorded is not None  # RunFinished could not be recorded either: the caller says so
    assert cell.arm.stops >= 1 and cell.arm.moves == 6  # stopped, and no move after the failed write
    assert not cell.of(RunFinished)  # never reached the displays: the store refused it first
    disk.make_room()
    assert len(cell.store.measurements(cell.campaign)) == 5  # what was committed stays


# --- the simulated station, a wrong tracker.position -----------------------------------------------------
def test_a_wrong_tracker_position_on_the_simulated_station_stops_after_three_lost_poses(tmp_path):
    from mocks.station import start_station

    sim = start_station(speed=100.0, seed=5, ideal=True)
    try:
        svc = sim.info["services"][0]
        config = default_config().with_overrides(
            robot__address=sim.address, tracker__url=svc["tracker_url"], robot__speed=1.0,
            robot__acceleration=2.0, campaign__calibration_poses=14, campaign__validation_poses=4,
            campaign__candidates=3000, tracker__position=(-3.0, 0.0, 0.3), timeouts__relock=1.0,
            timeouts__suspend=30.0, warmup__enabled=False, drift__every=0)  # lost poses in a row
        selector = campaign_chooser(config)

        def choose(request):  # the station's constraints, random poses: the tabu search's seconds
            return selector(dataclasses.replace(request, role=VALIDATION))  # are not what is tested

        events: list = []
        bus = EventBus()
        bus.subscribe(events.append)
        outcome = run_campaign(config, choose, bus=bus, clock=RealClock(100.0), devices=open_devices(config))
    finally:
        sim.stop()
    assert outcome.status == "failed" and outcome.exit_code == 3, outcome.error
    assert isinstance(outcome.error, TrackerLooksWrong)
    assert "tracker.position [-3.0, 0.0, 0.3] looks wrong" in str(outcome.error)
    # bounded: one re-lock wait for each of the three lost poses, then the run stopped
    assert [e.kind for e in events if isinstance(e, Suspended)] == ["beam_lost"] * 3
    assert len([e for e in events if isinstance(e, PoseSkipped)]) == 3
    finished = [e for e in events if isinstance(e, RunFinished)]
    assert finished[-1].status == "failed" and "TrackerLooksWrong" in finished[-1].detail
