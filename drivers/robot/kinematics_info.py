"""The controller's own kinematic model, read from its primary client interface (port 30001).

A UR controller moves and reports ``actual_TCP_pose`` with its nominal DH table plus the factory
calibration deltas of that arm. ur_rtde does not expose them; the primary (and secondary, 30002)
interface does, as the KinematicsInfo sub-package of every ROBOT_STATE message. The layout (as UR's
client library, UniversalRobots/Universal_Robots_Client_Library ``src/primary/``, parses it, all
big-endian):

* message: ``int32 length`` (header included), ``uint8 type``, payload; ROBOT_STATE is type 16 and
  its payload a run of sub-packages ``int32 length`` (header included), ``uint8 type``, payload;
  robot messages are type 20 (``uint64 timestamp, int8 source, uint8 message type`` first; the
  controller opens every connection with a VERSION message, message type 3);
* KinematicsInfo (sub-package 5): ``uint32 checksum[6]``, ``double dh_theta[6], dh_a[6], dh_d[6],
  dh_alpha[6]``, ``uint32 calibration_status``.

The parser is pure (bytes in, messages out), keeps partial messages for the next read, skips
message and sub-package types it does not know by their length, and tolerates sub-packages longer
than it expects (newer software appends fields). `read_kinematics_info` connects, reads until a
KinematicsInfo arrives and returns it, with every blocking call under one deadline.

The full DH values are kept as the controller sends them: the deltas on the parallel joints 2–4 of a
real calibration cancel each other over hundreds of metres (ur_calibration's documentation shows
d2 = 439 m), so nothing here bounds them. Turning them into deltas against the nominal table needs
the robot catalog, which lives in ``hil`` (``ControllerCalibration.from_dh(robot, *info.dh())``).
"""

from __future__ import annotations

import socket
import struct
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from drivers.robot.errors import KinematicsInfoUnavailable

PRIMARY_PORT = 30001
ROBOT_STATE = 16
ROBOT_MESSAGE = 20
KINEMATICS_INFO = 5
VERSION_MESSAGE = 3

_HEADER = struct.Struct(">iB")
_ROBOT_MESSAGE = struct.Struct(">QbB")
_KINEMATICS = struct.Struct(">6I24d")
#: Longest message accepted: a real ROBOT_STATE is about 1.4 kB (URSim 5.8); a length beyond this is
#: not a primary-interface stream (or a garbled one) and would make the reader wait forever.
MAX_MESSAGE = 1 << 20


@dataclass(frozen=True)
class PrimaryMessage:
    """One framed message: its type and its payload (the header removed)."""

    type: int
    payload: bytes


@dataclass(frozen=True)
class SubPackage:
    """One robot-state sub-package: its type and its payload (the header removed)."""

    type: int
    payload: bytes


@dataclass(frozen=True)
class VersionMessage:
    """The controller's VERSION robot message."""

    project: str
    major: int
    minor: int
    bugfix: int
    build: int
    build_date: str


@dataclass(frozen=True)
class KinematicsInfo:
    """The controller's KinematicsInfo: its full DH table (nominal + factory deltas) and checksums."""

    checksum: tuple[int, ...]
    dh_theta: tuple[float, ...]
    dh_a: tuple[float, ...]
    dh_d: tuple[float, ...]
    dh_alpha: tuple[float, ...]
    calibration_status: int

    def dh(self) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
        """(θ, a, d, α), the order of ``ControllerCalibration.from_dh``'s arguments."""
        return self.dh_theta, self.dh_a, self.dh_d, self.dh_alpha

    def as_dict(self) -> dict[str, Any]:
        """Plain JSON-ready fields, named as in the package."""
        return {"checksum": list(self.checksum), "dh_theta": list(self.dh_theta), "dh_a": list(self.dh_a),
                "dh_d": list(self.dh_d), "dh_alpha": list(self.dh_alpha),
                "calibration_status": self.calibration_status}


class PrimaryStreamError(ValueError):
    """The bytes are not a primary-interface stream (a length that cannot be right)."""


class PrimaryStream:
    """Cuts a byte stream into messages; `feed` as bytes arrive, in pieces of any size."""

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes) -> list[PrimaryMessage]:
        """The messages completed by `data`; an incomplete one waits for the next feed."""
        self._buf.extend(data)
        out: list[PrimaryMessage] = []
        while len(self._buf) >= _HEADER.size:
            length, mtype = _HEADER.unpack_from(self._buf, 0)
            if not _HEADER.size <= length <= MAX_MESSAGE:
                raise PrimaryStreamError(f"message length {length} (type {mtype}): not a primary-interface "
                                         "stream")
            if len(self._buf) < length:
                break
            out.append(PrimaryMessage(mtype, bytes(self._buf[_HEADER.size:length])))
            del self._buf[:length]
        return out

    @property
    def pending(self) -> int:
        """Bytes held for an incomplete message."""
        return len(self._buf)


def sub_packages(message: PrimaryMessage) -> Iterator[SubPackage]:
    """The sub-packages of a ROBOT_STATE message (none for other messages).

    A sub-package whose length is impossible (shorter than its header, or past the message's end)
    ends the walk: what follows cannot be framed.
    """
    if message.type != ROBOT_STATE:
        return
    data, i = message.payload, 0
    while i + _HEADER.size <= len(data):
        length, stype = _HEADER.unpack_from(data, i)
        if length < _HEADER.size or i + length > len(data):
            return
        yield SubPackage(stype, data[i + _HEADER.size:i + length])
        i += length


def parse_kinematics_info(payload: bytes) -> KinematicsInfo:
    """A KinematicsInfo sub-package's payload; PrimaryStreamError when it is too short.

    The status is the uint32 the client library reads; a payload carrying a single status byte
    (older documentation's uint8) is read as that byte.
    """
    if len(payload) < _KINEMATICS.size + 1:
        raise PrimaryStreamError(f"KinematicsInfo of {len(payload)} bytes; expected at least "
                                 f"{_KINEMATICS.size + 4}")
    values = _KINEMATICS.unpack_from(payload, 0)
    rest = payload[_KINEMATICS.size:]
    status = struct.unpack_from(">I", rest)[0] if len(rest) >= 4 else rest[0]
    dh = values[6:]
    return KinematicsInfo(checksum=tuple(values[:6]), dh_theta=tuple(dh[0:6]), dh_a=tuple(dh[6:12]),
                          dh_d=tuple(dh[12:18]), dh_alpha=tuple(dh[18:24]), calibration_status=int(status))


def parse_version(message: PrimaryMessage) -> VersionMessage | None:
    """The VERSION message's fields, or None when `message` is not one (or is cut short)."""
    if message.type != ROBOT_MESSAGE or len(message.payload) < _ROBOT_MESSAGE.size + 1:
        return None
    _, _, kind = _ROBOT_MESSAGE.unpack_from(message.payload, 0)
    if kind != VERSION_MESSAGE:
        return None
    body = message.payload[_ROBOT_MESSAGE.size:]
    n = struct.unpack_from(">b", body)[0]
    if n < 0 or len(body) < 1 + n + 10:
        return None
    major, minor, bugfix, build = struct.unpack_from(">BBii", body, 1 + n)
    return VersionMessage(body[1:1 + n].decode("ascii", "replace"), major, minor, bugfix, build,
                          body[1 + n + 10:].decode("ascii", "replace"))


def find_kinematics_info(messages: list[PrimaryMessage]) -> KinematicsInfo | None:
    """The first KinematicsInfo in `messages`, or None."""
    for message in messages:
        for sub in sub_packages(message):
            if sub.type == KINEMATICS_INFO:
                return parse_kinematics_info(sub.payload)
    return None


def read_kinematics_info(host: str, port: int = PRIMARY_PORT, timeout: float = 5.0) -> KinematicsInfo:
    """Connect to the primary (or secondary) interface and return the controller's KinematicsInfo.

    Everything — connect, every read — shares one deadline `timeout` seconds away; a refusal, a
    timeout, a closed link or a stream that is not the primary interface raise
    KinematicsInfoUnavailable. The controller sends robot state at 10 Hz, so an answer normally
    takes one read.
    """
    deadline = time.monotonic() + timeout
    where = f"{host}:{port}"
    try:
        with socket.create_connection((host, port), timeout=timeout) as s:
            stream = PrimaryStream()
            while True:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise KinematicsInfoUnavailable(f"no KinematicsInfo from {where} within {timeout:g} s")
                s.settimeout(left)
                chunk = s.recv(65536)
                if not chunk:
                    raise KinematicsInfoUnavailable(f"{where} closed the primary interface before sending "
                                                    "KinematicsInfo")
                info = find_kinematics_info(stream.feed(chunk))
                if info is not None:
                    return info
    except TimeoutError as exc:
        raise KinematicsInfoUnavailable(f"no KinematicsInfo from {where} within {timeout:g} s") from exc
    except OSError as exc:
        raise KinematicsInfoUnavailable(f"no primary interface at {where}: {exc}") from exc
    except PrimaryStreamError as exc:
        raise KinematicsInfoUnavailable(f"{where}: {exc}") from exc
