"""The sweep's tour as the plan builds it: segments rest to rest between the waypoints, within the
station's speed and acceleration, checked before anything moves; its verdict on still poses."""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry, look_at_tracker
from hil.arm.joint_directions import directions_along
from hil.arm.kinematics import Kinematics
from hil.calibration.sweep_path import SweepRefused, SweepTour, check_sweep
from hil.campaign.sweep_plan import stored_tour, sweep_tour, sweep_verdict, tour_segments
from hil.campaign.sweep_rests import REST_DWELL_S
from hil.errors import InputError
from hil.station.config import default_config

POSE = np.array([0.0, -1.2, 1.4, -1.8, -1.57, 0.0])


def swing(angle: float) -> np.ndarray:
    q = POSE.copy()
    q[0] = angle
    return q


def test_segments_run_rest_to_rest_through_the_waypoints_within_the_stations_limits():
    config = default_config()
    waypoints = np.array([swing(-0.3), swing(0.2), swing(0.5)])
    segs = sweep_tour(waypoints, config, get_robot("ur5e"), Geometry.nominal("ur5e"))
    assert [s.index for s in segs] == [0, 1]
    for seg, (a, b) in zip(segs, pairwise(waypoints), strict=True):
        assert np.allclose(seg.q[0], a) and np.allclose(seg.q[-1], b)
        speed = np.abs(np.diff(seg.q, axis=0)) * seg.rate_hz
        assert speed.max() <= config.robot["speed"] * (1 + 1e-9)
        assert np.allclose(seg.q[1] - seg.q[0], 0, atol=1e-4)  # starts (and ends) at rest


def test_a_tour_leaving_the_keep_in_box_is_refused_before_anything_moves():
    """Joint 1 from -45° to +45°: both ends inside the box, the arc between them bulges out past its
    x limit. The segment and the first sample outside are named; no segment is returned."""
    model = Geometry.nominal("ur5e")
    a, b = swing(-np.pi / 4), swing(np.pi / 4)
    ends = Kinematics(model).points(np.array([a, b]), frame="base")
    lo = ends.min(axis=0) - 0.02
    hi = ends.max(axis=0) + 0.02
    config = default_config().with_overrides(keep_in__min=list(map(float, lo)),
                                             keep_in__max=list(map(float, hi)))
    with pytest.raises(InputError, match=r"sweep segment 1 of 1 refused before the sweep moved: sweep "
                                         r"sample \d+ .* outside the keep-in box"):
        sweep_tour(np.array([a, b]), config, get_robot("ur5e"), model)


def test_the_verdict_needs_the_model_better_than_the_nominal_arm_then_the_bound():
    assert sweep_verdict(0.1e-3, 0.8e-3, "ur5e", None).passed
    worse = sweep_verdict(0.9e-3, 0.8e-3, "ur5e", None)
    assert not worse.passed and "not better than the nominal" in worse.reason
    assert not sweep_verdict(0.2e-3, 0.8e-3, "ur5e", 0.1e-3).passed


def test_a_segment_the_tracker_would_not_see_along_turns_the_wrist_toward_it():
    """Both ends face the tracker, the straight joint line between them turns the SMR away (found by a
    seeded search of nominal UR5e poses); the tour's segment goes through vias that aim the wrist and
    is seen along its whole length, from the one waypoint to the other."""
    tracker = look_at_tracker([2.5, 0.0, 0.5])
    model = Geometry.nominal("ur5e", (0.0, 0.0, 0.045), tracker)
    a = np.array([-0.499, -2.076, 1.33, -2.371, 2.147, 0.766])
    b = np.array([-1.619, -1.082, 1.609, -2.236, 3.064, 1.076])
    config, spec = default_config(), get_robot("ur5e")
    (straight,) = sweep_tour(np.array([a, b]), config, spec, model)  # no sight model: not checked
    with pytest.raises(SweepRefused, match="would not see the SMR"):
        check_sweep(SweepTour(np.arange(len(straight.q)) / straight.rate_hz, straight.q, b[None],
                              straight.rate_hz), model=model, acceptance_angle=config.smr["acceptance_angle"])
    (aimed,) = sweep_tour(np.array([a, b]), config, spec, model, sight_model=model)
    assert np.allclose(aimed.q[0], a) and np.allclose(aimed.q[-1], b)
    check_sweep(SweepTour(np.arange(len(aimed.q)) / aimed.rate_hz, aimed.q, b[None], aimed.rate_hz),
                model=model, acceptance_angle=config.smr["acceptance_angle"])


def test_the_tour_takes_the_nearest_segment_that_passes_and_moves_on_where_none_does():
    """Waypoints 0..4 on a line: the segment 0 → 1 is refused, so the tour sweeps 0 → 2; nothing from
    2 passes, so the arm moves to 1 unswept (the nearest left), then sweeps 1 → 3 → 4."""
    points = np.arange(5, dtype=float)[:, None] * np.ones((1, 6)) * 0.1
    refused = {(0, 1), (2, 1), (2, 3), (2, 4)}

    def segment(a, b):
        if (a, b) in refused:
            raise InputError(f"{a} to {b} refused")
        return np.array([points[a], points[b]])

    paths, why = tour_segments(points, segment)
    assert [(round(p[0, 0] * 10), round(p[-1, 0] * 10)) for p in paths] == [(0, 2), (1, 3), (3, 4)]
    assert [w for w, _ in why] == [(0, 1), (2, 1), (2, 3), (2, 4)]


def test_a_resumed_campaign_plans_the_stored_tour_again_exactly():
    """A resumed run does not know the SMR the bootstrap located, so it would check sight with another
    model and could order the tour otherwise: it plans the tour it stored instead, from each segment's
    knots (a tour stored without them: from its ends), and gets the same samples."""
    tracker = look_at_tracker([2.5, 0.0, 0.5])
    model = Geometry.nominal("ur5e", (0.0, 0.0, 0.045), tracker)
    a = np.array([-0.499, -2.076, 1.33, -2.371, 2.147, 0.766])
    b = np.array([-1.619, -1.082, 1.609, -2.236, 3.064, 1.076])
    config, spec = default_config(), get_robot("ur5e")
    planned = sweep_tour(np.array([a, b, swing(0.2)]), config, spec, model, sight_model=model)
    stored = [{"index": g.index, "from": list(g.start), "to": g.q[-1].tolist(), "knots": g.knots.tolist()}
              for g in planned]
    again = stored_tour(stored, config, spec, model)
    assert [g.index for g in again] == [g.index for g in planned]
    for g, h in zip(planned, again, strict=True):
        np.testing.assert_array_equal(g.q, h.q)
    older = [{"index": 0, "from": list(swing(-0.3)), "to": list(swing(0.2))}]
    (old,) = stored_tour(older, config, spec, model)
    np.testing.assert_allclose(old.q[[0, -1]], [swing(-0.3), swing(0.2)])


def test_a_sweep_at_its_own_tool_speed_keeps_each_joint_within_it_and_the_deflection_models_acceleration():
    """``campaign.sweep_speed`` (m/s at the tool) replaces robot.speed for the sweep: no joint faster than
    it over the reach, so the tour moves faster than the station's movej allows; the acceleration
    stays within robot.acceleration and 90 % of the compliant arm's quasi-static limit, which the fit
    would otherwise leave out."""
    from hil.arm.dynamics import DynamicsModel
    from hil.arm.physical import typical_compliance
    from hil.campaign.sweep_plan import SWEEP_ACCELERATION_SHARE, sweep_limits

    spec = get_robot("ur5e")
    model = Geometry.nominal("ur5e")
    model.compliance = typical_compliance("ur5e")
    waypoints = np.array([swing(-0.6), swing(0.4), swing(1.2)])
    slow = default_config()
    fast = slow.with_overrides(campaign__sweep_speed=0.85, robot__acceleration=4.0)
    speed, accel = sweep_limits(fast, spec, waypoints, model)
    quasi = DynamicsModel(model).acceleration_limit(waypoints).min()
    np.testing.assert_allclose(speed, np.minimum(0.85 / spec.reach, spec.max_joint_speed))
    assert accel == pytest.approx(SWEEP_ACCELERATION_SHARE * quasi) and accel < 4.0
    assert sweep_limits(fast.with_overrides(robot__acceleration=0.2), spec, waypoints, model)[1] == 0.2
    assert sweep_limits(fast, spec, waypoints, None)[1] == 4.0  # no compliance known: the station's
    np.testing.assert_allclose(sweep_limits(slow, spec, waypoints, model)[0],
                               np.minimum(0.5, spec.max_joint_speed))  # unset: today's movej limits

    tours = {}
    for name, config in (("slow", slow), ("fast", fast)):
        tours[name] = sweep_tour(waypoints, config, spec, model, limit_model=model)
        for seg in tours[name]:
            v = np.diff(seg.q, axis=0) * seg.rate_hz
            a = np.diff(v, axis=0) * seg.rate_hz
            lim = sweep_limits(config, spec, waypoints, model)
            assert np.abs(v).max() <= lim[0].max() * (1 + 1e-9)
            assert np.abs(a).max() <= lim[1] * 1.02  # the planner's sampled acceleration
    fast_s = sum(len(s.q) for s in tours["fast"]) / 500.0
    slow_s = sum(len(s.q) for s in tours["slow"]) / 500.0
    assert np.abs(np.diff(tours["fast"][0].q[:, 0])).max() * 500 > 0.5 * 1.4  # beyond robot.speed
    assert fast_s < 0.8 * slow_s
    stored = [{"index": g.index, "from": list(g.start), "to": g.q[-1].tolist(), "knots": g.knots.tolist()}
              for g in tours["fast"]]
    again = stored_tour(stored, fast, spec, model, limit_model=model, waypoints=waypoints)
    for g, h in zip(tours["fast"], again, strict=True):
        np.testing.assert_array_equal(g.q, h.q)


def test_a_sweep_speed_out_of_range_is_refused_with_its_field(tmp_path):
    from hil.station.config import load_config

    text = (tmp_path / "station.toml")
    text.write_text("[campaign]\nsweep_speed = 40.0\n")
    with pytest.raises(InputError, match=r"campaign\.sweep_speed"):
        load_config(text)


def test_the_tour_rests_at_the_validation_poses_its_segments_reach_once_each():
    """A validation pose among the waypoints is a rest where a segment starts or ends, the first time
    the tour reaches it (the arm stops there and it is measured still); one no segment reaches is not."""
    from hil.campaign.steps import SweepSegment
    from hil.campaign.sweep_plan import tour_visits

    a, b, c, d = swing(-0.3), swing(0.2), swing(0.5), swing(0.9)

    def seg(k, p, q):
        return SweepSegment(k, np.linspace(p, q, 5))

    segments = [seg(0, a, b), seg(1, b, c), seg(2, c, b)]
    visits = tour_visits(segments, {7: b, 8: d, 9: a})
    assert visits == [("rest", 9), ("segment", 0), ("rest", 7), ("segment", 1), ("segment", 2)]
    assert tour_visits(segments, {}) == [("segment", 0), ("segment", 1), ("segment", 2)]


def test_the_tour_passes_through_calibration_waypoints_and_stops_at_the_rests():
    """With `rests` the arm passes a calibration waypoint without stopping (one segment through it,
    sooner than two legs rest to rest: 10-20 % on such turns); at a rest the segments stay apart, the
    one arriving there coming up from below and holding."""
    config, spec, model = default_config(), get_robot("ur5e"), Geometry.nominal("ur5e")
    a, b, c = POSE + np.array([[-0.4, -0.2, 0.1, 0.0, 0.0, 0.0], [0.0, 0.1, 0.3, 0.2, 0.1, 0.1],
                               [0.4, 0.2, 0.35, 0.5, 0.3, 0.1]])
    stopping = sweep_tour(np.array([a, b, c]), config, spec, model)
    assert len(stopping) == 2
    (passing,) = sweep_tour(np.array([a, b, c]), config, spec, model, rests=np.zeros((0, 6)))
    np.testing.assert_allclose(passing.knots, [a, b, c])
    at_b = int(np.argmin(np.max(np.abs(passing.q - b), axis=1)))
    assert np.max(np.abs(passing.q[at_b] - b)) < 1e-2
    assert np.max(np.abs(passing.q[at_b + 1] - passing.q[at_b - 1])) * 500 / 2 > 0.1  # moving at b
    assert len(passing.q) < 0.95 * sum(len(s.q) for s in stopping)
    resting = sweep_tour(np.array([a, b, c]), config, spec, model, rests=b[None, :])
    assert len(resting) == 2 and len(resting[1].q) == len(stopping[1].q) and resting[1].dwell == 0
    # the rest's segment comes up to it from below in every joint and holds there
    # (`hil.campaign.sweep_rests`), its other end as the stopping tour's
    into = resting[0]
    approach = config.campaign["approach"]
    np.testing.assert_allclose(into.knots, [a, b - approach, b])
    assert into.dwell == round(REST_DWELL_S * 500)
    np.testing.assert_allclose(into.q[-into.dwell - 1:], np.repeat(b[None, :], into.dwell + 1, axis=0))
    assert np.all(directions_along(into.q)[-1] == 1.0)


def test_two_paths_are_joined_only_where_the_path_through_is_sooner_and_passes():
    from hil.campaign.sweep_plan import pass_through

    a, b, c = swing(0.0), swing(0.5), swing(1.0)
    paths = [(np.linspace(a, b, 300), np.array([a, b])), (np.linspace(b, c, 300), np.array([b, c]))]
    none = np.zeros((0, 6))

    def through(n):
        return lambda knots: (np.linspace(knots[0], knots[-1], n), knots)

    (joined,) = pass_through(paths, none, through(500))
    assert len(joined[0]) == 500 and len(joined[1]) == 3
    assert len(pass_through(paths, none, through(700))) == 2  # a turn overshot: slower through
    assert len(pass_through(paths, b[None, :], through(500))) == 2  # a rest: stopped at

    def refused(knots):
        raise InputError("leaves the keep-in box")

    assert len(pass_through(paths, none, refused)) == 2


def test_the_sweeps_fit_takes_the_joint_errors_asked_with_the_lost_motion():
    """"auto" is orders 1-2 of every joint and the lost motion (the sweep's fit is not cross-validated,
    so it cannot choose); the lost motion with it, which the stream's reversals identify."""
    from hil.arm.joint_error_columns import harmonic_index, lost_motion_index
    from hil.calibration.joint_error_request import parse_request
    from hil.campaign.sweep_plan import sweep_terms

    auto = sweep_terms(parse_request("auto"))
    assert len(auto) == 6 * 2 * 2 + 6
    assert harmonic_index(1, 2, "sin") in auto and harmonic_index(1, 3, "cos") not in auto
    assert lost_motion_index(5) in auto
    assert sweep_terms(parse_request("none")) == []
    asked = sweep_terms(parse_request("3"))
    assert asked == [harmonic_index(j, 3, k) for j in range(6) for k in ("cos", "sin")]
    assert lost_motion_index(0) in sweep_terms(parse_request("1,lost"))
    assert not any(i >= lost_motion_index(0) for i in asked)
