"""The compliant arm in the calibration model: sag in every prediction, its columns, identifiability."""

import numpy as np
import pinocchio as pin
import pytest

from hil.arm.geometry import Geometry
from hil.arm.gravity import GravityModel
from hil.arm.kinematics import (
    ALL_PARAMETER_NAMES,
    COMPLIANCE_SLICE,
    N_ALL_PARAMETERS,
    N_PARAMETERS,
    Kinematics,
    apply_update,
    deviation_from,
    generic_geometry,
    identifiable_parameters,
    identifiable_with_compliance,
)
from hil.arm.payload import Payload, gravity_of_mounting
from hil.arm.physical import typical_compliance

OFF_AXIS = Payload(3.0, (0.02, -0.01, 0.05))


def compliant(robot="ur5e", payload=OFF_AXIS, rng=None):
    g = generic_geometry(robot)
    if rng is not None:
        g = apply_update(g, rng.normal(0, 1e-3, N_PARAMETERS))
    g.payload = payload
    g.compliance = typical_compliance(robot) * np.array([1.0, 1.1, 0.9, 1.2, 0.8, 1.05])
    return g


def test_predictions_sag_by_compliance_times_gravity_torque(rng):
    g = compliant(rng=rng)
    Q = rng.uniform(-np.pi, np.pi, (8, 6))
    rigid = Kinematics(g.rigid())
    links = Q - g.compliance * GravityModel(g).torques(Q)
    assert np.allclose(Kinematics(g).points(Q), rigid.points(links), atol=1e-12)
    assert np.allclose(Kinematics(g).flange_poses(Q), rigid.flange_poses(links), atol=1e-12)
    sag = np.linalg.norm(Kinematics(g).points(Q) - rigid.points(Q), axis=1)
    assert sag.max() > 20e-6  # a 3 kg payload on a UR5e: tens of micrometres at least somewhere


def test_no_payload_means_the_arm_still_sags_under_its_own_weight(rng):
    g = compliant(payload=None)
    Q = rng.uniform(-np.pi, np.pi, (4, 6))
    assert np.linalg.norm(Kinematics(g).points(Q) - Kinematics(g.rigid()).points(Q), axis=1).max() > 5e-6


def test_compliance_columns_agree_with_finite_differences(rng):
    g = compliant(rng=rng)
    Q = rng.uniform(-np.pi, np.pi, (6, 6))
    p, J = Kinematics(g).point_and_jacobian(Q, compliance=True)
    assert J.shape == (6, 3, N_ALL_PARAMETERS)
    assert np.allclose(p, Kinematics(g).points(Q), atol=1e-12)
    h = 1e-8
    scale = np.abs(J[:, :, COMPLIANCE_SLICE]).max()  # m per rad/Nm: tens of metres on a UR5e
    for i in range(N_PARAMETERS, N_ALL_PARAMETERS):
        step = np.zeros(N_ALL_PARAMETERS)
        step[i] = h
        fd = (Kinematics(apply_update(g, step)).points(Q)
              - Kinematics(apply_update(g, -step)).points(Q)) / (2 * h)
        assert np.abs(fd - J[:, :, i]).max() <= 1e-7 * scale, ALL_PARAMETER_NAMES[i]
    # the geometry columns keep their meaning on a compliant arm (the torques' own change with the
    # small placement errors is second order: 1e-3 of a column at most)
    for i in (8, 20, 33, 43, 47):
        step = np.zeros(N_ALL_PARAMETERS)
        step[i] = 1e-7
        fd = (Kinematics(apply_update(g, step)).points(Q)
              - Kinematics(apply_update(g, -step)).points(Q)) / 2e-7
        assert np.abs(fd - J[:, :, i]).max() <= 1e-3 * np.abs(J[:, :, i]).max(), ALL_PARAMETER_NAMES[i]


def test_the_geometric_jacobian_is_unchanged_without_compliance(rng):
    g = generic_geometry("ur10e")
    Q = rng.uniform(-np.pi, np.pi, (3, 6))
    _, J51 = Kinematics(g).point_and_jacobian(Q)
    _, J57 = Kinematics(g).point_and_jacobian(Q, compliance=True)
    assert J51.shape[2] == N_PARAMETERS
    assert np.array_equal(J51, J57[:, :, :N_PARAMETERS])


def test_update_and_deviation_carry_the_compliance(rng):
    g0 = compliant()
    delta = np.r_[rng.normal(0, 1e-3, N_PARAMETERS), rng.normal(0, 1e-6, 6)]
    g1 = apply_update(g0, delta)
    assert np.allclose(g1.compliance, g0.compliance + delta[COMPLIANCE_SLICE])
    assert np.allclose(deviation_from(g0, g1, compliance=True), delta, atol=1e-12)
    assert deviation_from(g0, g1).shape == (N_PARAMETERS,)


def names(idx):
    return [ALL_PARAMETER_NAMES[i] for i in idx if i >= N_PARAMETERS]


def test_floor_arm_with_an_on_axis_payload_identifies_joints_2_to_5():
    """Joint 1's axis is vertical (no torque), joint 6 holds none when the payload sits on its axis."""
    idx = identifiable_with_compliance("ur5e", Payload(3.0, (0.0, 0.0, 0.05)))
    assert names(idx) == [f"compliance.j{i}" for i in (2, 3, 4, 5)]
    assert np.array_equal(idx[idx < N_PARAMETERS], identifiable_parameters("ur5e"))


def test_an_off_axis_payload_makes_joint_6_identifiable():
    idx = identifiable_with_compliance("ur10e", Payload(10.0, (0.08, 0.0, 0.05)))
    assert "compliance.j6" in names(idx)
    assert "compliance.j1" not in names(idx)


def test_a_wall_mounted_arm_loads_joint_1():
    wall = gravity_of_mounting((0, np.pi / 2, 0))
    idx = identifiable_with_compliance("ur5e", Payload(3.0, (0.0, 0.0, 0.05)), wall)
    assert "compliance.j1" in names(idx)


@pytest.mark.parametrize("robot", ["ur3e", "ur20"])
def test_the_set_is_found_for_every_arm(robot):
    assert len(identifiable_with_compliance(robot)) >= 27 + 3


def test_geometry_round_trip_with_the_non_geometric_blocks():
    g = compliant()
    g.gravity = gravity_of_mounting((np.pi, 0.0, 0.0))
    back = Geometry.from_dict(g.to_dict())
    assert np.allclose(back.compliance, g.compliance)
    assert back.payload == g.payload
    assert np.allclose(back.gravity, g.gravity)
    assert "gravity" not in Geometry.nominal("ur5e").to_dict()
    assert "compliance" not in g.rigid().to_dict()


def test_ik_of_a_compliant_model_gives_encoder_angles_whose_sagging_arm_reaches_the_target(rng):
    from hil.arm.ik import solve_ik

    g = compliant(rng=rng)
    kin = Kinematics(g)
    q0 = np.array([0.3, -1.2, 1.4, -0.8, 1.2, 0.4])
    target = pin.SE3(kin.flange_poses(q0)[0])
    q = solve_ik(kin, target, q0 + 0.05, tolerance=1e-12)
    assert np.abs(q - q0).max() < 1e-9
    rigid = solve_ik(Kinematics(g.rigid()), target, q0 + 0.05, tolerance=1e-12)
    assert np.abs(rigid - q0).max() > 1e-5  # the rigid answer misses the sag


def test_compensation_with_a_compliant_model_puts_the_sagging_arm_on_target(rng):
    from hil.compensation.solve import Compensator

    accurate = compliant(rng=rng)
    controller = Geometry.nominal("ur5e")
    comp = Compensator(accurate, controller)
    q0 = np.array([-0.4, -1.6, 1.2, -1.1, -1.4, 0.7])
    target = pin.SE3(Kinematics(controller).flange_poses(q0)[0])
    out = comp.solve(target, q0)
    reached = Kinematics(accurate).flange_poses(out.q)[0]
    assert np.linalg.norm(reached[:3, 3] - target.translation) < 1e-9
