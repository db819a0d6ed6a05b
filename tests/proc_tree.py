"""Tests' view of a process tree, from /proc (Linux): who descends from a pid, and who is still alive.

Used to check that nothing a killed `hil` started (the ur_rtde client, the simulator, multiprocessing's
resource tracker) is left running after it dies.
"""

from __future__ import annotations

import os
import time
from collections.abc import Iterable


def _stat(pid: int) -> tuple[int, str] | None:
    """(parent pid, state letter) of `pid`, or None once it has gone."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            text = f.read()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()  # the command name may hold spaces and parentheses
    return int(fields[1]), fields[0]


def descendants(root: int) -> set[int]:
    """Every live process below `root` (children, grandchildren...)."""
    parents: dict[int, int] = {}
    for name in os.listdir("/proc"):
        if name.isdigit() and (st := _stat(int(name))) is not None:
            parents[int(name)] = st[0]
    found, frontier = set(), {root}
    while frontier:
        frontier = {pid for pid, ppid in parents.items() if ppid in frontier} - found
        found |= frontier
    return found


def alive(pid: int) -> bool:
    """True while `pid` runs (a zombie, dead but not yet reaped, is not alive)."""
    st = _stat(pid)
    return st is not None and st[1] not in ("Z", "X")


def wait_gone(pids: Iterable[int], timeout: float) -> set[int]:
    """Wait up to `timeout` s for `pids` to end; returns those still alive."""
    left = set(pids)
    deadline = time.monotonic() + timeout
    while True:
        left = {pid for pid in left if alive(pid)}
        if not left or time.monotonic() > deadline:
            return left
        time.sleep(0.05)


def command_line(pid: int) -> str:
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return f.read().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""
