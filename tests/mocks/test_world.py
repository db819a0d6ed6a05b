import numpy as np
import pytest

from hil.arm.geometry import Geometry, look_at_tracker
from hil.arm.kinematics import Kinematics
from mocks.world import World


def world_at(q, tracker=(2.0, 0.0, 0.4)):
    truth = Geometry.nominal("ur5e", smr=(0.0, 0.0, 0.045), tracker=look_at_tracker(tracker))
    return World(truth, lambda: np.asarray(q, float))


def facing_tracker(world, rng, n=5000):
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    q[:, 1] = rng.uniform(-np.pi, 0, n)
    return [c for c in q if world.state(c)[1] < 20]


def test_visible_when_facing_the_tracker_and_hidden_when_facing_away(rng):
    world = world_at(np.zeros(6))
    poses = facing_tracker(world, rng)
    clear = [q for q in poses if not world.blocked_by_arm(q)]
    assert clear, "some poses must see the tracker"
    world.joints = lambda: clear[0]
    assert world.target().visible
    away = clear[0].copy()
    away[4] += np.pi  # wrist 2 half a turn: the SMR now faces away
    world.joints = lambda: away
    state = world.target()
    assert not state.visible and "faces away" in state.reason


def test_the_arm_itself_can_block_the_beam(rng):
    world = world_at(np.zeros(6))
    poses = facing_tracker(world, rng)
    blocked = [q for q in poses if world.blocked_by_arm(q)]
    assert blocked, "some poses facing the tracker have a link in the beam"
    world.joints = lambda: blocked[0]
    state = world.target()
    assert not state.visible and state.reason == "the arm blocks the line of sight"


def test_injected_blockage(rng):
    world = world_at(np.zeros(6))
    world.block_beam(True, "a person in the beam")
    assert world.target().reason == "a person in the beam"
    world.block_beam(False)
    assert world.target().reason != "a person in the beam"


def test_start_pose_sees_the_tracker_for_any_random_truth():
    from hil.calibration.synthetic import random_truth

    for seed in range(8):  # seed 5 puts the tracker low and to the side: the best-facing pose is blocked
        truth = random_truth("ur5e", np.random.default_rng(seed), ideal=True)
        world = World(truth, lambda: np.zeros(6))
        home = world.home_pose(np.random.default_rng(1))
        world.joints = lambda home=home: home
        assert world.target().visible, (seed, world.target().reason)


def test_a_warming_arm_moves_the_smr_by_expansion_times_rise_times_reach():
    """Every link translation grows by expansion·ΔT(t) (docs/design.md, Contracts: non-geometric errors);
    the SMR offset does not."""
    from hil.arm.thermal import Thermal

    thermal = Thermal(expansion=2.3e-5, rise=6.0, time_constant=900.0)
    truth = Geometry.nominal("ur5e", smr=(0.0, 0.0, 0.045), tracker=look_at_tracker((2.0, 0.0, 0.4)))
    truth.thermal = thermal
    q = np.array([0.3, -1.2, 1.4, -1.7, -1.4, 0.2])
    now = [0.0]
    world = World(truth, lambda: q, clock=lambda: now[0])
    cold, _ = world.state(q)
    flange = Kinematics(truth).flange_poses(q)[0, :3, 3]  # every translation of the chain grows
    for t in (60.0, 900.0, 3600.0):
        now[0] = t
        warm, _ = world.state(q)
        expected = thermal.expansion * thermal.rise_at(t) * np.linalg.norm(flange)
        assert np.linalg.norm(warm - cold) == pytest.approx(expected, rel=1e-6)
    assert np.linalg.norm(warm - cold) > 1e-4  # a tenth of a millimetre after an hour: what hil must see
    # without a clock the arm stays cold
    assert np.allclose(World(truth, lambda: q).state(q)[0], cold, atol=1e-12)


def test_the_world_rebuilds_the_warm_arm_only_when_it_grew():
    from hil.arm.thermal import Thermal

    truth = Geometry.nominal("ur5e", smr=(0.0, 0.0, 0.045), tracker=look_at_tracker((2.0, 0.0, 0.4)))
    truth.thermal = Thermal()
    now = [100.0]
    world = World(truth, lambda: np.zeros(6), clock=lambda: now[0])
    world.state(np.zeros(6))
    built = world._kin
    now[0] += 1e-3  # a millisecond grows a metre by 1.5e-13 m: the same model
    world.state(np.zeros(6))
    assert world._kin is built
    now[0] += 10.0
    world.state(np.zeros(6))
    assert world._kin is not built


def test_the_world_sees_the_arm_synthetic_measurements_see(rng):
    """The simulator's world and `synthetic.measure` describe one arm: compliant, loaded, warming."""
    from hil.calibration.synthetic import random_truth, true_points

    truth = random_truth("ur5e", np.random.default_rng(4), ideal=True)
    assert truth.compliant and truth.payload is not None and truth.thermal is not None
    q = rng.uniform(-np.pi, np.pi, (5, 6))
    world = World(truth, lambda: q[0], clock=lambda: 1200.0)
    seen = np.array([world.state(qi)[0] for qi in q])
    np.testing.assert_allclose(seen, true_points(truth, q, np.full(5, 1200.0)), atol=1e-12)
    rigid = World(truth.rigid(), lambda: q[0], clock=lambda: 1200.0)
    sag = np.linalg.norm(seen - np.array([rigid.state(qi)[0] for qi in q]), axis=1)
    assert np.all(sag > 1e-6)  # the compliant, warm arm is not the rigid cold one


def test_the_world_applies_lost_motion_by_each_joints_last_direction():
    """Move a joint up then down to the same angle: the SMR the tracker sees moves by the lag."""
    from mocks.ur.arm import ArmConfig, SimArm
    from mocks.ur.kin import dh_fk_factory

    class Clock:
        t = 0.0

        def now(self) -> float:
            return self.t

    def run(arm, clock, target):
        with arm.lock:
            arm.start_movej(np.asarray(target, float), 0.5, 1.0)
        for _ in range(100_000):
            clock.t += 0.002
            arm.tick()
            if arm.motion is None:
                return
        raise AssertionError("the move never ended")

    clock = Clock()
    arm = SimArm(ArmConfig(encoder_noise=0.0), dh_fk_factory("ur5e"), clock)  # type: ignore[arg-type]
    q = np.array([0.3, -1.3, 1.2, -1.5, -1.6, 0.1])
    arm.set_joints(q - 0.05)
    lag = np.array([0.0, 3e-4, 0.0, 0.0, 0.0, 0.0])  # joint 2 only
    truth = Geometry.nominal("ur5e", smr=(0.0, 0.0, 0.045), tracker=look_at_tracker((2.0, 0.0, 0.4)))
    truth.lost_motion = lag
    world = World(truth, arm.true_joints, directions=arm.joint_directions)
    run(arm, clock, q)  # every joint comes up to q
    assert arm.joint_directions().tolist() == [1.0] * 6
    from_below = world.target().position
    above = q.copy()
    above[1] += 0.05
    run(arm, clock, above)
    run(arm, clock, q)  # joint 2 comes down to the same angle
    assert arm.joint_directions().tolist() == [1.0, -1.0, 1.0, 1.0, 1.0, 1.0]
    from_above = world.target().position
    np.testing.assert_allclose(arm.true_joints(), q, atol=1e-12)
    kin = Kinematics(truth.ideal())
    up, down = q.copy(), q.copy()
    up[1] -= lag[1]  # the link lags below the encoder after coming up, above after coming down
    down[1] += lag[1]
    expected = kin.points(down)[0] - kin.points(up)[0]
    np.testing.assert_allclose(from_above - from_below, expected, atol=1e-9)
    assert np.linalg.norm(expected) > 1e-4  # 2 × 0.3 mrad at the shoulder: a few tenths of a mm
