"""Pure-Python pre-flight checks with hard timeouts, run before the ur_rtde constructors.

The ur_rtde Python constructors hold the GIL and block without a timeout if a controller accepts the
connection but never answers; nothing in the interpreter can interrupt them. So the driver first asks
the two questions itself, each bounded by a timeout: does RTDE answer (and with which controller
version), and what does the dashboard say (model, serial, remote control, safety, robot mode).
"""

from __future__ import annotations

import re
import socket
import struct
import time
from dataclasses import dataclass

from drivers.robot.errors import RobotUnreachable
from drivers.robot.model import ControllerInfo

_HDR = struct.Struct(">HB")


def _recv_exact(s: socket.socket, n: int, deadline: float) -> bytes:
    buf = b""
    while len(buf) < n:
        s.settimeout(max(deadline - time.monotonic(), 0.001))
        chunk = s.recv(n - len(buf))
        if not chunk:
            raise ConnectionError("closed by the controller")
        buf += chunk
    return buf


def _request(s: socket.socket, mtype: int, payload: bytes, deadline: float) -> bytes:
    s.sendall(_HDR.pack(3 + len(payload), mtype) + payload)
    while True:
        size, rtype = _HDR.unpack(_recv_exact(s, 3, deadline))
        body = _recv_exact(s, size - 3, deadline)
        if rtype == mtype:
            return body


def rtde_version(host: str, timeout: float, port: int = 30004) -> tuple[int, int, int, int]:
    """Negotiate RTDE protocol 2 and read the controller version, all within `timeout` seconds."""
    deadline = time.monotonic() + timeout
    try:
        with socket.create_connection((host, port), timeout=timeout) as s:
            ok = _request(s, 86, struct.pack(">H", 2), deadline)
            if not ok or ok[0] != 1:
                raise RobotUnreachable(f"{host}:{port} refused RTDE protocol version 2")
            body = _request(s, 118, b"", deadline)
            return struct.unpack(">IIII", body[:16])  # type: ignore[return-value]
    except (OSError, ConnectionError, struct.error) as exc:
        raise RobotUnreachable(f"no RTDE answer from {host}:{port}: {exc}") from exc


@dataclass(frozen=True)
class DashboardStatus:
    """Dashboard answers the driver needs before taking control."""

    model: str
    serial: str
    polyscope_version: str
    remote_control: bool | None  # None where the dashboard does not know (CB3, PolyScope < 5.6)
    safety: str
    robot_mode: str


def controller_model(reported: str, major: int) -> str:
    """The model as hil spells it from the dashboard's ``get robot model`` and the controller's major
    version: an e-Series dashboard (software 5.x) answers ``UR5`` for a UR5e, so the "e" is added;
    the UR20 and UR30 exist only as e-Series and keep their names; a CB3 (3.x) answers ``UR5``."""
    e_series = major >= 5 and reported[-1:].isdigit() and reported not in ("UR20", "UR30")
    return reported + ("e" if e_series else "")


def controller_series(major: int) -> tuple[str, float]:
    """The series ("e" or "cb3") and its RTDE rate in Hz: 500 Hz on an e-Series, 125 Hz on a CB3
    (Universal Robots, "Real-Time Data Exchange (RTDE) Guide", the output frequency ranges)."""
    return ("e", 500.0) if major >= 5 else ("cb3", 125.0)


def dashboard_knows_serial(major: int, minor: int) -> bool:
    """Whether the dashboard answers ``get serial number`` and ``is in remote control``: PolyScope
    5.6 and later (Universal Robots, "Dashboard Server e-Series" command list: both "added in version
    5.6.0"); a CB3 and an older e-Series do not."""
    return major >= 5 and (major, minor) >= (5, 6)


def ask_controller(host: str, timeout: float) -> ControllerInfo:
    """Who the controller at `host` is (model, serial, software, version), without taking control:
    RTDE's version negotiation and three dashboard questions, each bounded by `timeout`.

    Nothing is uploaded nor started, so a caller learns the robot's model in milliseconds and can
    refuse a station before opening the driver. `kinematics` stays None (the primary interface is not
    read). `RobotUnreachable` when either port does not answer.
    """
    version = rtde_version(host, timeout)
    major, minor = version[0], version[1]
    series, rate = controller_series(major)
    with DashboardLine(host, timeout) as dash:
        model = dash.ask("get robot model")
        serial = dash.ask("get serial number") if dashboard_knows_serial(major, minor) else ""
        software = polyscope_version(dash.ask("PolyscopeVersion"))
    return ControllerInfo(model=controller_model(model, major), serial=serial,
                          software_version=software or ".".join(map(str, version)), version=version,
                          series=series, rate_hz=rate)


def polyscope_version(reply: str) -> str:
    """The four-part version in the dashboard's ``PolyscopeVersion`` reply (the reply itself if none)."""
    m = re.search(r"\d+\.\d+\.\d+\.\d+", reply)
    return m.group(0) if m else reply


class DashboardLine:
    """A minimal dashboard client with a timeout on every line (for pre-flight and status checks)."""

    def __init__(self, host: str, timeout: float, port: int = 29999) -> None:
        self.host, self.port, self.timeout = host, port, timeout
        self._sock: socket.socket | None = None
        self._buf = b""

    def __enter__(self) -> DashboardLine:
        try:
            self._sock = socket.create_connection((self.host, self.port), timeout=self.timeout)
            self._readline()  # greeting
        except OSError as exc:
            self.close()
            raise RobotUnreachable(f"no dashboard answer from {self.host}:{self.port}: {exc}") from exc
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None

    def _readline(self) -> str:
        assert self._sock is not None
        deadline = time.monotonic() + self.timeout
        while b"\n" not in self._buf:
            self._sock.settimeout(max(deadline - time.monotonic(), 0.001))
            chunk = self._sock.recv(4096)
            if not chunk:
                raise ConnectionError("dashboard closed the connection")
            self._buf += chunk
        line, _, self._buf = self._buf.partition(b"\n")
        return line.decode("utf-8", "replace").strip()

    def ask(self, command: str) -> str:
        """Send one command, return its one-line reply."""
        assert self._sock is not None
        try:
            self._sock.sendall((command + "\n").encode())
            return self._readline()
        except OSError as exc:
            raise RobotUnreachable(f"dashboard {self.host}: {command!r} failed: {exc}") from exc

    def status(self, major: int, minor: int) -> DashboardStatus:
        new_enough = dashboard_knows_serial(major, minor)
        serial = self.ask("get serial number") if new_enough else ""
        remote = None
        if new_enough:
            remote = self.ask("is in remote control").strip().lower() == "true"
        version = polyscope_version(self.ask("PolyscopeVersion"))
        safety = self.ask("safetystatus" if major >= 5 else "safetymode").split(":")[-1].strip()
        robot_mode = self.ask("robotmode").split(":")[-1].strip()
        return DashboardStatus(model=self.ask("get robot model"), serial=serial,
                               polyscope_version=version, remote_control=remote,
                               safety=safety, robot_mode=robot_mode)
