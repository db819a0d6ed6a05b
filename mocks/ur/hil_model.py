"""The simulator's nominal kinematics and limits from hil's one kinematic model (hil.arm.catalog/kinematics).

`SimConfig.fk_factory` defaults to `nominal_fk`, so the simulated controller reports ``actual_TCP_pose``
with exactly the model the rest of the product uses; `mocks.ur.kin.dh_fk_factory` stays as a fallback.
"""

from __future__ import annotations

import numpy as np

from hil.arm.catalog import get_robot
from hil.arm.kinematics import Geometry, Kinematics
from mocks.ur.kin import FkFn


def nominal_fk(robot: str) -> FkFn:
    """q(6) -> 4x4 flange pose in the controller base frame, from hil's nominal geometry."""
    kin = Kinematics(Geometry.nominal(robot))

    def fk(q: np.ndarray) -> np.ndarray:
        return kin.flange_poses(np.asarray(q, dtype=float))[0]

    return fk


def limits(robot: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lower, upper, max joint speed) of the robot from hil's catalog."""
    spec = get_robot(robot)
    return spec.lower.copy(), spec.upper.copy(), np.asarray(spec.max_joint_speed, dtype=float).copy()
