"""The sweep's recording in the engine and the store: each segment streamed with the robot's `follow`
beside the tracker's stream, committed in chunks as `SweepChunk` events arrive, whole once its
`SweepSegmentDone` names its take; an interrupted sweep resumes from the store without sweeping again
what it has, and a segment cut short is swept again, its partial chunks never read."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

from drivers.robot.model import FollowResult, RobotIdentity
from drivers.tracker.device import PointStatus, StreamSample
from drivers.tracker.errors import TargetLost
from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.campaign.engine import Engine, RealClock
from hil.campaign.events import EventBus, Message, SweepChunk, SweepSegmentDone
from hil.campaign.runner import store_recorder, sweep_state
from hil.campaign.steps import SegmentRecord, Sweep, SweepRecorded, SweepSegment
from hil.campaign.sweep_plan import first_clock, streams_of
from hil.campaign.sweep_recording import CHUNK, anchor, breaks, tracker_record
from hil.station.config import default_config
from hil.store import Store
from tests.hil.campaign.fakes import FakeArm, TrackerParts

START = np.array([0.1, -1.4, 1.3, -1.5, -1.5, 0.2])
TRK_OFFSET = 1234.5  # the tracker's clock: its own, far from the controller's


@dataclass
class SweepArm(FakeArm):
    """A fake arm that streams: `follow` moves through the samples and reports, per sample, the
    controller's stamp and actual_q (the path itself, plus encoder noise); it can be interrupted
    (Ctrl-C) on the `interrupt_on`-th stream, half way."""

    interrupt_on: int | None = None

    def __post_init__(self) -> None:
        super().__post_init__()
        self.follows = 0
        self.clock = 100.0  # the controller's running time (s)
        self.streamed: list[np.ndarray] = []
        self.path: list[tuple[float, np.ndarray]] = []  # every (controller time, q) it went through

    def follow(self, Q: Any, *, lookahead: float = 0.1, gain: float = 300.0,
               settle: float = 0.0) -> FollowResult:
        self.follows += 1
        Q = np.asarray(Q, float)
        assert np.max(np.abs(Q[0] - self.q)) < 1e-9, "a stream starts where the arm stands"
        n = len(Q) // 2 if self.follows == self.interrupt_on else len(Q)
        t = self.clock + np.arange(n) * 0.002
        self.path += list(zip(t, Q[:n], strict=True))
        self.clock = float(t[-1]) + 0.5
        self.q = Q[n - 1].copy()
        if n < len(Q):
            raise KeyboardInterrupt
        self.streamed.append(Q)
        return FollowResult(times=np.arange(n) * 0.002, hold_end=0.0, period_count=n, period_mean=0.002,
                            period_max=0.002, controller_t=t,
                            actual_q=Q + self.rng.normal(0, 1e-6, Q.shape))


class StreamTracker(TrackerParts):
    """A fake emScon stream: the SMR where the arm's path put it, stamped on the tracker's clock
    (offset `TRK_OFFSET` from the controller's), `lost` samples in a row without a position."""

    def __init__(self, arm: SweepArm, truth: Geometry, lost: int = 0) -> None:
        self.arm, self.kin, self.lost = arm, Kinematics(truth), lost

    def stream(self, rate_hz: float, *, stop: threading.Event | None = None,
               **_: Any) -> Iterator[StreamSample]:
        seen, k = len(self.arm.path), 0
        while True:
            ended = stop is not None and stop.is_set()  # what the arm did before the stop was heard
            while len(self.arm.path) - seen > k:
                t, q = self.arm.path[seen + k]
                k += 1
                if 10 <= k < 10 + self.lost:
                    yield StreamSample(t, None, None, "beam lost")
                else:
                    yield StreamSample(t, tuple(map(float, self.kin.points(q)[0])), PointStatus.OK,
                                       stamp=t + TRK_OFFSET)
            if ended:
                return
            if stop is not None:
                stop.wait(0.001)


def segments(count: int = 4, n: int = 700) -> tuple[SweepSegment, ...]:
    """`count` rest-to-rest segments of `n` samples, joint 1 and 2 swinging a few tenths of a radian."""
    out, here = [], START.copy()
    for k in range(count):
        there = here + np.array([0.3, -0.1, 0.1, 0.0, 0.05, 0.0]) * (-1) ** k
        s = (1 - np.cos(np.linspace(0, np.pi, n))) / 2
        out.append(SweepSegment(k, here + s[:, None] * (there - here)))
        here = there
    return tuple(out)


@pytest.fixture
def store(tmp_path):
    with Store.open(tmp_path / "hil.db") as s:
        yield s


def engine_for(store: Store, campaign: str, arm: SweepArm, tracker: StreamTracker) -> Engine:
    bus = EventBus()
    bus.subscribe(store_recorder(store), critical=True)
    return Engine(arm, tracker, campaign, get_robot("ur5e"), bus=bus, clock=RealClock(), home=START)


def sweep_plan(step: Sweep) -> Iterator[Any]:
    return (yield step)


def test_an_interrupted_sweep_resumes_at_the_first_segment_not_recorded_whole(store):
    truth = Geometry.nominal("ur5e")
    cid = store.create_campaign(default_config().as_dict(), RobotIdentity("ur5e", "9999001"))
    plan = segments(4)
    arm = SweepArm(START, interrupt_on=3)  # Ctrl-C half way through the third segment
    tracker = StreamTracker(arm, truth, lost=5)
    with pytest.raises(KeyboardInterrupt):
        engine_for(store, cid, arm, tracker).run(sweep_plan(Sweep(plan, 4, 1000.0, "run-1")))
    kept = sweep_state(store, cid)
    assert sorted(kept) == [0, 1]  # the third was cut short: its chunks (if any) are not read
    for k in (0, 1):  # every sample the arm reported, once, in order, as the arm reported it
        assert len(kept[k].joint_t) == len(plan[k].q)
        assert np.allclose(np.diff(kept[k].joint_t), 0.002)
        assert np.allclose(kept[k].tracker_t, kept[k].joint_t + TRK_OFFSET)  # the tracker's own stamps
        assert np.allclose(kept[k].joint_q, plan[k].q, atol=1e-5)
        assert len(kept[k].tracker_t) == len(plan[k].q)
        assert np.isnan(kept[k].tracker_p).any(axis=1).sum() == 5 and breaks(kept[k].tracker_p) == 1
    # resumed: only the segments not recorded whole are swept, from the arm where it stopped
    left = tuple(s for s in plan if s.index not in kept)
    arm.interrupt_on = None
    got = engine_for(store, cid, arm, tracker).run(sweep_plan(Sweep(left, 4, 1000.0, "run-2")))
    assert isinstance(got, SweepRecorded) and [r.index for r in got.segments] == [2, 3]
    assert len(arm.streamed) == 4  # 0, 1, then 2 (again, whole) and 3: nothing recorded is swept again
    final = sweep_state(store, cid)
    assert sorted(final) == [0, 1, 2, 3]
    assert [final[k].session for k in range(4)] == ["run-1"] * 2 + ["run-2"] * 2
    assert np.allclose(final[2].joint_q, plan[2].q, atol=1e-5)
    done = store.events(cid, types=("SweepSegmentDone",))
    assert [e.segment for e in done] == [0, 1, 2, 3]
    assert all(isinstance(e, SweepSegmentDone) and e.joints == 700 and e.lost == 5 for e in done)


def test_chunks_are_committed_as_their_events_arrive_and_logged_without_their_samples(store):
    truth = Geometry.nominal("ur5e")
    cid = store.create_campaign(default_config().as_dict(), RobotIdentity("ur5e", "9999002"))
    arm = SweepArm(START)
    seen: list[tuple[str, int, int]] = []

    def count(event: Any) -> None:  # after the store (critical): the chunk is in it already
        if isinstance(event, SweepChunk):
            stamps, _ = store.stream_chunks(cid, event.segment, event.take, event.stream)
            seen.append((event.stream, event.chunk, len(stamps)))

    engine = engine_for(store, cid, arm, StreamTracker(arm, truth))
    engine.bus.subscribe(count)
    engine.run(sweep_plan(Sweep(segments(1, n=1201), 1, 1000.0, "run-1")))
    assert [s for s in seen if s[0] == "joints"] == [("joints", 0, CHUNK), ("joints", 1, 2 * CHUNK),
                                                     ("joints", 2, 1201)]
    logged = store.event_log(cid, types=("SweepChunk",))
    assert logged and all("stamps" not in d and "values" not in d and d["count"] > 0 for _, d in logged)


def test_lost_samples_are_placed_on_the_trackers_clock_and_breaks_counted():
    s = [StreamSample(10.0 + 0.001 * k, (0.0, 0.0, float(k)), PointStatus.OK, stamp=5.0 + 0.001 * k)
         for k in range(20)]
    s[5:8] = [StreamSample(10.005 + 0.001 * k, None, None, "lost") for k in range(3)]
    t, p = tracker_record(s)
    assert np.allclose(t, 5.0 + 0.001 * np.arange(20)) and breaks(p) == 1
    assert np.isnan(p[5:8]).all() and not np.isnan(np.delete(p, [5, 6, 7], axis=0)).any()


def test_segments_of_another_session_are_counted_not_joined():
    rec = [SegmentRecord(k, "a" if k < 3 else "b", np.arange(5) + 10.0 * k, np.zeros((5, 6)),
                         np.arange(4) + 10.0 * k, np.zeros((4, 3))) for k in range(4)]
    joints, tracker, left, _ = streams_of(rec)
    assert len(joints.t) == 15 and len(tracker.t) == 12 and left == {"other session": 4}


def test_the_first_clock_comes_from_the_host_anchors():
    """Each segment ties both instruments' stamps to the host's clock; a line through the anchors of
    segments minutes apart gives the map's offset and drift (here a fast-time station's: drift 3)."""
    host = np.arange(0.0, 2.0, 0.002)
    ctrl = 50.0 + 4.0 * host  # the controller's seconds run 4 times the host's
    samples = [StreamSample(float(h), (0.0, 0.0, 0.0), PointStatus.OK, stamp=1000.0 + float(h))
               for h in host[::3]]
    t_trk, t_ctrl = anchor(samples, ctrl, host)
    assert t_ctrl == pytest.approx(50.0 + 4.0 * (t_trk - 1000.0))
    recs = [SegmentRecord(k, "s", np.zeros(2), np.zeros((2, 6)), np.zeros(2), np.zeros((2, 3)),
                          (1000.0 + 30.0 * k, 50.0 + 4.0 * 30.0 * k)) for k in range(3)]
    offset, drift = first_clock(recs)
    assert drift == pytest.approx(3.0) and offset == pytest.approx(50.0 - 4.0 * 1000.0)
    assert first_clock([SegmentRecord(0, "s", np.zeros(2), np.zeros((2, 6)), np.zeros(2),
                                      np.zeros((2, 3)))]) == (None, 0.0)


def test_a_later_run_on_the_same_clocks_is_joined_one_on_restarted_clocks_is_not():
    def rec(k: int, session: str, shift: float = 0.0) -> SegmentRecord:
        t = 1000.0 + 30.0 * k
        return SegmentRecord(k, session, np.arange(5) + 10.0 * k, np.zeros((5, 6)), np.arange(4) + 10.0 * k,
                             np.zeros((4, 3)), (t, 50.0 + 1.00002 * t + shift))
    same = [rec(0, "a"), rec(1, "a"), rec(2, "b")]
    assert streams_of(same)[2] == {"other session": 0}
    restarted = [rec(0, "a"), rec(1, "a"), rec(2, "b", shift=-700.0)]  # the controller rebooted
    assert streams_of(restarted)[2] == {"other session": 4}


class LosingTracker(StreamTracker):
    """A stream that cannot start on the arm's second segment: the reflector is not found there."""

    def stream(self, rate_hz: float, **kw: Any) -> Iterator[StreamSample]:
        if len(self.arm.streamed) == 1:
            raise TargetLost("FindReflector found no reflector", 10004, 0)
        yield from super().stream(rate_hz, **kw)


def test_a_segment_that_keeps_losing_the_beam_is_left_out_and_the_sweep_goes_on(store):
    """As a pose visit that cannot be measured is skipped: the segment is said left out, the arm is
    stopped, and the next segments are swept and recorded (the plan visits still what it would have
    read)."""
    truth = Geometry.nominal("ur5e")
    cid = store.create_campaign(default_config().as_dict(), RobotIdentity("ur5e", "9999001"))
    arm = SweepArm(START)
    said: list = []
    engine = engine_for(store, cid, arm, LosingTracker(arm, truth))
    engine.bus.subscribe(said.append)
    got = engine.run(sweep_plan(Sweep(segments(3), 3, 1000.0, "run-1")))
    assert isinstance(got, SweepRecorded) and [r.index for r in got.segments] == [0, 2]
    assert sorted(sweep_state(store, cid)) == [0, 2]
    (left,) = [e for e in said if isinstance(e, Message)]
    assert "sweep segment 1 left out" in left.text and "no reflector" in left.text
    assert arm.stops >= 1
