"""The simulator's kinematics and limits from hil's one kinematic model (hil.arm.catalog/kinematics).

The simulated controller moves, reports ``actual_TCP_pose`` and solves FK/IK with its *own* model: the
nominal DH table plus its factory calibration deltas (`hil.arm.controller_model.ControllerCalibration`,
evaluated by `hil.arm.kinematics.Kinematics`), as a real UR controller does — so it knows neither the
arm's hidden errors nor exactly the nominal arm. `mocks.ur.kin.dh_fk_factory` stays as a standard-DH
fallback for tests that inject their own FK.
"""

from __future__ import annotations

import numpy as np

from hil.arm.catalog import get_robot
from hil.arm.controller_model import ControllerCalibration
from hil.arm.kinematics import Kinematics
from mocks.ur.kin import FkFn


def controller_fk(robot: str, calibration: ControllerCalibration | None = None) -> FkFn:
    """q(6) -> 4x4 flange pose in the controller base frame, from the controller's calibrated model."""
    kin = Kinematics((calibration or ControllerCalibration()).geometry(robot))

    def fk(q: np.ndarray) -> np.ndarray:
        return kin.flange_poses(np.asarray(q, dtype=float))[0]

    return fk


def nominal_fk(robot: str) -> FkFn:
    """q(6) -> 4x4 flange pose from hil's nominal geometry (a controller with zero deltas)."""
    return controller_fk(robot, None)


def limits(robot: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lower, upper, max joint speed) of the robot from hil's catalog."""
    spec = get_robot(robot)
    return spec.lower.copy(), spec.upper.copy(), np.asarray(spec.max_joint_speed, dtype=float).copy()
