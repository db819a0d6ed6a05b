import numpy as np
import pinocchio as pin
import pytest

from hil.arm.catalog import ROBOT_NAMES
from hil.arm.geometry import Geometry
from hil.arm.gravity import GravityModel, link_angles
from hil.arm.kinematics import Kinematics
from hil.arm.payload import Payload, gravity_of_mounting
from hil.arm.physical import link_inertias, rated_payload, typical_compliance


def independent_torques(geometry: Geometry, q: np.ndarray) -> np.ndarray:
    """τ_j = −Σ_{i ≥ j} ((c_i − o_j) × m_i·g)·z_j with frames from Kinematics (payload on joint 6)."""
    frames = Kinematics(geometry.rigid()).joint_frames(q)
    links = link_inertias(geometry.robot)
    out = np.zeros((len(frames), 6))
    for n, F in enumerate(frames):
        bodies = [(link.mass, F[i, :3, :3] @ np.array(link.com) + F[i, :3, 3], i)
                  for i, link in enumerate(links)]
        if geometry.payload is not None:
            com = F[6, :3, :3] @ np.array(geometry.payload.com) + F[6, :3, 3]
            bodies.append((geometry.payload.mass, com, 5))
        for j in range(6):
            o, z = F[j, :3, 3], F[j, :3, 2]
            out[n, j] = -sum(np.cross(c - o, m * geometry.gravity) @ z for m, c, i in bodies if i >= j)
    return out


def perturbed(robot: str, rng: np.random.Generator) -> Geometry:
    g = Geometry.nominal(robot)
    g.joints = [M * pin.exp6(np.r_[rng.normal(0, 2e-3, 3), rng.normal(0, 5e-3, 3)]) for M in g.joints]
    g.flange = g.flange * pin.exp6(rng.normal(0, 5e-3, 6))
    return g


MOUNTINGS = [(0.0, 0.0, 0.0), (0.4, -0.7, 1.1), (np.pi / 2, 0.0, 0.0), (np.pi, 0.0, 0.0)]  # floor … ceiling


@pytest.mark.parametrize("robot", ROBOT_NAMES)
@pytest.mark.parametrize("mounting", range(len(MOUNTINGS)))
def test_torques_match_an_independent_computation(robot, mounting):
    rng = np.random.default_rng([ROBOT_NAMES.index(robot), mounting])
    g = perturbed(robot, rng).with_payload(Payload(rated_payload(robot), (0.03, -0.05, 0.08)))
    g.gravity = gravity_of_mounting(MOUNTINGS[mounting])
    q = rng.uniform(-np.pi, np.pi, (20, 6))
    got = GravityModel(g).torques(q)
    want = independent_torques(g, q)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())


def test_without_payload_only_the_links_count():
    g = Geometry.nominal("ur5e")
    q = np.random.default_rng(3).uniform(-np.pi, np.pi, (10, 6))
    np.testing.assert_allclose(GravityModel(g).torques(q), independent_torques(g, q), atol=1e-9)
    np.testing.assert_allclose(GravityModel(g.with_payload(Payload(0.0))).torques(q),
                               GravityModel(g).torques(q), atol=1e-12)


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_floor_mounted_joint_1_holds_no_torque(robot):
    g = Geometry.nominal(robot).with_payload(Payload(rated_payload(robot), (0.1, 0.05, 0.1)))
    tau = GravityModel(g).torques(np.random.default_rng(5).uniform(-2 * np.pi, 2 * np.pi, (50, 6)))
    np.testing.assert_allclose(tau[:, 0], 0.0, atol=1e-10)
    assert np.abs(tau[:, 1]).max() > 10.0


def test_one_vector_or_a_batch():
    gm = GravityModel(Geometry.nominal("ur10e"))
    q = np.array([0.1, -1.2, 0.8, -0.3, 1.4, 0.2])
    assert gm.torques(q).shape == (1, 6)
    np.testing.assert_array_equal(gm.torques(q)[0], gm.torques(np.stack([q, q]))[1])
    with pytest.raises(ValueError):
        gm.torques(np.zeros(5))


def test_the_model_keeps_its_own_copy_of_the_geometry():
    g = Geometry.nominal("ur5e")
    gm = GravityModel(g)
    before = gm.torques(np.zeros(6))
    g.payload = Payload(5.0)
    g.gravity = gravity_of_mounting((0.5, 0.0, 0.0))
    np.testing.assert_array_equal(gm.torques(np.zeros(6)), before)


def test_link_angles_of_a_rigid_arm_are_a_copy():
    g = Geometry.nominal("ur5e")
    q = np.array([[0.1, -1.0, 1.0, 0.2, 0.3, 0.4]])
    out = link_angles(g, q)
    np.testing.assert_array_equal(out, q)
    assert out is not q and not np.shares_memory(out, q)
    g.compliance = np.zeros(6)
    np.testing.assert_array_equal(link_angles(g, q[0]), q)


def test_link_angles_lag_by_compliance_times_torque():
    g = Geometry.nominal("ur10e").with_payload(Payload(8.0, (0, 0, 0.1)))
    g.compliance = typical_compliance("ur10e")
    q = np.random.default_rng(9).uniform(-np.pi, np.pi, (15, 6))
    want = q - g.compliance * independent_torques(g, q)
    np.testing.assert_allclose(link_angles(g, q), want, atol=1e-15)
    np.testing.assert_array_equal(link_angles(g, q, GravityModel(g)), link_angles(g, q))


STRETCHED = np.array([0.0, 0.0, 0.0, 0.0, np.pi / 2, 0.0])  # upper arm, forearm horizontal; tool out


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_stretched_arm_with_rated_payload_sags_some_tenths_of_a_millimetre(robot):
    g = Geometry.nominal(robot).with_payload(Payload(rated_payload(robot)))
    g.compliance = typical_compliance(robot)
    kin = Kinematics(g.rigid())
    F = kin.flange_poses(STRETCHED)[0]
    assert abs(F[2, 2]) < 1e-12 and F[:3, 2] @ F[:3, 3] > 0  # flange axis horizontal, pointing out
    sag = kin.flange_poses(link_angles(g, STRETCHED))[0][:3, 3] - F[:3, 3]
    assert 0.1e-3 < np.linalg.norm(sag) < 0.9e-3
    assert sag[2] < 0 and abs(sag[2]) > 0.9 * np.linalg.norm(sag)  # it sags down


@pytest.mark.parametrize("robot", ["ur5e", "ur10e"])
def test_the_sag_is_the_issues_order_of_magnitude(robot):
    """The issue's check on the two arms it names: 0.1–0.9 mm at full reach with the rated payload."""
    g = Geometry.nominal(robot).with_payload(Payload(rated_payload(robot)))
    g.compliance = typical_compliance(robot)
    kin = Kinematics(g.rigid())
    for q in (STRETCHED, STRETCHED + np.array([0, -np.pi, 0, 0, 0, 0])):  # along −x, then +x
        F = kin.flange_poses(q)[0]
        assert abs(F[2, 2]) < 1e-12 and F[:3, 2] @ F[:3, 3] > 0
        d = np.linalg.norm(kin.points(link_angles(g, q), "base", "flange") - kin.points(q, "base", "flange"))
        assert 0.1e-3 < d < 0.9e-3
