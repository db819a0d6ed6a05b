"""A JSON-lines control channel for injecting faults into a running simulator from outside.

Request: one JSON object per line, ``{"cmd": "<fault or 'state'|'ping'>", ...args}``.
Reply:   one JSON object per line, ``{"ok": true, "state": {...}}`` or ``{"ok": false, "error": "..."}``.

It listens on the simulator's own loopback address, so tests and ``hil sim`` users can trip a
protective stop mid-move in a simulator that runs in another process.
"""

from __future__ import annotations

import json
import socket
from typing import Any

from mocks.ur.controller import SimController
from mocks.ur.net import TcpService, read_line


class ControlServer(TcpService):
    """Serves `SimController.inject` and `state` over JSON lines."""

    name = "control"

    def __init__(self, controller: SimController, host: str, port: int = 0) -> None:
        super().__init__(host, port)
        self.controller = controller

    def handle(self, conn: socket.socket) -> None:
        buf = bytearray()
        while True:
            line = read_line(self, conn, buf)
            if line is None:
                return
            if not line.strip():
                continue
            conn.sendall((json.dumps(self.execute(line)) + "\n").encode())

    def execute(self, line: str) -> dict[str, Any]:
        try:
            req = json.loads(line)
            if not isinstance(req, dict) or "cmd" not in req:
                raise ValueError("request must be an object with 'cmd'")
            cmd = str(req.pop("cmd"))
            if cmd in ("state", "ping"):
                return {"ok": True, "state": self.controller.state()}
            if cmd == "pace":  # every step of a paced fast-time run: the clock alone, not the whole state
                return {"ok": True, "state": self.controller.pace(float(req["speed"]))}
            return {"ok": True, "state": self.controller.inject(cmd, **req)}
        except (ValueError, KeyError, TypeError) as exc:
            return {"ok": False, "error": str(exc)}


class ControlError(RuntimeError):
    """The simulator refused a control request."""


class ControlClient:
    """Client of the control channel; each call opens a short connection (robust to drop faults)."""

    def __init__(self, host: str, port: int, timeout: float = 5.0) -> None:
        self.host, self.port, self.timeout = host, port, timeout

    def call(self, cmd: str, **args: Any) -> dict[str, Any]:
        """Send one request; returns the simulator state after it, raises ControlError on refusal."""
        with socket.create_connection((self.host, self.port), timeout=self.timeout) as s:
            s.sendall((json.dumps({"cmd": cmd, **args}) + "\n").encode())
            buf = b""
            while not buf.endswith(b"\n"):
                chunk = s.recv(65536)
                if not chunk:
                    raise ControlError("control channel closed before replying")
                buf += chunk
        reply = json.loads(buf)
        if not reply.get("ok"):
            raise ControlError(reply.get("error", "refused"))
        return reply["state"]

    def state(self) -> dict[str, Any]:
        return self.call("state")
