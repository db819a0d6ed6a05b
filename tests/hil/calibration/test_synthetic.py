"""Synthetic truths are real arms (compliance, payload, warm-up) and measure as the simulator does."""

from __future__ import annotations

import numpy as np
import pytest

from hil.arm.kinematics import Kinematics
from hil.arm.payload import Payload, gravity_of_mounting
from hil.arm.physical import typical_compliance
from hil.arm.thermal import Thermal
from hil.calibration.model_file import load_truth, truth_document, write_json
from hil.calibration.synthetic import (
    ENCODER_SIGMA,
    Noise,
    approach_directions,
    measure,
    random_configurations,
    random_truth,
    smr_payload,
    true_points,
)


def test_a_realistic_truth_is_the_rigid_one_plus_its_non_geometric_blocks() -> None:
    rng_real, rng_rigid = np.random.default_rng(7), np.random.default_rng(7)
    real = random_truth("ur5e", rng_real)
    rigid = random_truth("ur5e", rng_rigid, rigid=True)
    for a, b in zip([*real.joints, real.flange, real.tracker], [*rigid.joints, rigid.flange, rigid.tracker],
                    strict=True):
        assert np.array_equal(a.homogeneous, b.homogeneous)
    assert np.array_equal(real.smr, rigid.smr)
    # the caller's generator went on the same way: poses and noise drawn next are the same
    assert rng_real.random() == rng_rigid.random()
    assert rigid.compliance is None and rigid.payload is None and rigid.thermal is None
    factor = real.compliance / typical_compliance("ur5e")
    assert np.all((factor >= 0.8) & (factor <= 1.2)) and np.ptp(factor) > 0
    assert real.payload == smr_payload(real.smr) and 0.5 <= real.payload.mass <= 1.0
    assert real.thermal == Thermal()


def test_the_smr_payload_sits_between_the_plate_and_the_smr() -> None:
    p = smr_payload(np.array([0.0, 0.0, 0.045]))
    assert p.com[0] == p.com[1] == 0.0 and 0.01 < p.com[2] < 0.045


def test_a_truth_with_every_block_survives_its_file(tmp_path) -> None:
    truth = random_truth("ur10e", np.random.default_rng(2))
    truth.gravity = gravity_of_mounting((0.4, -0.3, 0.0))  # a tilted base
    path = tmp_path / "truth.json"
    write_json(path, truth_document(truth, Noise(15e-6, 3e-6, standstill_sigma=1.6e-5)))
    back, noise = load_truth(path)
    assert noise == Noise(15e-6, 3e-6, standstill_sigma=1.6e-5)
    np.testing.assert_array_equal(back.compliance, truth.compliance)
    assert back.payload == Payload(truth.payload.mass, truth.payload.com)
    np.testing.assert_array_equal(back.gravity, truth.gravity)
    assert back.thermal == truth.thermal
    q = random_configurations("ur10e", 20, np.random.default_rng(3))
    np.testing.assert_allclose(Kinematics(back).points(q), Kinematics(truth).points(q), atol=1e-12)


def test_measure_warms_the_arm_pose_by_pose_when_given_running_times() -> None:
    truth = random_truth("ur5e", np.random.default_rng(5))
    q = random_configurations("ur5e", 6, np.random.default_rng(6))
    exact = Noise(0.0, 0.0)
    times = np.array([0.0, 0.0, 900.0, 900.0, 1e5, 1e5])
    q_read, p = measure(truth, q, exact, np.random.default_rng(0), times)
    np.testing.assert_array_equal(q_read, q)
    for i, t in enumerate(times):
        np.testing.assert_allclose(p[i], Kinematics(truth.warmed(t)).points(q[i])[0], atol=1e-12)
    cold = measure(truth, q, exact, np.random.default_rng(0))[1]
    np.testing.assert_allclose(cold, Kinematics(truth).points(q), atol=1e-12)
    np.testing.assert_allclose(p[:2], cold[:2], atol=1e-12)
    grown = np.linalg.norm(p[4:] - cold[4:], axis=1)
    assert np.all(grown > 1e-5)  # fully warm: tens of micrometres and more at the SMR
    # a rigid cold arm ignores the times
    rigid = truth.rigid()
    np.testing.assert_allclose(measure(rigid, q, exact, np.random.default_rng(0), times)[1],
                               Kinematics(rigid).points(q), atol=1e-12)
    with pytest.raises(ValueError, match="one running time per pose"):
        measure(truth, q, exact, np.random.default_rng(0), times[:3])


def test_the_default_noise_reads_the_joints_as_a_ur_does() -> None:
    assert Noise().encoder_sigma == ENCODER_SIGMA
    truth = random_truth("ur5e", np.random.default_rng(1), rigid=True)
    q = random_configurations("ur5e", 2000, np.random.default_rng(2))
    q_read, _ = measure(truth, q, Noise(), np.random.default_rng(3))
    assert np.std(q_read - q) == pytest.approx(ENCODER_SIGMA, rel=0.05)


def test_the_ideal_and_the_realistic_truth_of_one_seed_differ_only_by_joint_errors_and_lost_motion() -> None:
    rng_real, rng_ideal = np.random.default_rng(11), np.random.default_rng(11)
    real = random_truth("ur5e", rng_real, ideal=False)
    ideal = random_truth("ur5e", rng_ideal, ideal=True)
    assert rng_real.random() == rng_ideal.random()  # the caller's later draws are the same
    assert ideal.joint_errors is None and ideal.lost_motion is None
    assert real.has_joint_errors and real.has_lost_motion
    same = real.ideal()
    for a, b in zip([*same.joints, same.flange, same.tracker], [*ideal.joints, ideal.flange, ideal.tracker],
                    strict=True):
        assert np.array_equal(a.homogeneous, b.homogeneous)
    np.testing.assert_array_equal(same.compliance, ideal.compliance)
    assert same.payload == ideal.payload and same.thermal == ideal.thermal


def test_a_realistic_truth_with_its_joint_errors_and_lost_motion_survives_its_file(tmp_path) -> None:
    truth = random_truth("ur10e", np.random.default_rng(4), ideal=False)
    path = tmp_path / "truth.json"
    write_json(path, truth_document(truth, Noise()))
    back, _ = load_truth(path)
    assert back.joint_errors == truth.joint_errors
    np.testing.assert_array_equal(back.lost_motion, truth.lost_motion)
    q = random_configurations("ur10e", 20, np.random.default_rng(5))
    side = np.random.default_rng(6).choice([-1.0, 1.0], (20, 6))
    np.testing.assert_allclose(Kinematics(back).points(q, directions=side),
                               Kinematics(truth).points(q, directions=side), atol=1e-12)


def test_measure_applies_lost_motion_by_the_approach() -> None:
    truth = random_truth("ur5e", np.random.default_rng(8), ideal=False)
    q = random_configurations("ur5e", 10, np.random.default_rng(9))
    up = true_points(truth, q, directions=np.ones(6))
    down = true_points(truth, q, directions=-np.ones(6))
    middle = true_points(truth, q)
    np.testing.assert_allclose(0.5 * (up + down), middle, atol=1e-9)  # the lag is symmetric
    assert 1e-6 < np.max(np.linalg.norm(up - down, axis=1)) < 1e-3
    _, p = measure(truth, q, Noise(0.0, 0.0), np.random.default_rng(1), directions=np.ones(6))
    np.testing.assert_allclose(p, up, atol=1e-12)


def test_approach_directions_follow_a_sequence_of_poses() -> None:
    q = np.array([[0.0] * 6, [0.1, -0.1, 0.0, 0.1, 0.1, 0.1], [0.2, -0.2, 0.0, 0.0, 0.1, 0.1]])
    d = approach_directions(q)
    assert d[0].tolist() == [0.0] * 6
    assert d[1].tolist() == [1.0, -1.0, 0.0, 1.0, 1.0, 1.0]
    assert d[2].tolist() == [1.0, -1.0, 0.0, -1.0, 1.0, 1.0]  # a joint standing keeps its last side


def test_offline_noise_grows_with_distance_as_the_tracker_simulators() -> None:
    """`Noise()` errs as the GeoCOM/emScon simulators do (`hil.calibration.tracker_noise`): 7.5 µm along
    the beam at any distance, 3 µrad × distance across it; a flat σ is isotropic as before."""
    from hil.calibration.tracker_noise import ANGLE_SIGMA, DISTANCE_SIGMA
    from mocks.geocom.noise import NoiseSpec

    rng = np.random.default_rng(7)
    for distance in (2.0, 10.0):
        beam = np.array([0.6, 0.8, 0.0])  # a horizontal line of sight
        across_h = np.array([0.8, -0.6, 0.0])
        point = distance * beam
        errors = Noise().perturb(np.tile(point, (20000, 1)), rng) - point
        assert np.std(errors @ beam) == pytest.approx(DISTANCE_SIGMA, rel=0.05)
        assert np.std(errors @ across_h) == pytest.approx(ANGLE_SIGMA * distance, rel=0.05)
        assert np.std(errors[:, 2]) == pytest.approx(ANGLE_SIGMA * distance, rel=0.05)
    assert NoiseSpec() == NoiseSpec(DISTANCE_SIGMA, ANGLE_SIGMA)  # the simulators' figures are these
    point = np.array([3.0, 0.0, 0.0])
    flat = Noise(1e-3).perturb(np.tile(point, (20000, 1)), rng) - point
    assert np.std(flat, axis=0) == pytest.approx([1e-3] * 3, rel=0.05)


def test_a_truth_keeps_its_tracker_noise_model(tmp_path) -> None:

    rng = np.random.default_rng(3)
    truth = random_truth("ur5e", rng)
    for noise in (Noise(), Noise(0.5e-3), Noise(None, 1e-5, 20e-6, 5e-6)):
        write_json(tmp_path / "t.json", truth_document(truth, noise))
        assert load_truth(tmp_path / "t.json")[1] == noise
