"""The sweep campaign's own part of the plan: the tour, its check, its resume and the join.

A sweep campaign (``campaign.mode = "sweep"``; docs/design.md, The calibration campaign) is the usual
bootstrap (the tracker pose, the SMR, a first model from a few still poses) and warm-up, then one
`hil.campaign.steps.Sweep` through the calibration poses the selection chose (the waypoints, in the
tour's order) instead of a stop at each, then validation on still poses the fit never saw, exactly as
stop-and-go's, so the verdict means the same.

The tour is planned segment by segment, from one waypoint at rest to the next at rest
(`hil.calibration.sweep_path.plan_sweep`, within ``robot.speed`` and ``robot.acceleration``): a
segment is the unit a resumed campaign keeps or sweeps again, and its stops are reversals that make
the clock offset observable. Every segment is checked before anything of the sweep moves
(`check_sweep`, and the keep-in box along it with the model the engine checks moves with): a tour
that leaves the box or the joint limits is bad input naming the segment and its first offending
sample.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from hil.arm.catalog import RobotSpec
from hil.arm.geometry import Geometry
from hil.arm.kinematics_cache import kinematics_of
from hil.calibration.stream_join import JointStream, TrackerStream
from hil.campaign.steps import SegmentRecord, SweepSegment
from hil.errors import InputError

#: The campaign modes (`hil.station.config.MODES`).
STOP_AND_GO, SWEEP = "stop-and-go", "sweep"

#: Tracker samples a second while sweeping: emScon's continuous-time mode at its 1 ms separation, the
#: AT960's 1000 Hz (docs/design.md, Facts: two clocks; Leica AT960 datasheet).
TRACKER_RATE_HZ = 1000.0

#: The controller period's rate the servo samples are planned at when the controller did not say
#: (UR e-series RTDE, 500 Hz: docs/design.md, Facts: streaming on UR).
CONTROLLER_RATE_HZ = 500.0


def sweep_tour(waypoints: np.ndarray, config: Any, spec: RobotSpec, check_model: Geometry,
               rate_hz: float = CONTROLLER_RATE_HZ) -> list[SweepSegment]:
    """The tour through `waypoints` (m, 6) as segments between consecutive waypoints, each planned
    rest to rest within the station's joint speed and acceleration and checked before anything moves
    (module docstring). InputError naming the segment and the first offending sample."""
    from hil.calibration.sweep_path import check_sweep, plan_sweep

    keep_in = (np.asarray(config.keep_in["min"], float), np.asarray(config.keep_in["max"], float))
    segments: list[SweepSegment] = []
    for k in range(len(waypoints) - 1):
        a, b = np.asarray(waypoints[k], float), np.asarray(waypoints[k + 1], float)
        tour = plan_sweep(b[None, :], a, max_speed=float(config.robot["speed"]),
                          max_acceleration=float(config.robot["acceleration"]), rate_hz=rate_hz)
        try:
            check_sweep(tour, spec=spec, keep_in=keep_in, model=check_model)
        except (InputError, ValueError) as exc:
            raise InputError(f"sweep segment {k + 1} of {len(waypoints) - 1} refused before anything "
                             f"moved: {exc}") from None
        outside = _outside_box(tour.q, keep_in, check_model)
        if outside is not None:
            i, p = outside
            raise InputError(f"sweep segment {k + 1} of {len(waypoints) - 1} refused before anything moved: "
                             f"sample {i} puts the SMR at {np.round(p, 4).tolist()} m, outside the keep-in "
                             "box (campaign.keep_in)")
        segments.append(SweepSegment(k, np.asarray(tour.q, float)))
    return segments


def _outside_box(q: np.ndarray, keep_in: tuple[np.ndarray, np.ndarray], model: Geometry
                 ) -> tuple[int, np.ndarray] | None:
    """The first sample of `q` whose SMR (base frame, `model`) leaves the box, or None. Every sample is
    checked: a tour is a few thousand, one batched forward kinematics."""
    pts = kinematics_of(model).points(np.asarray(q, float), frame="base")
    bad = np.flatnonzero(~np.all((pts >= keep_in[0]) & (pts <= keep_in[1]), axis=1))
    return None if bad.size == 0 else (int(bad[0]), pts[bad[0]])


def streams_of(records: Sequence[SegmentRecord]) -> tuple[JointStream, TrackerStream, dict[str, int]]:
    """The recorded segments as one joint stream and one tracker stream on the instruments' clocks.

    Segments recorded by different runs of the campaign (`SegmentRecord.session`) may be on clocks
    that restarted between them (a controller rebooted, a simulator started again): one clock map
    cannot hold them, so only the session with the most segments (the latest on a tie) is joined and
    the others' tracker samples are counted as left out (``other session``)."""
    if not records:
        raise InputError("the sweep recorded no segment")
    sessions: dict[str, int] = {}
    for r in records:
        sessions[r.session] = sessions.get(r.session, 0) + 1
    ordered = list(dict.fromkeys(r.session for r in records))
    keep = max(ordered, key=lambda s: (sessions[s], ordered.index(s)))
    chosen = sorted((r for r in records if r.session == keep), key=lambda r: float(r.joint_t[0]))
    left = {"other session": int(sum(len(r.tracker_t) for r in records if r.session != keep))}
    jt = np.concatenate([r.joint_t for r in chosen])
    jq = np.concatenate([r.joint_q for r in chosen])
    tt = np.concatenate([r.tracker_t for r in chosen])
    tp = np.concatenate([r.tracker_p for r in chosen])
    j_order, t_order = np.argsort(jt, kind="stable"), np.argsort(tt, kind="stable")
    jt, jq, tt, tp = jt[j_order], jq[j_order], tt[t_order], tp[t_order]
    jk = np.concatenate([[True], np.diff(jt) > 0])
    tk = np.concatenate([[True], np.diff(tt) > 0])
    return JointStream(jt[jk], jq[jk]), TrackerStream(tt[tk], tp[tk]), left


def record_from_store(segment: int, session: str, joints: tuple[list[float], list[Any]],
                      tracker: tuple[list[float], list[Any]]) -> SegmentRecord:
    """A stored segment (`hil.store.queries.StoreQueries.stream_chunks` of its take) as a record."""
    jt, jq = joints
    tt, tp = tracker
    points = np.array([(np.nan,) * 3 if v is None else v for v in tp], dtype=float).reshape(-1, 3)
    return SegmentRecord(segment, session, np.asarray(jt, float), np.asarray(jq, float).reshape(-1, 6),
                         np.asarray(tt, float), points)
