"""Binary messages of the primary/secondary client interfaces (ports 30001/30002), controller side.

Layout as UR's client library parses it (UniversalRobots/Universal_Robots_Client_Library,
``include/ur_client_library/primary/``, checked against its URSim 5.8 capture in
``tests/test_primary_parser.cpp``); everything is big-endian:

* a message is ``int32 length`` (the whole message, header included), ``uint8 type``, payload;
* VERSION is a robot message (type 20): ``uint64 timestamp, int8 source, uint8 message type (3)``,
  then ``int8 name length, name, uint8 major, uint8 minor, int32 bugfix, int32 build``, the build
  date to the end (URSim: source -2, name "URControl");
* ROBOT_STATE (type 16) is a run of sub-packages, each ``int32 length`` (its header included),
  ``uint8 type``, payload. This controller sends RobotModeData (0), JointData (1), CartesianInfo (4)
  and KinematicsInfo (5) — the ones a client needs here; a real controller sends more (masterboard,
  tool, configuration, …), which a client skips by their length.

Sub-package payloads:

* RobotModeData: ``uint64 timestamp (µs)``, seven bools (real robot connected, real robot enabled,
  power on, emergency stopped, protective stopped, program running, program paused), ``int8 robot
  mode``, ``uint8 control mode``, ``double target speed fraction, speed scaling, target speed
  fraction limit``; e-series adds one reserved byte (47 bytes in all, 46 on CB3 3.x).
* JointData, per joint: ``double q_actual, q_target, qd_actual; float I_actual, V_actual, T_motor,
  T_micro; uint8 joint mode`` (41 bytes).
* CartesianInfo: ``double x, y, z, rx, ry, rz`` (the TCP in the base frame, as actual_TCP_pose),
  then the TCP offset, six doubles.
* KinematicsInfo: ``uint32 checksum[6]``, ``double dh_theta[6], dh_a[6], dh_d[6], dh_alpha[6]`` (the
  full table the controller uses: nominal + its calibration deltas), ``uint32 calibration status``
  (the library reads a uint32; URSim, uncalibrated, sends 0 with all checksums 0xFFFFFFFF).
"""

from __future__ import annotations

import struct
from collections.abc import Mapping, Sequence
from enum import IntEnum
from typing import Any

import numpy as np

HEADER = struct.Struct(">iB")  # message length, message type
SUB_HEADER = struct.Struct(">iB")  # sub-package length, sub-package type
ROBOT_MESSAGE_HEADER = struct.Struct(">QbB")  # timestamp, source, robot message type
ROBOT_MODE = struct.Struct(">Q7?bBddd")
JOINT = struct.Struct(">3d4fB")
CARTESIAN = struct.Struct(">12d")
KINEMATICS = struct.Struct(">6I24dI")

#: The source a URSim 5.8 VERSION message carries (the client library's captured test message).
SOURCE_CONTROLLER = -2
#: Calibration status sent in KinematicsInfo. Its values are not documented by the client library;
#: URSim sends 0.
CALIBRATION_STATUS = 0


class MessageType(IntEnum):
    """Primary-interface message types (the client library's ``RobotPackageType``)."""

    ROBOT_STATE = 16
    ROBOT_MESSAGE = 20


class RobotMessageType(IntEnum):
    """Robot message sub-types (``RobotMessagePackageType``)."""

    TEXT = 0
    VERSION = 3


class StateType(IntEnum):
    """Robot state sub-package types (``RobotStateType``)."""

    ROBOT_MODE_DATA = 0
    JOINT_DATA = 1
    TOOL_DATA = 2
    MASTERBOARD_DATA = 3
    CARTESIAN_INFO = 4
    KINEMATICS_INFO = 5
    CONFIGURATION_DATA = 6


def message(mtype: int, payload: bytes) -> bytes:
    """One framed message."""
    return HEADER.pack(HEADER.size + len(payload), mtype) + payload


def sub_package(stype: int, payload: bytes) -> bytes:
    """One framed robot-state sub-package."""
    return SUB_HEADER.pack(SUB_HEADER.size + len(payload), stype) + payload


def version_message(version: Sequence[int], timestamp_us: int = 0, build_date: str = "01-01-2024, 00:00:00",
                    project: str = "URControl") -> bytes:
    """The VERSION robot message a controller sends first on connect."""
    name = project.encode("ascii")
    major, minor, bugfix, build = (int(v) for v in version)
    body = (ROBOT_MESSAGE_HEADER.pack(timestamp_us, SOURCE_CONTROLLER, RobotMessageType.VERSION)
            + struct.pack(">b", len(name)) + name + struct.pack(">BBii", major, minor, bugfix, build)
            + build_date.encode("ascii"))
    return message(MessageType.ROBOT_MESSAGE, body)


def robot_mode_data(snapshot: Mapping[str, Any], *, e_series: bool, paused: bool = False) -> bytes:
    """RobotModeData from an RTDE-style snapshot of the arm (`mocks.ur.arm.SimArm.snapshot`)."""
    bits = int(snapshot["safety_status_bits"])
    robot_bits = int(snapshot["robot_status_bits"])
    body = ROBOT_MODE.pack(
        round(float(snapshot["timestamp"]) * 1e6),
        True,  # a real robot is connected (what a URSim in simulation mode reports too)
        True,
        bool(robot_bits & 1),  # RobotBit.POWER_ON
        bool(bits & (1 << 7)),  # SafetyBit.EMERGENCY_STOPPED
        bool(bits & (1 << 2)),  # SafetyBit.PROTECTIVE_STOPPED
        bool(robot_bits & 2),  # RobotBit.PROGRAM_RUNNING
        paused,
        int(snapshot["robot_mode"]),
        0,  # control mode: position
        float(snapshot["target_speed_fraction"]),
        float(snapshot["speed_scaling"]),
        1.0,  # target speed fraction limit
    )
    return sub_package(StateType.ROBOT_MODE_DATA, body + (b"\x00" if e_series else b""))


def joint_data(snapshot: Mapping[str, Any]) -> bytes:
    """JointData from a snapshot: actual and target joints, speeds, currents, temperatures, modes."""
    rows = zip(snapshot["actual_q"], snapshot["target_q"], snapshot["actual_qd"], snapshot["actual_current"],
               snapshot["actual_joint_voltage"], snapshot["joint_temperatures"], snapshot["joint_mode"],
               strict=True)
    body = b"".join(JOINT.pack(q, qt, qd, i, v, t, t, int(m)) for q, qt, qd, i, v, t, m in rows)
    return sub_package(StateType.JOINT_DATA, body)


def cartesian_info(snapshot: Mapping[str, Any], tcp_offset: Sequence[float]) -> bytes:
    """CartesianInfo: the TCP pose the controller computes (its own model) and the TCP offset."""
    return sub_package(StateType.CARTESIAN_INFO,
                       CARTESIAN.pack(*snapshot["actual_TCP_pose"], *(float(v) for v in tcp_offset)))


def kinematics_info(checksums: Sequence[int], theta: Sequence[float], a: Sequence[float], d: Sequence[float],
                    alpha: Sequence[float], status: int = CALIBRATION_STATUS) -> bytes:
    """KinematicsInfo: per-joint checksums, the full DH table the controller moves with, the status."""
    values = [np.asarray(v, dtype=float).reshape(6) for v in (theta, a, d, alpha)]
    return sub_package(StateType.KINEMATICS_INFO,
                       KINEMATICS.pack(*(int(c) & 0xFFFFFFFF for c in checksums),
                                       *np.concatenate(values).tolist(), int(status)))


def robot_state(packages: Sequence[bytes]) -> bytes:
    """A ROBOT_STATE message made of already framed sub-packages."""
    return message(MessageType.ROBOT_STATE, b"".join(packages))
