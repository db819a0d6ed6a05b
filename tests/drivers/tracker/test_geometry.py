"""The polar→Cartesian convention, pinned to absolute directions (not only round trips)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from drivers.tracker.geometry import cartesian_to_polar, polar_to_cartesian


@pytest.mark.parametrize(
    ("hz", "v", "expected"),
    [
        (0.0, math.pi / 2, (0.0, 2.0, 0.0)),  # Hz 0 looks along +y (north)
        (math.pi / 2, math.pi / 2, (2.0, 0.0, 0.0)),  # clockwise seen from above: Hz 90° → +x (east)
        (math.pi, math.pi / 2, (0.0, -2.0, 0.0)),
        (1.0, 0.0, (0.0, 0.0, 2.0)),  # V is the zenith angle: 0 is straight up
        (0.0, math.pi / 4, (0.0, math.sqrt(2), math.sqrt(2))),
    ],
)
def test_convention(hz: float, v: float, expected: tuple[float, float, float]) -> None:
    np.testing.assert_allclose(polar_to_cartesian(hz, v, 2.0), expected, atol=1e-12)


def test_vectorised_shape() -> None:
    assert polar_to_cartesian([0.1, 0.2], [1.0, 1.1], [2.0, 3.0]).shape == (2, 3)


def test_origin_has_no_direction() -> None:
    with pytest.raises(ValueError):
        cartesian_to_polar([0.0, 0.0, 0.0])


coord = st.floats(-20, 20, allow_nan=False)


@given(coord, coord, coord)
def test_round_trip(x: float, y: float, z: float) -> None:
    p = np.array([x, y, z])
    if np.linalg.norm(p) < 1e-3:
        return
    hz, v, d = cartesian_to_polar(p)
    assert 0 <= hz < 2 * math.pi and 0 <= v <= math.pi
    np.testing.assert_allclose(polar_to_cartesian(hz, v, d), p, atol=1e-9)
