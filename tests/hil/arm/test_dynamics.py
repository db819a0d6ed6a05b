"""The moving arm's torques against pinocchio called independently, and the at-rest equality with
`hil.arm.gravity`."""

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.dynamics import DEFAULT_TOLERANCE_RAD, DynamicsModel, moving_link_angles
from hil.arm.geometry import Geometry
from hil.arm.gravity import GravityModel, link_angles
from hil.arm.payload import Payload, gravity_of_mounting
from hil.arm.physical import link_inertias, rated_payload, typical_compliance


def independent_model(g: Geometry) -> pin.Model:
    """A pinocchio model built here from the geometry's joint origins and UR's masses: one body per
    link (sphere inertia of radius 0.05 m, as gravity.py documents), the payload a point mass."""
    model = pin.Model()
    parent = 0
    for i, (origin, link) in enumerate(zip(g.joints, link_inertias(g.robot), strict=True)):
        parent = model.addJoint(parent, pin.JointModelRZ(), origin, f"j{i}")
        body = pin.Inertia(link.mass, np.array(link.com), 0.4 * link.mass * 0.05**2 * np.eye(3))
        model.appendBodyToJoint(parent, body, pin.SE3.Identity())
    if g.payload is not None:
        com = g.flange.translation + g.flange.rotation @ np.array(g.payload.com)
        model.appendBodyToJoint(parent, pin.Inertia(g.payload.mass, com, np.zeros((3, 3))),
                                pin.SE3.Identity())
    model.gravity.linear = np.array(g.gravity, dtype=float)
    return model


def loaded(robot: str, mounting: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Geometry:
    g = Geometry.nominal(robot).with_payload(Payload(rated_payload(robot), (0.02, -0.03, 0.07)))
    g.gravity = gravity_of_mounting(mounting)
    g.compliance = typical_compliance(robot)
    return g


@pytest.mark.parametrize("robot", ["ur5e", "ur10e", "ur3e"])
@pytest.mark.parametrize("mounting", [(0.0, 0.0, 0.0), (0.4, -0.7, 1.1)])
def test_torques_are_pinocchios_rnea(robot, mounting):
    g = loaded(robot, mounting)
    rng = np.random.default_rng(7)
    q, qd, qdd = rng.uniform(-3, 3, (25, 6)), rng.uniform(-2, 2, (25, 6)), rng.uniform(-5, 5, (25, 6))
    model = independent_model(g)
    data = model.createData()
    want = np.array([pin.rnea(model, data, *row) for row in zip(q, qd, qdd, strict=True)])
    got = DynamicsModel(g).torques(q, qd, qdd)
    np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-9)
    # the inertial part is not negligible on these draws: the test would see a gravity-only model
    gravity = GravityModel(g).torques(q)
    assert np.abs(got - gravity).max() > 1.0


def test_at_rest_the_lag_is_gravitys():
    g = loaded("ur5e", (np.pi / 2, 0.0, 0.0))
    q = np.random.default_rng(1).uniform(-np.pi, np.pi, (30, 6))
    dm = DynamicsModel(g)
    np.testing.assert_array_equal(dm.torques(q), GravityModel(g).torques(q))
    np.testing.assert_allclose(moving_link_angles(g, q, np.zeros((30, 6)), np.zeros((30, 6)), dm),
                               link_angles(g, q), rtol=0, atol=1e-15)


def test_moving_lag_is_compliance_times_the_full_torque():
    g = loaded("ur10e")
    rng = np.random.default_rng(2)
    q, qd, qdd = rng.uniform(-3, 3, (5, 6)), rng.uniform(-1, 1, (5, 6)), rng.uniform(-2, 2, (5, 6))
    model = independent_model(g)
    data = model.createData()
    tau = np.array([pin.rnea(model, data, *row) for row in zip(q, qd, qdd, strict=True)])
    np.testing.assert_allclose(moving_link_angles(g, q, qd, qdd), q - g.compliance * tau, atol=1e-14)
    rigid = g.rigid()
    np.testing.assert_array_equal(moving_link_angles(rigid, q, qd, qdd), q)


def test_natural_frequency_and_the_trusted_acceleration():
    g = loaded("ur5e")
    dm = DynamicsModel(g)
    q = np.random.default_rng(4).uniform(-3, 3, (8, 6))
    model = independent_model(g)
    data = model.createData()
    M = np.array([np.diag(pin.crba(model, data, qn)) for qn in q])
    np.testing.assert_allclose(dm.inertia_diagonal(q), M, rtol=1e-12)
    wn = dm.natural_frequencies(q)
    np.testing.assert_allclose(wn, 1.0 / np.sqrt(g.compliance * M), rtol=1e-12)
    limit = dm.acceleration_limit(q)
    np.testing.assert_allclose(limit, wn**2 * DEFAULT_TOLERANCE_RAD, rtol=1e-12)
    # the ring a step of that size excites is the quasi-static deflection change c·M·Δq̈ = tolerance
    np.testing.assert_allclose(g.compliance * M * limit, DEFAULT_TOLERANCE_RAD, rtol=1e-12)
    # the docstring's figures: a stretched-out UR5e with its rated payload
    plain = Geometry.nominal("ur5e").with_payload(Payload(rated_payload("ur5e")))
    plain.compliance = typical_compliance("ur5e")
    stretched = DynamicsModel(plain).acceleration_limit(np.zeros(6))[0]
    assert 0.5 < stretched[0] < 0.7 and 0.5 < stretched[1] < 0.7 and 7 < stretched[3] < 11


def test_rigid_joints_have_no_limit_and_bad_shapes_are_refused():
    dm = DynamicsModel(Geometry.nominal("ur5e"))
    assert np.isinf(dm.acceleration_limit(np.zeros(6))).all()
    with pytest.raises(ValueError, match="qd"):
        dm.torques(np.zeros((2, 6)), np.zeros((3, 6)))
    with pytest.raises(ValueError, match="tolerance"):
        dm.acceleration_limit(np.zeros(6), 0.0)


def test_a_moving_arm_at_rest_is_the_kinematics_prediction():
    from hil.arm.dynamics import MovingArm
    from hil.arm.kinematics import Kinematics
    from hil.calibration.synthetic import random_truth

    truth = random_truth("ur5e", np.random.default_rng(5), ideal=False)
    q = np.random.default_rng(6).uniform(-2, 2, (12, 6))
    arm = MovingArm(truth)
    np.testing.assert_allclose(arm.points(q), Kinematics(truth).points(q), atol=1e-12)
    qdd = np.full((12, 6), 3.0)
    moved = arm.points(q, np.zeros((12, 6)), qdd)
    assert 1e-7 < np.linalg.norm(moved - arm.points(q), axis=1).max() < 1e-3  # micrometres, not more
