"""The planner checks every point of a move the UR driver will check: a path that leaves the keep-in
box only between the planner's own evenly spaced points, at one of the driver's (s = k/7), is refused
by the planner, not mid-campaign by the driver."""

from __future__ import annotations

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.arm.safety import DRIVER_PATH_CHECKS, check_target, path_fractions
from hil.errors import InputError


def test_the_fractions_hold_the_drivers() -> None:
    driver = np.linspace(0.0, 1.0, DRIVER_PATH_CHECKS)
    assert all(np.isclose(path_fractions(16), s).any() for s in driver)
    assert all(np.isclose(path_fractions(16), s).any() for s in np.linspace(0.0, 1.0, 16))


def a_move_peaking_between_the_planners_points(spec, model) -> tuple[np.ndarray, np.ndarray, float]:
    """A seeded move whose SMR x at s = 4/7 exceeds x at every k/15 and at both ends; the bound between."""
    rng = np.random.default_rng(11)
    kin = Kinematics(model)
    own = np.linspace(0.0, 1.0, 16)
    for _ in range(2000):
        start = rng.uniform(-2.0, 2.0, 6)
        q = start + rng.uniform(-1.5, 1.5, 6)
        if np.any(q < spec.lower) or np.any(q > spec.upper):
            continue
        x_own = kin.points(start + own[:, None] * (q - start), frame="base")[:, 0]
        x_driver = kin.points((start + 4 / 7 * (q - start))[None], frame="base")[0, 0]
        if x_driver > x_own.max() + 1e-4:
            return start, q, float((x_driver + x_own.max()) / 2)
    raise AssertionError("no such move among 2000 seeded ones")


def test_a_path_outside_only_at_a_drivers_point_is_refused() -> None:
    spec = get_robot("ur5e")
    model = Geometry.nominal(spec, (0.0, 0.0, 0.045))
    start, q, bound = a_move_peaking_between_the_planners_points(spec, model)
    box = (np.array([-5.0, -5.0, -5.0]), np.array([bound, 5.0, 5.0]))
    with pytest.raises(InputError, match="path to the target"):
        check_target(q, spec, box, model, start=start)
