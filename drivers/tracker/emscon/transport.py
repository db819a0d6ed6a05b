"""TCP to an emScon server: ``tcp://host:port`` (default port 700), whole packets with deadlines.

The transport knows sizes, not meanings: `receive` returns the next complete packet (as the header's
``lPacketSize`` frames it) or None at the deadline. A closed or reset socket is `ConnectionLost`; bytes
that cannot be framed are `GarbledReply`, after which the connection is closed, because TPI has no
marker to resynchronise on.
"""

from __future__ import annotations

import contextlib
import select
import socket
import time
import urllib.parse
from collections import deque
from dataclasses import dataclass

from drivers.tracker.emscon.packets import PacketError, PacketReader
from drivers.tracker.errors import ConnectionLost, GarbledReply

DEFAULT_PORT = 700  # emScon's TPI port


@dataclass(frozen=True)
class TcpConfig:
    """Where the emScon server listens and how long to wait for it to accept."""

    url: str
    connect_timeout: float = 5.0

    def __post_init__(self) -> None:
        parse_url(self.url)
        if not 0 < self.connect_timeout < float("inf"):
            raise ValueError("connect_timeout must be positive and finite")


def parse_url(url: str) -> tuple[str, int]:
    """(host, port) of ``tcp://host[:port]`` (``socket://`` is accepted too, as pyserial spells it)."""
    parts = urllib.parse.urlsplit(url)
    if parts.scheme not in ("tcp", "socket") or not parts.hostname:
        raise ValueError(f"emScon URL must look like tcp://host:700, got {url!r}")
    try:
        port = parts.port or DEFAULT_PORT
    except ValueError:
        raise ValueError(f"emScon URL {url!r}: the port is not a number in 1..65535") from None
    return parts.hostname, port


class TcpTransport:
    """One TCP connection carrying TPI packets. No I/O before `open()`."""

    def __init__(self, config: TcpConfig) -> None:
        self.config = config
        self._sock: socket.socket | None = None
        self._reader = PacketReader()
        self._ready: deque[bytes] = deque()

    @property
    def is_open(self) -> bool:
        return self._sock is not None

    def open(self) -> TcpTransport:
        host, port = parse_url(self.config.url)
        try:
            sock = socket.create_connection((host, port), timeout=self.config.connect_timeout)
        except OSError as exc:
            raise ConnectionLost(f"cannot connect to the emScon server at {host}:{port}: "
                                 f"{exc.strerror or exc}") from None
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        sock.settimeout(self.config.connect_timeout)
        self._sock = sock
        self._reader = PacketReader()
        self._ready.clear()
        return self

    def close(self) -> None:
        sock, self._sock = self._sock, None
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
            sock.close()

    def send(self, packet: bytes) -> None:
        sock = self._require()
        try:
            sock.sendall(packet)
        except OSError as exc:
            self.close()
            raise ConnectionLost(f"emScon connection lost while sending: {exc.strerror or exc}") from None

    def receive(self, deadline: float) -> bytes | None:
        """The next whole packet, or None once `deadline` (time.monotonic) has passed."""
        while not self._ready:
            sock = self._require()
            remaining = max(0.0, deadline - time.monotonic())  # 0: only what has already arrived
            try:
                readable, _, _ = select.select([sock], [], [], remaining)
            except (OSError, ValueError) as exc:
                self.close()
                raise ConnectionLost(f"emScon connection lost: {exc}") from None
            if not readable:
                return None
            try:
                data = sock.recv(65536)
            except OSError as exc:
                self.close()
                raise ConnectionLost(f"emScon connection lost: {exc.strerror or exc}") from None
            if not data:
                self.close()
                raise ConnectionLost("the emScon server closed the connection")
            try:
                self._ready.extend(self._reader.feed(data))
            except PacketError as exc:
                self.close()
                raise GarbledReply(f"emScon stream out of step ({exc}); reconnecting") from None
        return self._ready.popleft()

    def _require(self) -> socket.socket:
        if self._sock is None:
            raise ConnectionLost("the emScon connection is not open")
        return self._sock
