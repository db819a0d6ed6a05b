"""The script port (30003): receives URScript programs and starts them.

A program is complete when a top-level ``end`` line closes its ``def name():``. The ur_rtde control
script becomes a `ControlScript`, other short programs a `CustomProgram`; both replace whatever was
running, as on the real controller. Programs are refused (logged, not started) in local control or
when the arm cannot move — the client then times out waiting for ``runtime_state`` PLAYING.
"""

from __future__ import annotations

import logging
import socket

from mocks.ur.arm import SimArm
from mocks.ur.net import TcpService, read_line
from mocks.ur.script import make_program, parse_program

log = logging.getLogger(__name__)


class ScriptServer(TcpService):
    """Primary/secondary script interface of the simulated controller (receive only)."""

    name = "script"

    def __init__(self, arm: SimArm, host: str, port: int = 30003) -> None:
        super().__init__(host, port)
        self.arm = arm
        self.programs_received = 0

    def handle(self, conn: socket.socket) -> None:
        buf = bytearray()
        lines: list[str] = []
        while True:
            line = read_line(self, conn, buf, limit=1 << 20)
            if line is None:
                return
            if not lines and not line.strip():
                continue
            lines.append(line)
            head = lines[0].strip()
            if not (head.startswith("def ") or head.startswith("sec ")):
                log.info("script: ignoring a bare command %r", head[:80])
                lines.clear()
                continue
            if line.rstrip() == "end":
                self._run("\n".join(lines) + "\n")
                lines.clear()

    def _run(self, text: str) -> None:
        parsed = parse_program(text.replace("sec ", "def ", 1) if text.startswith("sec ") else text)
        if parsed is None:
            log.info("script: not a program")
            return
        self.programs_received += 1
        started = self.arm.load_program(make_program(parsed))
        log.info("script: program %s %s", parsed.name, "started" if started else "refused")
