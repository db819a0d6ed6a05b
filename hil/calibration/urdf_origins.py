"""From a calibrated chain placement back to the URDF joint origin that produces it.

The chain hil identifies on (issue 32) is not the URDF's joints as written: pinocchio folds the fixed
joints between two moving joints into the next moving joint's placement, and every joint is turned into
a rotation (or translation) about its own z axis by a constant rotation A that takes z onto the URDF's
`<axis>`. With F the folded fixed joints in front of URDF joint i and O its `<origin>`, the chain's
placement of joint i is

    M_i = A_{i-1}⁻¹ · F_i · O_i · A_i          (A_0 = identity: the base link has no axis)

since the URDF's motion about its axis is A · Rz(q) · A⁻¹. A calibrated M_i is therefore written back as

    O_i = (A_{i-1}⁻¹ · F_i)⁻¹ · M_i · A_i⁻¹ = `joint_origin(fixed_part, M_i, axis_rotation)`

with `fixed_part` = A_{i-1}⁻¹ · F_i, everything else in the file (the fixed joints themselves, the
axis) left as it is. The same form writes a calibrated tip placement into the last fixed joint in front
of the tip (`fixed_part` = A_N⁻¹ · the fixed joints before it, `axis_rotation` = the fixed joints after
it), so no fixed joint has to be added to the user's file.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from hil.calibration.urdf_rewrite import Origin


def origin_placement(origin: Origin) -> pin.SE3:
    """The placement a URDF origin stands for (R = Rz(yaw)·Ry(pitch)·Rx(roll), then xyz)."""
    rotation = pin.rpy.rpyToMatrix(np.asarray(origin.rpy, dtype=float))
    return pin.SE3(rotation, np.asarray(origin.xyz, dtype=float))


def placement_origin(placement: pin.SE3) -> Origin:
    """The URDF origin of `placement` (pinocchio's `matrixToRpy`: pitch in [-π/2, π/2])."""
    xyz = tuple(float(v) for v in placement.translation)
    rpy = tuple(float(v) for v in pin.rpy.matrixToRpy(placement.rotation))
    return Origin(xyz, rpy)  # type: ignore[arg-type]


def joint_origin(fixed_part: pin.SE3, placement: pin.SE3, axis_rotation: pin.SE3) -> pin.SE3:
    """The URDF `<origin>` O with fixed_part · O · axis_rotation = `placement` (module docstring)."""
    return fixed_part.inverse() * placement * axis_rotation.inverse()


def axis_rotation(axis: Sequence[float]) -> pin.SE3:
    """A rotation taking z onto the unit vector `axis`: the smallest one (about z × axis), and for
    axis = −z a half turn about x. Any rotation that does so makes a valid chain; this one is the
    identity for a z axis, so a URDF whose joints all turn about z keeps its placements unchanged."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    z = np.array([0.0, 0.0, 1.0])
    c = float(z @ a)
    if c < -1.0 + 1e-12:
        return pin.SE3(pin.exp3(np.array([np.pi, 0.0, 0.0])), np.zeros(3))
    v = np.cross(z, a)
    s = float(np.linalg.norm(v))
    if s < 1e-15:
        return pin.SE3.Identity()
    return pin.SE3(pin.exp3(v / s * np.arctan2(s, c)), np.zeros(3))
