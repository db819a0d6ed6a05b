"""A sweep's rests read off its own streams: the arm comes up to the pose from below, holds, and the
tracker's stream while it holds is the still measurement.

Stop-and-go measures a still pose with a move approached from below (`hil.campaign.steps.acquire`),
a wait for the tracker to agree with itself and stationary readings: about a second and a half at the
example station (two readings of ``tracker.measure_time``, the approach leg, the joint reading). A
sweep that rests at a pose already streams both instruments at 1 kHz and 500 Hz, so its segment ends
the same way instead: its path comes up the last ``campaign.approach`` to the pose in every joint
(`approach_knots`: every joint then lags to the same side as a stop-and-go pose's, so the pose means
what stop-and-go's means), holds there `REST_DWELL_S` (`with_dwell`), and the last `REST_WINDOW_S` of
the hold in the tracker's stream is the reading (`rest_reading`), judged still as stop-and-go judges
its readings (`hil.campaign.stillness.judge`, on `REST_BLOCKS` block means against
``campaign.stability``). Where it is not still, or the beam was lost, the pose is measured the
stop-and-go way after all: the reading is never forced.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hil.arm.joint_directions import directions_along
from hil.campaign.events import Message, PointMeasured, PoseReached
from hil.campaign.steps import Emit, Plan, PoseRecord, SegmentRecord, SweepSegment
from hil.campaign.stillness import judge

#: s the arm holds at a rest. A stop rings in the arm's first mode (7-12 Hz for a lightweight 6-axis
#: arm, Wu 2021, doi 10.20517/ir.2021.11; the simulator's `mocks.ringing`: 9 Hz, ζ 0.10, a time
#: constant 1/(ζωₙ) of 0.18 s): 0.5 s is 2.8 time constants, 6 % of the ring left when the hold ends,
#: and the reading is its last `REST_WINDOW_S`, which starts 1.7 time constants in. hil's choice.
REST_DWELL_S = 0.5
#: s of the hold's end that make the reading: 200 samples at the AT960's 1000 Hz, averaging the
#: per-sample noise down as a 0.2 s stationary measurement does.
REST_WINDOW_S = 0.2
#: Block means the window is judged still by: each 50 ms, a reading's worth of samples.
REST_BLOCKS = 4
#: The share of the window's expected samples that must be there (the beam kept, no stall).
REST_PRESENT = 0.8


@dataclass(frozen=True)
class RestReading:
    """A still point read off a segment's hold: tracker point (m) and joints (rad), their spreads."""

    p: np.ndarray
    p_spread: np.ndarray
    q: np.ndarray
    q_spread: np.ndarray
    samples: int


def approach_knots(knots: np.ndarray, approach: float) -> np.ndarray:
    """`knots` with a knot `approach` rad below the last one in every joint before it: the path then
    ends coming up to its pose, as stop-and-go's visits do (`Move.approach`). None added for 0."""
    knots = np.asarray(knots, dtype=float)
    if approach <= 0:
        return knots
    return np.vstack([knots[:-1], knots[-1] - approach, knots[-1:]])


def ends_from_below(q: np.ndarray) -> bool:
    """Whether a planned path's joints all last move up (`hil.arm.joint_directions`'s rule): a smooth
    path through the approach knot may overshoot its end and come back down, and then its rest would
    not lag as a stop-and-go pose does."""
    signs = directions_along(np.asarray(q, dtype=float)[-max(2, len(q) // 2):])
    return bool(np.all(signs[-1] > 0))


def with_dwell(q: np.ndarray, rate_hz: float, dwell_s: float = REST_DWELL_S) -> tuple[np.ndarray, int]:
    """`q` (n, 6) with its last sample held `dwell_s` at `rate_hz` more; the samples added."""
    hold = round(dwell_s * rate_hz)
    q = np.asarray(q, dtype=float)
    return np.vstack([q, np.repeat(q[-1:], hold, axis=0)]), hold


def _tail(t: np.ndarray, share: float) -> np.ndarray:
    """The samples in the last `share` of the span of stamps `t`."""
    if len(t) < 2:
        return np.zeros(len(t), dtype=bool)
    return t >= t[-1] - share * (t[-1] - t[0])


def rest_reading(record: SegmentRecord, segment: SweepSegment, stability: float,
                 window_s: float = REST_WINDOW_S) -> RestReading | str:
    """The still point of `segment`'s hold in its `record`, or why there is none.

    Each stream's stamps run on its own clock, and the map between them is what the fit finds later;
    a hold needs none: the window is the same share of each stream's span as the last `window_s` is
    of the planned path (the servo loop sends the path at a steady period, so a stream's time is
    proportional to the path's whichever clock stamps it), inside the hold's last part with room."""
    if segment.dwell <= 0:
        return "the segment does not hold at its end"
    rate = float(segment.rate_hz)
    window = round(window_s * rate)
    if window >= segment.dwell:
        return f"the hold ({segment.dwell / rate:g} s) is no longer than the reading's window"
    share = window / max(1, len(segment.q) - 1)
    tt, tp = np.asarray(record.tracker_t, float), np.asarray(record.tracker_p, float)
    in_window = _tail(tt, share)
    span = float(tt[-1] - tt[0]) if len(tt) > 1 else 0.0
    expected = share * span / float(np.median(np.diff(tt))) if len(tt) > 2 else 0.0
    present = in_window & np.isfinite(tp).all(axis=1)
    if expected <= 0 or present.sum() < REST_PRESENT * expected or present.sum() < 2 * REST_BLOCKS:
        return f"{int(present.sum())} tracker samples in the hold's last {window_s:g} s (the beam lost?)"
    P = tp[present]
    blocks = np.array([b.mean(axis=0) for b in np.array_split(P, REST_BLOCKS)])
    verdict = judge(blocks, stability)
    if not verdict.still:
        return f"the hold was not still: {verdict.describe(stability)}"
    jq = np.asarray(record.joint_q, float)
    Q = jq[_tail(np.asarray(record.joint_t, float), share)]
    if len(Q) < 2:
        return "fewer than two joint frames in the hold's window"
    return RestReading(P.mean(axis=0), P.std(axis=0, ddof=1), Q.mean(axis=0), Q.std(axis=0, ddof=1),
                       len(P))


def hold_point(campaign: str, index: int, role: str, target: np.ndarray, segment: SweepSegment | None,
               record: SegmentRecord | None, stability: float) -> Plan:
    """Pose `index` (`role`) read off the hold of `segment` (its `record`), its `PoseReached` and
    `PointMeasured` emitted as a visit's are (the store keeps the point); returns the `PoseRecord`, or
    None when the pose must be visited still instead (said why when the hold was not good enough)."""
    if segment is None or record is None or segment.dwell <= 0:
        return None
    read = rest_reading(record, segment, stability)
    if isinstance(read, str):
        yield Emit(Message(campaign=campaign, level="info", text=f"{role} pose {index} measured with a "
                                                                 f"stop: {read}"))
        return None
    seconds = segment.dwell / float(segment.rate_hz)
    target = [float(v) for v in target]
    yield Emit(PoseReached(campaign=campaign, index=index, role=role, q=read.q.tolist(),
                           q_spread=read.q_spread.tolist(), seconds=seconds))
    yield Emit(PointMeasured(campaign=campaign, index=index, role=role, q=read.q.tolist(), p=read.p.tolist(),
                             p_spread=read.p_spread.tolist(), samples=read.samples,
                             q_spread=read.q_spread.tolist(), target=target))
    return PoseRecord(index, role, np.asarray(target), read.q, read.q_spread, read.p, read.p_spread,
                      read.samples, seconds)
