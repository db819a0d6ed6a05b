"""The sweep campaign's own part of the plan: the tour, its check, its resume and the join.

A sweep campaign (``campaign.mode = "sweep"``; docs/design.md, The calibration campaign) is the
bootstrap (the tracker pose, the SMR, a first model from a few still poses, swept:
`hil.campaign.sweep_bootstrap`) and warm-up, then one
`hil.campaign.steps.Sweep` through the calibration poses the selection chose (the waypoints, in the
tour's order) instead of a stop at each. The validation poses are waypoints of the same tour where the
arm rests (`tour_visits`): each is measured still there, approached from below as stop-and-go's poses
are (read off the hold of the segment arriving there, `hil.campaign.sweep_rests`), and the fit leaves
out every sample whose joints pass within `VALIDATION_GUARD_RAD` of one, so the verdict is on still
poses the fit never saw and means what stop-and-go's means — without a second tour to reach them
(bench/sweep_time.py: that tour alone cost about 0.4 of a stop-and-go campaign). A validation pose no
segment reaches is measured after the sweep.

The tour is planned segment by segment, from one waypoint at rest to the next at rest
(`hil.calibration.sweep_path.plan_sweep`, within ``robot.speed`` and ``robot.acceleration``): a
segment is the unit a resumed campaign keeps or sweeps again, and its stops are reversals that make
the clock offset observable. Every segment is checked before anything of the sweep moves
(`check_sweep`): the keep-in box along it with the model the engine checks moves with, and the SMR in
the tracker's view along it (facing the tracker within the acceptance angle, the beam clear of the
arm) with the tracker where the bootstrap found it.

Two poses the tracker sees do not make a straight joint path between them that it sees: the SMR turns
with the wrist, and the tracker's emScon never re-locks by itself mid-stream, so a segment that leaves
its view loses the rest of its samples (measured on the simulated station before this check: about
half of each segment's tracker samples lost, beam broken once in 9 of 10 segments). So the tour's order
is chosen for the segments that pass (`tour_segments`): from each waypoint, the nearest one not yet
swept whose segment passes; where none does, the arm goes to the nearest by an ordinary move, not
recorded (the engine's safe route; the tracker re-locks at the next segment's start). A tour with no
segment that passes is bad input naming the first refused one and why.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from hil.arm.catalog import RobotSpec
from hil.arm.geometry import Geometry
from hil.calibration.joint_error_request import JointErrorRequest
from hil.calibration.stream_join import JointStream, TrackerStream
from hil.campaign.acceptance import Verdict, class_bound
from hil.campaign.steps import SegmentRecord, SweepSegment
from hil.campaign.sweep_rests import approach_knots, ends_from_below, with_dwell
from hil.errors import InputError

log = logging.getLogger(__name__)

#: The campaign modes (`hil.station.config.MODES`).
STOP_AND_GO, SWEEP = "stop-and-go", "sweep"

#: Tracker samples a second while sweeping: emScon's continuous-time mode at its 1 ms separation, the
#: AT960's 1000 Hz (docs/design.md, Facts: two clocks; Leica AT960 datasheet).
TRACKER_RATE_HZ = 1000.0

#: The controller period's rate the servo samples are planned at when the controller did not say
#: (UR e-series RTDE, 500 Hz: docs/design.md, Facts: streaming on UR).
CONTROLLER_RATE_HZ = 500.0


#: How far (s) a later run's anchors may lie from the main run's first clock map and still be on the
#: same clocks: the anchors are good to the links' latency, milliseconds, but a loaded host delivers
#: RTDE frames in bursts tens of milliseconds late (times the speed in fast time: 50 ms was exceeded at
#: speed 4, load 8-20); a restarted instrument's clock is off by its whole running time, the minutes
#: a campaign ran at least. Half a second tells the two apart with room on both sides.
CLOCK_AGREEMENT_S = 0.5


#: rad: no tracker sample whose joints are within this (the largest joint difference) of a validation
#: pose is fitted (`hil.calibration.stream_join`, ``validation pose``): a tour resting at a validation
#: pose passes through it, and the verdict must be on poses the fit never saw. 0.05 rad is about 40 mm
#: at a UR5e's reach, 50 ms of travel at 1 rad/s, the margin bench/sweep_time.py cuts around its rests;
#: a choice of hil's, not a published figure.
VALIDATION_GUARD_RAD = 0.05

#: The share of the deflection model's quasi-static acceleration limit a sweep at ``campaign.sweep_speed``
#: plans to (`sweep_limits`): the fit leaves out samples beyond the limit itself, so a tour planned at it
#: would lose its fastest stretches to rounding; 10 % below keeps them (bench/sweep_time.py's default).
SWEEP_ACCELERATION_SHARE = 0.9


def sweep_limits(config: Any, spec: RobotSpec, waypoints: np.ndarray, limit_model: Geometry | None = None
                 ) -> tuple[np.ndarray, float]:
    """Each joint's speed limit (rad/s, (6,)) and the joint acceleration limit (rad/s²) of the sweep.

    Unless ``campaign.sweep_speed`` is set, the station's movej limits: ``robot.speed`` (within the
    arm's joint maxima) and ``robot.acceleration``. With it (a tool speed, m/s), the sweep's own: every
    joint at most that speed over the arm's reach (so no point of the arm outruns it), and the
    acceleration at most ``robot.acceleration`` and `SWEEP_ACCELERATION_SHARE` of the deflection
    model's quasi-static limit at the waypoints (`hil.arm.dynamics.DynamicsModel.acceleration_limit`
    of `limit_model`, the bootstrap's compliant arm): beyond it the joints ring by more than the
    tracker sees and the fit leaves the samples out (`hil.calibration.stream_join`), so a tour planned
    faster buys nothing."""
    top = np.asarray(spec.max_joint_speed, float)
    accel = float(config.robot["acceleration"])
    tool = config.campaign.get("sweep_speed")
    if tool is None:
        return np.minimum(float(config.robot["speed"]), top), accel
    speed = np.minimum(float(tool) / float(spec.reach), top)
    if limit_model is not None and limit_model.compliant and len(waypoints):
        from hil.arm.dynamics import DynamicsModel

        quasi = float(DynamicsModel(limit_model).acceleration_limit(np.asarray(waypoints, float)).min())
        accel = min(accel, SWEEP_ACCELERATION_SHARE * quasi)
    return speed, accel


def hop_limits(config: Any, spec: RobotSpec, waypoints: np.ndarray, limit_model: Geometry | None
               ) -> tuple[float | None, float | None]:
    """Joint speed (rad/s) and acceleration (rad/s²) of the unswept moves between a sweep's segments
    (`Sweep.speed`, `Sweep.acceleration`): the sweep's own limits (`sweep_limits`) when
    ``campaign.sweep_speed`` is set, else (None, None), the station's movej."""
    if config.campaign.get("sweep_speed") is None:
        return None, None
    speed, accel = sweep_limits(config, spec, waypoints, limit_model)
    return float(np.min(speed)), accel


def sweep_tour(waypoints: np.ndarray, config: Any, spec: RobotSpec, check_model: Geometry,
               rate_hz: float = CONTROLLER_RATE_HZ, sight_model: Geometry | None = None,
               limit_model: Geometry | None = None, rests: np.ndarray | None = None) -> list[SweepSegment]:
    """The tour through `waypoints` (m, 6) as segments rest to rest, each within the station's joint
    speed and acceleration (and the arm's joint speed maxima), inside the keep-in box (`check_model`,
    the arm the engine checks moves with) and, with `sight_model` (its tracker and SMR: the
    bootstrap's), in the tracker's view within ``smr.acceptance_angle`` — all checked before anything
    moves. The order is `tour_segments`'; InputError when no segment of the tour passes, naming the
    first refused and its first offending sample. The limits are `sweep_limits`' (`limit_model`: the
    arm whose deflection bounds the acceleration). With `rests` (the poses the tour must stop at) the
    arm passes through the other waypoints without stopping where it can (`pass_through`)."""
    from hil.calibration.selection import aimed_vias
    from hil.calibration.sweep_path import SweepRefused, check_sweep, plan_leg

    keep_in = (np.asarray(config.keep_in["min"], float), np.asarray(config.keep_in["max"], float))
    speed, accel = sweep_limits(config, spec, waypoints, limit_model)
    angle = float(config.smr["acceptance_angle"])
    pts = np.asarray(waypoints, dtype=float)
    rest_at = np.zeros(len(pts), dtype=bool)
    if rests is not None:
        rest_at = np.array([any(np.allclose(p, r, rtol=0.0, atol=1e-9) for r in np.asarray(rests, float)
                                .reshape(-1, 6)) for p in pts], dtype=bool).reshape(len(pts))
    approach = float(config.campaign.get("approach", 0.0) or 0.0)

    def checked(a: int, through: np.ndarray, b: int) -> tuple[np.ndarray, np.ndarray]:
        knots = np.vstack([pts[a][None, :], through])
        # a rest's path comes up to it from below in every joint, as a stop-and-go visit does
        return planned(approach_knots(knots, approach) if rest_at[b] else knots)

    def planned(knots: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        tour = plan_leg(knots, max_speed=speed, max_acceleration=accel, rate_hz=rate_hz)
        check_sweep(tour, max_speed=speed, max_acceleration=accel, spec=spec, keep_in=keep_in,
                    model=check_model)
        if sight_model is not None:
            check_sweep(tour, model=sight_model, acceptance_angle=angle)
        return np.asarray(tour.q, float), knots

    def segment(a: int, b: int) -> tuple[np.ndarray, np.ndarray]:
        """The checked path from waypoint `a` to `b`: straight in joint space, else through vias that
        turn the wrist toward the tracker (`aimed_vias`); SweepRefused (the straight one's) if neither
        may be swept."""
        try:
            return checked(a, pts[b][None, :], b)
        except SweepRefused:
            if sight_model is None:
                raise
            vias = aimed_vias(sight_model.robot, sight_model.smr, sight_model.tracker.translation,
                              pts[a], pts[b], angle)
            try:
                return checked(a, np.vstack([vias, pts[b][None, :]]), b)
            except SweepRefused:
                pass
            raise

    paths, refused = tour_segments(pts, segment, SweepRefused)
    log.info("sweep tour: %d segments through %d waypoints (%d straight or aimed paths refused)",
             len(paths), len(pts), len(refused))
    if not paths:
        (a, _), why = refused[0] if refused else ((0, 0), "fewer than two waypoints")
        raise InputError(f"sweep segment {a + 1} of {len(pts) - 1} refused before the sweep moved: {why}")
    if rests is None:
        return [SweepSegment(k, q, float(rate_hz), knots) for k, (q, knots) in enumerate(paths)]
    rest_poses = np.asarray(rests, float).reshape(-1, 6)
    paths = pass_through(paths, rest_poses, planned, SweepRefused)
    out = []
    for k, (q, knots) in enumerate(paths):
        # a path that ends at a rest coming up in every joint holds there: the rest is read off the
        # streams (`hil.campaign.sweep_rests`); one that overshoots its end leaves it to a still visit
        hold = 0
        if any(np.allclose(q[-1], r, rtol=0.0, atol=1e-9) for r in rest_poses) and \
                (approach <= 0 or ends_from_below(q)):
            q, hold = with_dwell(q, rate_hz)
        out.append(SweepSegment(k, q, float(rate_hz), knots, hold))
    return out


def pass_through(paths: list[tuple[np.ndarray, np.ndarray]], rests: np.ndarray, plan: Any,
                 refusal: type[Exception] = InputError) -> list[tuple[np.ndarray, np.ndarray]]:
    """The tour's paths with the arm passing through its calibration waypoints instead of stopping:
    two paths in a row that meet at a waypoint which is not one of `rests` (the validation poses,
    where it must stop) become one path through both's knots, planned and checked again by
    `plan(knots)` → (q, knots), if it is the sooner; where that is refused (`refusal`: the smooth path
    through them leaves the keep-in box or the tracker's view) or slower (a joint reversing there: the
    path through overshoots) the two stay apart. A stop costs a deceleration and an
    acceleration at the quasi-static limit (about 1 rad/s² in a UR5e's shoulder): bench/sweep_time.py
    passes its waypoints the same way."""
    out = list(paths[:1])
    for q, knots in paths[1:]:
        last_q, last_knots = out[-1]
        meets = np.allclose(last_q[-1], q[0], rtol=0.0, atol=1e-9)
        at_rest = any(np.allclose(q[0], r, rtol=0.0, atol=1e-9) for r in rests)
        if meets and not at_rest:
            try:
                joined = plan(np.vstack([last_knots, knots[1:]]))
            except refusal:
                joined = None
            # a joint reversing at the waypoint overshoots it on a path through it: sooner stopped
            if joined is not None and len(joined[0]) < len(last_q) + len(q) - 1:
                out[-1] = joined
                continue
        out.append((q, knots))
    return out


def stored_tour(segments: Sequence[dict[str, Any]], config: Any, spec: RobotSpec, check_model: Geometry,
                rate_hz: float = CONTROLLER_RATE_HZ, limit_model: Geometry | None = None,
                waypoints: np.ndarray | None = None) -> list[SweepSegment]:
    """The tour a campaign planned first (its stored `SweepPlanned` segments), planned again from
    each segment's knots (its start and end for a tour stored without them) and checked again for the
    limits, speed, acceleration and keep-in box. The sight check is not repeated: a resumed run knows
    the tracker as stored but not the SMR the bootstrap located, and the tour must stay the one whose
    segment numbers name what the store holds. The limits are `sweep_limits`' at `waypoints` (the
    campaign's calibration poses, as the first run planned them; by default the stored segments' ends)."""
    from hil.calibration.sweep_path import SweepRefused, check_sweep, plan_leg

    keep_in = (np.asarray(config.keep_in["min"], float), np.asarray(config.keep_in["max"], float))
    if waypoints is None:
        waypoints = np.array([seg[k] for seg in segments for k in ("from", "to")], dtype=float).reshape(-1, 6)
    speed, accel = sweep_limits(config, spec, waypoints, limit_model)
    out: list[SweepSegment] = []
    for k, seg in enumerate(segments):
        knots = np.asarray(seg.get("knots") or [seg["from"], seg["to"]], dtype=float)
        try:
            tour = plan_leg(knots, max_speed=speed, max_acceleration=accel, rate_hz=rate_hz)
            check_sweep(tour, max_speed=speed, max_acceleration=accel, spec=spec, keep_in=keep_in,
                        model=check_model)
        except SweepRefused as exc:
            raise InputError(f"stored sweep segment {k + 1} of {len(segments)} refused before the sweep "
                             f"moved: {exc}") from None
        q, hold = np.asarray(tour.q, float), int(seg.get("dwell", 0))
        if hold > 0:  # the hold the first run planned at its end (`hil.campaign.sweep_rests`)
            q = np.vstack([q, np.repeat(q[-1:], hold, axis=0)])
        out.append(SweepSegment(int(seg.get("index", k)), q, float(rate_hz), knots, hold))
    return out


#: The harmonic orders a sweep's fit takes for ``campaign.joint_errors = "auto"``: its fit is not
#: cross-validated (each fold would be a joint fit of the streams), so "auto" cannot choose by it, and
#: orders 1-2 of every joint with the lost motion are the class bench/sweep_time.py measured (held-out
#: 0.67-1.00 of stop-and-go's error on realistic arms); without them a realistic arm's sweep fitted
#: 5 x stop-and-go's truth error (bench/sweep_campaign.py, UR5e, 121 against 24 µm).
AUTO_ORDERS = (1, 2)


def sweep_terms(request: JointErrorRequest) -> list[int]:
    """The joint-error terms (indices of the extended vector) a sweep's fit identifies for the
    campaign's ``campaign.joint_errors`` `request`: none, `AUTO_ORDERS` and the lost motion for
    "auto", or the orders asked (and the lost motion if asked). The stream's reversals identify the
    lost motion: a moving joint lags to the side it last moved, as a still one does
    (`hil.calibration.sweep_fit`)."""
    from hil.arm.joint_error_columns import harmonic_index, lost_motion_index

    if request.mode == "none":
        return []
    orders = AUTO_ORDERS if request.mode == "auto" else request.orders
    lost = request.mode == "auto" or request.lost_motion
    out = [harmonic_index(j, k, kind) for j in range(6) for k in orders for kind in ("cos", "sin")]
    return out + ([lost_motion_index(j) for j in range(6)] if lost else [])


def tour_visits(segments: Sequence[SweepSegment], rests: Mapping[int, np.ndarray]) -> list[tuple[str, int]]:
    """The tour as the engine takes it: ``("segment", index)`` in order, with ``("rest", i)`` where a
    segment starts or ends at validation pose `i` of `rests` (plan index → joints), the first time
    the tour reaches it. There the arm stops and the pose is measured still, approached from below
    as stop-and-go's poses are, before the tour goes on; a validation pose no segment reaches is not
    a rest (it is measured after the sweep)."""
    out: list[tuple[str, int]] = []
    reached: set[int] = set()

    def rest_at(q: np.ndarray) -> None:
        for i, v in rests.items():
            if i not in reached and np.allclose(q, v, rtol=0.0, atol=1e-9):
                reached.add(i)
                out.append(("rest", i))
                return

    for g in segments:
        rest_at(g.q[0])
        out.append(("segment", g.index))
        rest_at(g.q[-1])
    return out


def tour_segments(waypoints: np.ndarray, segment: Any, refusal: type[Exception] = InputError
                  ) -> tuple[list[Any], list[tuple[tuple[int, int], str]]]:
    """The tour's segments in order (what `segment(a, b)` returned for each), and the ones refused
    ((from, to) waypoint indices, why).

    From the first waypoint: to the nearest waypoint not yet visited (by the largest joint difference,
    what a joint move's time follows) whose `segment(a, b)` passes (it raises `refusal` otherwise);
    where none does, to the nearest by a move that is not swept. A nearest-neighbour order, written here
    because the tour has an edge rule (a segment must pass its checks) that the library tour solvers
    (scipy has none; the selection's own tour is over still poses) do not take."""
    n = len(waypoints)
    if n < 2:
        return [], []
    paths: list[Any] = []
    refused: list[tuple[tuple[int, int], str]] = []
    here, left = 0, set(range(1, n))
    while left:
        order = sorted(left, key=lambda j: (float(np.max(np.abs(waypoints[j] - waypoints[here]))), j))
        for j in order:
            try:
                paths.append(segment(here, j))
            except refusal as exc:
                refused.append(((here, j), str(exc)))
                continue
            here = j
            break
        else:  # no segment from here passes: the next nearest by an ordinary move
            here = order[0]
        left.discard(here)
    return paths, refused


def sweep_verdict(after: float, before: float, robot: str, acceptance: float | None) -> Verdict:
    """The sweep's verdict on its held-out still poses. Stop-and-go's automatic rule needs a
    cross-validated RMS, and a sweep's fit is not cross-validated (refitting the streams fold by fold
    costs a fit each): the sweep's model must predict the held-out poses better than the nominal arm
    (located by the same bootstrap) does, and then their RMS must be within `acceptance` or, unset,
    the robot class's bound (`hil.campaign.acceptance.class_bound`)."""
    rms = f"validation RMS {after * 1e3:.4f} mm"
    if acceptance is not None:
        limit, rule, said = float(acceptance), "threshold", f"acceptance {float(acceptance) * 1e3:.4f} mm"
    else:
        limit, rule = class_bound(robot), "auto"
        said = f"the {robot} class bound {limit * 1e3:.4f} mm"
    if not after < before:
        return Verdict(False, limit, f"{rms} is not better than the nominal arm's {before * 1e3:.4f} mm "
                                     "on the held-out poses", rule)
    passed = after <= limit
    return Verdict(passed, limit, f"{rms} {'<=' if passed else '>'} {said}", rule)


def streams_of(records: Sequence[SegmentRecord]
               ) -> tuple[JointStream, TrackerStream, dict[str, int], list[SegmentRecord]]:
    """The recorded segments as one joint stream and one tracker stream on the instruments' clocks,
    the tracker samples left out by reason, and the segments joined.

    Segments recorded by different runs of the campaign (`SegmentRecord.session`) may be on clocks
    that restarted between them (a controller rebooted, a simulator started again): one clock map
    cannot hold them. The session with the most segments (the latest on a tie) is joined, and with it
    every other whose host-clock anchors lie on its first map within `CLOCK_AGREEMENT_S` (the
    instruments' clocks went on); the rest's tracker samples are counted as left out
    (``other session``)."""
    if not records:
        raise InputError("the sweep recorded no segment")
    sessions: dict[str, int] = {}
    for r in records:
        sessions[r.session] = sessions.get(r.session, 0) + 1
    ordered = list(dict.fromkeys(r.session for r in records))
    keep = max(ordered, key=lambda s: (sessions[s], ordered.index(s)))
    main = [r for r in records if r.session == keep]
    offset, drift = first_clock(main)
    joined = {keep}
    for other in ordered:  # a run whose instruments' clocks went on (no restart) joins the main one
        anchors = [r.anchor for r in records if r.session == other and r.anchor is not None]
        if other != keep and offset is not None and anchors and all(
                abs(c - (offset + (1.0 + drift) * t)) < CLOCK_AGREEMENT_S for t, c in anchors):
            joined.add(other)
    chosen = sorted((r for r in records if r.session in joined), key=lambda r: float(r.joint_t[0]))
    left = {"other session": int(sum(len(r.tracker_t) for r in records if r.session not in joined))}
    jt = np.concatenate([r.joint_t for r in chosen])
    jq = np.concatenate([r.joint_q for r in chosen])
    tt = np.concatenate([r.tracker_t for r in chosen])
    tp = np.concatenate([r.tracker_p for r in chosen])
    j_order, t_order = np.argsort(jt, kind="stable"), np.argsort(tt, kind="stable")
    jt, jq, tt, tp = jt[j_order], jq[j_order], tt[t_order], tp[t_order]
    jk = np.concatenate([[True], np.diff(jt) > 0])
    tk = np.concatenate([[True], np.diff(tt) > 0])
    if not tk.all():  # one instant twice (a segment's end, the next's start): counted once, left out
        left["repeated stamp"] = int((~tk).sum())
    return JointStream(jt[jk], jq[jk]), TrackerStream(tt[tk], tp[tk]), left, chosen


def record_from_store(segment: int, session: str, joints: tuple[list[float], list[Any]],
                      tracker: tuple[list[float], list[Any]], anchor: Sequence[float] | None = None
                      ) -> SegmentRecord:
    """A stored segment (`hil.store.queries.StoreQueries.stream_chunks` of its take) as a record."""
    jt, jq = joints
    tt, tp = tracker
    points = np.array([(np.nan,) * 3 if v is None else v for v in tp], dtype=float).reshape(-1, 3)
    return SegmentRecord(segment, session, np.asarray(jt, float), np.asarray(jq, float).reshape(-1, 6),
                         np.asarray(tt, float), points,
                         None if anchor is None else (float(anchor[0]), float(anchor[1])))


def first_clock(records: Sequence[SegmentRecord]) -> tuple[float | None, float]:
    """A first guess of the map t_ctrl = a + (1 + d)·t_trk from the segments' host-clock anchors
    (`hil.campaign.sweep_recording.anchor`): a line through them (two or more segments: seconds to
    minutes apart, so the drift is fixed to the anchors' milliseconds over that span), else drift 0
    through the one anchor; (None, 0) without any (the join's own first guess then)."""
    pts = np.array([r.anchor for r in records if r.anchor is not None], dtype=float).reshape(-1, 2)
    if len(pts) == 0:
        return None, 0.0
    if len(pts) == 1 or np.ptp(pts[:, 0]) < 1.0:
        return float(np.mean(pts[:, 1] - pts[:, 0])), 0.0
    slope, offset = np.polyfit(pts[:, 0], pts[:, 1], 1)
    return float(offset), float(slope - 1.0)
