import signal
import threading
import time

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry, pose_to_dict
from hil.arm.kinematics import Kinematics
from hil.calibration.synthetic import random_truth
from hil.campaign.calibration_plan import CALIBRATION, Choice, ResumeState, calibration_plan
from hil.campaign.engine import (
    ABORTED,
    DONE,
    FAILED,
    INTERRUPTED,
    Engine,
    RealClock,
    RunAborted,
    RunInterrupted,
    StopRequested,
    Suspender,
    SuspendTimeout,
)
from hil.campaign.events import (
    EventBus,
    PlanReady,
    PointMeasured,
    PoseSkipped,
    Resumed,
    StateChanged,
    Suspended,
    SuspendExtended,
)
from hil.campaign.steps import Acquire, Move, acquire, check_motion, dry_run
from hil.errors import InputError
from hil.station.config import default_config
from tests.hil.campaign.fakes import (
    FakeArm,
    FakeBeamLost,
    FakeHardwareFault,
    FakeProtectiveStop,
    FakeTracker,
    visible_poses,
)


class Station:
    """A fake station: hidden truth, fake arm and tracker, an engine and the events it emitted."""

    def __init__(self, seed=3, tracker_known=True, cal=12, val=6, **arm_kw):
        self.rng = np.random.default_rng(seed)
        self.truth = random_truth("ur5e", self.rng, ideal=True)
        start = visible_poses(self.truth, 1, self.rng)[0]
        self.arm = FakeArm(start, **arm_kw)
        self.tracker = FakeTracker(self.arm, self.truth)
        # warm-up and drift watch off: these tests count moves and measurements of the plan's poses
        # (tests/hil/campaign/test_warmup.py tests those); a fixed settle: one tracker measurement a pose
        # (tests/hil/campaign/test_settle_on_evidence.py tests the "stable" one); one move a pose, no
        # approach leg (tests/hil/campaign/test_approach.py tests that)
        overrides = dict(campaign__calibration_poses=cal, campaign__validation_poses=val,
                         campaign__approach=0.0,
                         robot__settle_time=0.0, robot__settle="fixed",
                         smr__offset=tuple(self.truth.smr + 0.003),
                         warmup__enabled=False, drift__every=0)
        if tracker_known:
            overrides["tracker__position"] = tuple(self.truth.tracker.translation + 0.05)
        self.config = default_config().with_overrides(**overrides)
        self.events = []
        bus = EventBus()
        bus.subscribe(self.events.append, critical=True)
        self.engine = Engine(self.arm, self.tracker, "c1", get_robot("ur5e"), bus=bus,
                             clock=RealClock(), suspenders=self.suspenders(), suspend_timeout=5.0)

    def suspenders(self):
        return [
            Suspender("protective_stop", lambda e: isinstance(e, FakeProtectiveStop),
                      lambda: self.arm.safety_normal(), "clear the protective stop on the pendant",
                      poll=0.01),
            Suspender("beam_lost", lambda e: isinstance(e, FakeBeamLost), lambda: self.tracker.relock(),
                      "bring the SMR back into the beam", poll=0.01),
        ]

    def choose(self, request):
        # the tracker *estimate* in request.model is what a real selector would use
        return Choice(visible_poses(request.model, request.count, self.rng), {"method": "test"})

    def plan(self, **kw):
        return calibration_plan(self.config, self.choose, "c1", **kw)

    def of(self, kind):
        return [e for e in self.events if isinstance(e, kind)]


def test_full_campaign_identifies_the_truth():
    st = Station()
    result = st.engine.run(st.plan())
    assert st.engine.state == DONE
    assert result.passed and result.after.rms < 60e-6 < 1e-3 < result.before.rms
    held_out = visible_poses(st.truth, 50, st.rng)
    err = Kinematics(result.fit.geometry).points(held_out) - Kinematics(st.truth).points(held_out)
    assert np.sqrt(np.mean(np.sum(err**2, 1))) < 60e-6
    measured = st.of(PointMeasured)
    assert len(measured) == 18 and st.tracker.measurements == 18
    assert [e.role for e in measured].count(CALIBRATION) == 12
    plan = st.of(PlanReady)[0]
    assert len(plan.poses) == 18
    assert st.engine.stats.motion >= 0 and st.engine.stats.total > 0


def test_bootstrap_locates_an_unknown_tracker():
    st = Station(tracker_known=False)
    result = st.engine.run(st.plan())
    est, true = result.tracker_estimate, st.truth.tracker
    # small moves and a rough SMR guess: centimetres, but enough to plan line of sight
    assert np.linalg.norm(est.translation - true.translation) < 0.15
    roles = [e.role for e in st.of(PointMeasured)]
    assert roles.count("bootstrap") >= 4 and result.passed


def test_bootstrap_with_the_beam_never_seen_fails_saying_why():
    st = Station(tracker_known=False)
    st.tracker.lose_beam = 10**6
    st.engine.suspenders = [Suspender("beam_lost", lambda e: isinstance(e, FakeBeamLost), lambda: False,
                                      "bring the SMR back into the beam", poll=0.01, timeout=0.05,
                                      on_timeout="skip")]
    with pytest.raises(Exception, match=r"cannot locate the tracker: 0 of \d+ bootstrap points measured"):
        st.engine.run(st.plan())
    assert st.engine.state == FAILED


def test_protective_stop_mid_move_suspends_and_resumes():
    st = Station(protective_stop_on_moves={3})
    result = st.engine.run(st.plan())
    assert [e.kind for e in st.of(Suspended)] == ["protective_stop"]
    assert "pendant" in st.of(Suspended)[0].message
    assert [e.kind for e in st.of(Resumed)] == ["protective_stop"]
    assert st.arm.stops >= 1 and result.passed
    # the interrupted pose was visited again from its move: every target reached exactly once
    assert len(st.of(PointMeasured)) == 18
    states = [e.state for e in st.of(StateChanged)]
    assert states[:3] == ["running", "suspended", "running"] and states[-1] == "done"


def test_lost_beam_relocks_and_goes_on():
    st = Station()
    st.tracker.lose_beam = 2
    result = st.engine.run(st.plan())
    assert [e.kind for e in st.of(Suspended)] == ["beam_lost"]
    assert st.tracker.relocks >= 1 and result.passed


def test_unhandled_fault_stops_the_arm_and_fails():
    st = Station(fail_on_move=5)
    with pytest.raises(FakeHardwareFault):
        st.engine.run(st.plan())
    assert st.engine.state == FAILED and st.arm.stops == 1
    assert len(st.of(PointMeasured)) == 4  # what was measured was emitted (and so recorded)


def test_suspender_that_never_clears_times_out():
    st = Station(protective_stop_on_moves={2}, safety_clear_after_checks=10**9)
    st.engine.suspend_timeout = 0.2
    with pytest.raises(SuspendTimeout, match="protective_stop did not clear"):
        st.engine.run(st.plan())
    assert st.engine.state == FAILED


def test_ctrl_c_mid_move_stops_the_arm_first_and_ends_interrupted_not_aborted():
    st = Station()
    original = st.arm.move_to
    stops_at_event = []
    st.engine.bus.subscribe(lambda e: stops_at_event.append(st.arm.stops) if isinstance(e, StateChanged)
                            else None)

    def move(q, **kw):
        if st.arm.moves == 4:
            raise RunInterrupted(signal.SIGTERM)  # what the CLI's handler raises, wherever it lands
        return original(q, **kw)

    st.arm.move_to = move
    with pytest.raises(RunInterrupted):
        st.engine.run(st.plan())
    assert st.engine.state == INTERRUPTED and st.arm.stops == 1
    states = [e.state for e in st.of(StateChanged)]
    assert states[-2:] == ["stopping", "interrupted"] and "aborted" not in states
    assert stops_at_event[-2:] == [1, 1]  # the arm was stopped before anything else happened
    assert not st.of(Suspended)  # an interruption is never a suspension to wait out


def test_abort_from_another_thread_stops_the_arm():
    st = Station(cal=30, val=10)
    original = st.arm.move_to

    def slow_move(q, **kw):
        if st.arm.moves == 6:  # the request made from another thread during this move; waited for, as a
            # loaded machine may not run that thread before the fake arm has finished every pose
            abort = threading.Thread(target=st.engine.request_abort)
            abort.start()
            abort.join(10)
        return original(q, **kw)

    st.arm.move_to = slow_move
    with pytest.raises(RunAborted):
        st.engine.run(st.plan())
    assert st.engine.state == ABORTED and st.arm.stops == 1
    assert len(st.of(PointMeasured)) < 40


def test_interrupt_stops_a_move_in_progress_and_ends_the_run_interrupted():
    """A UI's quit: the arm's stop goes out at once (not after the pose visit) and the run ends
    interrupted (resumable), not failed by the stopped move's error nor aborted."""
    st = Station(cal=30, val=10)
    stopped = threading.Event()
    original_move, original_stop = st.arm.move_to, st.arm.stop

    def long_move(q, **kw):
        if st.arm.moves == 5:  # the 6th move runs until the arm is stopped
            st.arm.moves += 1
            threading.Thread(target=st.engine.request_interrupt, args=("quit mid-run",)).start()
            assert stopped.wait(5.0), "the arm was not stopped during the move"
            raise FakeHardwareFault("motion aborted by stop()")
        return original_move(q, **kw)

    def stop():
        stopped.set()
        original_stop()

    st.arm.move_to, st.arm.stop = long_move, stop
    with pytest.raises(StopRequested, match="quit mid-run"):
        st.engine.run(st.plan())
    assert st.engine.state == INTERRUPTED
    assert len(st.of(PointMeasured)) == 5
    assert "failed" not in [e.state for e in st.of(StateChanged)]


def beam_station(timeout: float, clear) -> Station:
    """A station whose first measurement loses the beam; the beam suspender skips on time-out."""
    st = Station()
    st.tracker.lose_beam = 1
    st.engine.suspenders = [Suspender("beam_lost", lambda e: isinstance(e, FakeBeamLost), clear,
                                      "clear the line of sight", poll=0.01, timeout=timeout,
                                      on_timeout="skip")]
    return st


def test_the_operator_skips_a_suspended_pose_now():
    st = beam_station(60.0, lambda: False)
    st.engine.bus.subscribe(lambda e: isinstance(e, Suspended) and st.engine.request_skip())
    result = st.engine.run(st.plan())
    suspended = st.of(Suspended)[0]
    assert (suspended.timeout, suspended.on_timeout) == (60.0, "skip")
    assert suspended.message == "clear the line of sight" and "FakeBeamLost" in suspended.detail
    [skipped] = st.of(PoseSkipped)
    assert "skipped by the operator" in skipped.reason and "beam lost" in skipped.reason
    assert len(st.of(PointMeasured)) == 17 and result.passed


def test_a_skip_asked_for_before_a_suspension_is_not_applied_to_it():
    st = beam_station(60.0, lambda: True)
    st.engine.request_skip()
    st.engine.run(st.plan())
    assert not st.of(PoseSkipped) and len(st.of(Resumed)) == 1


def test_waiting_longer_moves_the_time_limit_of_the_suspension():
    start = []

    def clear():  # the beam comes back after 0.5 s: past the 0.2 s limit, within the extended one
        return time.monotonic() - start[0] > 0.5

    st = beam_station(0.2, clear)

    def extend(event):
        if isinstance(event, Suspended):
            start.append(time.monotonic())
            for _ in range(5):
                st.engine.request_extend()

    st.engine.bus.subscribe(extend)
    st.engine.run(st.plan())
    [extended] = st.of(SuspendExtended)
    assert extended.kind == "beam_lost" and 0.9 < extended.timeout <= 1.2
    assert not st.of(PoseSkipped) and [e.kind for e in st.of(Resumed)] == ["beam_lost"]


def test_pause_and_resume_between_poses():
    st = Station()
    done = []

    def pause_then_resume(event):
        if isinstance(event, PointMeasured) and event.index == 2 and not done:
            done.append(1)
            st.engine.request_pause()
        # the resume once the engine is paused, not after a fixed delay: a resume that came before the
        # engine looked at its pause request (a loaded machine) would cancel the pause unseen
        if isinstance(event, StateChanged) and event.state == "paused":
            threading.Timer(0.1, st.engine.request_resume).start()

    st.engine.bus.subscribe(pause_then_resume)
    st.engine.run(st.plan())
    states = [e.state for e in st.of(StateChanged)]
    assert "paused" in states and states[-1] == "done"


def test_resume_measures_only_what_is_missing():
    st = Station()
    first = st.plan()
    with pytest.raises(RunAborted):
        st.engine.max_retries = 0

        def abort_after_7(event):
            if isinstance(event, PointMeasured) and len(st.of(PointMeasured)) == 7:
                st.engine.request_abort()

        st.engine.bus.subscribe(abort_after_7)
        st.engine.run(first)
    plan_event = st.of(PlanReady)[0]
    records = {(r.role, r.index): r for r in st.engine.records}
    assert len(records) == 7
    resume = ResumeState(poses=[(p["index"], p["role"], np.array(p["q"])) for p in plan_event.poses],
                         tracker=Geometry.from_dict({**Geometry.nominal("ur5e").to_dict(),
                                                     "tracker": plan_event.tracker}).tracker,
                         records=records)
    st2 = Station()
    st2.arm, st2.tracker = st.arm, st.tracker
    st2.engine.robot, st2.engine.tracker = st.arm, st.tracker
    before = st.tracker.measurements
    result = st2.engine.run(st2.plan(resume=resume))
    assert st.tracker.measurements - before == 18 - 7
    assert result.passed and len(result.records) == 18


def test_engine_refuses_targets_outside_the_limits_without_moving():
    st = Station()
    bad = acquire(0, CALIBRATION, [0, 0, 3.5, 0, 0, 0], settle=0, joint_samples=1, samples=1)

    def plan():
        yield bad

    with pytest.raises(InputError, match="q3 = 3.5000 rad is outside the joint limits"):
        st.engine.run(plan())
    assert st.arm.moves == 0 and st.arm.stops == 1


def test_dry_run_checks_every_motion_before_the_arm_moves():
    st = Station()

    def plan():
        for i, q in enumerate(visible_poses(st.truth, 5, st.rng)):
            record = yield acquire(i, CALIBRATION, q, settle=0, joint_samples=1, samples=1)
            assert record == ("canned", i)
        return "done"

    cfg = st.config
    steps, value = dry_run(plan(), lambda step: ("canned", step.index) if isinstance(step, Acquire) else None)
    assert value == "done" and len(steps) == 5
    spec = get_robot("ur5e")
    model = Geometry.nominal("ur5e", cfg.smr["offset"])
    box = (np.array([-2.0, -2.0, -2.0]), np.array([2.0, 2.0, 2.0]))
    assert check_motion(steps, spec, box, model) == 5
    tight = (np.array([-0.1, -0.1, -0.1]), np.array([0.1, 0.1, 0.1]))
    with pytest.raises(InputError, match="outside the keep-in box"):
        check_motion(steps, spec, tight, model)
    with pytest.raises(InputError, match="joint limits"):
        check_motion([Move((0, 0, 0, 0, 7.0, 0))], spec)
    assert pose_to_dict(model.tracker)["xyz"] == [0.0, 0.0, 0.0]
