"""What the selector needs from a kinematic model (it never imports hil's; it receives one).

``hil.calibration.selection.SelectionModel`` is the implementation the product uses; tests may pass
any object with these attributes.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from selector.arm import ArmShape


class PoseModel(Protocol):
    """Batched kinematics of one arm + SMR + tracker, restricted to the identifiable parameters."""

    #: Joint limits (rad) and the per-joint maximum speeds (rad/s), each (6,).
    lower: np.ndarray
    upper: np.ndarray
    max_joint_speed: np.ndarray
    #: SMR centre in the flange frame (m).
    smr: np.ndarray
    #: Names of the identified parameters (the Jacobian's columns) and their expected error sizes.
    parameter_names: Sequence[str]
    parameter_scale: np.ndarray
    #: Capsule model of the arm's links.
    arm: ArmShape

    def frames(self, q: np.ndarray) -> np.ndarray:
        """(N, 7, 4, 4): the six joint frames after rotation and the flange, robot base frame."""
        ...

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """(N, 3, n): identification Jacobian of the SMR position w.r.t. the identified parameters."""
        ...
