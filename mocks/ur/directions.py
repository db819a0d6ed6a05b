"""Which way each simulated joint last moved: what a joint's lost motion depends on.

The simulated world must know that direction at every reading: `JointDirections` follows the joint
stream cycle by cycle (`SimArm.tick`), so a move that goes up and comes back down between two
tracker readings leaves the direction of its last leg. The rule is the contract's (docs/design.md,
Contracts: non-geometric errors), kept once in `hil.arm.joint_directions`, which hil's sweep fit
reads the recorded joint stream with.
"""

from __future__ import annotations

from hil.arm.joint_directions import DIRECTION_THRESHOLD, JointDirections

__all__ = ["DIRECTION_THRESHOLD", "JointDirections"]
