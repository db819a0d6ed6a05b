"""A sweep's rests read off its own streams: the hold's last part is the reading when it is still,
and nothing is read (the pose is visited still) when it rang, lost the beam or did not hold."""

from __future__ import annotations

import numpy as np

from hil.arm.joint_directions import directions_along
from hil.calibration.sweep_path import plan_leg
from hil.campaign.events import Message, PointMeasured, PoseReached
from hil.campaign.steps import Emit, PoseRecord, SegmentRecord, SweepSegment, dry_run
from hil.campaign.sweep_rests import (
    REST_DWELL_S,
    approach_knots,
    ends_from_below,
    hold_point,
    rest_reading,
    with_dwell,
)

POSE = np.array([0.0, -1.2, 1.4, -1.8, -1.57, 0.0])
END = np.array([0.4, -1.0, 1.2, -1.6, -1.4, 0.3])
STABILITY = 50e-6


def _held(rate: float = 500.0) -> SweepSegment:
    leg = plan_leg(approach_knots(np.vstack([POSE, END]), 0.005), max_speed=1.0, max_acceleration=1.0,
                   rate_hz=rate)
    q, hold = with_dwell(np.asarray(leg.q), rate)
    return SweepSegment(3, q, rate, None, hold)


def _record(segment: SweepSegment, tail: np.ndarray | None = None, speed: float = 4.0,
            seed: int = 0) -> SegmentRecord:
    """The segment's record as a station at `speed` streams it: controller stamps `speed` times the
    servo loop's wall period apart, the tracker's 1 ms apart on its own clock, starting 30 ms early
    and ending 20 ms late; the SMR on a line while moving and at `END`'s point (noise 10 µm) while
    the arm holds, plus `tail` (added to the last samples)."""
    rng = np.random.default_rng(seed)
    n = len(segment.q)
    wall = np.arange(n) / segment.rate_hz
    joint_t = 1000.0 + speed * wall
    joint_q = segment.q + rng.normal(0.0, 5e-6, segment.q.shape)
    tracker_t = 50.0 + np.arange(-0.03, wall[-1] + 0.02, 0.001)
    moving = n - segment.dwell
    share = np.clip((tracker_t - 50.0) / wall[moving], 0.0, 1.0)[:, None]
    p = np.array([0.1, 0.2, 2.0]) + share * np.array([0.3, -0.1, 0.05])
    p = p + rng.normal(0.0, 10e-6, p.shape)
    if tail is not None:
        p[-len(tail):] += tail
    return SegmentRecord(segment.index, "s", joint_t, joint_q, tracker_t, p)


def test_a_still_hold_is_read_as_a_still_pose_from_its_last_part():
    segment = _held()
    assert segment.dwell == round(REST_DWELL_S * 500)
    read = rest_reading(_record(segment), segment, STABILITY)
    assert not isinstance(read, str), read
    np.testing.assert_allclose(read.p, [0.4, 0.1, 2.05], atol=5e-6)  # 200 samples of 10 µm noise
    np.testing.assert_allclose(read.q, END, atol=2e-6)
    assert 180 <= read.samples <= 230
    assert np.all(read.p_spread < 20e-6)


def test_a_hold_that_rings_lost_the_beam_or_is_absent_is_not_read():
    segment = _held()
    t = np.arange(300) / 1000.0
    ring = 200e-6 * np.cos(2 * np.pi * 9.0 * t)[:, None] * np.array([1.0, 0.0, 0.0])
    assert "not still" in rest_reading(_record(segment, tail=ring), segment, STABILITY)
    lost = np.zeros((150, 3))
    lost[:] = np.nan
    assert "beam" in rest_reading(_record(segment, tail=lost), segment, STABILITY)
    moving = SweepSegment(3, segment.q[: -segment.dwell], 500.0)
    assert "does not hold" in rest_reading(_record(segment), moving, STABILITY)


def test_the_path_into_a_rest_comes_up_to_it_in_every_joint():
    knots = approach_knots(np.vstack([POSE, END]), 0.005)
    np.testing.assert_allclose(knots, [POSE, END - 0.005, END])
    q = np.asarray(plan_leg(knots, max_speed=1.0, max_acceleration=1.0).q)
    assert ends_from_below(q) and np.all(directions_along(q)[-1] == 1.0)
    down = np.asarray(plan_leg(np.vstack([POSE, END]), max_speed=1.0, max_acceleration=1.0).q)[::-1]
    assert not ends_from_below(down)  # straight in from above: it would lag the other way
    np.testing.assert_allclose(approach_knots(np.vstack([POSE, END]), 0.0), [POSE, END])


def test_a_hold_read_is_a_measured_point_and_one_not_read_says_why():
    segment = _held()
    steps, record = dry_run(hold_point("c", 7, "validation", END, segment, _record(segment), STABILITY),
                            lambda step: None)
    events = [s.event for s in steps if isinstance(s, Emit)]
    assert [type(e) for e in events] == [PoseReached, PointMeasured]
    assert isinstance(record, PoseRecord) and record.index == 7 and record.role == "validation"
    assert events[1].samples == record.samples and events[1].target == END.tolist()
    t = np.arange(300) / 1000.0
    ring = 200e-6 * np.cos(2 * np.pi * 9.0 * t)[:, None] * np.array([0.0, 1.0, 0.0])
    steps, record = dry_run(hold_point("c", 7, "validation", END, segment, _record(segment, tail=ring),
                                       STABILITY), lambda step: None)
    assert record is None
    (said,) = [s.event for s in steps if isinstance(s, Emit)]
    assert isinstance(said, Message) and "validation pose 7 measured with a stop" in said.text
    assert dry_run(hold_point("c", 7, "validation", END, None, None, STABILITY), lambda s: None) == ([], None)
