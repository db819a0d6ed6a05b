"""Exports of a calibrated geometry: URDF, the ROS ``ur_description`` kinematics YAML, JSON.

The URDF's root link ``base`` is the controller's base frame (the frame ``actual_TCP_pose`` uses,
``ur_description``'s ``base``/``base_link_inertia``), joints carry ``ur_description``'s names, and
``tool0`` is the flange. It also carries the SMR (``smr`` under ``tool0``) and the tracker frame
(``tracker`` under ``base``) so the whole measurement chain can be inspected in any URDF viewer.

The YAML is what ``ur_description`` loads as ``kinematics_params``: six joint origins (``shoulder`` …
``wrist_3``, each ``x y z roll pitch yaw``, R = Rz(yaw)·Ry(pitch)·Rx(roll)) and a ``hash``. It has no
place for a flange change, which is why identification leaves the flange nominal (the SMR offset
absorbs it); a geometry whose flange is not nominal is refused rather than silently exported wrong.
"""

from __future__ import annotations

import hashlib
import json
from typing import TYPE_CHECKING, Any

import numpy as np

import hil
from hil.arm.catalog import JOINT_NAMES, get_robot
from hil.errors import InputError

if TYPE_CHECKING:  # pinocchio (and the geometry built on it) load on first use: `hil show` needs FORMATS
    import pinocchio as pin

    from hil.arm.geometry import Geometry

ROS_SEGMENTS: tuple[str, ...] = ("shoulder", "upper_arm", "forearm", "wrist_1", "wrist_2", "wrist_3")
LINK_NAMES: tuple[str, ...] = ("shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link",
                               "wrist_2_link", "wrist_3_link")
FORMATS: tuple[str, ...] = ("urdf", "ros-kinematics", "json")


def _num(v: float) -> str:
    return repr(float(v))


def _origin(M: pin.SE3) -> str:
    import pinocchio as pin

    rpy = pin.rpy.matrixToRpy(M.rotation)
    xyz = " ".join(_num(v) for v in M.translation)
    return f'<origin xyz="{xyz}" rpy="{" ".join(_num(v) for v in rpy)}"/>'


def to_urdf(geometry: Geometry, comment: str = "") -> str:
    """URDF of the calibrated arm (kinematics only: no meshes or inertias)."""
    from xml.sax.saxutils import quoteattr  # pulls in urllib: only when writing a URDF

    from hil.arm.geometry import pose

    spec = get_robot(geometry.robot)
    lines = ['<?xml version="1.0"?>']
    if comment:
        lines.append(f"<!-- {comment.replace('--', '- -')} -->")
    lines.append(f"<robot name={quoteattr(spec.name + '_calibrated')}>")
    lines.append('  <link name="base"/>')
    parent = "base"
    for i, (joint, link) in enumerate(zip(JOINT_NAMES, LINK_NAMES, strict=True)):
        lines += [
            f'  <link name="{link}"/>',
            f'  <joint name="{joint}_joint" type="revolute">',
            f'    <parent link="{parent}"/>',
            f'    <child link="{link}"/>',
            f"    {_origin(geometry.joints[i])}",
            '    <axis xyz="0 0 1"/>',
            f'    <limit lower="{_num(spec.lower[i])}" upper="{_num(spec.upper[i])}" '
            f'effort="{_num(spec.effort[i])}" velocity="{_num(spec.max_joint_speed[i])}"/>',
            "  </joint>",
        ]
        parent = link
    for name, parent_link, M in (("tool0", "wrist_3_link", geometry.flange),
                                 ("smr", "tool0", pose(geometry.smr)),
                                 ("tracker", "base", geometry.tracker)):
        lines += [
            f'  <link name="{name}"/>',
            f'  <joint name="{parent_link}-{name}" type="fixed">',
            f'    <parent link="{parent_link}"/>',
            f'    <child link="{name}"/>',
            f"    {_origin(M)}",
            "  </joint>",
        ]
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def _check_flange_nominal(geometry: Geometry, source: str) -> None:
    import pinocchio as pin

    from hil.arm.geometry import Geometry

    nominal = Geometry.nominal(geometry.robot).flange
    diff = pin.log6(nominal.inverse() * geometry.flange).vector
    if np.max(np.abs(diff)) > 1e-12:
        raise InputError(f"{source}: field 'flange' differs from the nominal flange; the ROS kinematics "
                         "YAML cannot carry a flange change (export URDF or JSON instead)")


def to_ros_kinematics(geometry: Geometry, comment: str = "", source: str = "model") -> str:
    """``ur_description`` kinematics YAML of the calibrated joint origins, with a hash."""
    import pinocchio as pin
    import yaml

    _check_flange_nominal(geometry, source)
    segments: dict[str, Any] = {}
    for name, M in zip(ROS_SEGMENTS, geometry.joints, strict=True):
        x, y, z = (float(v) for v in M.translation)
        roll, pitch, yaw = (float(v) for v in pin.rpy.matrixToRpy(M.rotation))
        segments[name] = {"x": x, "y": y, "z": z, "roll": roll, "pitch": pitch, "yaw": yaw}
    digest = hashlib.sha256(json.dumps(segments, sort_keys=True).encode()).hexdigest()[:16]
    doc = {"kinematics": {**segments, "hash": f"calib_{digest}"}}
    header = f"# {comment}\n" if comment else ""
    return header + yaml.safe_dump(doc, sort_keys=False, default_flow_style=False)


def from_ros_kinematics(text: str, robot: str, source: str = "kinematics.yaml") -> Geometry:
    """The geometry (nominal flange, no SMR, tracker at the base) of a ``ur_description`` YAML."""
    import yaml

    from hil.arm.geometry import Geometry, pose

    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise InputError(f"{source}: not valid YAML ({exc})") from None
    block = doc.get("kinematics") if isinstance(doc, dict) else None
    if not isinstance(block, dict):
        raise InputError(f"{source}: missing field 'kinematics'")
    joints = []
    for name in ROS_SEGMENTS:
        seg = block.get(name)
        if not isinstance(seg, dict):
            raise InputError(f"{source}: missing field 'kinematics.{name}'")
        try:
            vals = [float(seg[k]) for k in ("x", "y", "z", "roll", "pitch", "yaw")]
        except (KeyError, TypeError, ValueError):
            raise InputError(f"{source}: field 'kinematics.{name}' needs numbers x y z roll pitch yaw"
                             ) from None
        joints.append(pose(vals[:3], vals[3:]))
    nominal = Geometry.nominal(robot)
    return Geometry(nominal.robot, joints, nominal.flange, np.zeros(3))


def to_json(document: dict[str, Any]) -> str:
    """The model document as JSON text."""
    return json.dumps(document, indent=2) + "\n"


def export(document: dict[str, Any], geometry: Geometry, fmt: str, source: str = "model") -> str:
    """Text of `geometry` in format `fmt` (one of FORMATS)."""
    provenance = document.get("input", {}) if isinstance(document.get("input"), dict) else {}
    comment = (f"calibrated by hil {hil.__version__} from {provenance.get('file') or source} "
               f"sha256 {provenance.get('sha256') or 'unknown (not recorded in the model)'}")
    if fmt in ("urdf", "ros-kinematics") and geometry.compliant:
        # neither format has a place for a joint's compliance: say what is left out, never drop it silently
        c = ", ".join(f"{v:.3g}" for v in geometry.compliance)
        load = (f"payload {geometry.payload.mass:g} kg at {list(geometry.payload.com)} m"
                if geometry.payload is not None else "no payload")
        comment += (f"; RIGID GEOMETRY ONLY: this format cannot hold the model's joint compliance "
                    f"[{c}] rad/Nm ({load}); positions predicted from it omit the gravity sag, "
                    "which hil fk and hil compensate apply from the JSON model")
    if geometry.chain is not None and fmt == "ros-kinematics":
        raise InputError(f"{source}: --format ros-kinematics is ur_description's kinematics_params, six "
                         f"UR joints; the {geometry.robot} model is of an arm from its URDF (export "
                         "--format urdf or json)")
    if geometry.chain is not None and fmt == "urdf":
        # the user's own URDF with the calibrated joint origins spliced in, every other byte kept (no
        # comment is added: the provenance stays in the JSON model)
        from hil.calibration.calibrated_urdf import calibrated_urdf

        return calibrated_urdf(geometry.chain, list(geometry.joints), geometry.flange).decode("utf-8")
    if fmt == "urdf":
        return to_urdf(geometry, comment)
    if fmt == "ros-kinematics":
        return to_ros_kinematics(geometry, comment, source)
    if fmt == "json":
        return to_json(document)
    raise InputError(f"--format: unknown format {fmt!r}, choose one of {', '.join(FORMATS)}")
