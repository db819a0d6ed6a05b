"""`Kinematics.point_and_jacobian` with given torques: a moving arm's point and compliance columns, and
the joint-rz columns the sweep fit reads as ∂p/∂q (the SMR's velocity)."""

import numpy as np

from hil.arm.dynamics import DynamicsModel, MovingArm
from hil.arm.kinematics import COMPLIANCE_SLICE, Kinematics
from hil.calibration.synthetic import random_truth


def _moving_state(seed: int = 3):
    truth = random_truth("ur5e", np.random.default_rng(seed), ideal=False)
    rng = np.random.default_rng(seed)
    q = rng.uniform(-2.0, 2.0, (5, 6))
    qd, qdd = rng.normal(0, 1.0, (5, 6)), rng.normal(0, 3.0, (5, 6))
    return truth, q, qd, qdd


def test_gravity_torques_reproduce_the_static_answer():
    truth, q, _, _ = _moving_state()
    kin = Kinematics(truth)
    p0, J0 = kin.point_and_jacobian(q, True)
    p1, J1 = kin.point_and_jacobian(q, True, torques=kin.gravity.torques(q))
    np.testing.assert_allclose(p1, p0, atol=1e-15)
    np.testing.assert_allclose(J1, J0, atol=1e-15)


def test_moving_torques_give_the_moving_arms_point_and_its_compliance_columns():
    truth, q, qd, qdd = _moving_state()
    tau = DynamicsModel(truth).torques(q, qd, qdd)
    p, J = Kinematics(truth).point_and_jacobian(q, True, torques=tau)
    np.testing.assert_allclose(p, MovingArm(truth).points(q, qd, qdd), atol=1e-12)
    # a compliance column is the point's change per unit of compliance under these torques
    h = 1e-7
    for j in (1, 2):
        bent = truth.copy()
        bent.compliance = truth.compliance.copy()
        bent.compliance[j] += h
        numeric = (MovingArm(bent).points(q, qd, qdd) - p) / h
        np.testing.assert_allclose(J[:, :, COMPLIANCE_SLICE][:, :, j], numeric, rtol=1e-4, atol=1e-9)


def test_a_joint_origins_rz_column_is_the_points_derivative_in_that_joint():
    truth, q, _, _ = _moving_state()
    rigid = truth.rigid()
    _, J = Kinematics(rigid).point_and_jacobian(q)
    h = 1e-7
    for j in range(6):
        dq = np.zeros(6)
        dq[j] = h
        numeric = (Kinematics(rigid).points(q + dq) - Kinematics(rigid).points(q - dq)) / (2 * h)
        np.testing.assert_allclose(J[:, :, 6 * j + 5], numeric, atol=1e-8)
