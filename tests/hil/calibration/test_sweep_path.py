"""The swept tour: within its limits on every sample, at rest at both ends, through every waypoint in a
short order, smooth; and `check_sweep` refusing a bad tour before anything moves, naming the sample."""

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.calibration.selection import hidden_reason
from hil.calibration.sweep_path import (
    SweepRefused,
    SweepTour,
    check_sweep,
    leg_seconds,
    plan_sweep,
    tour_order,
)
from hil.calibration.synthetic import random_configurations, random_truth
from hil.errors import InputError

SPEED = np.array([0.4, 0.4, 0.5, 0.6, 0.6, 0.6])
ACCEL = np.array([0.5, 0.5, 1.0, 2.0, 2.0, 2.0])


@pytest.fixture(scope="module")
def tour() -> SweepTour:
    waypoints = random_configurations("ur5e", 12, np.random.default_rng(4))
    waypoints[:, 2] *= 0.9  # the elbow's limits are ±π: keep the path's overshoot off them
    return plan_sweep(waypoints, np.zeros(6), max_speed=SPEED, max_acceleration=ACCEL,
                      spec=get_robot("ur5e"))


def test_every_sample_is_within_the_limits_and_the_ends_at_rest(tour):
    v = np.abs(np.diff(tour.q, axis=0)) * tour.rate_hz
    assert np.all(v <= SPEED) and np.all(np.abs(tour.accelerations()) <= ACCEL)
    # the limits are used, not just respected: the binding joint runs near one of them
    assert max((v / SPEED).max(), (np.abs(tour.accelerations()) / ACCEL).max()) > 0.9
    np.testing.assert_allclose(tour.q[0], np.zeros(6), atol=1e-12)
    np.testing.assert_allclose(tour.q[-1], tour.waypoints[-1], atol=1e-12)
    np.testing.assert_allclose(tour.velocities()[[0, -1]], 0.0, atol=0.01 * SPEED.min())
    np.testing.assert_allclose(np.diff(tour.t), 1.0 / tour.rate_hz)
    assert tour.duration == pytest.approx(tour.t[-1])


def test_it_passes_through_every_waypoint(tour):
    nearest = np.round(tour.waypoint_times * tour.rate_hz).astype(int)
    # within the half period between samples: half a period of the fastest joint speed
    assert np.all(np.abs(tour.q[nearest] - tour.waypoints) <= SPEED / tour.rate_hz)
    assert np.all(np.diff(tour.waypoint_times) > 0)


def test_the_acceleration_is_continuous(tour):
    # jerk piecewise constant: the acceleration's step between samples stays at jerk × period, far
    # below the acceleration limit (a corner would jump by up to twice the limit)
    jump = np.abs(np.diff(tour.accelerations()[1:-1], axis=0))
    assert jump.max() < 0.05 * ACCEL.min()


def test_stops_are_rests_held_for_the_dwell():
    rng = np.random.default_rng(6)
    waypoints, stops = rng.uniform(-1.0, 1.0, (5, 6)), rng.uniform(-1.0, 1.0, (3, 6))
    tour = plan_sweep(waypoints, np.zeros(6), max_speed=SPEED, max_acceleration=ACCEL, stops=stops,
                      dwell_s=0.5)
    assert sorted(map(tuple, tour.stops)) == sorted(map(tuple, stops))
    v = tour.velocities()
    for pose, ts in zip(tour.stops, tour.stop_times, strict=True):
        i = round(ts * tour.rate_hz)
        np.testing.assert_allclose(tour.q[i: i + 250], np.broadcast_to(pose, (250, 6)), atol=1e-12)
        assert np.abs(v[i - 1]).max() < 0.01 * SPEED.min()  # it arrives at rest
    nearest = np.round(tour.waypoint_times * tour.rate_hz).astype(int)
    assert np.all(np.abs(tour.q[nearest] - tour.waypoints) <= SPEED / tour.rate_hz)
    assert np.all(np.abs(np.diff(tour.q, axis=0)) * tour.rate_hz <= SPEED)
    assert np.all(np.abs(tour.accelerations()) <= ACCEL)
    d = tour.approach_directions()
    assert d.shape == (3, 6) and set(np.unique(d)) <= {-1.0, 0.0, 1.0}


def test_each_stop_holds_its_own_dwell_and_a_tour_of_rests_alone_is_allowed():
    # a sweep campaign holds its validation rests for the stop-and-go dwell and its bootstrap rests for
    # fewer readings; with no waypoints the tour is its rests and the legs between them
    rng = np.random.default_rng(8)
    stops = rng.uniform(-1.0, 1.0, (4, 6))
    dwell = np.array([0.1, 0.6, 0.3, 1.2])
    tour = plan_sweep(np.zeros((0, 6)), np.zeros(6), max_speed=SPEED, max_acceleration=ACCEL, stops=stops,
                      dwell_s=dwell)
    assert tour.waypoints.shape == (0, 6) and len(tour.stops) == 4
    for pose, ts in zip(tour.stops, tour.stop_times, strict=True):
        k = int(np.flatnonzero(np.all(stops == pose, axis=1))[0])
        i, hold = round(ts * tour.rate_hz), round(dwell[k] * tour.rate_hz)
        np.testing.assert_allclose(tour.q[i: i + hold + 1], np.broadcast_to(pose, (hold + 1, 6)), atol=1e-12)
        if i + hold + 1 < len(tour.q):  # and no longer: the next leg's first sample moves
            assert np.abs(tour.q[i + hold + 1] - pose).max() > 0
    moving = np.abs(np.diff(tour.q, axis=0)).max(axis=1) > 0
    # the whole tour is its legs plus the holds: the dwell is each stop's own, not one for all
    assert tour.duration == pytest.approx(moving.sum() / tour.rate_hz + dwell.sum(), abs=5 / tour.rate_hz)
    same = plan_sweep(np.zeros((0, 6)), np.zeros(6), max_speed=SPEED, max_acceleration=ACCEL, stops=stops,
                      dwell_s=1.2)
    assert same.duration == pytest.approx(tour.duration + (4 * 1.2 - dwell.sum()), abs=2 / tour.rate_hz)
    with pytest.raises(InputError, match="one per stop"):
        plan_sweep(np.zeros((0, 6)), np.zeros(6), max_speed=SPEED, max_acceleration=ACCEL, stops=stops,
                   dwell_s=[0.1, 0.2])
    with pytest.raises(InputError, match="at least one"):
        plan_sweep(np.zeros((0, 6)), np.zeros(6), max_speed=SPEED, max_acceleration=ACCEL)


def test_the_order_distance_is_a_rest_to_rest_leg_time():
    # the ordering's distance is what one rest-to-rest leg of the tour takes (its first timing, exact
    # for one cubic segment), so a tour of rests is ordered by the time it costs
    rng = np.random.default_rng(9)
    for _ in range(5):
        a, b = rng.uniform(-1.0, 1.0, (2, 6))
        b[rng.integers(6)] = a[rng.integers(6)]  # any joint may stand
        leg = plan_sweep(np.zeros((0, 6)), a, max_speed=SPEED, max_acceleration=ACCEL, stops=b[None])
        assert leg.duration == pytest.approx(float(leg_seconds(a, b, SPEED, ACCEL)), rel=0.02, abs=0.004)
    assert float(leg_seconds(a, b, SPEED)) == pytest.approx(np.max(np.abs(b - a) / SPEED))


def test_the_order_is_short():
    # poses on a line, shuffled: the shortest tour from one end visits them in order
    line = np.outer(np.arange(1, 9), np.full(6, 0.1))
    shuffled = np.random.default_rng(2).permutation(8)
    order = tour_order(np.zeros(6), line[shuffled], SPEED)
    assert list(shuffled[order]) == list(range(8))


def test_a_waypoint_on_a_joint_limit_is_refused_where_the_spline_overshoots_it():
    # the elbow rises to π and turns back there: the spline carries it a little beyond
    start = np.array([0.5, -1.0, 3.0, -1.0, 1.0, 0.0])
    waypoints = np.array([[0.5, -1.0, np.pi, -1.0, 1.0, 0.0], [1.0, -1.5, 1.0, -1.5, 1.5, 0.5]])
    with pytest.raises(SweepRefused, match=r"sweep sample \d+ .*joint 3 at 3.14\d+ rad is outside"):
        plan_sweep(waypoints, start, max_speed=SPEED, max_acceleration=ACCEL, spec=get_robot("ur5e"))


def test_bad_input_and_impossible_limits_are_refused():
    with pytest.raises(InputError, match="finite"):
        plan_sweep(np.full((2, 6), np.nan), np.zeros(6), max_speed=1.0, max_acceleration=1.0)
    with pytest.raises(InputError, match="max_speed"):
        plan_sweep(np.ones((2, 6)), np.zeros(6), max_speed=-1.0, max_acceleration=1.0)


def test_check_sweep_names_the_first_offending_sample(tour):
    spec = get_robot("ur5e")
    check_sweep(tour, spec=spec, max_acceleration=ACCEL)  # the planned tour passes
    too_fast = SweepTour(tour.t, tour.q, tour.waypoints, tour.rate_hz)
    with pytest.raises(SweepRefused, match=r"sweep sample \d+ .*joint \d steps at"):
        check_sweep(too_fast, max_speed=0.9 * np.abs(tour.velocities()).max(axis=0))
    q = tour.q.copy()
    q[123, 2] = 3.5  # beyond the elbow's ±π
    with pytest.raises(SweepRefused, match=r"sweep sample 123 .*joint 3 at 3.5000 rad is outside"):
        check_sweep(SweepTour(tour.t, q, tour.waypoints, tour.rate_hz), spec=spec)
    with pytest.raises(SweepRefused, match="accelerates"):
        check_sweep(tour, max_acceleration=0.9 * np.abs(tour.accelerations()).max(axis=0))


def test_keep_in_and_line_of_sight_refuse_before_motion(tour):
    truth = random_truth("ur5e", np.random.default_rng(3))
    with pytest.raises(SweepRefused, match="outside the keep-in box"):
        check_sweep(tour, keep_in=(np.array([-2.0, -2.0, 0.5]), np.array([2.0, 2.0, 2.0])), model=truth)
    check_sweep(tour, keep_in=(np.full(3, -2.0), np.full(3, 2.0)), model=truth)  # a box it stays in
    # a tour through a pose the tracker cannot see is refused at a sample, naming why
    rng = np.random.default_rng(8)
    hidden = next(q for q in random_configurations("ur5e", 200, rng)
                  if hidden_reason("ur5e", truth.smr, truth.tracker.translation, q, 30.0) is not None)
    blind = plan_sweep(hidden[None], hidden + 0.02, max_speed=SPEED, max_acceleration=ACCEL)
    with pytest.raises(SweepRefused, match=r"sweep sample \d+ .*would not see the SMR"):
        check_sweep(blind, model=truth, acceptance_angle=30.0)
