"""Fault injection for the simulated tracker: one-shot reply faults and a breakable beam.

Tests queue a fault; the next reply sent on any link consumes it. Beam faults are evaluated by
the instrument at every optical check (lock status, measurement, lock-in, search).
"""

from __future__ import annotations

import enum
import threading
from collections import deque
from dataclasses import dataclass


class ReplyFault(enum.Enum):
    """What to do to the next reply."""

    DROP = "drop"  # never send it
    STALL = "stall"  # send part, pause, send the rest
    DELAY = "delay"  # pause, then send the whole reply (it arrives stale if the client gave up)
    GARBLE = "garble"  # overwrite bytes with noise that is not printable ASCII
    WRONG_TRID = "wrong_trid"  # answer with another transaction id
    BAD_CRC = "bad_crc"  # wrong checksum (or a bogus one if the request had none)
    CORRUPT_DIGIT = "corrupt_digit"  # change one digit: still parses; only CRC-16 can catch it
    TRUNCATE = "truncate"  # send the first half only, no terminator (a partial line)
    UNPLUG = "unplug"  # close the link instead of answering


@dataclass(frozen=True)
class QueuedFault:
    """A reply fault with its parameters."""

    kind: ReplyFault
    seconds: float = 0.0  # STALL duration
    split: float = 0.5  # STALL / TRUNCATE: fraction of the reply sent first


class FaultInjector:
    """Thread-safe fault queue shared by the instrument and its links."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._reply_faults: deque[QueuedFault] = deque()
        self._beam_broken_for: int | None = 0  # None = until restore_target()

    # --- reply faults
    def queue(self, kind: ReplyFault, seconds: float = 0.0, split: float = 0.5) -> None:
        """Apply ``kind`` to the next reply not yet claimed by an earlier queued fault.

        ``seconds`` is the pause of STALL/DELAY; ``split`` the fraction sent before a STALL pause
        or before a TRUNCATE cut.
        """
        if not 0.0 < split < 1.0:
            raise ValueError("split must be in (0, 1)")
        if not 0.0 <= seconds < 3600:
            raise ValueError("stall seconds must be in [0, 3600)")
        with self._lock:
            self._reply_faults.append(QueuedFault(kind, seconds, split))

    def drop_next_reply(self) -> None:
        """The next request gets no answer."""
        self.queue(ReplyFault.DROP)

    def stall_next_reply(self, seconds: float, split: float = 0.5) -> None:
        """The next reply stops after ``split`` of its bytes for ``seconds``."""
        self.queue(ReplyFault.STALL, seconds, split)

    def delay_next_reply(self, seconds: float) -> None:
        """The next reply leaves, complete, only after ``seconds``."""
        self.queue(ReplyFault.DELAY, seconds)

    def garble_next_reply(self) -> None:
        """The next reply carries line noise."""
        self.queue(ReplyFault.GARBLE)

    def wrong_trid_next_reply(self) -> None:
        """The next reply answers with another transaction id."""
        self.queue(ReplyFault.WRONG_TRID)

    def bad_crc_next_reply(self) -> None:
        """The next reply has a wrong CRC-16."""
        self.queue(ReplyFault.BAD_CRC)

    def corrupt_digit_next_reply(self) -> None:
        """One digit of the next reply's values changes (undetectable without CRC-16)."""
        self.queue(ReplyFault.CORRUPT_DIGIT)

    def truncate_next_reply(self, split: float = 0.5) -> None:
        """Only the first part of the next reply is sent, without terminator."""
        self.queue(ReplyFault.TRUNCATE, split=split)

    def unplug(self) -> None:
        """The link closes instead of answering the next request."""
        self.queue(ReplyFault.UNPLUG)

    def take_reply_fault(self) -> QueuedFault | None:
        """Claim the next queued reply fault (called by a link)."""
        with self._lock:
            return self._reply_faults.popleft() if self._reply_faults else None

    def pending(self) -> int:
        """Number of reply faults not yet consumed."""
        with self._lock:
            return len(self._reply_faults)

    # --- beam
    def lose_target(self, checks: int | None = None) -> None:
        """Break the beam for the next ``checks`` optical checks, or until `restore_target`."""
        if checks is not None and checks < 0:
            raise ValueError("checks must be >= 0")
        with self._lock:
            self._beam_broken_for = checks

    def restore_target(self) -> None:
        """Un-break the beam (the tracker still needs a lock-in)."""
        with self._lock:
            self._beam_broken_for = 0

    def beam_broken(self) -> bool:
        """Consume one optical check; True while the injected beam break lasts."""
        with self._lock:
            if self._beam_broken_for is None:
                return True
            if self._beam_broken_for > 0:
                self._beam_broken_for -= 1
                return True
            return False
