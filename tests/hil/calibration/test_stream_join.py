"""The stream join against known injected clocks: offset and drift recovered within the stated σ,
gaps and beam breaks left out and counted, a 1 ms sync error visible in the residual."""

import numpy as np
import pytest

from hil.arm.dynamics import DynamicsModel, MovingArm
from hil.calibration.stream_clocks import ClockMap, InstrumentClock, StationClocks
from hil.calibration.stream_join import JointStream, StreamJoin, TrackerStream, join_streams
from hil.calibration.synthetic import random_truth
from hil.calibration.synthetic_stream import sweep_streams
from hil.errors import InputError


@pytest.fixture(scope="module")
def truth():
    return random_truth("ur5e", np.random.default_rng(1), ideal=False)


@pytest.fixture(scope="module")
def arm(truth):
    return MovingArm(truth)


def _error_at(fit, truth_map, t):
    return float(fit.map(t) - truth_map(t))


@pytest.mark.parametrize("seed", [3, 4])
def test_recovers_injected_offset_and_drift_within_its_uncertainty(truth, arm, seed):
    clocks = StationClocks(
        tracker=InstrumentClock(offset_s=812.25 + seed, drift_ppm=-25.0, jitter_s=5e-6, latency_s=7e-4),
        controller=InstrumentClock(offset_s=0.0, drift_ppm=18.0))
    s = sweep_streams(truth, tool_speed=0.25, duration=10.0, clocks=clocks, seed=seed)
    fit = join_streams(s.joints, s.tracker, arm.points, DynamicsModel(truth).acceleration_limit)
    want = clocks.controller_from_tracker()
    assert abs(_error_at(fit, want, fit.t_ref)) < 3 * fit.sigma_at_ref_s
    assert abs(fit.drift - want.drift) < 3 * fit.sigma_drift
    # the σ are small enough to mean something: sub-microsecond, a fraction of a ppm
    assert fit.sigma_at_ref_s < 1e-6 and fit.sigma_drift < 1e-6
    # over the whole sweep the map is right to a few microseconds: micrometres at this speed
    ends = s.tracker.t[[0, -1]]
    assert np.abs(fit.map(ends) - want(ends)).max() < 5e-6
    assert fit.used > 9900 and fit.rms_m < 30e-6


def test_a_stream_with_a_beam_break_and_a_joint_gap_is_joined_and_its_samples_counted(truth, arm):
    clocks = StationClocks.realistic()
    s = sweep_streams(truth, tool_speed=0.25, duration=10.0, clocks=clocks, seed=5,
                      beam_breaks=[(3.0, 3.4)], joint_gaps=[(6.0, 6.25)])
    join = StreamJoin(s.joints, s.tracker, arm.points, relock_guard_s=0.05)
    fit = join.fit()
    want = clocks.controller_from_tracker()
    assert abs(_error_at(fit, want, fit.t_ref)) < 3 * fit.sigma_at_ref_s
    left = fit.left_out
    assert left["beam lost"] == pytest.approx(400, abs=2)  # 0.4 s at 1 kHz
    assert left["after a gap"] == pytest.approx(50, abs=2)  # the re-lock guard
    assert left["joint gap"] == pytest.approx(250, abs=10)  # 0.25 s without joints
    assert fit.used + sum(left.values()) == len(s.tracker.t)
    # the residual of the left-out lost samples is NaN, never a number
    assert np.isnan(join.residuals(fit.map)[~np.isfinite(s.tracker.p).all(axis=1)]).all()


def test_a_1_ms_sync_error_at_a_quarter_metre_a_second_shows_in_the_residual(truth, arm):
    clocks = StationClocks.realistic()
    s = sweep_streams(truth, tool_speed=0.25, duration=10.0, clocks=clocks, seed=6)
    join = StreamJoin(s.joints, s.tracker, arm.points)
    right = clocks.controller_from_tracker()
    late = ClockMap(right.offset_s + 1e-3, right.drift)
    r_right, r_late = join.residuals(right), join.residuals(late)
    ok = np.isfinite(r_right).all(axis=1) & np.isfinite(r_late).all(axis=1)
    rms_right = np.sqrt(np.mean(np.sum(r_right[ok] ** 2, axis=1)))
    rms_late = np.sqrt(np.mean(np.sum(r_late[ok] ** 2, axis=1)))
    assert rms_right < 30e-6  # noise only
    # the sync error costs the tool's speed × 1 ms: 0.25 mm RMS, on top of the noise in quadrature
    assert np.sqrt(rms_late**2 - rms_right**2) == pytest.approx(s.tool_speed_rms * 1e-3, rel=0.05)
    assert s.tool_speed_rms == pytest.approx(0.25, rel=0.05)


def test_samples_beyond_the_acceleration_limit_are_left_out(truth, arm):
    s = sweep_streams(truth, tool_speed=0.25, duration=10.0, clocks=StationClocks.ideal(), seed=7)
    true_qdd = s.path.at(s.tracker.t)[2]  # ideal clocks: a stamp is the true time
    # the shoulder's median |q̈| (the others unlimited): the path exceeds it half of the time
    limit = np.r_[np.median(np.abs(true_qdd[:, 0])), np.full(5, np.inf)]
    join = StreamJoin(s.joints, s.tracker, arm.points, lambda q: np.broadcast_to(limit, q.shape))
    used, left = join.trust(ClockMap(0.0, 0.0))
    beyond = (np.abs(true_qdd) > limit).any(axis=1)
    assert 0.4 < beyond.mean() < 0.6
    assert left["acceleration"] == pytest.approx(int(beyond.sum()), rel=0.02)
    # where the join and the true path disagree, the true |q̈| is near the limit: the encoders' 5 µrad
    # noise differentiated twice over the 50 ms window (≈ 0.01 rad/s²) decides those; the stream's
    # first and last windows, where the fit is one-sided, aside
    inner = (s.tracker.t > s.tracker.t[0] + 0.05) & (s.tracker.t < s.tracker.t[-1] - 0.05)
    differ = ((used & beyond) | (~used & ~beyond)) & inner
    assert np.abs(np.abs(true_qdd[differ, 0]) / limit[0] - 1.0).max() < 0.15


def test_streams_that_cannot_be_joined_are_refused_with_one_line(truth, arm):
    with pytest.raises(InputError, match="joint stream: stamps must increase"):
        JointStream(np.array([0.0, 0.002, 0.002]), np.zeros((3, 6)))
    with pytest.raises(InputError, match=r"tracker stream: expected t \(M,\) and p \(M, 3\)"):
        TrackerStream(np.arange(3.0), np.zeros((3, 2)))
    s = sweep_streams(truth, tool_speed=0.25, duration=2.0, clocks=StationClocks.ideal(), seed=8)
    far = TrackerStream(s.tracker.t + 100.0, s.tracker.p)
    with pytest.raises(InputError, match="do not overlap"):
        StreamJoin(s.joints, far, arm.points).fit(initial_offset_s=0.0)


def test_a_fast_time_station_is_joined_from_its_speed_as_first_drift(truth, arm):
    # a simulated station at 10x: the tracker's clock keeps the wall's rate, a tenth of the controller's
    s = sweep_streams(truth, tool_speed=0.25, duration=4.0, clocks=StationClocks.ideal(), seed=9)
    slow = TrackerStream(s.tracker.t / 10.0 + 5.0, s.tracker.p)
    fit = StreamJoin(s.joints, slow, arm.points).fit(initial_drift=9.0)
    want = ClockMap(-50.0, 9.0)
    assert abs(fit.drift - want.drift) < 3 * fit.sigma_drift
    assert abs(_error_at(fit, want, fit.t_ref)) < 3 * fit.sigma_at_ref_s


def test_samples_near_a_guarded_pose_are_left_out_with_their_reason():
    """The validation poses a sweep rests at are guarded: no sample whose joints lie within the radius
    of one is trusted, each counted once as ``validation pose``."""
    t = np.arange(0.0, 2.0, 0.002)
    q = np.zeros((len(t), 6))
    q[:, 0] = np.sin(np.pi * t)  # 0 → 1 → 0 rad
    joints = JointStream(t, q)
    tt = np.arange(0.0, 2.0, 0.001)
    tracker = TrackerStream(tt, np.zeros((len(tt), 3)))

    def points(qq, qd, qdd, directions=None):
        return np.column_stack([qq[:, 0], np.zeros(len(qq)), np.zeros(len(qq))])

    pose = np.zeros(6)
    pose[0] = 1.0
    plain = StreamJoin(joints, tracker, points)
    guarded = StreamJoin(joints, tracker, points, guard=(pose[None, :], 0.05))
    ident = ClockMap(0.0, 0.0)
    use_plain, _ = plain.trust(ident)
    use, left = guarded.trust(ident)
    frame = np.clip(np.searchsorted(t, tt), 0, len(t) - 1)  # the joint frame a sample is judged by
    near = np.abs(q[frame, 0] - 1.0) < 0.05
    assert left["validation pose"] == int((near & use_plain).sum()) > 100
    assert not (use & near).any() and (use | near).sum() == use_plain.sum() + (near & ~use_plain).sum()
