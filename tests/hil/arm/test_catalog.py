import numpy as np
import pytest

from hil.arm.catalog import ROBOT_NAMES, get_robot
from hil.errors import InputError, UnknownRobotError


def test_catalog_has_every_supported_arm():
    assert set(ROBOT_NAMES) == {"ur3e", "ur5e", "ur10e", "ur16e", "ur20", "ur30", "ur3", "ur5", "ur10"}


@pytest.mark.parametrize("name,d1,a2,a3,d4,d5,d6", [
    ("ur5e", 0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996),
    ("ur10e", 0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655),
    ("ur5", 0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823),
    ("ur20", 0.2363, -0.862, -0.7287, 0.201, 0.1593, 0.1543),
])
def test_dh_values_match_the_published_table(name, d1, a2, a3, d4, d5, d6):
    dh = get_robot(name).dh
    assert dh.d == (d1, 0.0, 0.0, d4, d5, d6)
    assert dh.a == (0.0, a2, a3, 0.0, 0.0, 0.0)
    assert np.allclose(dh.alpha, [np.pi / 2, 0, 0, np.pi / 2, -np.pi / 2, 0])


def test_lookup_is_case_insensitive_and_rate_follows_series():
    assert get_robot("UR5e").name == "ur5e"
    assert get_robot("ur5e").rate_hz == 500.0
    assert get_robot("UR10").rate_hz == 125.0


def test_unknown_robot_is_an_input_error_listing_the_choices():
    with pytest.raises(UnknownRobotError, match="ur5e") as info:
        get_robot("kuka")
    assert isinstance(info.value, InputError)


def test_limits_mask():
    spec = get_robot("ur5e")
    q = np.zeros((3, 6))
    q[1, 2] = 3.5  # elbow beyond ±π
    q[2, 0] = 6.0
    assert spec.within_limits(q).tolist() == [True, False, True]
    assert spec.within_limits(q, margin=0.5).tolist() == [True, False, False]
