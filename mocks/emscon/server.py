"""Serve an `EmsconInstrument` over TCP as emScon does: one client at a time, binary TPI packets.

``EmsconSimulator(source).start()`` listens on a loopback address (``.url``, ``tcp://127.0.0.1:<port>``).
Time: the instrument runs on simulated seconds since `start()`, read from the ``clock`` given (the
robot simulator's ``SimClock.now`` in the station, so both simulators agree) or, without one, from
the wall clock times ``ServerConfig.time_scale``. The tracker's own clock, which stamps continuous
samples, counts the same simulated time divided by ``time_scale`` (`tracker_clock`): a quartz in the
simulated world, so its map to the controller's clock stays one straight line also when a paced
station (`hil.station.paced_clock`) switches the simulation between its fast speed and the wall's rate,
and, while the simulation runs at its nominal speed, a second of it passes in a wall second, as a real
tracker's does for the host that maps its stamps by an offset (`drivers.tracker.emscon.tracker`). A
session thread reads commands, answers them, ticks the instrument every ``poll_s`` of wall time and
lets continuous samples out every ``batch_s`` (emScon's TcpDataPacketRate: 3..10 packets/s).

A second connection while a client is served gets ``ErrorResponse(ES_C_Unknown,
MultiConnectionsNotAllowed)`` and is closed; once the client leaves, the next one is accepted. A packet
that does not frame or decode closes the connection. Faults (for tests and the station's control
channel): `drop` (close the client now), `stall` (neither read nor send for N wall seconds), `garbage`
(a few random bytes that are not a packet), `laser_cold` (the laser is not warm for N simulated
seconds).
"""

from __future__ import annotations

import contextlib
import logging
import random
import select
import socket
import struct
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from types import TracebackType

from drivers.tracker.emscon.packets import (
    MAX_PACKET,
    PacketError,
    PacketReader,
    ResultStatus,
    encode_error,
)
from mocks.emscon.instrument import EmsconConfig, EmsconInstrument
from mocks.geocom.target import TargetSource

log = logging.getLogger(__name__)

ES_C_UNKNOWN = 64  # ES_C_Unknown: the command an unsolicited refusal names


@dataclass(frozen=True)
class ServerConfig:
    """Everything `EmsconSimulator` needs besides the target (times in wall seconds)."""

    instrument: EmsconConfig = field(default_factory=EmsconConfig)
    address: str = "127.0.0.1"  # any 127.x.y.z
    port: int = 0  # 0: pick a free one
    # simulated seconds per wall second when no clock is given; with one, the clock's nominal speed:
    # simulated seconds per second of the tracker's clock either way
    time_scale: float = 1.0
    poll_s: float = 0.01  # how often the session ticks the instrument and notices stop()
    batch_s: float = 0.1  # continuous samples leave about this often
    send_timeout_s: float = 2.0  # a client that does not read for this long is dropped
    seed: int | None = 0  # garbage bytes

    def __post_init__(self) -> None:
        if not self.address.startswith("127."):
            raise ValueError(f"the simulator serves loopback only (127.x.y.z), not {self.address}")
        if not (self.time_scale > 0 and self.poll_s > 0 and self.batch_s > 0 and self.send_timeout_s > 0):
            raise ValueError("time_scale, poll_s, batch_s and send_timeout_s must be positive")


class EmsconSimulator:
    """The simulated emScon server; `start()` / `stop()` or a context manager."""

    def __init__(self, source: TargetSource, config: ServerConfig | None = None,
                 clock: Callable[[], float] | None = None) -> None:
        self.config = config or ServerConfig()
        self._clock = clock if clock is not None else self._scaled_wall
        self._t0_wall, self._t0 = self._start_pair()
        self.instrument = EmsconInstrument(source, self.config.instrument, now=0.0)
        self.instrument.source_epoch = self._t0
        self.stopping = threading.Event()
        self._lock = threading.Lock()  # the instrument and the client socket
        self._listener: socket.socket | None = None
        self._client: socket.socket | None = None
        self._threads: list[threading.Thread] = []
        self._stall_until = 0.0
        self._garbage = 0  # garbage bursts to send
        self._dropped: socket.socket | None = None
        self._rand = random.Random(self.config.seed)
        self.port: int | None = None
        self.refused = 0  # connections turned away

    def _start_pair(self) -> tuple[float, float]:
        """(wall clock, simulated clock) at the server's start: the simulated time, and the tracker's
        clock with it, count from here, and the station's true clock map
        (`mocks.station.StationService.clock_map`) rests on it. Without a clock given, simulated time
        is the scaled wall clock from this instant (0 here)."""
        self._t0_wall = time.monotonic()
        return self._t0_wall, self._clock()

    def _scaled_wall(self) -> float:
        return (time.monotonic() - self._t0_wall) * self.config.time_scale

    def now(self) -> float:
        """Simulated seconds since the server started (the tracker's clock)."""
        return self._clock() - self._t0

    @property
    def started_at(self) -> float:
        """The simulated time (the ``clock`` given) at `start()`: where the tracker's clock reads 0."""
        return self._t0

    def tracker_clock(self) -> float:
        """The tracker's own clock (seconds since the server started): the simulated time over
        ``time_scale`` (module docstring)."""
        return self.now() / self.config.time_scale

    def paired_times(self) -> tuple[float, float]:
        """(`now`, `tracker_clock`) of one instant: the instrument maps its samples' stamps onto
        simulated time by such pairs, and the tracker's clock is a function of the simulated one, so
        one read gives both."""
        now = self.now()
        return now, now / self.config.time_scale

    @property
    def url(self) -> str:
        """``tcp://<address>:<port>`` (after `start()`)."""
        if self.port is None:
            raise RuntimeError("simulator not started")
        return f"tcp://{self.config.address}:{self.port}"

    @property
    def connected(self) -> bool:
        return self._client is not None

    # ------------------------------------------------------------------------------ lifecycle
    def start(self) -> EmsconSimulator:
        """Listen and serve."""
        self.stopping.clear()
        self._t0_wall, self._t0 = self._start_pair()
        self.instrument.source_epoch = self._t0  # the source's record is on the same clock
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((self.config.address, self.config.port))
        sock.listen(4)
        sock.settimeout(self.config.poll_s)
        self._listener = sock
        self.port = sock.getsockname()[1]
        self._spawn(self._accept_loop, "emscon-accept")
        log.info("emScon simulator on %s", self.url)
        return self

    def stop(self, timeout: float = 2.0) -> None:
        """Stop all threads and close every socket (idempotent)."""
        self.stopping.set()
        self.drop()
        for t in self._threads:
            t.join(timeout)
        self._threads.clear()
        if self._listener is not None:
            self._listener.close()
            self._listener = None

    def __enter__(self) -> EmsconSimulator:
        return self.start()

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.stop()

    def _spawn(self, target: Callable[[], None], name: str) -> None:
        self._threads = [t for t in self._threads if t.is_alive()]
        thread = threading.Thread(target=target, name=name, daemon=True)
        thread.start()
        self._threads.append(thread)

    # ------------------------------------------------------------------------------ faults
    def drop(self) -> None:
        """Close the client connection now (the session thread notices and cleans up)."""
        conn = self._client
        if conn is not None:
            self._dropped = conn
            with contextlib.suppress(OSError):
                conn.shutdown(socket.SHUT_RDWR)

    def stall(self, seconds: float) -> None:
        """Neither read, answer nor send anything for ``seconds`` of wall time."""
        if not 0 <= seconds < 3600:
            raise ValueError("stall seconds must be in [0, 3600)")
        self._stall_until = time.monotonic() + seconds

    def garbage(self) -> None:
        """Send the client a few random bytes that are not a packet (between two packets)."""
        with self._lock:
            self._garbage += 1

    def laser_cold(self, seconds: float) -> None:
        """The laser is not warm for ``seconds`` of simulated time from now."""
        with self._lock:
            self.instrument.laser_cold(seconds, self.now())

    def _garbage_bytes(self) -> bytes:
        # a size field no packet can have, so a reader knows at once that the stream is out of step
        low, high = self._rand.randint(-(2**31), 7), self._rand.randint(MAX_PACKET + 1, 2**31 - 1)
        size = self._rand.choice([low, high])
        return struct.pack("<i", size) + self._rand.randbytes(self._rand.randint(4, 12))

    # ------------------------------------------------------------------------------ serving
    def _accept_loop(self) -> None:
        listener = self._listener
        assert listener is not None
        while not self.stopping.is_set():
            try:
                conn, peer = listener.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            conn.settimeout(self.config.send_timeout_s)
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            if self._busy():
                self.refused += 1
                log.info("emScon: refusing a second client from %s", peer)
                with contextlib.suppress(OSError):
                    conn.sendall(encode_error(ES_C_UNKNOWN, ResultStatus.MultiConnectionsNotAllowed))
                _close(conn)
                continue
            log.info("emScon client connected from %s", peer)
            self._client = conn
            self._spawn(lambda c=conn: self._session(c), "emscon-session")

    def _stalled(self) -> bool:
        return time.monotonic() < self._stall_until

    def _busy(self) -> bool:
        """Whether a client is being served (one that has just hung up is waited out, not counted)."""
        conn = self._client
        if conn is None:
            return False
        if _peer_closed(conn):
            deadline = time.monotonic() + 1.0
            while self._client is conn and time.monotonic() < deadline:
                self.stopping.wait(0.002)
        return self._client is not None

    def _session(self, conn: socket.socket) -> None:
        reader = PacketReader()
        last_flush = time.monotonic()
        try:
            while not self.stopping.is_set() and self._dropped is not conn:
                if self._stalled():
                    self.stopping.wait(self.config.poll_s)
                    continue
                ready, _, _ = select.select([conn], [], [], self._wait())
                if self._stalled():  # (a stall that began while waiting holds what just arrived)
                    continue
                if ready:
                    data = conn.recv(65536)
                    if not data:
                        return  # the client closed (or a drop fault shut the socket)
                    try:
                        packets = reader.feed(data)
                    except PacketError as exc:
                        log.info("emScon: closing a stream out of step: %s", exc)
                        return
                    for packet in packets:
                        with self._lock:
                            try:
                                out = self.instrument.handle(packet, *self.paired_times())
                            except PacketError as exc:
                                log.info("emScon: closing after an undecodable packet: %s", exc)
                                return
                        self._send(conn, out)
                flush = time.monotonic() - last_flush >= self.config.batch_s
                if flush:
                    last_flush = time.monotonic()
                with self._lock:
                    now, clock = self.paired_times()
                    out = self.instrument.tick(now, flush=flush, watch=flush, clock=clock)
                    bursts, self._garbage = self._garbage, 0
                out += [self._garbage_bytes() for _ in range(bursts)]
                self._send(conn, out)
        except OSError as exc:
            log.info("emScon: client link error %s", exc)
        finally:
            with self._lock:
                self.instrument.disconnect()
            self._client = None
            _close(conn)
            log.info("emScon client gone")

    def _wait(self) -> float:
        """Wall seconds to wait for the client before ticking: `poll_s`, or less when the instrument has
        something due sooner (`EmsconInstrument.next_due`), so a stationary result leaves at the end of
        its measuring time and not up to a poll later."""
        with self._lock:
            due = self.instrument.next_due()
            if due is None:
                return self.config.poll_s
            now = self.now()
            return min(self.config.poll_s, max(0.0, self.instrument.wall_seconds(due - now)))

    def _send(self, conn: socket.socket, packets: list[bytes]) -> None:
        if packets:
            conn.sendall(b"".join(packets))


def _peer_closed(conn: socket.socket) -> bool:
    """Whether the other end has closed (an EOF is waiting); unread data is not consumed."""
    try:
        ready, _, _ = select.select([conn], [], [], 0)
        return bool(ready) and conn.recv(1, socket.MSG_PEEK | socket.MSG_DONTWAIT) == b""
    except (OSError, ValueError):
        return True


def _close(conn: socket.socket) -> None:
    with contextlib.suppress(OSError):
        conn.shutdown(socket.SHUT_RDWR)
    with contextlib.suppress(OSError):
        conn.close()
