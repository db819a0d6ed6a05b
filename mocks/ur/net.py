"""A small threaded TCP service base with the faults a network link can have.

Each controller port (RTDE, dashboard, script, control channel) is a `TcpService`: one accept thread,
one handler thread per connection, every socket operation under a short timeout so that ``stop()``
always returns. ``drop(refuse_s)`` closes every open connection and, for ``refuse_s`` real seconds,
closes the listening socket too so reconnects are refused — which is what a cable pulled out of a
controller looks like from the client.
"""

from __future__ import annotations

import contextlib
import logging
import socket
import threading
import time

log = logging.getLogger(__name__)

POLL_S = 0.2


class TcpService:
    """Listen on (host, port); `handle(conn)` runs in its own thread for every accepted connection."""

    name = "tcp"

    def __init__(self, host: str, port: int) -> None:
        self.host = host
        self.port = port
        self._listener: socket.socket | None = None
        self._conns: set[socket.socket] = set()
        self._lock = threading.Lock()
        self._stopping = threading.Event()
        self._refuse_until = 0.0
        self._thread: threading.Thread | None = None

    # -------------------------------------------------------------- lifecycle
    def start(self) -> None:
        """Bind now (so a port clash raises here, in the caller) and start accepting."""
        self._listener = self._bind()
        self.port = self._listener.getsockname()[1]
        self._thread = threading.Thread(target=self._accept_loop, name=f"{self.name}-accept", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        self._stopping.set()
        self.drop()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        if self._listener is not None:
            self._listener.close()
            self._listener = None

    @property
    def stopping(self) -> bool:
        return self._stopping.is_set()

    def drop(self, refuse_s: float = 0.0) -> None:
        """Close all open connections; refuse new ones for `refuse_s` real seconds."""
        if refuse_s > 0:
            self._refuse_until = time.monotonic() + refuse_s
        with self._lock:
            conns = list(self._conns)
            self._conns.clear()
        for c in conns:
            with contextlib.suppress(OSError):
                c.shutdown(socket.SHUT_RDWR)
            c.close()

    def connection_count(self) -> int:
        with self._lock:
            return len(self._conns)

    # -------------------------------------------------------------- internals
    def _bind(self) -> socket.socket:
        s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            s.bind((self.host, self.port))
            s.listen(8)
        except OSError:
            s.close()
            raise
        s.settimeout(POLL_S)
        return s

    def _accept_loop(self) -> None:
        while not self._stopping.is_set():
            if time.monotonic() < self._refuse_until:
                if self._listener is not None:
                    self._listener.close()
                    self._listener = None
                time.sleep(min(POLL_S, max(self._refuse_until - time.monotonic(), 0.0)))
                continue
            if self._listener is None:
                try:
                    self._listener = self._bind()
                except OSError:
                    log.warning("%s: cannot re-bind %s:%d yet", self.name, self.host, self.port)
                    time.sleep(POLL_S)
                    continue
            try:
                conn, _ = self._listener.accept()
            except TimeoutError:
                continue
            except OSError:
                if not self._stopping.is_set():
                    time.sleep(0.01)
                continue
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            conn.settimeout(POLL_S)
            with self._lock:
                self._conns.add(conn)
            threading.Thread(target=self._run_handler, args=(conn,), name=f"{self.name}-conn",
                             daemon=True).start()

    def _run_handler(self, conn: socket.socket) -> None:
        try:
            self.handle(conn)
        except OSError as exc:
            log.debug("%s: connection ended: %s", self.name, exc)
        except Exception:
            log.exception("%s: handler failed", self.name)
        finally:
            with self._lock:
                self._conns.discard(conn)
            with contextlib.suppress(OSError):
                conn.close()
            self.on_close(conn)

    def alive(self, conn: socket.socket) -> bool:
        """True while the connection is registered and the service runs."""
        with self._lock:
            return conn in self._conns and not self._stopping.is_set()

    def handle(self, conn: socket.socket) -> None:
        raise NotImplementedError

    def on_close(self, conn: socket.socket) -> None:
        """Hook: a connection ended (for cleaning per-connection state)."""


def read_line(service: TcpService, conn: socket.socket, buf: bytearray, limit: int = 65536) -> str | None:
    """The next ``\\n``-terminated line (without the newline), or None when the connection ends."""
    while True:
        i = buf.find(b"\n")
        if i >= 0:
            line = bytes(buf[:i]).decode("utf-8", "replace").rstrip("\r")
            del buf[: i + 1]
            return line
        if not service.alive(conn) or len(buf) > limit:
            return None
        try:
            chunk = conn.recv(4096)
        except TimeoutError:
            continue
        except OSError:
            return None
        if not chunk:
            return None
        buf.extend(chunk)
