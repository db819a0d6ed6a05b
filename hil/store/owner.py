"""Which process runs a campaign, and whether it is still there.

A campaign's status says ``running`` (or paused, suspended, stopping) from its `RunStarted` until its
`RunFinished`; a process that dies in between (kill -9, a power cut, an OOM kill) never writes the
latter. So the store notes the owner of every run — the process that records its `RunStarted` is the
one running the engine — and a reader asks whether that process still exists: same host, same boot,
the pid alive and started at the same moment (a pid is reused; a reboot reuses them all). Anything it
cannot tell (another host, an owner recorded by an older hil) counts as alive: a live run is never
reported dead.
"""

from __future__ import annotations

import os
import socket
from collections.abc import Mapping
from functools import cache
from typing import Any


@cache
def _boot_id() -> str:
    """This boot's id (Linux), "" where there is none."""
    try:
        with open("/proc/sys/kernel/random/boot_id") as f:
            return f.read().strip()
    except OSError:
        return ""


def _stat(pid: int) -> tuple[str, int] | None:
    """(state letter, start time in clock ticks since boot) of `pid` from /proc (Linux), or None."""
    try:
        with open(f"/proc/{int(pid)}/stat") as f:
            text = f.read()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()  # the command name may hold spaces and parentheses
    return fields[0], int(fields[19])


def this_process() -> dict[str, Any]:
    """The owner record of the calling process."""
    stat = _stat(os.getpid())
    return {"host": socket.gethostname(), "pid": os.getpid(), "boot": _boot_id(),
            "started": stat[1] if stat else None}


def is_gone(owner: Any) -> bool:
    """True only when the process `owner` describes has certainly ended."""
    if not isinstance(owner, Mapping) or not isinstance(owner.get("pid"), int):
        return False  # no owner recorded (an older hil): cannot tell
    if owner.get("host") != socket.gethostname():
        return False  # another machine's process: cannot tell
    if owner.get("boot") and _boot_id() and owner["boot"] != _boot_id():
        return True  # the machine has rebooted since (a power cut)
    pid = owner["pid"]
    if pid <= 0:  # never signal a process group
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:
        pass  # exists, another user's
    except OSError:
        return False
    stat = _stat(pid)
    if stat is None:
        return False
    state, started = stat
    if state in ("Z", "X"):
        return True  # killed, not yet reaped by its parent
    return owner.get("started") is not None and owner["started"] != started  # the pid was reused
