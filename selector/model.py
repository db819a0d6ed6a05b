"""What the selector needs from a kinematic model (it never imports hil's; it receives one).

``hil.calibration.selection.SelectionModel`` is the implementation the product uses; tests may pass
any object with these attributes.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from selector.arm import ArmShape, ChainShape


class PoseModel(Protocol):
    """Batched kinematics of one arm + SMR + tracker, restricted to the identifiable parameters."""

    #: Joint limits (rad, or m for a prismatic joint) and the per-joint maximum speeds, each (n,): six
    #: for a UR, any number for an arm from its URDF.
    lower: np.ndarray
    upper: np.ndarray
    max_joint_speed: np.ndarray
    #: SMR centre in the flange frame (m).
    smr: np.ndarray
    #: Names of the identified parameters (the Jacobian's columns) and their expected error sizes.
    parameter_names: Sequence[str]
    parameter_scale: np.ndarray
    #: Capsule model of the arm's links (`ChainShape` for an arm that is not a UR).
    arm: ArmShape | ChainShape
    #: Optional, for an arm that is not a UR: ``collides(q) -> (N,) bool``, its own self-collision check
    #: (a URDF's collision meshes) used instead of the capsules'; ``aim_joint``, the joint
    #: `selector.candidates.aim_wrist` turns to face the SMR to the tracker (None: none; default 4).

    def frames(self, q: np.ndarray) -> np.ndarray:
        """(N, n + 1, 4, 4): the n joint frames after their motion and the flange (last), robot base
        frame (n = 6 on a UR)."""
        ...

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """(N, 3, n): identification Jacobian of the SMR position w.r.t. the identified parameters."""
        ...
