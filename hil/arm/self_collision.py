"""Does a posture fold the arm onto itself? The selector's link capsules on hil's joint frames.

The capsules (`selector.arm.ArmShape`: their layout, radii and which pairs may not meet) are the ones
the pose selection keeps its candidates apart with, so a transit posture the campaign routes through
is held to the same rule as a measurement pose. Only the joint frames come from here: hil's own
forward kinematics (`hil.arm.kinematics`, pinocchio) of the arm's nominal geometry with its SMR.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from hil.arm.catalog import RobotSpec, get_robot
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from selector.arm import COLLISION_MARGIN, ArmShape

#: The SMR offset (flange frame, m) the tool capsule ends at when the SMR's is unknown or on the
#: flange: a typical 1.5" SMR in its nest, so the capsule still covers what the flange carries.
DEFAULT_SMR: tuple[float, float, float] = (0.0, 0.0, 0.045)


def arm_shape(robot: str | RobotSpec) -> ArmShape:
    """The arm's link capsules: a UR5e's scaled by (|a2| / 0.425)^0.6 (link thickness grows with the
    upper arm's length, less than proportionally)."""
    spec = robot if isinstance(robot, RobotSpec) else get_robot(robot)
    return ArmShape.scaled((abs(spec.dh.a[1]) / 0.425) ** 0.6)


class SelfCollision:
    """The self-collision check of one arm carrying an SMR at `smr` (flange frame, m)."""

    def __init__(self, spec: RobotSpec, smr: Sequence[float] | None = None,
                 margin: float = COLLISION_MARGIN) -> None:
        offset = None if smr is None else np.asarray(smr, dtype=float)
        if offset is None or np.linalg.norm(offset) < 1e-3:
            offset = np.asarray(DEFAULT_SMR)
        self.shape = arm_shape(spec)
        self.margin = margin
        self._smr = offset
        self._kinematics = Kinematics(Geometry.nominal(spec, smr=offset))

    def free(self, q: np.ndarray) -> np.ndarray:
        """(N,) whether each of configurations `q` (N, 6) keeps every non-adjacent pair of links apart."""
        frames = self._kinematics.joint_frames(q)
        smr = np.einsum("nij,j->ni", frames[:, 6, :3, :3], self._smr) + frames[:, 6, :3, 3]
        return self.shape.collision_free(self.shape.segments(frames, smr), self.margin)

    def collides(self, q: np.ndarray) -> bool:
        """Whether any of configurations `q` (N, 6) brings two non-adjacent links together."""
        return not bool(np.all(self.free(q)))
