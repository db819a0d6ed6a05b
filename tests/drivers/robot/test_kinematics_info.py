"""The primary-interface parser and KinematicsInfo reader, on packets built here from the documented layout.

Layout (UR's client library, ``src/primary/``): message = int32 length (header included), uint8 type,
payload; ROBOT_STATE (16) = sub-packages of int32 length (header included), uint8 type, payload;
robot message (20) = uint64 timestamp, int8 source, uint8 message type, body; KinematicsInfo (5) =
uint32 checksum[6], double dh_theta[6], dh_a[6], dh_d[6], dh_alpha[6], uint32 calibration status.
"""

from __future__ import annotations

import socket
import struct
import threading
from collections.abc import Iterator

import pytest

from drivers.robot.errors import KinematicsInfoUnavailable, RobotConnectionError
from drivers.robot.kinematics_info import (
    KinematicsInfo,
    PrimaryStream,
    PrimaryStreamError,
    find_kinematics_info,
    parse_kinematics_info,
    parse_version,
    read_kinematics_info,
    sub_packages,
)
from mocks.ur.testing import random_loopback

CHECKSUM = (11, 22, 33, 44, 55, 4294967295)
THETA = (1e-5, 1.60233952386695, -1.68607190752171, 0.0837331147700119, -1e-7, 4e-8)
A = (2.1e-5, 0.0193171326277006, -0.569251663611088, -4.6e-5, -6.4e-5, 0.0)
# a real calibration's cancelling d values on the parallel joints (ur_calibration's documentation)
D = (0.180539811714259, 439.140974079901, -446.027059806332, 7.0603368964236, 0.119811341150314,
     0.115670917257426)
ALPHA = (1.57014608044242, 0.0013941666682559, 0.00693818880325995, 1.56998468543761, -1.57038520649543, 0.0)


def message(mtype: int, payload: bytes) -> bytes:
    return struct.pack(">iB", 5 + len(payload), mtype) + payload


def sub(stype: int, payload: bytes) -> bytes:
    return struct.pack(">iB", 5 + len(payload), stype) + payload


def kinematics_payload(status: bytes = struct.pack(">I", 1)) -> bytes:
    return struct.pack(">6I24d", *CHECKSUM, *THETA, *A, *D, *ALPHA) + status


def version_message() -> bytes:
    name = b"URControl"
    body = struct.pack(">QbB", 0, -2, 3) + struct.pack(">b", len(name)) + name
    body += struct.pack(">BBii", 5, 15, 2, 12345) + b"01-02-2024, 10:20:30"
    return message(20, body)


def robot_state(*subs: bytes) -> bytes:
    return message(16, b"".join(subs))


def stream_bytes() -> bytes:
    """A VERSION message, a state without KinematicsInfo, an unknown message, then a full state."""
    mode = sub(0, struct.pack(">Q7?bBddd", 123, True, True, True, False, False, True, False, 7, 0, 1.0, 1.0,
                              1.0) + b"\x00")
    joints = sub(1, b"".join(struct.pack(">3d4fB", 0.1 * j, 0.1 * j, 0.0, 0.5, 48.0, 30.0, 30.0, 253)
                             for j in range(6)))
    cartesian = sub(4, struct.pack(">12d", *range(12)))
    unknown_sub = sub(99, b"\x01\x02\x03")  # a sub-package this reader does not know
    longer = sub(5, kinematics_payload() + b"\xaa\xbb")  # newer software may append fields
    return (version_message() + robot_state(mode, joints, cartesian) + message(25, b"program state")
            + robot_state(mode, unknown_sub, joints, cartesian, longer))


def expected() -> KinematicsInfo:
    return KinematicsInfo(CHECKSUM, THETA, A, D, ALPHA, 1)


def test_a_whole_stream_parses_into_messages_and_the_kinematics_info() -> None:
    messages = PrimaryStream().feed(stream_bytes())
    assert [m.type for m in messages] == [20, 16, 25, 16]
    version = parse_version(messages[0])
    assert version is not None
    assert (version.project, version.major, version.minor, version.bugfix, version.build) == (
        "URControl", 5, 15, 2, 12345)
    assert version.build_date == "01-02-2024, 10:20:30"
    assert [s.type for s in sub_packages(messages[1])] == [0, 1, 4]
    assert [s.type for s in sub_packages(messages[3])] == [0, 99, 1, 4, 5]
    assert find_kinematics_info(messages[:3]) is None
    assert find_kinematics_info(messages) == expected()


@pytest.mark.parametrize("piece", [1, 2, 3, 7, 64, 1000])
def test_partial_reads_give_the_same_messages(piece: int) -> None:
    data = stream_bytes()
    stream = PrimaryStream()
    got = []
    for i in range(0, len(data), piece):
        got.extend(stream.feed(data[i:i + piece]))
    assert got == PrimaryStream().feed(data)
    assert stream.pending == 0
    assert find_kinematics_info(got) == expected()


def test_an_incomplete_message_waits_for_the_rest() -> None:
    data = version_message() + robot_state(sub(5, kinematics_payload()))
    stream = PrimaryStream()
    assert [m.type for m in stream.feed(data[:-10])] == [20]
    assert stream.pending == len(data) - 10 - len(version_message())
    rest = stream.feed(data[-10:])
    assert find_kinematics_info(rest) == expected()


def test_the_as_dict_and_dh_views() -> None:
    info = expected()
    assert info.dh() == (THETA, A, D, ALPHA)
    assert info.as_dict() == {"checksum": list(CHECKSUM), "dh_theta": list(THETA), "dh_a": list(A),
                              "dh_d": list(D), "dh_alpha": list(ALPHA), "calibration_status": 1}


def test_a_one_byte_status_is_read_as_that_byte() -> None:
    assert parse_kinematics_info(kinematics_payload(b"\x02")).calibration_status == 2


def test_a_short_kinematics_info_is_refused() -> None:
    with pytest.raises(PrimaryStreamError, match="KinematicsInfo of 100 bytes"):
        parse_kinematics_info(kinematics_payload()[:100])


def test_a_sub_package_running_past_its_message_ends_the_walk() -> None:
    broken = struct.pack(">iB", 500, 5) + b"\x00" * 10
    msg = PrimaryStream().feed(robot_state(sub(0, b"x"), broken))[0]
    assert [s.type for s in sub_packages(msg)] == [0]


@pytest.mark.parametrize("length", [0, 4, -1, 1 << 21])
def test_an_impossible_message_length_is_not_a_primary_stream(length: int) -> None:
    with pytest.raises(PrimaryStreamError, match="not a primary-interface stream"):
        PrimaryStream().feed(struct.pack(">iB", length, 16) + b"\x00" * 8)


def test_a_truncated_version_message_is_not_a_version() -> None:
    msg = PrimaryStream().feed(message(20, struct.pack(">QbB", 0, -2, 3) + b"\x09URC"))[0]
    assert parse_version(msg) is None


# ------------------------------------------------------------------ read_kinematics_info over TCP
class FakePrimary:
    """A one-connection server on a loopback address sending `chunks`, then holding the link open
    (or closing it: `hold` False)."""

    def __init__(self, chunks: list[bytes], hold: bool = True) -> None:
        self.sock = socket.create_server((random_loopback(), 0))
        self.host, self.port = self.sock.getsockname()[:2]
        self.chunks = chunks
        self.hold = hold
        self.done = threading.Event()
        threading.Thread(target=self._serve, daemon=True).start()

    def _serve(self) -> None:
        conn, _ = self.sock.accept()
        with conn:
            for chunk in self.chunks:
                conn.sendall(chunk)
            if self.hold:
                self.done.wait(5.0)

    def close(self) -> None:
        self.done.set()
        self.sock.close()


@pytest.fixture
def serve() -> Iterator[list[FakePrimary]]:
    servers: list[FakePrimary] = []
    yield servers
    for s in servers:
        s.close()


def test_read_kinematics_info_reads_until_the_package_arrives(serve: list[FakePrimary]) -> None:
    data = stream_bytes()
    server = FakePrimary([data[:50], data[50:700], data[700:]])
    serve.append(server)
    assert read_kinematics_info(server.host, server.port, timeout=5.0) == expected()


def test_no_kinematics_info_within_the_timeout_is_a_typed_error(serve: list[FakePrimary]) -> None:
    server = FakePrimary([version_message()])
    serve.append(server)
    with pytest.raises(KinematicsInfoUnavailable, match="no KinematicsInfo .* within 0.3 s"):
        read_kinematics_info(server.host, server.port, timeout=0.3)


def test_a_link_closed_before_the_package_is_a_typed_error(serve: list[FakePrimary]) -> None:
    server = FakePrimary([version_message()], hold=False)
    serve.append(server)
    with pytest.raises(KinematicsInfoUnavailable, match="closed the primary interface"):
        read_kinematics_info(server.host, server.port, timeout=2.0)


def test_garbage_is_a_typed_error(serve: list[FakePrimary]) -> None:
    server = FakePrimary([b"HTTP/1.1 200 OK\r\n\r\n"])
    serve.append(server)
    with pytest.raises(KinematicsInfoUnavailable, match="not a primary-interface stream"):
        read_kinematics_info(server.host, server.port, timeout=2.0)


def test_a_refused_connection_is_a_typed_error() -> None:
    with socket.create_server((random_loopback(), 0)) as s:
        host, port = s.getsockname()[:2]
    with pytest.raises(KinematicsInfoUnavailable, match="no primary interface") as err:
        read_kinematics_info(host, port, timeout=2.0)
    assert isinstance(err.value, RobotConnectionError)
