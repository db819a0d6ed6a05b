"""One heavy test at a time across the suite's workers.

A sweep campaign test runs a 500 Hz servo loop, a simulated station streaming its tracker at 1 kHz and
the streams' joint fit: three of them at once beside the rest of the suite on 2 cores starved a
simulator of the CPU long enough (over the 2.5 s ur_rtde waits) to drop another test's RTDE link.
Tests that hold this lock run one after another; the others are not held up."""

from __future__ import annotations

import contextlib
import fcntl
import time
from collections.abc import Iterator
from pathlib import Path


@contextlib.contextmanager
def one_at_a_time(folder: Path, name: str, timeout_s: float) -> Iterator[None]:
    """Hold the lock `name` (a file in `folder`, which every worker of the run shares) for the block;
    TimeoutError after `timeout_s` of waiting for it."""
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / f"{name}.lock", "w") as handle:
        deadline = time.monotonic() + timeout_s
        while True:
            try:
                fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() > deadline:
                    raise TimeoutError(f"waited {timeout_s:.0f} s for the {name} lock") from None
                time.sleep(0.5)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)
