"""The arm's residual vibration (`mocks.ringing`): the tracker sees it, the joints do not; it decays
as its constants say and grows with the stop's deceleration."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from hil.arm.geometry import Geometry, look_at_tracker
from mocks.ringing import OMEGA_N, ZETA, Ringing
from mocks.ur.arm import ArmConfig, SimArm
from mocks.ur.kin import dh_fk_factory
from mocks.world import World

Q0 = np.array([0.3, -1.3, 1.2, -1.5, -1.6, 0.1])
Q1 = np.array([-0.3, -1.1, 1.0, -1.4, -1.5, 0.3])


class ManualClock:
    def __init__(self) -> None:
        self.t = 0.0
        self.speed = 1.0

    def now(self) -> float:
        return self.t


def ringing_station():
    """A simulated arm and a world that rings with it, on a clock the test advances by hand."""
    clock = ManualClock()
    arm = SimArm(ArmConfig(encoder_noise=0.0), dh_fk_factory("ur5e"), clock)  # type: ignore[arg-type]
    arm.set_joints(Q0)
    truth = Geometry.nominal("ur5e", smr=(0.0, 0.0, 0.045), tracker=look_at_tracker((2.0, 0.0, 0.4)))
    world = World(truth, arm.true_joints, clock=clock.now, ringing=Ringing())
    arm.listeners.append(world.ringing.listener(world.tip_direction))
    return arm, world, clock


def run_until_still(arm: SimArm, clock: ManualClock, dt: float = 0.002) -> None:
    for _ in range(100_000):
        clock.t += dt
        arm.tick()
        if arm.motion is None:
            return
    raise AssertionError("the move never ended")


def test_the_tracker_sees_the_ring_and_the_joints_do_not():
    arm, world, clock = ringing_station()
    with arm.lock:
        arm.start_movej(Q1, 0.5, 1.0)
    run_until_still(arm, clock)
    rigid = world.state(Q1)[0]
    seen, joints = [], []
    for _ in range(500):  # one second after the stop, at the controller's rate
        clock.t += 0.002
        arm.tick()
        seen.append(np.linalg.norm(world.target().position - rigid))
        joints.append(np.max(np.abs(np.asarray(arm.snapshot["actual_q"]) - Q1)))
    assert max(seen[:25]) > 30e-6  # tens of micrometres in the first 50 ms
    assert max(seen[-50:]) < 0.02 * max(seen[:25])  # e^(−ζωₙ·0.9) ≈ 0.6 % left a second later
    assert max(joints) < 1e-12  # the encoders see none of it


def test_the_ring_decays_with_its_constants():
    ring = Ringing()
    direction = np.array([0.0, 0.5, 0.0])
    ring.record(0.0, 3.0, 0.5, 1.0, direction)  # a long move: the start's ring is gone by the stop
    wd = OMEGA_N * math.sqrt(1 - ZETA**2)
    period = 2 * math.pi / wd
    x = [ring.offset(3.0 + k * period)[1] for k in range(6)]
    ratios = [b / a for a, b in itertools.pairwise(x)]
    assert ratios == pytest.approx([math.exp(-ZETA * OMEGA_N * period)] * 5, rel=1e-3)
    # it starts at the quasi-static deflection of the stop, lever × deceleration / ωₙ², plus what is
    # left of the deceleration's onset half a second earlier (e^(−ζωₙ·0.5) ≈ 6 %)
    assert x[0] == pytest.approx(0.5 * 1.0 / OMEGA_N**2, rel=0.08)
    assert ring.offset(3.0)[[0, 2]] == pytest.approx([0.0, 0.0])  # along the direction of travel only


def test_a_harder_stop_rings_more_and_a_cut_move_not_at_all():
    soft, hard = Ringing(), Ringing()
    soft.record(0.0, 3.0, 0.5, 1.0, np.array([0.5, 0.0, 0.0]))
    hard.record(0.0, 3.0, 0.5, 4.0, np.array([0.5, 0.0, 0.0]))  # the same profile's times, 4× the ramps
    for t in (3.0, 3.05, 3.3):
        assert hard.offset(t)[0] == pytest.approx(4 * soft.offset(t)[0], rel=1e-9)
    hard.cut(1.5)  # stopped half way: its ring is dropped (module docstring)
    assert np.all(hard.offset(3.0) == 0.0)


def test_the_ring_is_deterministic_given_the_motion():
    a, w1, c1 = ringing_station()
    b, w2, c2 = ringing_station()
    for arm, clock in ((a, c1), (b, c2)):
        with arm.lock:
            arm.start_movej(Q1, 0.5, 1.0)
        run_until_still(arm, clock)
    for dt in (0.0, 0.05, 0.1):
        c1.t += dt
        c2.t += dt
        assert np.array_equal(w1.target().position, w2.target().position)


def test_offsets_in_one_pass_are_the_offsets_one_by_one():
    ring = Ringing()
    ring.record(0.0, 1.2, 0.4, 2.0, np.array([0.5, -0.2, 0.1]))
    ring.record(1.5, 0.8, 0.4, 1.0, np.array([0.0, 0.3, 0.4]))
    t = np.linspace(-0.5, 4.0, 301)
    np.testing.assert_allclose(ring.offsets(t), [ring.offset(float(x)) for x in t], rtol=1e-12, atol=1e-18)


def test_a_reading_integrates_the_ring_as_asked():
    arm, world, clock = ringing_station()
    with arm.lock:
        arm.start_movej(Q1, 1.0, 2.0)
    run_until_still(arm, clock)
    ends = clock.t + np.array([0.0, 0.05, 0.1, 0.3])
    world.reading_time = 0.1
    integrated = world.ring_offsets(ends)
    np.testing.assert_allclose(integrated, [world.ring_offset(float(t)) for t in ends], rtol=1e-12)
    instants = world.ring_offsets(ends, reading_time=0.0)
    expected = np.array([world.ringing.offset(float(t)) for t in ends]) @ world.truth.tracker.rotation
    np.testing.assert_allclose(instants, expected, rtol=1e-12)
    assert not np.allclose(integrated, instants, atol=1e-7)  # 0.1 s of a 9 Hz ring is not an instant
