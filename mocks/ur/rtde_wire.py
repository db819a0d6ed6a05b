"""The RTDE wire format, controller side: message types, framing and the variable type table.

RTDE (protocol version 2) frames every message as a big-endian ``uint16`` size (header included), a
``uint8`` message type and a payload. Recipes name variables; the controller answers a recipe setup with
the comma-separated type of each name (``NOT_FOUND`` for names it does not know, ``IN_USE`` for input
registers another client already writes). Data packages then carry the values packed in recipe order.
The type of each variable here follows the controller's RTDE guide, because the ur_rtde client unpacks
with its own fixed table and a mismatch would silently desynchronise the stream.
"""

from __future__ import annotations

import re
import struct
from collections.abc import Sequence
from enum import IntEnum
from typing import Any

HEADER = struct.Struct(">HB")
HEADER_SIZE = HEADER.size
PROTOCOL_VERSION = 2


class MsgType(IntEnum):
    """RTDE message types (their ASCII letters)."""

    REQUEST_PROTOCOL_VERSION = 86  # V
    GET_URCONTROL_VERSION = 118  # v
    TEXT_MESSAGE = 77  # M
    DATA_PACKAGE = 85  # U
    CONTROL_PACKAGE_SETUP_OUTPUTS = 79  # O
    CONTROL_PACKAGE_SETUP_INPUTS = 73  # I
    CONTROL_PACKAGE_START = 83  # S
    CONTROL_PACKAGE_PAUSE = 80  # P


# struct format of each RTDE type name (big-endian, no padding)
TYPE_FORMATS: dict[str, str] = {
    "BOOL": "?",
    "UINT8": "B",
    "UINT32": "I",
    "UINT64": "Q",
    "INT32": "i",
    "DOUBLE": "d",
    "VECTOR3D": "3d",
    "VECTOR6D": "6d",
    "VECTOR6INT32": "6i",
    "VECTOR6UINT32": "6I",
}

OUTPUT_TYPES: dict[str, str] = {
    "timestamp": "DOUBLE",
    "target_q": "VECTOR6D",
    "target_qd": "VECTOR6D",
    "target_qdd": "VECTOR6D",
    "target_current": "VECTOR6D",
    "target_moment": "VECTOR6D",
    "actual_q": "VECTOR6D",
    "actual_qd": "VECTOR6D",
    "actual_qdd": "VECTOR6D",
    "actual_current": "VECTOR6D",
    "actual_current_as_torque": "VECTOR6D",
    "actual_moment": "VECTOR6D",
    "joint_control_output": "VECTOR6D",
    "actual_TCP_pose": "VECTOR6D",
    "actual_TCP_speed": "VECTOR6D",
    "actual_TCP_force": "VECTOR6D",
    "target_TCP_pose": "VECTOR6D",
    "target_TCP_speed": "VECTOR6D",
    "actual_digital_input_bits": "UINT64",
    "joint_temperatures": "VECTOR6D",
    "actual_execution_time": "DOUBLE",
    "robot_mode": "INT32",
    "joint_mode": "VECTOR6INT32",
    "safety_mode": "INT32",
    "safety_status": "INT32",
    "actual_tool_accelerometer": "VECTOR3D",
    "speed_scaling": "DOUBLE",
    "target_speed_fraction": "DOUBLE",
    "actual_momentum": "DOUBLE",
    "actual_main_voltage": "DOUBLE",
    "actual_robot_voltage": "DOUBLE",
    "actual_robot_current": "DOUBLE",
    "actual_joint_voltage": "VECTOR6D",
    "actual_digital_output_bits": "UINT64",
    "runtime_state": "UINT32",
    "robot_status_bits": "UINT32",
    "safety_status_bits": "UINT32",
    "standard_analog_input0": "DOUBLE",
    "standard_analog_input1": "DOUBLE",
    "standard_analog_output0": "DOUBLE",
    "standard_analog_output1": "DOUBLE",
    "ft_raw_wrench": "VECTOR6D",
    "payload": "DOUBLE",
    "payload_cog": "VECTOR3D",
    "payload_inertia": "VECTOR6D",
    "output_bit_registers0_to_31": "UINT32",
    "output_bit_registers32_to_63": "UINT32",
}
for _i in range(48):
    OUTPUT_TYPES[f"output_int_register_{_i}"] = "INT32"
    OUTPUT_TYPES[f"output_double_register_{_i}"] = "DOUBLE"

INPUT_TYPES: dict[str, str] = {
    "speed_slider_mask": "UINT32",
    "speed_slider_fraction": "DOUBLE",
    "standard_digital_output_mask": "UINT8",
    "standard_digital_output": "UINT8",
    "configurable_digital_output_mask": "UINT8",
    "configurable_digital_output": "UINT8",
    "tool_digital_output_mask": "UINT8",
    "tool_digital_output": "UINT8",
    "standard_analog_output_mask": "UINT8",
    "standard_analog_output_type": "UINT8",
    "standard_analog_output_0": "DOUBLE",
    "standard_analog_output_1": "DOUBLE",
    "input_bit_registers0_to_31": "UINT32",
    "input_bit_registers32_to_63": "UINT32",
    "external_force_torque": "VECTOR6D",
}
for _i in range(48):
    INPUT_TYPES[f"input_int_register_{_i}"] = "INT32"
    INPUT_TYPES[f"input_double_register_{_i}"] = "DOUBLE"

_REGISTER = re.compile(r"^input_(int|double)_register_(\d+)$")


def frame(msg_type: int, payload: bytes = b"") -> bytes:
    """One RTDE message: header (size incl. header, type) + payload."""
    return HEADER.pack(HEADER_SIZE + len(payload), msg_type) + payload


def recipe_struct(types: Sequence[str]) -> struct.Struct:
    """The big-endian struct that packs a recipe's values (after its recipe-id byte)."""
    return struct.Struct(">" + "".join(TYPE_FORMATS[t] for t in types))


def flatten(values: Sequence[Any]) -> list[Any]:
    """Values in recipe order, with vectors spread out, ready for `struct.pack`."""
    out: list[Any] = []
    for v in values:
        if isinstance(v, list | tuple):
            out.extend(v)
        elif hasattr(v, "tolist"):
            tl = v.tolist()
            if isinstance(tl, list):
                out.extend(tl)
            else:
                out.append(tl)
        else:
            out.append(v)
    return out


def unflatten(types: Sequence[str], flat: Sequence[Any]) -> list[Any]:
    """Inverse of `flatten` for a recipe: group the unpacked scalars back into per-variable values."""
    out: list[Any] = []
    i = 0
    for t in types:
        fmt = TYPE_FORMATS[t]
        n = int(fmt[:-1]) if len(fmt) > 1 else 1
        if n == 1:
            out.append(flat[i])
        else:
            out.append(list(flat[i : i + n]))
        i += n
    return out


def register_of(name: str) -> tuple[str, int] | None:
    """('int'|'double', index) when `name` is an input register, else None."""
    m = _REGISTER.match(name)
    return (m.group(1), int(m.group(2))) if m else None
