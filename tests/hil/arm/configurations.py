"""Which of a UR arm's eight configurations a joint vector is in, told independently of hil.arm.branches."""

from __future__ import annotations

import math

import numpy as np

from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics


def _shoulder_offset(robot: str, q: np.ndarray) -> float:
    """q1 − (ψ + π/2), ψ the wrist centre's bearing: ±φ (Hawkins 2013), by the nominal arm's FK."""
    F = Kinematics(Geometry.nominal(robot)).flange_poses(np.asarray(q, float))[0]
    w = F[:3, 3] - get_robot(robot).dh.d[5] * F[:3, 2]
    return float(q[0] - math.atan2(w[1], w[0]) - math.pi / 2)


def configuration(robot: str, q: np.ndarray) -> tuple[int, int, int]:
    """(shoulder, elbow, wrist) signs: joint 1 on either side of the wrist centre's bearing + π/2,
    joint 3 bent either way, joint 5 either way."""
    return (int(np.sign(math.sin(_shoulder_offset(robot, q)))), int(np.sign(math.sin(q[2]))),
            int(np.sign(math.sin(q[4]))))


def away_from_singularities(robot: str, q: np.ndarray, margin: float = 0.3) -> bool:
    """Shoulder, elbow and wrist well clear of their singularities (the sines of φ, q3 and q5 above
    `margin`): the eight configurations are distinct."""
    return min(abs(math.sin(_shoulder_offset(robot, q))), abs(math.sin(q[2])), abs(math.sin(q[4]))) > margin
