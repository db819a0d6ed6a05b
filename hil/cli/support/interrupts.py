"""Ctrl-C, SIGTERM and a closed terminal's SIGHUP, for a headless run: one clean interruption.

Inside `interruptible()` the first of these signals raises `RunInterrupted` in the main thread,
wherever it is: the engine stops the arm at once and the runner records the campaign as
``interrupted`` (resumable: re-running the same command continues it, as after ``kill -9``). Later
signals are ignored while that unwinds (closing the devices is bounded by the drivers' timeouts), so
a second Ctrl-C cannot cut the cleanup short and leave a traceback. After SIGHUP the terminal is
gone: the standard streams that were on it are pointed at /dev/null, so the final lines cannot fail.

The exit code of an interrupted run is 128 + the signal number (130 for Ctrl-C), the shell's
convention.
"""

from __future__ import annotations

import contextlib
import os
import signal
import threading
from collections.abc import Iterator
from types import FrameType

from hil.campaign.interruption import RunInterrupted

SIGNALS: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


def _leave_terminal() -> None:
    """Point stdin/stdout/stderr that were on the (now hung up) terminal at /dev/null."""
    null = os.open(os.devnull, os.O_RDWR)
    try:
        for fd in (0, 1, 2):
            with contextlib.suppress(OSError):
                if os.isatty(fd):
                    os.dup2(null, fd)
    finally:
        os.close(null)


@contextlib.contextmanager
def interruptible() -> Iterator[list[int]]:
    """Turn SIGINT, SIGTERM and SIGHUP into `RunInterrupted` while the block runs.

    Yields the list of signal numbers received (the first one raised). Outside the main thread (where
    Python cannot install handlers) it changes nothing.
    """
    received: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield received
        return

    def handler(signum: int, frame: FrameType | None) -> None:
        received.append(signum)
        if signum == signal.SIGHUP:
            _leave_terminal()
        if len(received) == 1:
            raise RunInterrupted(signum)

    previous = {sig: signal.signal(sig, handler) for sig in SIGNALS}
    try:
        yield received
    finally:
        for sig, old in previous.items():
            signal.signal(sig, signal.SIG_DFL if old is None else old)  # None: set outside Python
