"""The calibration geometry of one arm + SMR + tracker, and its JSON "geometry block".

A `Geometry` is what identification estimates and every other part evaluates: the joint origins (six for
a UR; any number for an arm from its URDF, whose `hil.arm.chain.Chain` the geometry carries) in the
URDF convention (joint i rotates about the z axis of its origin frame, joint 1's origin in the robot base
frame, joint i's in joint i-1's rotated frame), the flange frame in joint 6's frame, the SMR centre in
the flange frame and the tracker frame in the robot base frame. The JSON block is the contract shared by
model files (``hil-model/1``) and simulator truths (``hil-truth/1``); see
docs/design.md, Contracts: geometry JSON.

Orientations in files are URDF ``rpy``: R = Rz(yaw)·Ry(pitch)·Rx(roll), which is pinocchio's
``rpyToMatrix`` convention.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from hil.arm.catalog import RobotSpec, get_robot
from hil.arm.chain import Chain, Robot, ur_chain
from hil.arm.joint_errors import JointErrors, block_of
from hil.arm.payload import FLOOR_GRAVITY, Payload, parse_gravity
from hil.arm.thermal import Thermal
from hil.arm.urdf_chain import chain_from_text
from hil.errors import InputError
from hil.files.quantities import quantity, real

#: Largest joint compliance a file may give (rad/Nm): the "joint compliance" row of `hil.files.quantities`.
MAX_COMPLIANCE = quantity("joint compliance").high


def pose(xyz: Sequence[float], rpy: Sequence[float] = (0.0, 0.0, 0.0)) -> pin.SE3:
    """SE(3) from URDF-style translation (m) and roll-pitch-yaw (rad)."""
    return pin.SE3(pin.rpy.rpyToMatrix(*map(float, rpy)), np.asarray(xyz, dtype=float))


def pose_to_dict(M: pin.SE3) -> dict[str, list[float]]:
    """URDF-style ``{"xyz": [...], "rpy": [...]}`` of a pose, at full float precision."""
    return {"xyz": [float(v) for v in M.translation],
            "rpy": [float(v) for v in pin.rpy.matrixToRpy(M.rotation)]}


def _dh_origin(a: float, alpha: float, d_next: float) -> pin.SE3:
    """Tx(a)·Rx(α)·Tz(d_next): the fixed part of the DH chain between two joint rotations."""
    return pose((a, 0.0, 0.0), (alpha, 0.0, 0.0)) * pose((0.0, 0.0, d_next))


@dataclass
class Geometry:
    """Joint origins, flange, SMR offset and tracker pose of one arm (metres, radians).

    The optional non-geometric blocks (docs/design.md, Contracts: non-geometric errors): `compliance`
    (rad/Nm per joint; None is a rigid
    arm), the `payload` it carries (None: nothing), `gravity` in the base frame (the mounting) and, in
    a simulator's truth only, `thermal` growth; the angle-dependent `joint_errors` and the joints'
    `lost_motion` (rad; `hil.arm.joint_errors`). `Kinematics` applies them all to the encoder angles.

    The measured tool, when a fit of 6-D or several-reflector measurements identified it
    (`hil.arm.tool_frame`): `tool_rotation`, the measured frame's orientation in the flange frame (its
    origin is `smr`), and `reflectors`, every reflector's centre in the flange frame (row 0 is `smr`).
    None: a single SMR, whose orientation nothing measures.
    """

    robot: str
    joints: list[pin.SE3]
    flange: pin.SE3
    smr: np.ndarray
    tracker: pin.SE3 = field(default_factory=pin.SE3.Identity)
    compliance: np.ndarray | None = None
    payload: Payload | None = None
    gravity: np.ndarray = field(default_factory=lambda: FLOOR_GRAVITY.copy())
    thermal: Thermal | None = None
    joint_errors: JointErrors | None = None
    lost_motion: np.ndarray | None = None
    tool_rotation: np.ndarray | None = None  # (3, 3) measured frame -> flange frame
    reflectors: np.ndarray | None = None  # (R, 3) m, flange frame; reflectors[0] == smr
    #: the arm's chain when it is not a catalog UR (from its URDF); None: the UR named by `robot`
    chain: Chain | None = None

    def __post_init__(self) -> None:
        if self.chain is not None and self.chain.is_ur:
            self.chain = None  # a UR is known by its name: one representation, as its files have
        if self.chain is None and len(self.joints) != 6:
            raise InputError(f"a UR geometry has 6 joint origins, got {len(self.joints)}")
        if self.chain is not None and len(self.joints) != self.chain.dof:
            raise InputError(f"the {self.chain.name} geometry has {self.chain.dof} joint origins, got "
                             f"{len(self.joints)}")
        self.joints = [pin.SE3(M) for M in self.joints]
        self.flange = pin.SE3(self.flange)
        self.tracker = pin.SE3(self.tracker)
        self.smr = np.array(self.smr, dtype=float).reshape(3)
        if self.compliance is not None:
            self.compliance = np.array(self.compliance, dtype=float).reshape(6)
        self.gravity = np.array(self.gravity, dtype=float).reshape(3)
        if self.lost_motion is not None:
            self.lost_motion = np.array(self.lost_motion, dtype=float).reshape(6)
        if self.tool_rotation is not None:
            self.tool_rotation = np.array(self.tool_rotation, dtype=float).reshape(3, 3)
        if self.reflectors is not None:
            self.reflectors = np.array(self.reflectors, dtype=float).reshape(-1, 3)
            self.reflectors[0] = self.smr

    @property
    def compliant(self) -> bool:
        """Whether the arm sags under gravity (a compliance block with a non-zero value)."""
        return self.compliance is not None and bool(np.any(self.compliance != 0.0))

    @property
    def has_joint_errors(self) -> bool:
        """Whether the link angles carry angle-dependent errors (a non-empty `joint_errors`)."""
        return self.joint_errors is not None and not self.joint_errors.empty

    @property
    def has_lost_motion(self) -> bool:
        """Whether the links lag their encoders in the direction of the last motion."""
        return self.lost_motion is not None and bool(np.any(self.lost_motion != 0.0))

    @property
    def encoder_exact(self) -> bool:
        """Whether the link angles equal the encoder readings (no sag, joint errors or lost motion)."""
        return not (self.compliant or self.has_joint_errors or self.has_lost_motion)

    @property
    def spec(self) -> RobotSpec:
        """The catalog entry of a UR (UnknownRobotError for an arm from a URDF: what needs it is UR-only)."""
        return get_robot(self.robot)

    @property
    def arm(self) -> Chain:
        """The arm's kinematic structure: its URDF chain, or the catalog UR's."""
        return ur_chain(self.robot) if self.chain is None else self.chain

    @property
    def identity(self) -> Robot:
        """What names the robot to the identification: the catalog name of a UR, else the chain."""
        return self.robot if self.chain is None else self.chain

    @classmethod
    def nominal(cls, robot: Robot, smr: Sequence[float] = (0.0, 0.0, 0.0),
                tracker: pin.SE3 | None = None) -> Geometry:
        """The nominal geometry from the catalog DH table.

        Standard DH T = Π Rz(qi)·Tz(di)·Tx(ai)·Rx(αi) regrouped so each joint rotates about the z axis
        of its origin: origin1 = Tz(d1), origin(i+1) = Tx(ai)·Rx(αi)·Tz(d(i+1)), flange = Tx(a6)·Rx(α6).
        This is exactly ``ur_description``'s layout, and the flange is the controller's tool0 frame.
        An arm from a URDF (a `Chain`) takes its chain's nominal origins and flange.
        """
        if isinstance(robot, Chain) and not robot.is_ur:
            return cls(robot.name, list(robot.origins), robot.flange, np.asarray(smr, float),
                       pin.SE3.Identity() if tracker is None else tracker, chain=robot)
        if isinstance(robot, Chain):
            robot = robot.name
        spec = robot if isinstance(robot, RobotSpec) else get_robot(robot)
        d, a, alpha = spec.dh.d, spec.dh.a, spec.dh.alpha
        joints = [pose((0.0, 0.0, d[0]))]
        joints += [_dh_origin(a[i], alpha[i], d[i + 1]) for i in range(5)]
        flange = _dh_origin(a[5], alpha[5], 0.0)
        return cls(spec.name, joints, flange, np.asarray(smr, float),
                   pin.SE3.Identity() if tracker is None else tracker)

    def copy(self) -> Geometry:
        return Geometry(self.robot, list(self.joints), self.flange, self.smr.copy(), self.tracker,
                        None if self.compliance is None else self.compliance.copy(), self.payload,
                        self.gravity.copy(), self.thermal, self.joint_errors,
                        None if self.lost_motion is None else self.lost_motion.copy(),
                        None if self.tool_rotation is None else self.tool_rotation.copy(),
                        None if self.reflectors is None else self.reflectors.copy(), self.chain)

    def ideal(self) -> Geometry:
        """The same arm without angle-dependent joint errors and lost motion (hil's arm before they were
        modelled: geometry, compliance, payload and warm-up only)."""
        out = self.copy()
        out.joint_errors, out.lost_motion = None, None
        return out

    def rigid(self) -> Geometry:
        """The same arm without its non-geometric blocks (what URDF and ROS YAML can hold)."""
        return Geometry(self.robot, list(self.joints), self.flange, self.smr.copy(), self.tracker,
                        chain=self.chain)

    def with_payload(self, payload: Payload | None) -> Geometry:
        """The same arm carrying another payload (a model predicts for the payload it is told of)."""
        out = self.copy()
        out.payload = payload
        return out

    def warmed(self, t: float) -> Geometry:
        """The arm after `t` seconds of running: link translations grown by its `thermal` block.

        Every joint origin's and the flange's translation is scaled by 1 + expansion·ΔT(t); the SMR
        offset and the tracker pose do not grow (docs/design.md, Contracts: non-geometric errors).
        Without a thermal block: unchanged.
        """
        return self.grown(None if self.thermal is None else self.thermal.rise_at(t))

    def grown(self, rise: float | None) -> Geometry:
        """The arm at a temperature rise of `rise` K (as `warmed`, for an arm that did not run all the
        time: the simulator's `mocks.heating`). None or no thermal block: unchanged."""
        out = self.copy()
        if self.thermal is None or rise is None:
            return out
        k = self.thermal.scale_of(rise)
        out.joints = [pin.SE3(M.rotation, k * M.translation) for M in self.joints]
        out.flange = pin.SE3(self.flange.rotation, k * self.flange.translation)
        return out

    # --- the JSON geometry block -------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        """The geometry block shared by model and truth files."""
        return {
            "robot": self.robot,
            "joints": [pose_to_dict(M) for M in self.joints],
            "flange": pose_to_dict(self.flange),
            "smr": [float(v) for v in self.smr],
            "tracker": pose_to_dict(self.tracker),
            **self.urdf_dict(),
            **self.tool_dict(),
            **self.non_geometric_dict(),
        }

    def urdf_dict(self) -> dict[str, Any]:
        """An arm from a URDF: the ``urdf`` block (the file's name, sha256, base and tip links and its
        whole text, so a model needs nothing else; docs/design.md, Contracts: geometry JSON). A UR: none."""
        if self.chain is None or self.chain.urdf is None:
            return {}
        u = self.chain.urdf
        return {"urdf": {"file": u.file, "sha256": u.sha256, "base": u.base, "tip": u.tip,
                         "joints": list(self.chain.joint_names), "text": u.text}}

    def urdf_origins(self) -> dict[str, pin.SE3]:
        """This geometry's joint origins as the URDF's joint ``<origin>`` elements (joint name → pose in
        its parent link's frame), the hook the URDF export writes from. InputError for a UR."""
        if self.chain is None or self.chain.urdf is None:
            raise InputError(f"the {self.robot} model was not made from a URDF")
        return self.chain.urdf.urdf_origins(self.joints)

    def tool_dict(self) -> dict[str, Any]:
        """The measured tool's optional keys: ``tool_rpy`` (the measured frame's orientation in the
        flange frame, URDF rpy; its origin is ``smr``) and ``reflectors`` (every reflector's centre in
        the flange frame, the first equal to ``smr``)."""
        out: dict[str, Any] = {}
        if self.tool_rotation is not None:
            out["tool_rpy"] = [float(v) for v in pin.rpy.matrixToRpy(self.tool_rotation)]
        if self.reflectors is not None:
            out["reflectors"] = [[float(v) for v in row] for row in self.reflectors]
        return out

    def non_geometric_dict(self) -> dict[str, Any]:
        """The optional blocks this arm has (compliance, payload, gravity when not floor, thermal, joint
        errors, lost motion)."""
        out: dict[str, Any] = {}
        if self.compliance is not None:
            out["compliance"] = [float(v) for v in self.compliance]
        if self.payload is not None:
            out["payload"] = self.payload.to_dict()
        if not np.allclose(self.gravity, FLOOR_GRAVITY, rtol=0.0, atol=1e-12):
            out["gravity"] = [float(v) for v in self.gravity]
        if self.thermal is not None:
            out["thermal"] = self.thermal.to_dict()
        if self.joint_errors is not None:
            out["joint_errors"] = self.joint_errors.to_list()
        if self.lost_motion is not None:
            out["lost_motion"] = [float(v) for v in self.lost_motion]
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "geometry") -> Geometry:
        """Parse a geometry block; a missing or malformed key raises InputError naming it."""
        if not isinstance(data, Mapping):
            raise InputError(f"{source}: expected a JSON object")
        robot = _require(data, "robot", source)
        if not isinstance(robot, str):
            raise InputError(f"{source}: field 'robot' must be a robot name")
        chain = _urdf_chain(data["urdf"], source) if data.get("urdf") is not None else None
        spec = get_robot(robot) if chain is None else None
        name = spec.name if spec is not None else robot
        dof = 6 if chain is None else chain.dof
        joints = _require(data, "joints", source)
        if not isinstance(joints, list) or len(joints) != dof:
            raise InputError(f"{source}: field 'joints' must be a list of {dof} origins")
        parsed = [_pose_field(j, f"joints[{i}]", source) for i, j in enumerate(joints)]
        flange = _pose_field(_require(data, "flange", source), "flange", source)
        smr = _vector(_require(data, "smr", source), "smr", source)
        tracker = _pose_field(_require(data, "tracker", source), "tracker", source)
        compliance = None
        if data.get("compliance") is not None:
            compliance = _vector(data["compliance"], "compliance", source, 6)
            for j, c in enumerate(compliance):
                quantity("joint compliance").check(float(c), f"{source}: field 'compliance'[{j}]")
        payload = (Payload.from_dict(data["payload"], f"{source}: payload")
                   if data.get("payload") is not None else None)
        gravity = (parse_gravity(data["gravity"], f"{source}: gravity")
                   if data.get("gravity") is not None else FLOOR_GRAVITY.copy())
        thermal = (Thermal.from_dict(data["thermal"], f"{source}: thermal")
                   if data.get("thermal") is not None else None)
        joint_errors, lost_motion = block_of(data, source)
        tool_rotation = None
        if data.get("tool_rpy") is not None:
            tool_rotation = pin.rpy.rpyToMatrix(*_vector(data["tool_rpy"], "tool_rpy", source))
        reflectors = None
        if data.get("reflectors") is not None:
            rows = data["reflectors"]
            if not isinstance(rows, list) or not rows:
                raise InputError(f"{source}: field 'reflectors' must be a non-empty list of [x, y, z]")
            reflectors = np.array([_vector(r, f"reflectors[{k}]", source) for k, r in enumerate(rows)])
            if not np.allclose(reflectors[0], smr, rtol=0.0, atol=1e-9):
                raise InputError(f"{source}: field 'reflectors[0]' must equal 'smr' (the first reflector "
                                 "is the SMR)")
        if chain is not None and (compliance is not None or thermal is not None or joint_errors is not None
                                  or lost_motion is not None):
            raise InputError(f"{source}: compliance, thermal growth and joint errors are modelled for "
                             "Universal Robots arms only, not for an arm from its URDF")
        return cls(name, parsed, flange, smr, tracker, compliance, payload, gravity, thermal,
                   joint_errors, lost_motion, tool_rotation, reflectors, chain)


def _urdf_chain(block: Any, source: str) -> Chain:
    """The chain a model's ``urdf`` block names: its text parsed again between its base and tip, the
    text's sha256 checked against the block's (a file edited by hand is refused, not trusted)."""
    if not isinstance(block, Mapping):
        raise InputError(f"{source}: field 'urdf' must be an object with file, sha256, base, tip, text")
    fields = {}
    for key in ("file", "sha256", "base", "tip", "text"):
        value = _require(block, key, f"{source}: urdf")
        if not isinstance(value, str):
            raise InputError(f"{source}: field 'urdf.{key}' must be a string")
        fields[key] = value
    if hashlib.sha256(fields["text"].encode("utf-8")).hexdigest() != fields["sha256"]:
        raise InputError(f"{source}: field 'urdf.text' does not match 'urdf.sha256' (the URDF was changed)")
    return chain_from_text(fields["text"], fields["base"], fields["tip"],
                           f"{source}: urdf ({fields['file']})", fields["file"])


def _require(data: Mapping[str, Any], key: str, source: str) -> Any:
    if key not in data:
        raise InputError(f"{source}: missing field '{key}'")
    return data[key]


def _vector(value: Any, name: str, source: str, n: int = 3) -> np.ndarray:
    if not isinstance(value, list | tuple) or len(value) != n:
        raise InputError(f"{source}: field '{name}' must be a list of {n} numbers")
    try:
        out = np.array([float(v) for v in value])
    except (TypeError, ValueError):
        raise InputError(f"{source}: field '{name}' must be a list of {n} numbers") from None
    if not np.all(np.isfinite(out)):
        raise InputError(f"{source}: field '{name}' has a non-finite value")
    for i, v in enumerate(out):
        real(float(v), f"{source}: field '{name}'[{i}]")  # a denormal is no physical value either
    return out


def _pose_field(value: Any, name: str, source: str) -> pin.SE3:
    if not isinstance(value, Mapping):
        raise InputError(f"{source}: field '{name}' must be an object with 'xyz' and 'rpy'")
    xyz = _vector(_require(value, "xyz", f"{source}: {name}"), f"{name}.xyz", source)
    rpy = _vector(_require(value, "rpy", f"{source}: {name}"), f"{name}.rpy", source)
    return pose(xyz, rpy)


def parse_triplet(text: str, name: str) -> np.ndarray:
    """Parse "X,Y,Z" (a CLI option) into a finite 3-vector; InputError naming the option otherwise."""
    parts = [p.strip() for p in str(text).split(",")]
    try:
        values = np.array([float(p) for p in parts])
    except ValueError:
        raise InputError(f"{name}: expected three numbers X,Y,Z, got {text!r}") from None
    if values.shape != (3,) or not np.all(np.isfinite(values)):
        raise InputError(f"{name}: expected three finite numbers X,Y,Z, got {text!r}")
    return values


def look_at_tracker(position: Sequence[float]) -> pin.SE3:
    """A tracker frame at `position` (base frame) with z up and x pointing at the robot base.

    Used when the user gives only the tracker's approximate position: the orientation about the
    vertical is irrelevant to line of sight, and identification re-estimates the whole pose anyway.
    """
    p = np.asarray(position, dtype=float)
    yaw = math.atan2(-p[1], -p[0]) if np.hypot(p[0], p[1]) > 1e-9 else 0.0
    return pose(p, (0.0, 0.0, yaw))
