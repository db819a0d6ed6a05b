"""The kinematic structure of one serial arm: its joints (each a rotation or a translation along the z
axis of its origin frame), their nominal origins, limits and speeds, and the flange.

Every arm hil models is such a chain: a UR from its catalog DH table (`ur_chain`) or any serial arm from
its URDF (`hil.arm.urdf_chain.chain_from_urdf`, which rotates each joint frame so its axis is z). The
geometry (`hil.arm.geometry`), the kinematics and the identification's parameter layout
(`hil.arm.kinematics`) read the number and the kinds of joints from here, so one code path serves both.

A chain is immutable and compared by `key` (the catalog name for a UR, the URDF's sha256 with base and
tip otherwise), which is what the caches of identifiable sets are keyed on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import pinocchio as pin

from hil.arm.catalog import RobotSpec, get_robot

#: A joint that rotates about the z axis of its origin frame.
REVOLUTE = "RZ"
#: A joint that translates along the z axis of its origin frame.
PRISMATIC = "PZ"


@dataclass(frozen=True, eq=False)
class UrdfJoint:
    """How one actuated joint of a chain maps back onto its URDF joint (the export's terms).

    The chain's origin i is ``A(i−1)ᵀ · fixed · O_urdf · A(i)``: `fixed` the URDF's fixed joints
    folded in before this joint (from the previous actuated joint's child link, or from the base link),
    `O_urdf` the URDF joint's own ``<origin>`` and `A` the rotation taking z onto the joint's URDF axis.
    """

    name: str  # the URDF joint's name
    parent: str  # its parent link
    child: str  # its child link
    fixed: pin.SE3  # the folded fixed joints before it, in the previous joint's URDF child frame
    axis_rotation: np.ndarray  # (3, 3): z → the URDF axis, in the URDF joint frame
    origin: pin.SE3  # the URDF joint's nominal <origin>


@dataclass(frozen=True, eq=False)
class UrdfSource:
    """The URDF a chain was made from: enough to rebuild the chain and to rewrite the file."""

    text: str  # the file, exactly as read
    sha256: str  # of its UTF-8 bytes
    base: str  # the base link (the robot base frame of the model)
    tip: str  # the link the SMR is mounted on (the flange frame)
    file: str  # the name it was read under (for messages only)
    joints: tuple[UrdfJoint, ...]  # one per actuated joint of the chain, base to tip
    tip_fixed: pin.SE3  # the fixed joints from the last actuated joint's child link to the tip link

    def urdf_origins(self, origins: list[pin.SE3]) -> dict[str, pin.SE3]:
        """Each actuated URDF joint's ``<origin>`` that reproduces the chain's joint `origins`
        (calibrated ones: the URDF export writes these, keeping the folded fixed joints as they are).

        Inverts the chain's ``A(i−1)ᵀ · fixed · O_urdf · A(i)``: O_urdf = fixed⁻¹ · A(i−1) · origin · A(i)ᵀ.
        """
        out: dict[str, pin.SE3] = {}
        previous = np.eye(3)
        for joint, origin in zip(self.joints, origins, strict=True):
            before = pin.SE3(previous, np.zeros(3))
            after = pin.SE3(joint.axis_rotation.T, np.zeros(3))
            out[joint.name] = joint.fixed.inverse() * before * origin * after
            previous = joint.axis_rotation
        return out


@dataclass(frozen=True, eq=False)
class Chain:
    """A serial arm's joints from base to tip: kinds (`REVOLUTE`/`PRISMATIC`), names, nominal origins
    (joint i's in joint i−1's moved frame, the first in the base frame), the flange in the last joint's
    frame, position limits (rad or m), speed limits (rad/s or m/s)."""

    name: str
    title: str
    kinds: tuple[str, ...]
    joint_names: tuple[str, ...]
    origins: tuple[pin.SE3, ...] = field(repr=False)
    flange: pin.SE3 = field(repr=False)
    lower: np.ndarray = field(repr=False)
    upper: np.ndarray = field(repr=False)
    velocity: np.ndarray = field(repr=False)
    key: str = ""
    urdf: UrdfSource | None = field(default=None, repr=False)

    @property
    def dof(self) -> int:
        """The number of actuated joints."""
        return len(self.kinds)

    @property
    def is_ur(self) -> bool:
        """Whether this is a catalog UR (the controller's model, compliance, thermal, joint errors and the
        campaign need one)."""
        return self.urdf is None

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Chain) and other.key == self.key

    def __hash__(self) -> int:
        return hash(self.key)

    def within_limits(self, q: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """Boolean mask (per configuration) of joint vectors inside the limits shrunk by `margin`."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        return np.all((q >= self.lower + margin) & (q <= self.upper - margin), axis=1)

    def sampling_range(self) -> tuple[np.ndarray, np.ndarray]:
        """Finite bounds to draw configurations from: the limits, a revolute joint's clipped to ±π (one
        turn reaches every posture; wider limits only repeat them)."""
        lo, hi = self.lower.copy(), self.upper.copy()
        rev = np.array([k == REVOLUTE for k in self.kinds])
        lo[rev] = np.maximum(lo[rev], -math.pi)
        hi[rev] = np.minimum(hi[rev], math.pi)
        return lo, hi


def _pose(xyz: tuple[float, float, float], roll: float = 0.0) -> pin.SE3:
    return pin.SE3(pin.rpy.rpyToMatrix(roll, 0.0, 0.0), np.asarray(xyz, dtype=float))


@lru_cache(maxsize=16)
def _ur_chain(name: str) -> Chain:
    spec = get_robot(name)
    d, a, alpha = spec.dh.d, spec.dh.a, spec.dh.alpha
    # standard DH regrouped so each joint rotates about the z axis of its origin (docs/design.md, Facts:
    # UR nominal DH): origin1 = Tz(d1), origin(i+1) = Tx(ai)·Rx(αi)·Tz(d(i+1)), flange = Tx(a6)·Rx(α6)
    origins = [_pose((0.0, 0.0, d[0]))]
    origins += [_pose((a[i], 0.0, 0.0), alpha[i]) * _pose((0.0, 0.0, d[i + 1])) for i in range(5)]
    flange = _pose((a[5], 0.0, 0.0), alpha[5])
    from hil.arm.catalog import JOINT_NAMES

    return Chain(spec.name, spec.title, (REVOLUTE,) * 6, JOINT_NAMES, tuple(origins), flange,
                 spec.lower.copy(), spec.upper.copy(), spec.max_joint_speed.copy(), key=f"ur:{spec.name}")


def ur_chain(robot: str | RobotSpec) -> Chain:
    """The chain of a catalog UR (six revolute joints, its DH table's origins, its limits and speeds)."""
    return _ur_chain(robot.name if isinstance(robot, RobotSpec) else get_robot(robot).name)


#: What the offline commands accept as "the robot": a catalog name, its spec, or a chain (a URDF's).
Robot = str | RobotSpec | Chain


def chain_of(robot: Robot) -> Chain:
    """The chain of a catalog name, spec or chain (returned as it is)."""
    return robot if isinstance(robot, Chain) else ur_chain(robot)


def robot_name(robot: Robot) -> str:
    """The name a model file and a report give the robot: the catalog name, or the URDF's robot name."""
    if isinstance(robot, Chain):
        return robot.name
    return robot.name if isinstance(robot, RobotSpec) else get_robot(robot).name
