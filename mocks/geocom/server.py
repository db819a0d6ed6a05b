"""Serve a `GeoComInstrument` on a real pty and on TCP, in-process, with wire-level realism.

``GeoComSimulator(source).start()`` opens a pty (``.pty_path`` — give it to pyserial like any
serial device) and a TCP listener (``.url`` — ``socket://127.0.0.1:<port>``). Both links share one
instrument, so both see the same lock, atmosphere and faults. Realism knobs (`LinkConfig`):

* byte pacing at ``baudrate`` (a pty does none by itself): the request's own transmission time
  is waited before answering, then the reply is written chunk by chunk at line speed;
* replies split into random chunks; occasional random stalls (``stall_probability``);
* the one-shot faults of `mocks.geocom.faults`.
"""

from __future__ import annotations

import contextlib
import logging
import os
import random
import select
import socket
import threading
import tty
from collections.abc import Callable
from dataclasses import dataclass, field
from types import TracebackType

from mocks.geocom.faults import FaultInjector, QueuedFault, ReplyFault
from mocks.geocom.instrument import GeoComInstrument, InstrumentConfig
from mocks.geocom.target import TargetSource

log = logging.getLogger(__name__)

_POLL_S = 0.02  # how quickly link threads notice stop()


@dataclass(frozen=True)
class LinkConfig:
    """Wire behaviour of both links."""

    baudrate: int | None = None  # None: no pacing (as fast as the OS moves bytes)
    bits_per_byte: int = 10  # 8N1: start + 8 data + stop
    terminator: bytes = b"\r\n"
    max_chunk: int = 0  # >0: replies are written in random chunks of 1..max_chunk bytes
    stall_probability: float = 0.0
    stall_seconds: float = 0.0
    seed: int | None = 0

    def byte_time(self) -> float:
        """Seconds one byte takes on the wire (0 without pacing)."""
        return self.bits_per_byte / self.baudrate if self.baudrate else 0.0


@dataclass(frozen=True)
class SimulatorConfig:
    """Everything `GeoComSimulator` needs besides the target."""

    instrument: InstrumentConfig = field(default_factory=InstrumentConfig)
    link: LinkConfig = field(default_factory=LinkConfig)
    address: str = "127.0.0.1"  # any 127.x.y.z
    port: int = 0  # 0: pick a free one
    serve_pty: bool = True
    serve_tcp: bool = True


class _Session:
    """One byte stream: split requests, answer them, apply faults and pacing."""

    def __init__(
        self,
        sim: GeoComSimulator,
        recv: Callable[[float], bytes | None],
        send: Callable[[bytes], None],
        close: Callable[[], None],
        name: str,
    ) -> None:
        self.sim, self._recv, self._send, self._close, self.name = sim, recv, send, close, name
        self._buffer = bytearray()
        self._rand = random.Random(sim.config.link.seed)

    def run(self) -> None:
        term = self.sim.config.link.terminator
        try:
            while not self.sim.stopping.is_set():
                data = self._recv(_POLL_S)
                if data is None:
                    return
                self._buffer.extend(data)
                while (idx := self._buffer.find(term)) >= 0:
                    line = bytes(self._buffer[:idx])
                    del self._buffer[: idx + len(term)]
                    if not self._answer(line):
                        return
                if len(self._buffer) > 65536:
                    self._buffer.clear()
        except OSError as exc:
            log.debug("%s: link error %s", self.name, exc)
        finally:
            self._close()

    def _wait(self, seconds: float) -> None:
        if seconds > 0:
            self.sim.stopping.wait(seconds)

    def _answer(self, line: bytes) -> bool:
        link = self.sim.config.link
        self._wait(len(line) * link.byte_time())  # the request's own time on the wire
        reply = self.sim.instrument.handle_line(line)
        if reply is None:
            return True
        fault = self.sim.faults.take_reply_fault()
        if fault is not None and fault.kind is ReplyFault.UNPLUG:
            log.info("%s: unplugged by fault injection", self.name)
            return False
        if fault is not None and fault.kind is ReplyFault.DROP:
            return True
        if fault is not None and fault.kind is ReplyFault.DELAY:
            self._wait(fault.seconds)
        data = _apply_fault(reply, fault, self._rand) if fault else reply
        if fault is not None and fault.kind is ReplyFault.TRUNCATE:
            self._write(data[: max(1, int(len(data) * fault.split))])
            return True
        data += link.terminator
        stall_at, stall_s = None, 0.0
        if fault is not None and fault.kind is ReplyFault.STALL:
            stall_at, stall_s = max(1, int(len(data) * fault.split)), fault.seconds
        elif link.stall_probability > 0 and self._rand.random() < link.stall_probability:
            stall_at, stall_s = self._rand.randrange(1, len(data)), link.stall_seconds
        if stall_at is not None:
            self._write(data[:stall_at])
            self._wait(stall_s)
            data = data[stall_at:]
        self._write(data)
        return True

    def _write(self, data: bytes) -> None:
        link = self.sim.config.link
        pos = 0
        while pos < len(data) and not self.sim.stopping.is_set():
            size = self._rand.randint(1, link.max_chunk) if link.max_chunk > 0 else len(data)
            chunk = data[pos : pos + size]
            self._send(chunk)
            self._wait(len(chunk) * link.byte_time())
            pos += len(chunk)


def _apply_fault(reply: bytes, fault: QueuedFault, rand: random.Random) -> bytes:
    """The reply frame as the fault corrupts it (terminator not included)."""
    colon = reply.find(b":")
    if fault.kind is ReplyFault.GARBLE:
        pos = rand.randrange(colon + 1, len(reply)) if colon + 1 < len(reply) else len(reply)
        return reply[:pos] + b"\x00\xfe#" + reply[pos + 1 :]
    if fault.kind is ReplyFault.WRONG_TRID:
        head, rest = reply[:colon], reply[colon:]
        parts = head.split(b",")
        parts[2] = str((int(parts[2]) % 32767) + 1).encode()
        return b",".join(parts) + rest
    if fault.kind is ReplyFault.BAD_CRC:
        if len(reply) > 5 and reply[-5:-4] == b";":
            good = int(reply[-4:], 16)
            return reply[:-4] + b"%04X" % (good ^ 0x5A5A)
        return reply + b";0000"
    if fault.kind is ReplyFault.CORRUPT_DIGIT:
        body_end = len(reply) - 5 if reply[-5:-4] == b";" else len(reply)
        digits = [i for i in range(colon + 1, body_end) if reply[i : i + 1].isdigit()]
        if digits:
            i = digits[len(digits) // 2]
            new = b"%d" % ((int(reply[i : i + 1]) + 5) % 10)
            return reply[:i] + new + reply[i + 1 :]
    return reply


class GeoComSimulator:
    """The simulated tracker on a pty and a TCP port; `start()` / `stop()` or a context manager."""

    def __init__(
        self,
        source: TargetSource,
        config: SimulatorConfig | None = None,
        faults: FaultInjector | None = None,
        sleep: Callable[[float], None] | None = None,
        now: Callable[[], float] | None = None,
    ) -> None:
        self.config = config or SimulatorConfig()
        self.faults = faults or FaultInjector()
        # `sleep`: how the instrument waits out its measuring time (a simulated clock's, in a station);
        # `now`: that clock, so a reading is of its own instant (`GeoComInstrument._measure`)
        self.instrument = GeoComInstrument(source, self.config.instrument, self.faults,
                                           **({"sleep": sleep} if sleep is not None else {}), now=now)
        self.stopping = threading.Event()
        self._threads: list[threading.Thread] = []
        self._master_fd: int | None = None
        self._slave_fd: int | None = None
        self._listener: socket.socket | None = None
        self._conns: list[socket.socket] = []
        self._conn_lock = threading.Lock()
        self.pty_path: str | None = None
        self.port: int | None = None

    @property
    def url(self) -> str:
        """``socket://<address>:<port>`` for pyserial (after `start()`)."""
        if self.port is None:
            raise RuntimeError("simulator not started or TCP disabled")
        return f"socket://{self.config.address}:{self.port}"

    def start(self) -> GeoComSimulator:
        """Open the pty and the TCP listener and start serving."""
        if not self.config.address.startswith("127."):
            raise ValueError(f"the simulator serves loopback only (127.x.y.z), not {self.config.address}")
        self.stopping.clear()
        if self.config.serve_pty:
            master, slave = os.openpty()
            tty.setraw(slave)  # no echo, no CR/LF translation before the client configures it
            self._master_fd, self._slave_fd = master, slave
            self.pty_path = os.ttyname(slave)
            self._spawn(self._serve_pty, "geocom-pty")
        if self.config.serve_tcp:
            sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((self.config.address, self.config.port))
            sock.listen(4)
            sock.settimeout(_POLL_S)
            self._listener = sock
            self.port = sock.getsockname()[1]
            self._spawn(self._serve_tcp, "geocom-tcp")
        log.info("GeoCOM simulator on %s and %s", self.pty_path, self.port and self.url)
        return self

    def stop(self, timeout: float = 2.0) -> None:
        """Stop all threads and close every descriptor (idempotent)."""
        self.stopping.set()
        for t in self._threads:
            t.join(timeout)
        self._threads.clear()
        self._close_pty()
        if self._listener is not None:
            self._listener.close()
            self._listener = None
        with self._conn_lock:
            for conn in self._conns:
                with contextlib.suppress(OSError):
                    conn.close()
            self._conns.clear()

    def __enter__(self) -> GeoComSimulator:
        return self.start()

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.stop()

    def _spawn(self, target: Callable[[], None], name: str) -> None:
        thread = threading.Thread(target=target, name=name, daemon=True)
        thread.start()
        self._threads.append(thread)

    # --- pty
    def _close_pty(self) -> None:
        for attr in ("_master_fd", "_slave_fd"):
            fd = getattr(self, attr)
            if fd is not None:
                setattr(self, attr, None)
                with contextlib.suppress(OSError):
                    os.close(fd)

    def _serve_pty(self) -> None:
        master = self._master_fd
        assert master is not None

        def recv(timeout: float) -> bytes | None:
            ready, _, _ = select.select([master], [], [], timeout)
            return os.read(master, 4096) if ready else b""

        def send(data: bytes) -> None:
            view = memoryview(data)
            while view:
                view = view[os.write(master, view) :]

        _Session(self, recv, send, self._close_pty, "pty").run()

    # --- tcp
    def _serve_tcp(self) -> None:
        listener = self._listener
        assert listener is not None
        while not self.stopping.is_set():
            try:
                conn, peer = listener.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            with self._conn_lock:
                self._conns.append(conn)
            log.info("tracker client connected from %s", peer)
            self._spawn(lambda c=conn: self._serve_conn(c), "geocom-conn")

    def _serve_conn(self, conn: socket.socket) -> None:
        def recv(timeout: float) -> bytes | None:
            ready, _, _ = select.select([conn], [], [], timeout)
            if not ready:
                return b""
            data = conn.recv(4096)
            return data if data else None  # b"" from recv = peer closed

        def close() -> None:
            with contextlib.suppress(OSError):
                conn.shutdown(socket.SHUT_RDWR)
            with contextlib.suppress(OSError):
                conn.close()

        _Session(self, recv, conn.sendall, close, "tcp").run()
