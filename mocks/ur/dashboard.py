"""The dashboard server (port 29999): line-based text commands, PolyScope 5 replies.

It answers what ur_rtde sends at connect (PolyscopeVersion, get serial number, is in remote control)
and what an operator or a driver needs (robotmode, safetymode/safetystatus, running, programState,
play/stop/pause, unlock protective stop, close (safety) popup, power on/off, brake release, get robot
model). Commands that move or start things are refused when the controller is in local control, as on
a real PolyScope 5.
"""

from __future__ import annotations

import logging
import socket
from collections.abc import Callable

from mocks.ur.arm import SimArm
from mocks.ur.net import TcpService, read_line
from mocks.ur.status import RuntimeState

log = logging.getLogger(__name__)

GREETING = "Connected: Universal Robots Dashboard Server"
_NEEDS_REMOTE = {"play", "stop", "pause", "power on", "power off", "brake release", "unlock protective stop",
                 "load", "restart safety", "shutdown"}


class DashboardServer(TcpService):
    """Dashboard on the simulated controller."""

    name = "dashboard"

    def __init__(self, arm: SimArm, host: str, port: int = 29999, *, model: str = "UR5",
                 serial: str = "20235500001", version: tuple[int, int, int, int] = (5, 15, 0, 0)) -> None:
        super().__init__(host, port)
        self.arm = arm
        self.model = model
        self.serial = serial
        self.version = version
        self.unresponsive = False  # fault: read commands, answer nothing
        self._handlers: dict[str, Callable[[str], str]] = {
            "robotmode": lambda _: f"Robotmode: {self.arm.robot_mode.name}",
            "safetymode": lambda _: f"Safetymode: {self.arm.safety_mode.name}",
            "safetystatus": lambda _: f"Safetystatus: {self.arm.safety_mode.name}",
            "running": lambda _: "Program running: "
            + ("true" if self.arm.runtime_state == RuntimeState.PLAYING else "false"),
            "programstate": self._program_state,
            "get serial number": lambda _: self.serial,
            "get robot model": lambda _: self.model,
            "polyscopeversion": lambda _: "URSoftware {}.{}.{}.{} (Jan 01 2024)".format(*self.version),
            "version": lambda _: "{}.{}.{}.{}".format(*self.version),
            "is in remote control": lambda _: "true" if self.arm.remote_control else "false",
            "play": self._play,
            "stop": self._stop,
            "pause": self._pause,
            "unlock protective stop": lambda _: self.arm.unlock_protective_stop()[1],
            "close safety popup": self._close_safety_popup,
            "close popup": lambda _: "closing popup",
            "power on": self._power_on,
            "power off": lambda _: (self.arm.power_off(), "Powering off")[1],
            "brake release": lambda _: (self.arm.brake_release(), "Brake releasing")[1],
            "get loaded program": lambda _: "No program loaded",
            "isprogramsaved": lambda _: "true <unnamed>",
            "restart safety": self._restart_safety,
            "quit": lambda _: "Disconnected",
        }

    def handle(self, conn: socket.socket) -> None:
        conn.sendall((GREETING + "\n").encode())
        buf = bytearray()
        while True:
            line = read_line(self, conn, buf)
            if line is None:
                return
            cmd = line.strip()
            if not cmd:
                continue
            reply = self.execute(cmd)
            if self.unresponsive:
                continue
            conn.sendall((reply + "\n").encode())
            if cmd.lower() == "quit":
                return

    def execute(self, cmd: str) -> str:
        """The reply line for one dashboard command."""
        key = cmd.lower()
        handler = self._handlers.get(key)
        if handler is None:
            return f"could not understand: '{cmd}'"
        if key in _NEEDS_REMOTE and not self.arm.remote_control:
            return f"Failed to execute: {cmd}. Robot is in local control"
        return handler(cmd)

    def _program_state(self, _: str) -> str:
        prog = self.arm.program
        state = self.arm.runtime_state.name
        return f"{state} {prog.name if prog else '<unnamed>'}"

    def _play(self, _: str) -> str:
        return "Failed to execute: play"  # no .urp program loaded in the simulator

    def _stop(self, _: str) -> str:
        self.arm.stop_program()
        return "Stopped"

    def _pause(self, _: str) -> str:
        with self.arm.lock:
            if self.arm.program is None:
                return "Failed to execute: pause"
            self.arm.program_paused = True
            if self.arm.motion is not None:
                self.arm.start_stop(4.0)
        return "Pausing program"

    def _close_safety_popup(self, _: str) -> str:
        self.arm.safety_popup = False
        return "closing safety popup"

    def _power_on(self, _: str) -> str:
        self.arm.power_on()
        return "Powering on"

    def _restart_safety(self, _: str) -> str:
        return "Restarting safety"
