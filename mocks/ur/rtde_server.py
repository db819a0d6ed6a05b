"""The controller side of RTDE (port 30004).

Per connection: protocol version negotiation, controller version, one output recipe (variables +
frequency), numbered input recipes, start/pause. Once started, the controller's tick thread calls
`broadcast` every cycle and each connection gets its recipe packed from the arm's latest snapshot at
its own frequency (500 Hz divided down). Input data packages write the arm's input registers at once;
the control script reads them on the next cycle — the same timing the real controller has.

A package longer than its recipe is unpacked up to the recipe's length and the rest ignored: ur_rtde
1.6.5 sends twelve doubles with recipe 6 in ``getForwardKinematics(q)`` with a zero TCP offset, and the
real controller then reads stale registers 6..11 (the upstream bug the driver works around).
"""

from __future__ import annotations

import contextlib
import logging
import socket
import struct
import threading
from dataclasses import dataclass, field
from typing import Any

from mocks.ur.arm import SimArm
from mocks.ur.net import TcpService
from mocks.ur.rtde_wire import (
    HEADER,
    HEADER_SIZE,
    INPUT_TYPES,
    OUTPUT_TYPES,
    MsgType,
    flatten,
    frame,
    recipe_struct,
    register_of,
    unflatten,
)

log = logging.getLogger(__name__)


@dataclass
class _Input:
    names: list[str]
    types: list[str]
    st: struct.Struct


@dataclass
class _Conn:
    sock: socket.socket
    send_lock: threading.Lock = field(default_factory=threading.Lock)
    out_names: list[str] = field(default_factory=list)
    out_struct: struct.Struct | None = None
    decimation: int = 1
    inputs: dict[int, _Input] = field(default_factory=dict)
    started: bool = False
    protocol: int = 1


class RtdeServer(TcpService):
    """RTDE on the simulated controller."""

    name = "rtde"

    def __init__(self, arm: SimArm, host: str, port: int = 30004,
                 version: tuple[int, int, int, int] = (5, 15, 0, 0)) -> None:
        super().__init__(host, port)
        self.arm = arm
        self.version = version
        self._clients: dict[socket.socket, _Conn] = {}
        self._clients_lock = threading.Lock()
        self._register_owner: dict[tuple[str, int], socket.socket] = {}
        self.stalled = False  # fault: stop sending data (the client times out after 2.5 s)

    # ------------------------------------------------------------------ data out
    def broadcast(self, tick: int) -> None:
        """Send the latest snapshot to every started connection due on this tick."""
        with self._clients_lock:
            conns = [c for c in self._clients.values() if c.started and c.out_struct is not None]
        if not conns or self.stalled:
            return
        snap = self.arm.snapshot
        for c in conns:
            if tick % c.decimation:
                continue
            assert c.out_struct is not None
            try:
                body = c.out_struct.pack(*flatten([snap[n] for n in c.out_names]))
                pkt = frame(MsgType.DATA_PACKAGE, b"\x01" + body)
                with c.send_lock:
                    c.sock.sendall(pkt)
            except (OSError, struct.error) as exc:
                log.debug("rtde: dropping a client: %s", exc)
                self._close(c.sock)

    def _close(self, sock: socket.socket) -> None:
        with contextlib.suppress(OSError):
            sock.shutdown(socket.SHUT_RDWR)

    # ------------------------------------------------------------------ requests in
    def handle(self, conn: socket.socket) -> None:
        c = _Conn(conn)
        with self._clients_lock:
            self._clients[conn] = c
        buf = bytearray()
        while self.alive(conn):
            try:
                chunk = conn.recv(65536)
            except TimeoutError:
                continue
            if not chunk:
                return
            buf.extend(chunk)
            while len(buf) >= HEADER_SIZE:
                size, mtype = HEADER.unpack_from(buf, 0)
                if size < HEADER_SIZE:
                    log.warning("rtde: bad message size %d; closing", size)
                    return
                if len(buf) < size:
                    break
                payload = bytes(buf[HEADER_SIZE:size])
                del buf[:size]
                self._dispatch(c, mtype, payload)

    def on_close(self, conn: socket.socket) -> None:
        with self._clients_lock:
            self._clients.pop(conn, None)
            for key in [k for k, v in self._register_owner.items() if v is conn]:
                del self._register_owner[key]

    def _reply(self, c: _Conn, mtype: int, payload: bytes) -> None:
        with c.send_lock:
            c.sock.sendall(frame(mtype, payload))

    def _dispatch(self, c: _Conn, mtype: int, payload: bytes) -> None:
        if mtype == MsgType.REQUEST_PROTOCOL_VERSION:
            (ver,) = struct.unpack(">H", payload[:2])
            ok = ver in (1, 2)
            if ok:
                c.protocol = ver
            self._reply(c, mtype, struct.pack(">B", 1 if ok else 0))
        elif mtype == MsgType.GET_URCONTROL_VERSION:
            self._reply(c, mtype, struct.pack(">IIII", *self.version))
        elif mtype == MsgType.CONTROL_PACKAGE_SETUP_OUTPUTS:
            self._setup_outputs(c, payload)
        elif mtype == MsgType.CONTROL_PACKAGE_SETUP_INPUTS:
            self._setup_inputs(c, payload)
        elif mtype == MsgType.CONTROL_PACKAGE_START:
            c.started = True
            self._reply(c, mtype, b"\x01")
        elif mtype == MsgType.CONTROL_PACKAGE_PAUSE:
            c.started = False
            self._reply(c, mtype, b"\x01")
        elif mtype == MsgType.DATA_PACKAGE:
            self._data_in(c, payload)
        else:
            log.debug("rtde: ignoring message type %d", mtype)

    def _setup_outputs(self, c: _Conn, payload: bytes) -> None:
        if c.protocol >= 2:
            (freq,) = struct.unpack(">d", payload[:8])
            names_raw = payload[8:]
        else:
            freq, names_raw = 125.0, payload
        names = [n for n in names_raw.decode("ascii", "replace").split(",") if n]
        types = [OUTPUT_TYPES.get(n, "NOT_FOUND") for n in names]
        rate = self.arm.config.rate_hz
        if "NOT_FOUND" in types or not names or not (0 < freq <= rate):
            self._reply(c, MsgType.CONTROL_PACKAGE_SETUP_OUTPUTS, b"\x00" + ",".join(types).encode())
            return
        c.out_names = names
        c.out_struct = recipe_struct(types)
        c.decimation = max(1, round(rate / freq))
        self._reply(c, MsgType.CONTROL_PACKAGE_SETUP_OUTPUTS, b"\x01" + ",".join(types).encode())

    def _setup_inputs(self, c: _Conn, payload: bytes) -> None:
        names = [n for n in payload.decode("ascii", "replace").split(",") if n]
        types = [INPUT_TYPES.get(n, "NOT_FOUND") for n in names]
        with self._clients_lock:
            for i, n in enumerate(names):
                reg = register_of(n)
                if reg is not None and self._register_owner.get(reg, c.sock) is not c.sock:
                    types[i] = "IN_USE"
            ok = bool(names) and all(t in INPUT_TYPES.values() for t in types)
            if ok:
                for n in names:
                    reg = register_of(n)
                    if reg is not None:
                        self._register_owner[reg] = c.sock
        if not ok:
            self._reply(c, MsgType.CONTROL_PACKAGE_SETUP_INPUTS, b"\x00" + ",".join(types).encode())
            return
        rid = len(c.inputs) + 1
        c.inputs[rid] = _Input(names, types, recipe_struct(types))
        self._reply(c, MsgType.CONTROL_PACKAGE_SETUP_INPUTS, bytes([rid]) + ",".join(types).encode())

    def _data_in(self, c: _Conn, payload: bytes) -> None:
        if not payload:
            return
        recipe = c.inputs.get(payload[0])
        if recipe is None:
            log.debug("rtde: data package for unknown recipe %d", payload[0])
            return
        body = payload[1:]
        if len(body) < recipe.st.size:
            log.warning("rtde: short data package for recipe %d (%d < %d bytes)", payload[0], len(body),
                        recipe.st.size)
            return
        values: list[Any] = unflatten(recipe.types, recipe.st.unpack_from(body, 0))
        self.arm.write_inputs(recipe.names, values)
