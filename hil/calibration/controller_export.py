"""The controller's own kinematic model as ur_description's kinematics YAML, the way UR's ur_calibration
makes it — so the controller's model and hil's can be loaded side by side in ROS.

UR's ur_calibration (Universal_Robots_ROS_Driver and Universal_Robots_ROS2_Driver, ``calibration.cpp``
and ``calibration_consumer.cpp``; read there, not copied) turns the controller's KinematicsInfo
(full DH values θ, a, d, α per joint) into the YAML ur_description loads:

1. each DH row becomes two transforms, a "d, θ" one Rz(θ)·Tz(d) and an "a, α" one Tx(a)·Rx(α);
2. the factory calibration carries huge, cancelling d values on the parallel joints 2–4 (UR's own
   example shows 439 m and −446 m), which would put the arm links' frames far outside the arm.
   For the upper arm and the forearm, d is set to zero and the link's end is slid along the *next*
   joint's axis to where that axis crosses the joint's xy-plane: the link's length and θ follow
   from that point, the next joint's d shrinks by the distance slid, and its frame — so the FK — is
   unchanged (`_slide_d_to_next_axis`);
3. the six joint origins are the products Rz(θ1)·Tz(d1), Tx(a1)·Rx(α1)·Rz(θ2)·Tz(d2), …, and the
   last "a, α" transform, the flange, is left out (ur_description's tool0 is fixed to the last link);
4. ``hash`` is the client library's ``KinematicsInfo::toHash``: ``"calib_"`` and the decimal
   ``std::hash<std::string>`` of θ, d, a, α of each joint in turn, each printed as C++'s default
   stream does (6 significant digits, like ``%g``) — the value ur_robot_driver compares with the
   controller's to warn about a calibration file of another robot (`ur_calibration_hash`).

hil differs in one place on purpose: the angles are written in the URDF convention ur_description
puts them in (``<origin rpy>``, R = Rz(yaw)·Ry(pitch)·Rx(roll)), where ur_calibration writes Eigen's
``eulerAngles(0, 1, 2)`` (R = Rx·Ry·Rz), which agrees with it only for a rotation about one axis.
The test reads the YAML back as a URDF would and checks the flange against the controller's own FK.

The θ deltas are all held (each is a turn about its joint's axis, so it becomes part of that
joint origin's yaw); the flange's δa6 and δα6 are not (ur_description's tool0 has no place for
them): a non-zero one is named in the file's header (`flange_not_held`), never dropped silently.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from hil.arm.controller_model import ControllerCalibration
from hil.calibration.exports import ROS_SEGMENTS
from hil.errors import InputError

# libstdc++'s std::hash<std::string> on a 64-bit target: _Hash_bytes (a MurmurHash2 variant by
# Austin Appleby) with this seed (libstdc++-v3/libsupc++/hash_bytes.cc, functional_hash.h).
_HASH_SEED = 0xC70F6907
_HASH_MUL = (0xC6A4A793 << 32) + 0x5BD1E995
_U64 = (1 << 64) - 1


def _shift_mix(v: int) -> int:
    return v ^ (v >> 47)


def std_hash(data: bytes) -> int:
    """``std::hash<std::string>`` of `data` as g++/libstdc++ computes it on a 64-bit machine
    (checked against a g++ build: see the tests' reference values)."""
    n = len(data)
    whole = n & ~7
    h = (_HASH_SEED ^ (n * _HASH_MUL)) & _U64
    for i in range(0, whole, 8):
        word = _shift_mix((int.from_bytes(data[i:i + 8], "little") * _HASH_MUL) & _U64)
        h = ((h ^ ((word * _HASH_MUL) & _U64)) * _HASH_MUL) & _U64
    if n & 7:
        h = ((h ^ int.from_bytes(data[whole:], "little")) * _HASH_MUL) & _U64
    return _shift_mix((_shift_mix(h) * _HASH_MUL) & _U64)


def ur_calibration_hash(theta: Sequence[float], a: Sequence[float], d: Sequence[float],
                        alpha: Sequence[float]) -> str:
    """The ``hash`` ur_calibration writes for these full DH values (KinematicsInfo::toHash).

    Python's ``%g`` is C's, which is what a default C++ stream prints a double as. Values rebuilt as
    nominal + delta can differ from the controller's in the last bit; at 6 digits that changes the
    hash only at an exact rounding tie.
    """
    text = "".join(format(float(v), "g") for j in range(6) for v in (theta[j], d[j], a[j], alpha[j]))
    return f"calib_{std_hash(text.encode())}"


def _rz(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    out = np.eye(4)
    out[:2, :2] = [[c, -s], [s, c]]
    return out


def _rx(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    out = np.eye(4)
    out[1:3, 1:3] = [[c, -s], [s, c]]
    return out


def _translation(x: float = 0.0, z: float = 0.0) -> np.ndarray:
    out = np.eye(4)
    out[0, 3], out[2, 3] = x, z
    return out


def _slide_d_to_next_axis(d_theta: list[np.ndarray], a_alpha: list[np.ndarray], theta: Sequence[float],
                          alpha: Sequence[float], k: int) -> None:
    """Joint k+1's (0-based k) d to zero, its link's end slid along joint k+2's axis (see step 2)."""
    if d_theta[k][2, 3] == 0.0:
        return
    root = d_theta[k] @ a_alpha[k]  # joint k+2's frame before its own d, in joint k+1's frame
    origin, axis = root[:3, 3], root[:3, 2]
    if abs(axis[2]) < 1e-6:
        raise InputError(f"the controller's DH table has joint {k + 2}'s axis perpendicular to joint "
                         f"{k + 1}'s: not a UR arm's (joints 2 to 4 are parallel)")
    slide = -origin[2] / axis[2]  # along the next axis to the xy-plane of joint k+1's frame
    point = origin + slide * axis
    # UR's arm links point along −x (their a is negative): the link keeps a negative length
    new_theta = math.atan2(-point[1], -point[0])
    d_theta[k] = _rz(new_theta)
    a_alpha[k] = _translation(x=-math.hypot(point[0], point[1])) @ _rz(theta[k] - new_theta) @ _rx(alpha[k])
    d_theta[k + 1][2, 3] -= slide  # the next joint's frame stays where it was


def ur_calibration_origins(theta: Sequence[float], a: Sequence[float], d: Sequence[float],
                           alpha: Sequence[float]) -> list[np.ndarray]:
    """The six joint origins (4×4, each in the previous joint's frame) ur_calibration derives from a
    full DH table; the flange Tx(a6)·Rx(α6) is not among them (see the module docstring)."""
    d_theta = [_rz(theta[j]) @ _translation(z=d[j]) for j in range(6)]
    a_alpha = [_translation(x=a[j]) @ _rx(alpha[j]) for j in range(6)]
    for k in (1, 2):  # the upper arm, then the forearm
        _slide_d_to_next_axis(d_theta, a_alpha, theta, alpha, k)
    return [d_theta[0]] + [a_alpha[j] @ d_theta[j + 1] for j in range(5)]


def flange_not_held(calibration: ControllerCalibration) -> str | None:
    """What of the controller's model the kinematics YAML cannot hold (its flange's δa6, δα6), or None."""
    da, dalpha = float(calibration.delta_a[5]), float(calibration.delta_alpha[5])
    if da == 0.0 and dalpha == 0.0:
        return None
    return (f"NOT HELD: the controller's flange has delta_a[5] = {da!r} m and delta_alpha[5] = "
            f"{dalpha!r} rad; ur_description's tool0 has no place for them, so tool0 here is the "
            "controller's flange without them")


def controller_ros_kinematics(calibration: ControllerCalibration, robot: str, comment: str = "") -> str:
    """ur_description kinematics YAML of the controller's own model, as ur_calibration makes it."""
    import pinocchio as pin
    import yaml

    theta, a, d, alpha = calibration.dh(robot)
    segments: dict[str, object] = {}
    for name, M in zip(ROS_SEGMENTS, ur_calibration_origins(theta, a, d, alpha), strict=True):
        x, y, z = (float(v) for v in M[:3, 3])
        roll, pitch, yaw = (float(v) for v in pin.rpy.matrixToRpy(M[:3, :3]))
        segments[name] = {"x": x, "y": y, "z": z, "roll": roll, "pitch": pitch, "yaw": yaw}
    doc = {"kinematics": {**segments, "hash": ur_calibration_hash(theta, a, d, alpha)}}
    lines = [comment] if comment else []
    lines += ["the controller's own model: nominal DH + its factory deltas (KinematicsInfo),",
              "joint origins arranged as UR's ur_calibration does, angles in the URDF convention"]
    missing = flange_not_held(calibration)
    if missing is not None:
        lines.append(missing)
    header = "".join(f"# {line}\n" for line in lines)
    return header + yaml.safe_dump(doc, sort_keys=False, default_flow_style=False)
