"""The ISO 9283 test cube: P1 at the centre, P2–P5 on the plane C1-C2-C7-C8 at 10 % of the diagonal
from its corners, and the cycle P1, P5, P4, P3, P2."""

from __future__ import annotations

import numpy as np
import pytest

from hil.errors import InputError
from hil.verify.cube import CYCLE_ORDER, POSE_NAMES, Cube


@pytest.fixture
def cube() -> Cube:
    return Cube(np.array([0.4, -0.1, 0.3]), 0.25)


def test_corners_are_the_cube_with_edges_along_the_base_axes(cube: Cube) -> None:
    c = cube.corners()
    assert np.allclose(c.min(axis=0), cube.centre - 0.125) and np.allclose(c.max(axis=0), cube.centre + 0.125)
    # C1-C2 and C7-C8 are opposite parallel edges (bottom front, top back)
    assert np.allclose(c[1] - c[0], [0.25, 0, 0]) and np.allclose(c[6] - c[7], [0.25, 0, 0])
    assert np.allclose(c[6] - c[2], [0, 0, 0.25])  # C7 above C3


def test_p1_is_the_centre_and_p2_to_p5_are_a_tenth_of_the_diagonal_in_from_c1_c2_c7_c8(cube: Cube) -> None:
    p = dict(zip(POSE_NAMES, cube.poses(), strict=True))
    c = cube.corners()
    L = cube.diagonal
    assert L == pytest.approx(np.sqrt(3) * 0.25) == pytest.approx(np.linalg.norm(c[6] - c[0]))
    assert np.allclose(p["P1"], cube.centre)
    for name, (near, far) in {"P2": (0, 6), "P3": (1, 7), "P4": (6, 0), "P5": (7, 1)}.items():
        assert np.linalg.norm(p[name] - c[near]) == pytest.approx(0.1 * L)  # 10 % of the diagonal
        assert np.linalg.norm(p[name] - c[far]) == pytest.approx(0.9 * L)  # on that diagonal
        assert np.linalg.norm(p[name] - p["P1"]) == pytest.approx(0.4 * L)


def test_every_pose_lies_in_the_measuring_plane(cube: Cube) -> None:
    n = cube.plane_normal()
    c = cube.corners()
    for corner in (0, 1, 6, 7):
        assert abs(n @ (c[corner] - cube.centre)) < 1e-12
    assert np.allclose((cube.poses() - cube.centre) @ n, 0.0, atol=1e-12)
    assert abs(n @ (c[2] - cube.centre)) > 0.1  # C3 is not in it


def test_cycle_and_round_trip(cube: Cube) -> None:
    assert CYCLE_ORDER == ("P1", "P5", "P4", "P3", "P2")
    again = Cube.from_dict(cube.to_dict())
    assert np.allclose(again.poses(), cube.poses())


def test_a_cube_without_a_positive_edge_is_refused() -> None:
    with pytest.raises(InputError, match="edge"):
        Cube(np.zeros(3), 0.0)
