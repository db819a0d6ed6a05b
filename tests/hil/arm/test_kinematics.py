import numpy as np
import pinocchio as pin
import pytest

from hil.arm.catalog import ROBOT_NAMES, get_robot
from hil.arm.geometry import Geometry, pose
from hil.arm.kinematics import (
    N_PARAMETERS,
    PARAMETER_NAMES,
    Kinematics,
    apply_update,
    deviation_from,
    generic_configurations,
    generic_geometry,
    identifiable_parameters,
    numerical_rank,
)


def dh_flange(robot: str, q: np.ndarray) -> np.ndarray:
    """Standard DH product written out independently of hil: Π Rz(θ)·Tz(d)·Tx(a)·Rx(α)."""
    dh = get_robot(robot).dh
    T = np.eye(4)
    for th, d, a, al in zip(q, dh.d, dh.a, dh.alpha, strict=True):
        ct, st, ca, sa = np.cos(th), np.sin(th), np.cos(al), np.sin(al)
        T = T @ np.array([[ct, -st * ca, st * sa, a * ct],
                          [st, ct * ca, -ct * sa, a * st],
                          [0, sa, ca, d],
                          [0, 0, 0, 1]])
    return T


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_fk_at_hand_computed_configurations(robot):
    d, a = get_robot(robot).dh.d, get_robot(robot).dh.a
    kin = Kinematics(Geometry.nominal(robot))
    zero = np.array([a[1] + a[2], -(d[3] + d[5]), d[0] - d[4]])  # arm stretched along -x
    turned = np.array([d[3] + d[5], a[1] + a[2], d[0] - d[4]])  # same, base turned by +90°
    q = np.array([[0.0] * 6, [np.pi / 2, 0, 0, 0, 0, 0]])
    got = kin.points(q, frame="base", point="flange")
    assert np.allclose(got, [zero, turned], atol=1e-12)


def test_ur5e_zero_pose_literal():
    got = Kinematics(Geometry.nominal("ur5e")).points(np.zeros(6), frame="base", point="flange")
    assert np.allclose(got, [[-0.8172, -0.2329, 0.0628]], atol=1e-12)


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_fk_matches_the_dh_product(robot, rng):
    kin = Kinematics(Geometry.nominal(robot))
    Q = rng.uniform(-np.pi, np.pi, (20, 6))
    F = kin.flange_poses(Q)
    for q, T in zip(Q, F, strict=True):
        assert np.allclose(T, dh_flange(robot, q), atol=1e-12)


def test_points_in_tracker_frame_and_smr_offset(rng):
    tracker = pose((2.0, -1.0, 0.3), (0.1, -0.2, 2.0))
    g = Geometry.nominal("ur10e", smr=(0.01, 0.02, 0.05), tracker=tracker)
    kin = Kinematics(g)
    Q = rng.uniform(-3, 3, (5, 6))
    F = kin.flange_poses(Q)
    smr_base = np.einsum("nij,j->ni", F[:, :3, :3], g.smr) + F[:, :3, 3]
    assert np.allclose(kin.points(Q, frame="base"), smr_base)
    expected = (smr_base - tracker.translation) @ tracker.rotation
    assert np.allclose(kin.points(Q), expected, atol=1e-12)
    frames = kin.joint_frames(Q)
    assert np.allclose(frames[:, 6], F)


def test_jacobian_agrees_with_finite_differences_for_every_parameter(rng):
    g = apply_update(generic_geometry("ur5e"), rng.normal(0, 1e-3, N_PARAMETERS))
    Q = rng.uniform(-np.pi, np.pi, (6, 6))
    p, J = Kinematics(g).point_and_jacobian(Q)
    assert J.shape == (6, 3, N_PARAMETERS)
    assert np.allclose(p, Kinematics(g).points(Q))
    h = 1e-6
    for i, name in enumerate(PARAMETER_NAMES):
        step = np.zeros(N_PARAMETERS)
        step[i] = h
        fd = (Kinematics(apply_update(g, step)).points(Q)
              - Kinematics(apply_update(g, -step)).points(Q)) / (2 * h)
        assert np.allclose(fd, J[:, :, i], atol=1e-8), name
        assert np.abs(J[:, :, i]).max() > 1e-3, name  # every column really moves the point


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_identifiable_set_has_27_parameters(robot):
    idx = identifiable_parameters(robot)
    assert len(idx) == 27
    J = Kinematics(generic_geometry(robot)).jacobian(generic_configurations(robot))
    assert numerical_rank(J.reshape(-1, N_PARAMETERS)) == 27
    assert numerical_rank(J[:, :, idx].reshape(-1, 27)) == 27
    names = {PARAMETER_NAMES[i] for i in idx}
    # the tracker pose and the SMR offset are always identified; the flange never is
    assert {"smr.x", "smr.y", "smr.z"} <= names
    assert {f"tracker.{a}" for a in ("tx", "ty", "tz", "rx", "ry", "rz")} <= names
    assert not any(n.startswith("flange.") or n.startswith("joint1.") for n in names)


def test_smr_on_the_joint6_axis_loses_one_parameter():
    """Why the set is chosen at a generic point: on the axis the whole model drops to rank 26."""
    on_axis = generic_geometry("ur5e")
    on_axis.smr = np.array([0.0, 0.0, 0.05])
    J = Kinematics(on_axis).jacobian(generic_configurations("ur5e")).reshape(-1, N_PARAMETERS)
    assert numerical_rank(J) == 26


def test_update_and_deviation_are_inverse(rng):
    g0 = generic_geometry("ur3e")
    delta = rng.normal(0, 1e-2, N_PARAMETERS)
    g1 = apply_update(g0, delta)
    assert np.allclose(deviation_from(g0, g1), delta, atol=1e-12)
    assert np.allclose(g1.joints[2].homogeneous, (g0.joints[2] * pin.exp6(delta[12:18])).homogeneous)


def test_bad_configuration_shape():
    with pytest.raises(ValueError, match="6 values"):
        Kinematics(Geometry.nominal("ur5e")).points(np.zeros(5))
