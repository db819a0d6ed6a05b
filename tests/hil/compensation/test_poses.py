"""UR pose vectors, numbers written back exactly, and the options a compensation starts from."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.compensation.poses import CANONICAL_NEAR, format_number, parse_near, parse_tcp, to_se3, to_vector
from hil.errors import InputError


def test_pose_vectors_round_trip() -> None:
    rng = np.random.default_rng(0)
    for _ in range(50):
        axis = rng.normal(size=3)
        v = np.r_[rng.uniform(-1, 1, 3), axis / np.linalg.norm(axis) * rng.uniform(0, math.pi - 1e-6)]
        assert np.allclose(to_vector(to_se3(v)), v, atol=1e-12)


@pytest.mark.parametrize("value", [0.1, -0.0, 1e-5, -3.2e-17, 0.30000000000000004, 123.456, 2.0, -1e-300])
def test_numbers_are_written_exactly_without_exponent(value: float) -> None:
    text = format_number(value)
    assert float(text) == value and "e" not in text.lower()


def test_near_defaults_to_the_canonical_configuration_and_checks_limits() -> None:
    spec = get_robot("ur5e")
    assert np.array_equal(parse_near(None, spec.lower, spec.upper), CANONICAL_NEAR)
    assert parse_near("0,-1.5,1.5,-1.5,-1.5,0", spec.lower, spec.upper)[1] == -1.5
    with pytest.raises(InputError, match=r"^--near: q3 = 4 rad is outside the joint limits"):
        parse_near("0,0,4,0,0,0", spec.lower, spec.upper)
    with pytest.raises(InputError, match=r"^--near: expected six finite numbers"):
        parse_near("0,0,0", spec.lower, spec.upper)


def test_tcp_is_the_flange_unless_given_and_in_metres() -> None:
    assert parse_tcp(None).isIdentity()
    assert np.allclose(parse_tcp("0,0,0.1,0,0,0").translation, [0, 0, 0.1])
    with pytest.raises(InputError, match=r"^--tcp: .* from the flange"):
        parse_tcp("0,0,150,0,0,0")
    with pytest.raises(InputError, match=r"^--tcp: expected six finite numbers"):
        parse_tcp("0,0,nan,0,0,0")
