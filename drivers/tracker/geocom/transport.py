"""Byte transport: pyserial's ``serial_for_url`` with a line reader that honours deadlines.

Any pyserial URL works: a device path (``/dev/ttyUSB0``, a pty slave), ``socket://host:port``,
``rfc2217://host:port`` and ``spy://<url>?file=log.txt`` (traffic logging). Nothing is opened in
the constructor; `open()` or the context manager connects.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from types import TracebackType

import serial

from drivers.tracker.errors import ConnectionLost, TrackerError, TrackerTimeout

log = logging.getLogger(__name__)

try:  # a vanished pty makes pyserial's ioctl/tcflush raise termios.error, which is not an OSError
    import termios

    _PORT_ERRORS: tuple[type[BaseException], ...] = (serial.SerialException, OSError, termios.error)
except ImportError:  # pragma: no cover - Windows
    _PORT_ERRORS = (serial.SerialException, OSError)

PARITIES = {"N": serial.PARITY_NONE, "E": serial.PARITY_EVEN, "O": serial.PARITY_ODD}


@dataclass(frozen=True)
class SerialConfig:
    """Where and how to talk to the tracker. All times in seconds, all finite."""

    url: str
    baudrate: int = 115200
    parity: str = "N"
    bytesize: int = 8
    stopbits: float = 1
    terminator: bytes = b"\r\n"
    poll_interval: float = 0.02  # granularity of one blocking read; bounds how late a deadline is seen
    write_timeout: float = 2.0
    max_line: int = 4096  # a line longer than this is noise, not a reply

    def __post_init__(self) -> None:
        if self.parity not in PARITIES:
            raise ValueError(f"parity must be one of {sorted(PARITIES)}, not {self.parity!r}")
        if not self.terminator:
            raise ValueError("terminator must not be empty")
        for name in ("poll_interval", "write_timeout"):
            value = getattr(self, name)
            if not 0 < value < float("inf"):
                raise ValueError(f"{name} must be positive and finite, not {value}")


class SerialTransport:
    """A line-oriented view of one pyserial port."""

    def __init__(self, config: SerialConfig) -> None:
        self.config = config
        self._port: serial.SerialBase | None = None
        self._buffer = bytearray()

    @property
    def terminator(self) -> bytes:
        """The line terminator (default CR/LF, as GeoCOM's default)."""
        return self.config.terminator

    @property
    def is_open(self) -> bool:
        """True between a successful `open()` and `close()`."""
        return self._port is not None and self._port.is_open

    def open(self) -> SerialTransport:
        """Open the port; ConnectionLost (naming the URL) if it does not exist or refuses."""
        cfg = self.config
        try:
            port = serial.serial_for_url(cfg.url, do_not_open=True)
            port.baudrate = cfg.baudrate
            port.parity = PARITIES[cfg.parity]
            port.bytesize = cfg.bytesize
            port.stopbits = cfg.stopbits
            port.timeout = cfg.poll_interval
            port.write_timeout = cfg.write_timeout
            port.open()
        except (serial.SerialException, OSError, ValueError) as exc:
            raise ConnectionLost(f"cannot open tracker port {cfg.url!r}: {exc}") from exc
        self._port = port
        self._buffer.clear()
        log.info("opened tracker port %s at %d baud", cfg.url, cfg.baudrate)
        return self

    def close(self) -> None:
        """Close the port (idempotent)."""
        port, self._port = self._port, None
        if port is not None:
            try:
                port.close()
            except _PORT_ERRORS:  # already gone: nothing left to release
                log.debug("error while closing %s", self.config.url, exc_info=True)

    def __enter__(self) -> SerialTransport:
        return self.open()

    def __exit__(
        self, exc_type: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def _require(self) -> serial.SerialBase:
        if self._port is None:
            raise TrackerError("tracker port is not open; call open() first")
        return self._port

    def write(self, data: bytes) -> None:
        """Write all of ``data``; ConnectionLost if the device is gone or the write times out."""
        port = self._require()
        try:
            port.write(data)
            port.flush()
        except serial.SerialTimeoutException as exc:
            raise ConnectionLost(f"write to {self.config.url} timed out") from exc
        except _PORT_ERRORS as exc:
            raise ConnectionLost(f"write to {self.config.url} failed: {exc}") from exc

    def discard_input(self) -> None:
        """Drop buffered and pending input (stale bytes from a reply we stopped waiting for)."""
        port = self._require()
        self._buffer.clear()
        try:
            port.reset_input_buffer()
        except _PORT_ERRORS as exc:
            raise ConnectionLost(f"{self.config.url}: {exc}") from exc

    def read_line(self, deadline: float) -> bytes:
        """The next line without its terminator; TrackerTimeout at ``deadline`` (time.monotonic).

        Partial bytes stay buffered across a timeout, so a late tail is seen as a (junk) line and
        skipped by the protocol layer instead of being glued to the next reply.
        """
        port = self._require()
        term = self.config.terminator
        while True:
            idx = self._buffer.find(term)
            if idx >= 0:
                line = bytes(self._buffer[:idx])
                del self._buffer[: idx + len(term)]
                return line
            if len(self._buffer) > self.config.max_line:
                log.warning("dropping %d bytes without terminator", len(self._buffer))
                self._buffer.clear()
            if time.monotonic() >= deadline:
                raise TrackerTimeout(f"no complete line from {self.config.url} in time")
            try:
                waiting = port.in_waiting
                chunk = port.read(max(1, min(waiting, 4096)))
            except _PORT_ERRORS as exc:
                raise ConnectionLost(f"tracker link {self.config.url} lost: {exc}") from exc
            self._buffer.extend(chunk)
