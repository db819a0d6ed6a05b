import numpy as np
import pytest

from hil.arm.catalog import ROBOT_NAMES, get_robot
from hil.arm.geometry import MAX_COMPLIANCE, Geometry, pose
from hil.arm.physical import (
    LinkInertia,
    gear_compliance,
    link_inertias,
    rated_payload,
    typical_compliance,
)
from hil.errors import UnknownRobotError

#: Datasheet weight of the whole arm (kg; UR product fact sheets) and ur_description's ``base_mass``
#: (config/<robot>/physical_parameters.yaml, "might be incorrect"): the moving links weigh the
#: difference, give or take.
ARM_WEIGHT = {"ur3e": (11.2, 2.0), "ur5e": (20.6, 4.0), "ur10e": (33.5, 4.0), "ur16e": (33.1, 4.0),
              "ur20": (64.0, 4.0), "ur30": (63.5, 4.0), "ur3": (11.0, 2.0), "ur5": (18.4, 4.0),
              "ur10": (28.9, 4.0)}

#: UR's article "DH Parameters for calculations of kinematics and dynamics" (universal-robots.com):
#: centres of mass in UR's DH frames i (after Rz(θ)·Tz(d)·Tx(a)·Rx(α)), UR5e.
UR5E_DH_FRAME_COM = [(0, -0.02561, 0.00193), (0.2125, 0, 0.11336), (0.15, 0.0, 0.0265),
                     (0, -0.0018, 0.01634), (0, 0.0018, 0.01634), (0, 0, -0.001159)]


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_tables_have_six_positive_links(robot):
    links = link_inertias(robot)
    assert len(links) == 6
    assert all(isinstance(link, LinkInertia) and link.mass > 0 for link in links)
    reach = get_robot(robot).reach
    assert all(len(link.com) == 3 and np.linalg.norm(link.com) < reach for link in links)


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_link_masses_add_up_to_the_datasheet_weight(robot):
    weight, base = ARM_WEIGHT[robot]
    total = sum(link.mass for link in link_inertias(robot))
    assert total < weight
    assert abs(total - (weight - base)) <= 0.2 * (weight - base)


def test_names_are_looked_up_like_the_catalog():
    assert link_inertias("UR5e") == link_inertias("ur5e")
    with pytest.raises(UnknownRobotError):
        link_inertias("ur7")
    with pytest.raises(UnknownRobotError):
        typical_compliance("ur7")


def test_centres_of_mass_are_urs_dh_values_moved_into_hils_joint_frames():
    """Joint frame i = DH frame i · Rx(−αᵢ)·Tx(−aᵢ), so a point p in DH frame i is Tx(aᵢ)·Rx(αᵢ)·p."""
    dh = get_robot("ur5e").dh
    for link, p, a, alpha in zip(link_inertias("ur5e"), UR5E_DH_FRAME_COM, dh.a, dh.alpha, strict=True):
        expected = pose((a, 0, 0), (alpha, 0, 0)).act(np.array(p, float))
        np.testing.assert_allclose(link.com, expected, atol=1e-12)


def test_hil_joint_frames_are_ur_description_link_frames():
    """ur_description config/ur5e/default_kinematics.yaml (commit 2221ec0f): joint origins xyz, rpy."""
    yaml = [((0, 0, 0.1625), (0, 0, 0)), ((0, 0, 0), (1.570796327, 0, 0)), ((-0.425, 0, 0), (0, 0, 0)),
            ((-0.3922, 0, 0.1333), (0, 0, 0)), ((0, -0.0997, -2.044881182297852e-11), (1.570796327, 0, 0)),
            ((0, 0.0996, -2.042830148012698e-11), (1.570796326589793, np.pi, np.pi))]
    g = Geometry.nominal("ur5e")
    for M, (xyz, rpy) in zip(g.joints, yaml, strict=True):
        np.testing.assert_allclose(M.homogeneous, pose(xyz, rpy).homogeneous, atol=1e-9)
    # wrist_3_link -> flange (rpy 0, -π/2, -π/2) -> tool0 (rpy π/2, 0, π/2) is hil's flange
    tool0 = pose((0, 0, 0), (0, -np.pi / 2, -np.pi / 2)) * pose((0, 0, 0), (np.pi / 2, 0, np.pi / 2))
    np.testing.assert_allclose(tool0.homogeneous, g.flange.homogeneous, atol=1e-12)


@pytest.mark.parametrize("robot", ROBOT_NAMES)
def test_rated_payload_and_compliance_are_sane(robot):
    assert 3.0 <= rated_payload(robot) <= 35.0
    c = typical_compliance(robot)
    assert c.shape == (6,)
    assert np.all(c > 0) and np.all(c < MAX_COMPLIANCE)
    assert np.all(c < gear_compliance(robot))
    # a bigger joint is stiffer: the wrists are at least as compliant as the shoulder
    assert np.all(c[3:] >= c[1])
