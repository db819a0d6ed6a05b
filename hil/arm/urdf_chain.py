"""A serial chain from a URDF: any arm's joints, limits and nominal origins between a base and a tip link.

Pinocchio parses the file (`pin.buildModelFromXML`: the tree, each joint's placement with the fixed
joints before it folded in, each link's frame); the few things its model does not keep in the URDF's
terms — a joint's declared type (a continuous joint becomes a two-coordinate joint there), its axis, its
limits, a ``<mimic>`` — are read from the same text's ``<joint>`` elements.

Each actuated joint's frame is rotated so its axis is z (A: z → axis), and the rotation is undone at
the start of the next origin (``A(i−1)ᵀ · fixed · O_urdf · A(i)``), so every joint becomes a rotation or
translation about z and the placement-error parameters of `hil.arm.kinematics` apply to any arm as they
do to a UR. `UrdfSource.urdf_origins` maps a calibrated chain back onto the URDF's joint origins.

Every way a URDF can fail to give one serial chain is one `InputError` line naming the file: unreadable
or malformed, base or tip not a link, tip not below base, several ends (naming them), an unsupported
joint type (floating, planar) or a mimic joint on the chain.
"""

from __future__ import annotations

import hashlib
import math
import os
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from hil.arm.chain import PRISMATIC, REVOLUTE, Chain, UrdfJoint, UrdfSource
from hil.errors import InputError
from hil.files.inputs import read_input_text

#: URDF joint types hil turns into chain joints, and the chain joint each becomes.
_KINDS = {"revolute": REVOLUTE, "continuous": REVOLUTE, "prismatic": PRISMATIC}
#: Speed limit assumed for a joint whose URDF gives none (rad/s or m/s): hil's assumption, a slow
#: cobot joint's (a UR e-series' slowest joint is 120°/s ≈ 2.1 rad/s); only the selector's move-time
#: estimate reads it.
DEFAULT_VELOCITY = 1.0


@dataclass(frozen=True)
class _XmlJoint:
    name: str
    kind: str  # the URDF type attribute
    parent: str
    child: str
    axis: np.ndarray
    lower: float
    upper: float
    velocity: float
    mimic: bool


def _float_attr(element: ET.Element | None, key: str, default: float, where: str) -> float:
    if element is None or element.get(key) is None:
        return default
    try:
        value = float(element.get(key, ""))
    except ValueError:
        raise InputError(f"{where}: attribute {key}={element.get(key)!r} is not a number") from None
    if not math.isfinite(value):
        raise InputError(f"{where}: attribute {key} is not finite")
    return value


def _xml_joints(root: ET.Element, source: str) -> dict[str, _XmlJoint]:
    out: dict[str, _XmlJoint] = {}
    for el in root.findall("joint"):  # top level only: <transmission> holds <joint> elements too
        name = el.get("name", "")
        where = f"{source}: joint {name!r}"
        parent, child, axis_el = el.find("parent"), el.find("child"), el.find("axis")
        axis = np.array([1.0, 0.0, 0.0])  # the URDF default
        if axis_el is not None and axis_el.get("xyz") is not None:
            try:
                axis = np.array([float(v) for v in axis_el.get("xyz", "").split()])
            except ValueError:
                raise InputError(f"{where}: axis xyz={axis_el.get('xyz')!r} is not three numbers") from None
            if axis.shape != (3,) or not np.all(np.isfinite(axis)):
                raise InputError(f"{where}: axis xyz={axis_el.get('xyz')!r} is not three numbers")
        limit = el.find("limit")
        kind = el.get("type", "")
        out[name] = _XmlJoint(
            name, kind, "" if parent is None else parent.get("link", ""),
            "" if child is None else child.get("link", ""), axis,
            _float_attr(limit, "lower", -math.inf if kind != "prismatic" else 0.0, where),
            _float_attr(limit, "upper", math.inf if kind != "prismatic" else 0.0, where),
            _float_attr(limit, "velocity", DEFAULT_VELOCITY, where) or DEFAULT_VELOCITY,
            el.find("mimic") is not None)
    return out


def _rotation_z_to(axis: np.ndarray) -> np.ndarray:
    """A rotation taking z onto the unit `axis` (the identity for z itself, a half turn about x for −z)."""
    a = axis / np.linalg.norm(axis)
    z = np.array([0.0, 0.0, 1.0])
    c = float(z @ a)
    if c > 1.0 - 1e-15:
        return np.eye(3)
    if c < -1.0 + 1e-15:
        return np.diag([1.0, -1.0, -1.0])
    return pin.Quaternion.FromTwoVectors(z, a).matrix()


def read_urdf(path: str | os.PathLike[str]) -> str:
    """The text of a URDF file; one-line InputError for a missing, unreadable or non-UTF-8 file."""
    return read_input_text(path, "a URDF file")


def chain_from_urdf(path: str | os.PathLike[str], base: str | None = None, tip: str | None = None) -> Chain:
    """The serial chain from `base` (default: the root link) to `tip` (default: the end of the only
    chain) of the URDF file at `path`. See `chain_from_text`."""
    return chain_from_text(read_urdf(path), base, tip, Path(path).name)


def chain_from_text(text: str, base: str | None = None, tip: str | None = None,
                    source: str = "URDF", file: str | None = None) -> Chain:
    """The serial chain of a URDF's text between links `base` and `tip` (module docstring): its actuated
    joints in order, fixed joints folded in, every axis turned onto z, limits and speeds from the file.

    `source` names the file in errors, `file` the name the chain records (default: `source`).
    InputError (one line) for anything that is not one serial chain.
    """
    try:
        root = ET.fromstring(text)
    except ET.ParseError as exc:
        raise InputError(f"{source}: not a URDF: malformed XML ({exc})") from None
    if root.tag != "robot":
        raise InputError(f"{source}: not a URDF: the root element is <{root.tag}>, not <robot>")
    joints = _xml_joints(root, source)
    links = [el.get("name", "") for el in root.findall("link")]
    if not links:
        raise InputError(f"{source}: the URDF has no links")
    try:
        model = pin.buildModelFromXML(text)
    except (RuntimeError, ValueError) as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise InputError(f"{source}: pinocchio cannot read the URDF: {first}") from None
    parent_of = {j.child: j for j in joints.values()}
    children: dict[str, list[str]] = {}
    for j in joints.values():
        children.setdefault(j.parent, []).append(j.child)
    roots = [name for name in links if name not in parent_of]
    if len(roots) != 1:
        raise InputError(f"{source}: the URDF has {len(roots)} root links ({', '.join(roots)}), not one")
    base = roots[0] if base is None else base
    for role, link in (("base", base), ("tip", tip)):
        if link is not None and link not in links:
            raise InputError(f"{source}: no link named {link!r} (the --{role} link)")
    if tip is None:
        ends: list[str] = []
        stack = [base]
        while stack:
            link = stack.pop()
            below = children.get(link, [])
            if not below:
                ends.append(link)
            stack.extend(below)
        if len(ends) != 1:
            raise InputError(f"{source}: the chain from {base!r} has {len(ends)} ends: "
                             f"{', '.join(sorted(ends))}; choose the SMR's link with --tip")
        tip = ends[0]
    path: list[_XmlJoint] = []  # joints from base down to tip
    link = tip
    while link != base:
        joint = parent_of.get(link)
        if joint is None:
            raise InputError(f"{source}: no chain from {base!r} to {tip!r}: {tip!r} is not below "
                             f"{base!r}")
        path.append(joint)
        link = joint.parent
    path.reverse()
    for joint in path:
        if joint.kind not in _KINDS and joint.kind != "fixed":
            raise InputError(f"{source}: joint {joint.name!r} is of type {joint.kind!r}; a chain "
                             "holds revolute, continuous, prismatic and fixed joints only")
        if joint.mimic:
            raise InputError(f"{source}: joint {joint.name!r} mimics another joint; a chain of "
                             "independent joints cannot hold it")
    actuated = [j for j in path if j.kind in _KINDS]
    if not actuated:
        raise InputError(f"{source}: no actuated joint between {base!r} and {tip!r}")

    def frame_placement(link_name: str) -> tuple[int, pin.SE3]:
        frame = model.frames[model.getFrameId(link_name, pin.FrameType.BODY)]
        return frame.parentJoint, frame.placement

    base_joint, base_placement = frame_placement(base)
    origins: list[pin.SE3] = []
    urdf_joints: list[UrdfJoint] = []
    previous_rotation = np.eye(3)
    previous_joint = base_joint
    for joint in actuated:
        jid = model.getJointId(joint.name)
        if model.parents[jid] != previous_joint:  # cannot happen for a tree pinocchio built
            raise InputError(f"{source}: joint {joint.name!r} does not follow the previous joint")
        placement = model.jointPlacements[jid]  # parent joint frame → this joint, fixed joints folded
        if previous_joint == base_joint:
            placement = base_placement.inverse() * placement
        parent_link = frame_placement(joint.parent)[1]
        fixed = parent_link if previous_joint != base_joint else base_placement.inverse() * parent_link
        origin_urdf = fixed.inverse() * placement
        A = _rotation_z_to(joint.axis)
        origins.append(pin.SE3(previous_rotation.T, np.zeros(3)) * placement * pin.SE3(A, np.zeros(3)))
        urdf_joints.append(UrdfJoint(joint.name, joint.parent, joint.child, fixed, A, origin_urdf))
        previous_rotation, previous_joint = A, jid
    tip_joint, tip_placement = frame_placement(tip)
    if tip_joint != previous_joint:  # cannot happen: every joint on the path is in `actuated` or fixed
        raise InputError(f"{source}: the tip {tip!r} does not follow the chain's last joint")
    flange = pin.SE3(previous_rotation.T, np.zeros(3)) * tip_placement
    sha = hashlib.sha256(text.encode("utf-8")).hexdigest()
    name = root.get("name") or Path(file or source).stem
    urdf = UrdfSource(text, sha, base, tip, file or source, tuple(urdf_joints), tip_placement)
    return Chain(name, f"{name} (URDF, {base} → {tip})",
                 tuple(_KINDS[j.kind] for j in actuated), tuple(j.name for j in actuated),
                 tuple(origins), flange,
                 np.array([j.lower for j in actuated]), np.array([j.upper for j in actuated]),
                 np.array([j.velocity for j in actuated]), key=f"urdf:{sha}:{base}:{tip}", urdf=urdf)
