"""Recording one segment of a sweep: the arm streamed by the driver, the tracker streamed beside it.

The engine's half of a sweep (`hil.campaign.steps.Sweep`). The robot's `follow` runs the servo loop in
the driver (under `drivers.robot.isolated.IsolatedURRobot`, in its child process, next to ur_rtde)
and hands back the controller's own record of the motion, RTDE ``timestamp`` and ``actual_q`` each
cycle; meanwhile a thread here takes the tracker's continuous stream (`Tracker.stream`, as a MOVEB run
does), whose samples carry the instrument's own stamps (`drivers.tracker.device.StreamSample.stamp`).
Neither clock is the host's, and neither is converted: the join estimates the map between them from
the data (`hil.calibration.stream_join`).

What a segment recorded becomes `SweepChunk` events of `CHUNK` samples each, then a
`SweepSegmentDone` naming the attempt's `take`: the store commits each chunk as its event arrives and a
segment counts only once its done event is in, so a run killed while committing loses only that
segment, which the resumed campaign sweeps again.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import numpy as np

from drivers.robot.model import FollowsPaths
from drivers.tracker.device import StreamSample, Tracker
from drivers.tracker.during import stream_during
from drivers.tracker.errors import TrackerError
from hil.campaign.events import Event, SweepChunk, SweepSegmentDone
from hil.campaign.steps import SegmentRecord, SweepSegment

#: Samples per stored chunk: a few hundred keep each commit small (tens of kB of JSON) while a
#: 1000 Hz stream needs only a few commits a second.
CHUNK = 500

#: servoJ lookahead (s) and gain of a sweep: MOVEB's (`hil.moveb.run`), within UR's documented ranges
#: (lookahead 0.03-0.2 s, gain 100-2000; docs/design.md, Facts: streaming on UR): a short lookahead
#: keeps the arm close to the planned path, which the tour was checked along.
LOOKAHEAD = 0.05
GAIN = 1000.0


def record_segment(robot: Any, tracker: Tracker, segment: SweepSegment, tracker_rate_hz: float,
                   session: str) -> SegmentRecord:
    """Stream `segment` with the robot's `follow` while the tracker streams; the two records.

    A tracker stream that fails (a dropped link) is raised after the motion, as the typed error it
    was, so the engine's suspenders can clear it and sweep the segment again. A robot that cannot
    stream (no `follow`) or does not report its joints while streaming is refused.

    The samples go out one per period of the servo loop, which keeps the wall clock's period: on a
    simulated station in fast time (its seconds `speed` times the wall's) the arm therefore follows
    the path `speed` times slower in the station's time than planned. Resampling the path to the
    station's time would be faithful, but the driver checks each step against the joint speed limits
    per wall period (`drivers.robot.ur.URRobot.follow`) and would refuse it; a real station (speed 1)
    follows the plan as planned."""
    if not isinstance(robot, FollowsPaths):
        raise TypeError(f"{type(robot).__name__} cannot stream a path (no follow): the sweep needs it")
    if tracker.lock_status() != "locked in":
        # the arm came here by a move that was not swept (`hil.campaign.sweep_plan.tour_segments`) or
        # the last segment lost the beam: emScon re-locks only when asked, so ask before streaming (a
        # failed search leaves the stream's start to fail as a lost target, which the engine suspends on)
        tracker.relock()
    samples, result = stream_during(
        tracker, tracker_rate_hz, lambda: robot.follow(segment.q, lookahead=LOOKAHEAD, gain=GAIN, settle=0.0),
        name="sweep-tracker-stream")
    if result.controller_t is None or result.actual_q is None or len(result.controller_t) < 2:
        raise TrackerError("the robot driver reported no joint stream for the sweep")
    tracker_t, tracker_p = tracker_record(samples)
    return SegmentRecord(segment.index, session, np.asarray(result.controller_t, float),
                         np.asarray(result.actual_q, float).reshape(-1, 6), tracker_t, tracker_p,
                         anchor(samples, result.controller_t if result.host_stamps is None
                                else result.host_stamps, result.host_t))


def anchor(samples: list[StreamSample], controller_t: np.ndarray, host_t: np.ndarray | None
           ) -> tuple[float, float] | None:
    """(tracker stamp, controller stamp) at the middle of the segment on the host's clock: each
    instrument's stamps fitted against when the host heard them (a straight line: over a segment's
    seconds their rates hardly differ), both read at one host instant. Good to the links' latency
    (milliseconds): a first guess the join then fixes from the motion itself, which a sweep on a
    clock with a large drift needs (a simulated station in fast time: its tracker keeps the wall's
    rate, so the map's drift is the speed − 1). None without host times or two stamped samples."""
    stamped = [s for s in samples if s.stamp is not None and s.position is not None]
    if host_t is None or len(host_t) < 2 or len(stamped) < 2:
        return None
    mid = float(np.median(host_t))
    ctrl = np.polyval(np.polyfit(np.asarray(host_t, float), np.asarray(controller_t, float), 1), mid)
    trk = np.polyval(np.polyfit([s.t for s in stamped], [s.stamp for s in stamped], 1), mid)
    return float(trk), float(ctrl)


def tracker_record(samples: list[StreamSample]) -> tuple[np.ndarray, np.ndarray]:
    """The tracker's stream on its own clock: stamps (M,) and points (M, 3), NaN where lost.

    A lost sample carries no instrument stamp (emScon sends nothing while the beam is broken): it is
    placed on the tracker's clock by the host-to-tracker offset of the segment's stamped samples
    (their median, which a delayed packet does not move), so the join can count the break. Repeated
    or backward stamps are dropped (the join needs them strictly increasing)."""
    stamped = [s for s in samples if s.stamp is not None]
    if not stamped:
        return np.zeros(0), np.zeros((0, 3))
    shift = float(np.median([s.stamp - s.t for s in stamped]))
    t = np.array([s.stamp if s.stamp is not None else s.t + shift for s in samples], dtype=float)
    p = np.array([s.position if s.position is not None else (np.nan,) * 3 for s in samples], dtype=float)
    order = np.argsort(t, kind="stable")
    t, p = t[order], p[order]
    keep = np.concatenate([[True], np.diff(t) > 0])
    return t[keep], p[keep]


def breaks(p: np.ndarray) -> int:
    """Runs of lost samples (NaN rows) in a tracker record: the beam breaks it saw."""
    lost = np.isnan(p).any(axis=1).astype(int)
    return int(np.sum(np.diff(np.concatenate([[0], lost])) == 1))


def segment_events(campaign: str, record: SegmentRecord, take: str, total: int,
                   seconds: float, planned: float = 0.0) -> Iterator[Event]:
    """The chunks of `record` (joints first, then the tracker's), then its `SweepSegmentDone`."""
    streams = (("joints", record.joint_t, [list(map(float, q)) for q in record.joint_q]),
               ("tracker", record.tracker_t,
                [None if np.isnan(p).any() else list(map(float, p)) for p in record.tracker_p]))
    for name, stamps, values in streams:
        for k, start in enumerate(range(0, len(stamps), CHUNK)):
            part = stamps[start:start + CHUNK]
            yield SweepChunk(campaign=campaign, segment=record.index, take=take, stream=name, chunk=k,
                             session=record.session, count=len(part),
                             stamps=tuple(float(v) for v in part),
                             values=tuple(values[start:start + CHUNK]))
    lost = int(np.isnan(record.tracker_p).any(axis=1).sum()) if len(record.tracker_p) else 0
    yield SweepSegmentDone(campaign=campaign, segment=record.index, segments=total, take=take,
                           session=record.session, joints=len(record.joint_t),
                           tracker=len(record.tracker_t) - lost, lost=lost, breaks=breaks(record.tracker_p),
                           seconds=float(seconds), planned=float(planned),
                           anchor=None if record.anchor is None else list(record.anchor))
