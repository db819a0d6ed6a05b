"""GeoCOM ASCII framing, value codec, CRC-16 and the one-request-in-flight client.

Frames (Leica GeoCOM reference, "ASCII protocol syntax")::

    request  [<LF>]%R1Q,<RPC>[,<TrId>]:[<P0>][,<P1>,...]<Term>
    reply    %R1P,<RC_COM>[,<TrId>]:<RC>[,<P0>,<P1>,...]<Term>

* ``<Term>`` is CR/LF by default; a leading LF clears the instrument's receive buffer, which is
  how the client resynchronises after a timeout.
* ``<TrId>`` is echoed by the instrument (0 when the request had none). The client numbers every
  request 1..32767 and discards any reply whose id differs: after a timeout the late reply of the
  previous request is still on the wire, and only the id tells it apart from the new one.
* Values: doubles in fixed-point decimal; integers in decimal (or ``0x`` hex); booleans as 0/1;
  strings in double quotes, with bytes outside 0x20..0x7E as ``\\xHH`` and ``\\ " % ~`` escaped by
  a backslash; BYTE values as two hex digits in single quotes (``'2f'``).

CRC-16 (opt-in). The GeoCOM code table has server/client checksum errors (3101/3102) and
"no checksum in ASCII protocol" (3110), but the public manual excerpts do not specify how an ASCII
frame carries one. This project therefore defines an *opt-in* extension, off by default so that
any plain GeoCOM peer works unchanged: the frame gets the suffix ``;HHHH`` — four upper-case hex
digits of CRC-16/ARC (poly 0x8005 reflected, init 0, check value 0xBB3D) over every byte from the
``%`` up to, not including, the ``;``. Without it a digit flipped by line noise is undetectable
(the result still parses); with it, it is caught.
"""

from __future__ import annotations

import logging
import math
import re
import threading
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Protocol

from drivers.tracker.errors import (
    ChecksumError,
    ConnectionLost,
    GarbledReply,
    ProtocolError,
    TrackerTimeout,
)
from drivers.tracker.geocom.codes import ReturnCode, describe

log = logging.getLogger(__name__)

REQUEST_PREFIX = b"%R1Q,"
REPLY_PREFIX = b"%R1P,"
MAX_TRID = 32767
DEFAULT_PRECISION = 15


# ----------------------------------------------------------------------------------------- CRC-16
def _make_crc_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
        table.append(crc)
    return tuple(table)


_CRC_TABLE = _make_crc_table()


def crc16(data: bytes) -> int:
    """CRC-16/ARC of ``data`` (the classic "CRC-16": reflected poly 0x8005, init 0, no final xor)."""
    crc = 0
    for byte in data:
        crc = (crc >> 8) ^ _CRC_TABLE[(crc ^ byte) & 0xFF]
    return crc


def add_crc(frame: bytes) -> bytes:
    """Append the ``;HHHH`` checksum suffix to a frame (without terminator)."""
    return frame + b";%04X" % crc16(frame)


def strip_crc(frame: bytes) -> bytes:
    """The frame without its ``;HHHH`` suffix; ChecksumError if it is missing or wrong."""
    if len(frame) < 5 or frame[-5:-4] != b";":
        raise ChecksumError("CRC-16 enabled but the frame carries no checksum")
    body, tail = frame[:-5], frame[-4:]
    try:
        got = int(tail.decode("ascii"), 16)
    except (UnicodeDecodeError, ValueError) as exc:
        raise ChecksumError(f"unreadable checksum {tail!r}") from exc
    want = crc16(body)
    if got != want:
        raise ChecksumError(f"checksum {got:04X} != computed {want:04X}")
    return body


# ------------------------------------------------------------------------------------ value codec
class Byte(int):
    """A GeoCOM BYTE parameter: sent as two hex digits in single quotes."""

    def __new__(cls, value: int) -> Byte:
        if not 0 <= int(value) <= 0xFF:
            raise ValueError(f"BYTE out of range: {value}")
        return super().__new__(cls, value)


Param = bool | int | float | str | Byte

_STRING_SPECIALS = {"\\", '"', "%", "~"}


def format_double(value: float, precision: int = DEFAULT_PRECISION) -> str:
    """Fixed-point decimal with at most ``precision`` decimals, trailing zeros trimmed (``1.5``)."""
    if not math.isfinite(value):
        raise ValueError(f"GeoCOM cannot carry a non-finite double: {value}")
    text = f"{value:.{precision}f}"
    if "." in text:
        text = text.rstrip("0")
        if text.endswith("."):
            text += "0"
    if text in ("-0.0", "-0"):
        text = "0.0"
    return text


def quote_string(text: str) -> str:
    """A GeoCOM string literal: double quotes, escapes for ``\\ " % ~`` and non-printables."""
    out = ['"']
    for ch in text:
        code = ord(ch)
        if code > 0xFF:
            raise ValueError(f"GeoCOM strings are 8-bit: {ch!r}")
        if ch in _STRING_SPECIALS:
            out.append("\\" + ch)
        elif 0x20 <= code <= 0x7E:
            out.append(ch)
        else:
            out.append(f"\\x{code:02X}")
    out.append('"')
    return "".join(out)


def encode_param(value: Param, precision: int = DEFAULT_PRECISION) -> str:
    """One request parameter as GeoCOM ASCII text."""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, Byte):
        return f"'{int(value):02X}'"
    if isinstance(value, int):
        return str(int(value))
    if isinstance(value, float):
        return format_double(value, precision)
    if isinstance(value, str):
        return quote_string(value)
    raise TypeError(f"unsupported GeoCOM parameter type: {type(value).__name__}")


_INT_RE = re.compile(r"^[+-]?(?:0[xX][0-9a-fA-F]+|[0-9]+)$")
_FLOAT_RE = re.compile(r"^[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?$")
_BYTE_RE = re.compile(r"^'([0-9a-fA-F]{2})'$")


def decode_int(text: str) -> int:
    """A GeoCOM integer (decimal or ``0x`` hex); ValueError otherwise."""
    if not _INT_RE.match(text):
        raise ValueError(f"not a GeoCOM integer: {text!r}")
    return int(text, 0) if "x" in text.lower() else int(text, 10)


def decode_double(text: str) -> float:
    """A GeoCOM double; ValueError for anything else (including nan/inf spelled out)."""
    if not _FLOAT_RE.match(text):
        raise ValueError(f"not a GeoCOM double: {text!r}")
    return float(text)


def decode_byte(text: str) -> int:
    """A GeoCOM BYTE ``'HH'``."""
    match = _BYTE_RE.match(text)
    if not match:
        raise ValueError(f"not a GeoCOM byte: {text!r}")
    return int(match.group(1), 16)


def decode_string(text: str) -> str:
    """A GeoCOM string literal back to text (reverses `quote_string`)."""
    if len(text) < 2 or text[0] != '"' or text[-1] != '"':
        raise ValueError(f"not a GeoCOM string: {text!r}")
    body, out, i = text[1:-1], [], 0
    while i < len(body):
        ch = body[i]
        if ch == '"':
            raise ValueError(f"unescaped quote in string: {text!r}")
        if ch != "\\":
            out.append(ch)
            i += 1
            continue
        if i + 1 >= len(body):
            raise ValueError(f"dangling backslash in string: {text!r}")
        nxt = body[i + 1]
        if nxt in "xX":
            hexdigits = body[i + 2 : i + 4]
            if len(hexdigits) != 2 or not all(c in "0123456789abcdefABCDEF" for c in hexdigits):
                raise ValueError(f"bad \\x escape in string: {text!r}")
            out.append(chr(int(hexdigits, 16)))
            i += 4
        else:
            out.append(nxt)
            i += 2
    return "".join(out)


def split_values(text: str) -> tuple[str, ...]:
    """Split a comma-separated value list, keeping commas inside double-quoted strings."""
    if text == "":
        return ()
    items, current, in_string, i = [], [], False, 0
    while i < len(text):
        ch = text[i]
        if in_string and ch == "\\" and i + 1 < len(text):
            current.append(text[i : i + 2])
            i += 2
            continue
        if ch == '"':
            in_string = not in_string
        if ch == "," and not in_string:
            items.append("".join(current))
            current = []
        else:
            current.append(ch)
        i += 1
    if in_string:
        raise ValueError(f"unterminated string in {text!r}")
    items.append("".join(current))
    return tuple(items)


# -------------------------------------------------------------------------------------- framing
@dataclass(frozen=True)
class Reply:
    """One decoded ``%R1P`` line. ``values`` stay text; the command layer types them."""

    rc_com: int
    trid: int | None
    rc: int
    values: tuple[str, ...]


_REPLY_RE = re.compile(r"^%R1P,([0-9]{1,5})(?:,([0-9]{1,5}))?:([0-9]{1,5})(?:,(.*))?$", re.DOTALL)


def build_request(
    rpc: int,
    params: Sequence[Param] = (),
    trid: int | None = None,
    *,
    crc: bool = False,
    precision: int = DEFAULT_PRECISION,
) -> bytes:
    """A request frame without terminator (``%R1Q,2108,7:100,1``)."""
    if not 0 <= rpc <= 65535:
        raise ValueError(f"RPC number out of range: {rpc}")
    head = f"%R1Q,{rpc}" if trid is None else f"%R1Q,{rpc},{trid}"
    frame = (head + ":" + ",".join(encode_param(p, precision) for p in params)).encode("ascii")
    return add_crc(frame) if crc else frame


def parse_reply(frame: bytes, *, crc: bool = False) -> Reply:
    """Decode one reply frame (no terminator). GarbledReply / ChecksumError on any defect."""
    if crc:
        frame = strip_crc(frame)
    try:
        text = frame.decode("ascii")
    except UnicodeDecodeError as exc:
        raise GarbledReply(f"non-ASCII bytes in reply {frame[:60]!r}") from exc
    if any(not 0x20 <= ord(c) <= 0x7E for c in text):
        raise GarbledReply(f"control characters in reply {frame[:60]!r}")
    match = _REPLY_RE.match(text)
    if not match:
        raise GarbledReply(f"not a GeoCOM reply: {frame[:60]!r}")
    rc_com, trid, rc, rest = match.groups()
    try:
        values = split_values(rest) if rest is not None else ()
    except ValueError as exc:
        raise GarbledReply(str(exc)) from exc
    return Reply(int(rc_com), int(trid) if trid is not None else None, int(rc), values)


def find_reply_frame(line: bytes) -> bytes | None:
    """The last ``%R1P,`` frame in a received line, or None when the line is only junk.

    A stale half line glued to the front of a fresh reply is dropped this way; ``%`` inside a
    string is always escaped, so an unescaped ``%R1P,`` can only start a frame.
    """
    start = line.rfind(REPLY_PREFIX)
    while start > 0 and line[start - 1 : start] == b"\\":
        start = line.rfind(REPLY_PREFIX, 0, start)
    return None if start < 0 else line[start:]


# --------------------------------------------------------------------------------------- client
class LineTransport(Protocol):
    """What the client needs from a transport (see `drivers.tracker.geocom.transport.SerialTransport`)."""

    def write(self, data: bytes) -> None: ...

    def read_line(self, deadline: float) -> bytes: ...

    def discard_input(self) -> None: ...

    @property
    def terminator(self) -> bytes: ...


class GeoComClient:
    """Request/reply over a line transport: one request in flight, transaction ids, resync.

    Thread-safe: a lock spans write-and-read, so concurrent callers queue instead of interleaving.
    Never returns a reply that is not provably the answer to the request just sent.
    """

    def __init__(
        self,
        transport: LineTransport,
        *,
        timeout: float = 2.0,
        crc: bool = False,
        precision: int = DEFAULT_PRECISION,
    ) -> None:
        if not timeout > 0:
            raise ValueError("timeout must be positive and finite")
        self.transport = transport
        self.timeout = float(timeout)
        self.crc = crc
        self.precision = precision
        self._lock = threading.Lock()
        self._trid = 0
        self._resync = True  # first request starts with LF: clears whatever the instrument holds

    def next_trid(self) -> int:
        """The id the next request will carry (1..MAX_TRID, wrapping; 0 means "none")."""
        return self._trid % MAX_TRID + 1

    def call(self, rpc: int, params: Iterable[Param] = (), *, timeout: float | None = None) -> Reply:
        """Send one request and return its reply; raises a typed `TrackerError` otherwise.

        Replies with another transaction id (stale) and lines that are not GeoCOM replies (the
        tail of a stale half line) are logged and skipped until the deadline.
        """
        limit = self.timeout if timeout is None else float(timeout)
        with self._lock:
            trid = self.next_trid()
            self._trid = trid
            frame = build_request(rpc, tuple(params), trid, crc=self.crc, precision=self.precision)
            prefix = b""
            if self._resync:
                self.transport.discard_input()
                prefix = b"\n"
                self._resync = False
            log.debug("-> %r", frame)
            try:
                self.transport.write(prefix + frame + self.transport.terminator)
                return self._await_reply(rpc, trid, time.monotonic() + limit)
            except (TrackerTimeout, GarbledReply, ChecksumError, ConnectionLost):
                self._resync = True
                raise

    def _await_reply(self, rpc: int, trid: int, deadline: float) -> Reply:
        while True:
            try:
                line = self.transport.read_line(deadline)
            except TrackerTimeout as exc:
                raise TrackerTimeout(f"RPC {rpc} (trid {trid}): no reply in time") from exc
            frame = find_reply_frame(line)
            if frame is None:
                log.debug("skipping junk line %r", line[:80])
                continue
            log.debug("<- %r", frame)
            reply = parse_reply(frame, crc=self.crc)
            if reply.trid != trid:
                log.info("discarding stale reply (trid %s, expected %d): %r", reply.trid, trid, frame[:80])
                continue
            if reply.rc_com in (ReturnCode.COM_SRVR_RX_CHECKSUM_ERROR, ReturnCode.COM_CLNT_RX_CHECKSUM_ERROR):
                raise ChecksumError(f"RPC {rpc}: instrument reports {describe(reply.rc_com)}")
            if reply.rc_com != ReturnCode.OK:
                raise ProtocolError(f"RPC {rpc}: communication error {describe(reply.rc_com)}", reply.rc_com)
            return reply
