"""Warm-up and drift watch (`hil.campaign.warmup`) on a fake arm that grows as it warms up.

The station runs on a virtual clock (tests/hil/campaign/thermal_fakes.py): an hour of warm-up takes a
second. The arm's links grow as `Geometry.warmed(t)` says (2.3e-5 /K, 6 K, a 900 s time constant unless
a test says otherwise), the tracker sees that grown arm, and the whole campaign — plan, engine, runner,
SQLite store — is the real one.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.arm.kinematics import Kinematics
from hil.arm.routes import UnsafePathError
from hil.arm.thermal import Thermal
from hil.calibration.synthetic import random_truth
from hil.campaign.calibration_plan import BOOTSTRAP, CALIBRATION, VALIDATION, Choice
from hil.campaign.engine import Engine, RunInterrupted
from hil.campaign.events import (
    DriftFlagged,
    EventBus,
    Message,
    PlanReady,
    PointMeasured,
    PoseSkipped,
    PoseStarted,
    ReferenceMeasured,
    RunFinished,
    WarmupFinished,
    WarmupProgress,
)
from hil.campaign.reference_lines import describe
from hil.campaign.runner import plan_saver, resume_state, run_campaign, store_recorder
from hil.campaign.steps import REFERENCE, Move, PoseRecord, ReadConditions, Skipped, acquire
from hil.campaign.warmup import APPROACH
from hil.station.config import default_config
from hil.store import Store
from hil.store.records import ROLES
from tests.hil.campaign.fakes import Point, visible_poses
from tests.hil.campaign.thermal_fakes import AMBIENT, Devices, VirtualClock, WarmingArm, WarmingTracker

#: The simulated arm's warm-up (docs/design.md, Facts: thermal growth: 2.3e-5 /K, 6 K, 900 s).
UR_THERMAL = Thermal()


class Cell:
    """A fake station whose arm warms up, its store, and runs of `run_campaign` on them (a re-run
    resumes what the store holds, as re-running ``hil calibrate`` does)."""

    def __init__(self, tmp_path, *, thermal: Thermal | None = UR_THERMAL, seed: int = 7, bootstrap=False,
                 **overrides) -> None:
        rng = np.random.default_rng(seed)
        self.rng = rng
        self.truth = random_truth("ur5e", rng, rigid=True)
        self.truth.thermal = thermal
        self.clock = VirtualClock()
        self.arm = WarmingArm(visible_poses(self.truth, 1, rng)[0], clock=self.clock, truth=self.truth)
        self.tracker = WarmingTracker(self.arm, self.truth, sigma=5e-6, clock=self.clock)
        keys = dict(campaign__calibration_poses=12, campaign__validation_poses=4, campaign__samples=5,
                    robot__settle_time=0.3, robot__joint_samples=2, smr__offset=tuple(self.truth.smr + 0.003),
                    campaign__compliance=False,
                    # the warm-up is the subject, not the verdict: the fake arm keeps warming between
                    # calibration and validation poses (2.5x the cross-validated RMS, which the automatic
                    # verdict rejects as a change between the two), so a threshold as before
                    campaign__acceptance=0.1e-3)
        if not bootstrap:
            keys["tracker__position"] = tuple(self.truth.tracker.translation + 0.05)
        self.config = default_config().with_overrides(**{**keys, **overrides})
        self.store = Store.open(tmp_path / "hil.db", synchronous="NORMAL")
        self.campaign = self.store.create_campaign(self.config, "ur5e")
        self.events: list = []

    def choose(self, request):
        return Choice(visible_poses(request.model, request.count, self.rng), {"method": "test"})

    def run(self, stop_after=None, engine_ready=None):
        """One run; `stop_after(event) -> bool` interrupts it (as SIGTERM) once true, after the store
        recorded that event; `engine_ready(engine)` as `run_campaign`'s."""
        fired: list = []

        def interrupter(event):
            if stop_after is not None and not fired and stop_after(event):
                fired.append(event)
                raise RunInterrupted(15)

        bus = EventBus()
        bus.subscribe(store_recorder(self.store), critical=True)
        bus.subscribe(plan_saver(self.store, self.campaign), critical=True)
        bus.subscribe(self.events.append, critical=True)
        bus.subscribe(interrupter, critical=True)
        resume = resume_state(self.store, self.campaign) if self.store.event_log(self.campaign) else None
        return run_campaign(self.config, self.choose, bus=bus, campaign=self.campaign, resume=resume,
                            devices=Devices(self.arm, self.tracker), clock=self.clock,
                            engine_ready=engine_ready)

    def of(self, kind):
        return [e for e in self.events if isinstance(e, kind)]

    def index(self, event) -> int:
        return next(i for i, e in enumerate(self.events) if e is event)


def test_the_warm_up_ends_once_the_fitted_drift_still_to_come_is_below_the_limit(tmp_path):
    cell = Cell(tmp_path)
    outcome = cell.run()
    assert outcome.status == "accepted", outcome.error
    (done,) = cell.of(WarmupFinished)
    assert done.converged and done.remaining < cell.config.warmup["limit"]
    # the series spans three fitted time constants; the arm's own is 900 s: about 45 min, not 2 hours
    assert done.seconds >= 3 * done.time_constant and 1800 < done.seconds < cell.config.warmup["max_time"]
    # the time constant comes from the joint temperatures the arm reports: the truth's, not noise's
    assert done.time_constant == pytest.approx(UR_THERMAL.time_constant, rel=0.02)
    warm = [e for e in cell.of(ReferenceMeasured) if e.phase == "warmup"]
    assert len(warm) == done.references == len(cell.of(WarmupProgress)) + 1
    # the truth: less than the limit of growth was left when the warm-up ended
    thermal, reach = cell.truth.thermal, 1.0
    left = reach * thermal.expansion * (thermal.rise - thermal.rise_at(cell.arm.clock.now))
    assert left < 2 * cell.config.warmup["limit"]
    # nothing was measured before the arm was warm; the last warm-up measurement is the baseline
    first_point = next(i for i, e in enumerate(cell.events) if isinstance(e, PointMeasured))
    assert cell.index(done) < first_point
    assert warm[-1].baseline and not any(e.baseline for e in warm[:-1])
    # the joints' temperatures, as the arm reports them, rise with the warm-up
    temps = np.array([e.temperatures for e in warm])
    assert temps[0, 0] > AMBIENT and np.all(np.diff(temps[:, 0]) > 0)
    # the cycle is the planned calibration poses, visited in order
    (plan,) = cell.of(PlanReady)
    cal = [np.array(p["q"]) for p in plan.poses if p["role"] == CALIBRATION]
    visited = [k for q in cell.arm.targets for k, c in enumerate(cal) if np.allclose(q, c)]
    first_round = visited[:visited.index(0, 1)]  # (a pose without a safe path is passed over)
    assert first_round == sorted(set(first_round)) and len(first_round) >= len(cal) // 2
    # the progress line says how far the reference moved, what is still to come and the limit
    line = describe(cell.of(WarmupProgress)[-1])
    assert line.startswith("warm-up: reference moved ") and "still to come" in line
    assert "(limit 10.0 µm)" in line
    block = outcome.result.drift
    assert block["warmup"]["converged"] and block["warmup"]["seconds"] == pytest.approx(done.seconds)
    # why it stopped, in the events and the result: the fit's rule, its upper limits, its τ's source
    assert done.rule == "fit" and done.decision.startswith("warm: at most")
    assert done.remaining_upper < cell.config.warmup["limit"] and done.span >= 3 * done.time_constant_upper
    checks = cell.of(WarmupProgress)
    assert [c.warm for c in checks] == [False] * (len(checks) - 1) + [True]
    assert all(c.time_constant_source == "temperatures" for c in checks if c.time_constant is not None)
    assert all(c.decision.startswith("not yet:") for c in checks[:-1])
    assert block["warmup"]["rule"] == "fit" and block["warmup"]["decision"] == done.decision
    assert block["warmup"]["evidence"]["remaining_upper"] == pytest.approx(done.remaining_upper)
    assert block["baseline"] == warm[-1].seq
    # what the rule judged, for the report to state: the series' span against three time constants
    span = warm[-1].elapsed - warm[0].elapsed
    assert block["warmup"]["span"] == pytest.approx(span) and span >= 3 * block["warmup"]["time_constant"]
    assert block["warmup"]["runs"][-1]["span"] == pytest.approx(span)


def test_a_warm_arm_is_warm_within_a_few_reference_measurements(tmp_path):
    cell = Cell(tmp_path, thermal=None)
    assert cell.run().status == "accepted"
    (done,) = cell.of(WarmupFinished)
    # from the fit's fewest points (4) on, as soon as its series spans three (short) time constants
    assert done.converged and 4 <= done.references <= 6 and done.seconds < 12 * 60


def test_a_warm_up_that_does_not_settle_stops_at_max_time_with_a_warning(tmp_path):
    slow = Thermal(rise=20.0, time_constant=3000.0)  # growing by ~0.1 mm over the allowed 15 min
    cell = Cell(tmp_path, thermal=slow, warmup__max_time=900.0, warmup__interval=120.0)
    outcome = cell.run()
    assert outcome.status == "accepted", outcome.error  # the run goes on: the verdict is validation's
    (done,) = cell.of(WarmupFinished)
    assert not done.converged and 900.0 <= done.seconds < 900.0 + 120.0
    line = describe(done)
    assert line.startswith("warning: warm-up stopped after") and "measuring anyway" in line
    block = outcome.result.drift["warmup"]
    assert block["ran"] and block["converged"] is False
    # the last warm-up measurement is still the baseline the drift watch compares with
    warm = [e for e in cell.of(ReferenceMeasured) if e.phase == "warmup"]
    assert warm[-1].baseline
    # and the report's notes say so (the result's notes come from the events)
    from hil.report.data import summarise_events
    assert any(n.startswith("warning: warm-up stopped") for n in summarise_events(cell.events)[1])


def test_the_drift_watch_measures_the_reference_every_n_poses_and_at_the_end(tmp_path):
    cell = Cell(tmp_path, thermal=None, warmup__enabled=False, drift__every=5)
    outcome = cell.run()
    assert outcome.status == "accepted", outcome.error
    assert not cell.of(WarmupFinished)
    refs = cell.of(ReferenceMeasured)
    assert all(r.phase == "drift" for r in refs)
    # a baseline before the first pose, then one after every 5 measured poses, one at the end
    measured = [i for i, e in enumerate(cell.events) if isinstance(e, PointMeasured)]
    at = [cell.index(r) for r in refs]
    assert at[0] < measured[0] and refs[0].baseline and refs[0].drift == 0.0
    between = [sum(1 for m in measured if a < m < b) for a, b in itertools.pairwise(at)]
    n = len(measured)
    assert between == [5] * (n // 5) + ([n % 5] if n % 5 else [])
    assert [r.seq for r in refs] == list(range(1, len(refs) + 1))
    block = outcome.result.drift
    assert block["every"] == 5 and not block["flagged"] and block["max"] < block["limit"]
    assert block["warmup"]["ran"] is False and block["warmup"]["enabled"] is False


def test_no_drift_watch_and_no_warm_up_leaves_the_campaign_as_it_was(tmp_path):
    cell = Cell(tmp_path, thermal=None, warmup__enabled=False, drift__every=0)
    outcome = cell.run()
    assert outcome.status == "accepted"
    assert not cell.of(ReferenceMeasured) and outcome.result.drift is None


def test_a_campaign_whose_reference_drifts_beyond_the_limit_is_flagged_and_keeps_its_verdict(tmp_path):
    # a cold arm measured without a warm-up: its links grow by tens of µm while the poses are measured
    fast = Thermal(rise=6.0, time_constant=300.0)
    cell = Cell(tmp_path, thermal=fast, warmup__enabled=False, drift__every=3, drift__limit=15e-6)
    outcome = cell.run()
    assert outcome.status == "accepted", outcome.error  # validation's verdict, unchanged by the flag
    (flag,) = cell.of(DriftFlagged)  # said once, when first seen
    assert flag.drift > 15e-6 and flag.limit == 15e-6
    block = outcome.result.drift
    assert block["flagged"] and block["max"] >= flag.drift
    (finished,) = cell.of(RunFinished)
    assert "drift flagged" in finished.detail and finished.status == "accepted"
    assert describe(flag).startswith("WARNING: drift: the reference moved")
    # the flag is in the store's log of the campaign
    assert [e["event"] for _, e in cell.store.event_log(cell.campaign, types=("DriftFlagged",))] == [
        "DriftFlagged"]


def test_reference_measurements_never_reach_the_fit_or_the_campaigns_points(tmp_path):
    cell = Cell(tmp_path, thermal=None, drift__every=2)
    outcome = cell.run()
    result = outcome.result
    refs = cell.of(ReferenceMeasured)
    assert len(refs) >= 6
    # no reference visit is a pose: no PoseStarted, PointMeasured or stored measurement of that role
    assert all(e.role in ROLES for e in cell.of(PoseStarted) + cell.of(PointMeasured))
    assert {m.role for m in cell.store.measurements(cell.campaign)} <= {BOOTSTRAP, CALIBRATION, VALIDATION}
    assert len(cell.store.measurements(cell.campaign)) == len(cell.of(PointMeasured))
    # the fit saw exactly the calibration (and bootstrap) points, the validation exactly its poses
    fitted = [r for r in result.records if r.role in (BOOTSTRAP, CALIBRATION)]
    assert len(result.fit.used) == len(fitted)
    assert result.after.count == sum(1 for r in result.records if r.role == VALIDATION)
    ref_points = {tuple(np.round(r.xyz, 12)) for r in refs}
    assert not ref_points & {tuple(np.round(r.p, 12)) for r in result.records}


def test_a_resumed_campaign_warms_up_again_keeps_its_references_and_redoes_no_pose(tmp_path):
    cell = Cell(tmp_path, drift__every=4)
    seen = []

    def after_six_points(event):
        if isinstance(event, PointMeasured) and event.role == CALIBRATION:
            seen.append(event.index)
        return len(seen) == 6

    assert cell.run(stop_after=after_six_points).status == "interrupted"
    first_run = cell.of(ReferenceMeasured)
    baseline = next(e for e in first_run if e.baseline)
    cell.clock.sleep(4 * 3600.0)  # the arm stands (and in truth would cool; the fake stays warm)
    outcome = cell.run()
    assert outcome.status == "accepted", outcome.error
    # the second run warmed up again before measuring what was left
    assert len(cell.of(WarmupFinished)) == 2
    second = [e for e in cell.of(ReferenceMeasured) if e.run == 2]
    assert second and second[0].phase == "warmup" and not any(e.baseline for e in second)
    # the same reference pose in both runs (stored with the plan)
    plans = cell.of(PlanReady)
    assert len(plans) == 2 and np.allclose(plans[0].reference, plans[1].reference)
    # no pose measured twice; the first run's six points are kept, not redone
    rows = cell.store.measurements(cell.campaign)
    assert len(rows) == len({m.index for m in rows}) == len(cell.of(PointMeasured))
    # every reference measurement of both runs is in the result, numbered on, the baseline the first run's
    block = outcome.result.drift
    assert [s["seq"] for s in block["series"]] == list(range(1, len(cell.of(ReferenceMeasured)) + 1))
    assert {s["run"] for s in block["series"]} == {1, 2} and block["baseline"] == baseline.seq
    assert [r["run"] for r in block["warmup"]["runs"]] == [1, 2]
    stored = cell.store.events(cell.campaign, types=("ReferenceMeasured",))
    assert [e.seq for e in stored] == [s["seq"] for s in block["series"]]


def test_a_campaign_interrupted_during_its_warm_up_gets_its_baseline_from_the_next_run(tmp_path):
    cell = Cell(tmp_path, bootstrap=True)
    assert cell.run(stop_after=lambda e: isinstance(e, WarmupProgress)).status == "interrupted"
    assert not any(e.baseline for e in cell.of(ReferenceMeasured))
    assert not [e for e in cell.of(PointMeasured) if e.role != BOOTSTRAP]
    outcome = cell.run()
    assert outcome.status == "accepted", outcome.error
    (base,) = [e for e in cell.of(ReferenceMeasured) if e.baseline]
    assert base.run == 2 and base.phase == "warmup"
    assert outcome.result.drift["baseline"] == base.seq
    assert [w.converged for w in cell.of(WarmupFinished)] == [True]


def test_the_reference_is_approached_from_the_same_side_every_time(tmp_path):
    cell = Cell(tmp_path, thermal=None, warmup__enabled=False, drift__every=4)
    cell.run()
    (plan,) = cell.of(PlanReady)
    ref = np.array(plan.reference)
    targets = cell.arm.targets
    visits = [i for i, q in enumerate(targets) if np.allclose(q, ref)]
    approached = [i for i in visits if np.allclose(targets[i - 1], ref - APPROACH)]
    # every reference visit came from the approach pose (the other visit: its validation measurement)
    assert len(approached) == len(cell.of(ReferenceMeasured)) == len(visits) - 1
    # the reference is one of the validation poses, near the middle of the planned ones
    assert any(np.allclose(ref, p["q"]) for p in plan.poses if p["role"] == VALIDATION)


# --- the engine's part ------------------------------------------------------------------------------
def _engine(arm, tracker, events, clock):
    bus = EventBus()
    bus.subscribe(events.append)
    keep = (np.array([-2.0, -2.0, 0.0]), np.array([2.0, 2.0, 2.0]))
    from hil.arm.geometry import Geometry
    return Engine(arm, tracker, "c1", get_robot("ur5e"), bus=bus, clock=clock, keep_in=keep,
                  check_model=Geometry.nominal("ur5e", (0.0, 0.0, 0.045)))


def test_the_engine_hands_a_reference_visit_back_to_the_plan_only(tmp_path):
    cell = Cell(tmp_path, thermal=None)
    events: list = []
    engine = _engine(cell.arm, cell.tracker, events, cell.clock)
    q = cell.arm.q.copy()

    def plan():
        record = yield acquire(1, REFERENCE, q, settle=0.1, joint_samples=2, samples=2)
        conditions = yield ReadConditions()
        return record, conditions

    record, conditions = engine.run(plan())
    assert isinstance(record, PoseRecord) and record.role == REFERENCE
    assert conditions.t > 0 and conditions.temperatures == (AMBIENT,) * 6
    assert not [e for e in events if isinstance(e, PoseStarted | PointMeasured)]
    assert engine.records == []


def _no_path_to(engine, *targets):
    """Make `engine` find no safe path to any of `targets` (what `Engine._route` says of a box the
    straight path, home and the upright posture all leave)."""
    route = engine._route

    def blocked(q, approach=0.0):
        if any(np.allclose(q, t) for t in targets):
            raise UnsafePathError(f"no safe path to {np.round(q, 3).tolist()}")
        return route(q, approach)

    engine._route = blocked


def test_an_optional_move_without_a_safe_path_is_skipped_not_a_failure(tmp_path):
    cell = Cell(tmp_path, thermal=None)
    events: list = []
    engine = _engine(cell.arm, cell.tracker, events, cell.clock)
    target = tuple(cell.arm.q + 0.01)
    _no_path_to(engine, target)

    def plan():
        skipped = yield Move(target, optional=True)
        visit = yield acquire(2, REFERENCE, target, settle=0.0, joint_samples=1, samples=1)
        return skipped, visit

    skipped, visit = engine.run(plan())
    assert isinstance(skipped, Skipped) and not skipped.lost
    assert isinstance(visit, Skipped)
    assert not [e for e in events if isinstance(e, PoseSkipped)]  # a reference is not a plan pose
    assert engine.state == "done"


def test_a_reference_pose_that_cannot_be_reached_is_said_and_the_run_goes_on(tmp_path):
    cell = Cell(tmp_path, thermal=None, drift__every=6, warmup__max_time=600.0)
    reference: list = []

    def block_the_reference(engine):
        engine.emit = _watching(engine.emit, reference, engine)

    outcome = cell.run(engine_ready=block_the_reference)
    assert outcome.status == "accepted", outcome.error
    assert reference and not cell.of(ReferenceMeasured)
    warnings = [m.text for m in cell.of(Message) if m.level == "warning"]
    assert warnings and all("the reference pose could not be measured" in w for w in warnings)
    (done,) = cell.of(WarmupFinished)
    assert not done.converged and done.reason == "the reference pose could not be measured"
    assert outcome.result.drift["max"] is None and not outcome.result.drift["flagged"]


def _watching(emit, reference, engine):
    """`engine.emit` that, once the plan names its reference pose (PlanReady), blocks every path to it."""
    def wrapped(event):
        if isinstance(event, PlanReady) and not reference:
            reference.append(np.array(event.reference))
            _no_path_to(engine, event.reference)
        emit(event)
    return wrapped


# --- the drift watch against an arm that rings --------------------------------------------------------
#: A ring like the simulated arm's (`mocks.ringing`: 9 Hz, ζ = 0.1; its realistic UR5e's reference,
#: 1 m/rad from the joints, rang 637 µm at the end of the 0.005 rad approach leg at 1 rad/s²) along
#: the tip's direction there (tracker frame), read by 0.1 s readings (GeoCOM's tracking rate).
RING_AMPLITUDE, RING_HZ, RING_ZETA, READING_S = 600e-6, 9.0, 0.10, 0.1
RING_DIRECTION = np.array([0.07, -0.39, 0.92]) / np.linalg.norm([0.07, -0.39, 0.92])


class RingingArm(WarmingArm):
    """A `WarmingArm` that stopped a little before the engine heard it had (a driver's latency, drawn
    per move), so each visit's readings meet its ring at another phase."""

    def move_to(self, q, *, speed=None, acceleration=None):
        reading = super().move_to(q, speed=speed, acceleration=acceleration)
        self.stopped_at = self.clock.now - self.rng.uniform(0.0, 0.15)
        return reading


class RingingTracker(WarmingTracker):
    """A `WarmingTracker` whose every reading integrates the arm's decaying ring over `READING_S`."""

    def ring(self, t: float) -> np.ndarray:
        omega = 2 * np.pi * RING_HZ
        s = np.linspace(t, t + READING_S, 9) - getattr(self.arm, "stopped_at", -1e9)
        x = np.where(s >= 0, np.exp(-RING_ZETA * omega * s) * np.cos(omega * s), 0.0)
        return RING_AMPLITUDE * float(x.mean()) * RING_DIRECTION

    def measure_point(self, samples: int = 1):
        self.measurements += 1
        p = Kinematics(self.truth).points(self.arm.q)[0]
        s = np.empty((samples, 3))
        for k in range(samples):
            s[k] = p + self.ring(self.clock.now) + self.rng.normal(0, self.sigma, 3)
            self.clock.sleep(READING_S)
        return Point(s.mean(0), s.std(0), samples)


def _ringing_cell(tmp_path, **overrides) -> Cell:
    cell = Cell(tmp_path, thermal=None, warmup__enabled=False, drift__every=3, **overrides)
    cell.arm = RingingArm(cell.arm.start, clock=cell.clock, truth=cell.truth)
    cell.tracker = RingingTracker(cell.arm, cell.truth, sigma=5e-6, clock=cell.clock)
    return cell


def test_the_drift_watch_reads_no_drift_on_a_ringing_arm_that_does_not_drift(tmp_path):
    """The arm does not grow at all; only its ring after each move and the tracker's noise differ
    between reference visits. Standing `drift.settle` s and averaging `drift.samples` readings, the
    watch reads the tracker's noise (20 readings of 5 µm: about 2.5 µm between two visits); read like
    a pose (no dwell, 5 readings) the same arm's ring reads as drift several times that."""
    cell = _ringing_cell(tmp_path / "still")
    cell.run()
    watched = [r.drift for r in cell.of(ReferenceMeasured) if not r.baseline]
    assert len(watched) >= 4 and max(watched) < 6e-6, watched
    hasty = _ringing_cell(tmp_path / "hasty", drift__settle=0.0, drift__samples=5)
    hasty.run()
    rung = [r.drift for r in hasty.of(ReferenceMeasured) if not r.baseline]
    assert max(rung) > 10e-6, rung
