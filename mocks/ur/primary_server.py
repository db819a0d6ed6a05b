"""The primary (30001) and secondary (30002) client interfaces of the simulated controller.

On connect the controller sends a VERSION message, then a ROBOT_STATE message every 100 ms (10 Hz)
for as long as the client stays (`mocks.ur.robot_state` builds the bytes). Each connection has its
own handler thread that reads the arm's latest snapshot (a dict the tick thread replaces whole) and
packs it, so serving clients never takes the arm's lock and cannot slow the 500 Hz tick.

Both interfaces also accept URScript on a real controller; this one reads and discards what a client
sends (programs go to the script port, 30003). A client that stops reading for long enough to block
a send (its socket buffer full: tens of seconds of state) is dropped, as a real controller drops
clients that do not keep up. ``stalled`` stops the state messages (the fault ``stall``), and
``drop(refuse_s)`` comes from `mocks.ur.net.TcpService` (the fault ``drop_connection``).
"""

from __future__ import annotations

import logging
import socket
import time
from collections.abc import Callable, Sequence

from mocks.ur.arm import SimArm
from mocks.ur.net import TcpService
from mocks.ur.robot_state import cartesian_info, joint_data, robot_mode_data, robot_state, version_message

log = logging.getLogger(__name__)

STATE_PERIOD = 0.1  # s: robot state at 10 Hz on both interfaces (UR client interface documentation)


class PrimaryServer(TcpService):
    """One of the two client interfaces; `name` says which ("primary" or "secondary")."""

    def __init__(self, arm: SimArm, host: str, port: int, *, name: str,
                 version: Sequence[int], kinematics: Callable[[], bytes]) -> None:
        super().__init__(host, port)
        self.name = name
        self.arm = arm
        self.version = tuple(int(v) for v in version)
        self.e_series = self.version[0] >= 5
        self.kinematics = kinematics  # -> the current KinematicsInfo sub-package (framed)
        self.stalled = False  # fault: stop sending state (the link stays open)
        self.messages_sent = 0

    def state_message(self) -> bytes:
        """The ROBOT_STATE message for the arm's latest snapshot."""
        arm = self.arm
        snap = arm.snapshot
        return robot_state([robot_mode_data(snap, e_series=self.e_series, paused=arm.program_paused),
                            joint_data(snap), cartesian_info(snap, list(arm.tcp)), self.kinematics()])

    def handle(self, conn: socket.socket) -> None:
        conn.sendall(version_message(self.version, int(time.monotonic() * 1e6)))
        due = time.monotonic()
        while self.alive(conn):
            wait = due - time.monotonic()
            if wait > 0:
                conn.settimeout(min(wait, 0.2))
                try:
                    data = conn.recv(65536)
                except TimeoutError:
                    continue
                if not data:
                    return
                log.debug("%s: ignoring %d bytes from a client", self.name, len(data))
                continue
            due += STATE_PERIOD
            if due < time.monotonic() - STATE_PERIOD:  # fell behind (loaded machine): no burst
                due = time.monotonic() + STATE_PERIOD
            if self.stalled:
                continue
            conn.settimeout(1.0)
            try:
                conn.sendall(self.state_message())
            except TimeoutError:
                log.info("%s: a client does not keep up; dropping it", self.name)
                return
            self.messages_sent += 1
