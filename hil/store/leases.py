"""Who may drive an arm: three guards, so one campaign runs in one process and one arm in one campaign.

Two campaigns, one arm: a second ``hil calibrate`` of the same station resumed the
campaign the first one was still running — both measured the same poses and both would have driven
the same arm. Three guards close that, each for a case the others cannot see:

1. **The arm's address lock** (`address_lock`, host-local). Taken on the robot's address *before
   connecting*, so a second process on this machine never even opens the arm's control interface
   (on a UR that would replace the first process's control script). It is an ``fcntl.flock`` on a file
   in a runtime directory: the kernel drops it when its process dies, however it dies, so it never
   needs cleaning up. It cannot see another machine, or the same arm reached under another name.
2. **The robot lease** (``robot:<serial>`` in the store's ``leases`` table). Taken right after connect,
   before the first motion, once the controller has said its serial: one arm is driven by one
   campaign at a time, even two *different* campaigns (different configs) of one store, and whatever
   address or host name reached it. It cannot see a second database file (guard 1 does, on one host).
3. **The campaign lease** (``campaign:<id>``). One running campaign is owned by exactly one process:
   it is what refuses the issue's second command, which found the running campaign and would have
   resumed it. It is taken with the robot lease in one transaction, and before the campaign's
   measurements are read for a resume, so what is resumed is what the owner left.

A lease row names its holder (host, pid, boot id, process start time: `hil.store.owner`) and is taken
by compare-and-set in one transaction: an ``INSERT ... ON CONFLICT DO NOTHING`` under the unique
name, or, when a row is there, a conditional ``UPDATE ... WHERE token = <the token read>`` that takes
it over only if its holder is gone. Plain SQL that a PostgreSQL store runs unchanged. A holder is gone
when `hil.store.owner.is_gone` says so (this host: the process has ended, or the machine rebooted) or,
for a holder on another host (which that cannot check), when its heartbeat is older than the lease's
``ttl``: a `Lease` renews it every ``ttl / 4`` seconds from a thread of its own. A live holder is
never displaced, however old its heartbeat: a process stopped in a debugger still owns the arm.
"""

from __future__ import annotations

import contextlib
import logging
import os
import re
import socket
import tempfile
import threading
import time
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

from hil.errors import InputError
from hil.store.owner import is_gone, this_process

log = logging.getLogger(__name__)

#: Seconds without a heartbeat after which a lease held from another host is taken over.
LEASE_TTL = 60.0

#: Where the address locks live: this variable, else ``$XDG_RUNTIME_DIR/hil``, else the temp dir.
LOCK_DIR_VAR = "HIL_LOCK_DIR"


class LeaseRefused(InputError):
    """Someone else (a live process) is running this campaign or driving this arm."""


def _when(t: float) -> str:
    return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(t))


def describe_holder(owner: Any, since: float) -> str:
    """``pid 1234 on host cell-7 since 2024-05-01 10:02:03``: who holds a lease, from its record."""
    if isinstance(owner, Mapping) and owner.get("pid") is not None:
        who = f"pid {owner.get('pid')} on host {owner.get('host') or '?'}"
    else:
        who = "another process"
    return f"{who} since {_when(since)}"


# Tokens of this process's leases not yet released. A row carrying this process as its owner but a
# token not here was left behind by a release that could not reach the database (a full disk, a lost
# PostgreSQL link): its run has ended, so the row holds nothing (the TUI runs the campaign again in
# the same process once the database is back).
_live_tokens: set[str] = set()
_tokens_lock = threading.Lock()


def holder_gone(owner: Any, heartbeat: float, now: float, ttl: float, token: str | None = None) -> bool:
    """Whether a lease's holder is certainly gone (see the module docstring); `token`, the row's, tells
    a lease this very process released (or failed to) from one it still holds."""
    if isinstance(owner, Mapping) and owner.get("host") == socket.gethostname():
        if token is not None and owner == this_process():
            with _tokens_lock:
                return token not in _live_tokens
        return is_gone(owner)
    return now - heartbeat > ttl


class Lease:
    """A claim on a campaign (and its robot) held in the store, released by `release` or ``with``.

    ``lost`` is set (and ``on_lost`` called with a reason) when the heartbeat finds the lease taken
    over, which only happens if this process looked dead for ``ttl`` seconds to another host: the run
    must then stop, as someone else now drives the arm.
    """

    def __init__(self, store: Any, campaign: str, token: str, names: tuple[str, ...], *,
                 ttl: float = LEASE_TTL, heartbeat: bool = True) -> None:
        self.store, self.campaign, self.token, self.names, self.ttl = store, campaign, token, names, ttl
        with _tokens_lock:
            _live_tokens.add(token)
        self.lost = threading.Event()
        self.on_lost: Callable[[str], None] | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        if heartbeat:
            self._thread = threading.Thread(target=self._beat, name=f"hil-lease-{campaign}", daemon=True)
            self._thread.start()

    def __repr__(self) -> str:
        return f"Lease({self.campaign!r}, {', '.join(self.names)})"

    def __enter__(self) -> Lease:
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()

    def _beat(self) -> None:
        while not self._stop.wait(self.ttl / 4):
            try:
                held = self.store.renew_lease(self)
            except Exception:  # a busy or failing store: the next beat tries again
                continue
            if not held:
                self.lost.set()
                if self.on_lost is not None:
                    self.on_lost(f"campaign {self.campaign}: its lease was taken over by another process")
                return

    def release(self) -> None:
        """Stop the heartbeat and give the lease up (only rows still carrying this lease's token).

        Never raises: it runs while a run unwinds, often after the failure that ended it (a full
        disk), which must stay the news. A lease that could not be deleted is logged; it is taken
        over as soon as this process has ended."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join()
        self._thread = None
        with _tokens_lock:
            _live_tokens.discard(self.token)  # whatever the database says next, this run holds nothing
        if not self.lost.is_set():
            self.lost.set()  # released: a second release does nothing
            try:
                self.store.release_lease(self)
            except Exception as exc:
                log.warning("could not release the lease of campaign %s: %s", self.campaign, exc)


# --- the host-local lock on the arm's address ------------------------------------------------------
def lock_dir(env: Mapping[str, str] | None = None) -> Path:
    """Where address locks live (per user: $XDG_RUNTIME_DIR is; the temp dir gets a per-user folder)."""
    env = os.environ if env is None else env
    if env.get(LOCK_DIR_VAR):
        return Path(env[LOCK_DIR_VAR])
    runtime = env.get("XDG_RUNTIME_DIR", "")
    if runtime and os.path.isabs(runtime) and os.path.isdir(runtime):
        return Path(runtime) / "hil"
    return Path(tempfile.gettempdir()) / f"hil-{os.getuid()}"


def _lock_path(address: str, env: Mapping[str, str] | None = None) -> Path:
    key = re.sub(r"[^A-Za-z0-9._-]", "_", address.strip().lower()) or "_"
    return lock_dir(env) / f"robot-{key[:200]}.lock"


@contextlib.contextmanager
def address_lock(address: str, *, what: str = "hil") -> Iterator[Path]:
    """Hold the host-local lock on the robot at `address` (guard 1); LeaseRefused if another process
    of this user holds it, naming that process. Released on exit, or by the kernel when this process
    dies. Two opens of the file in one process are two locks too (flock locks an open file)."""
    import fcntl

    path = _lock_path(address)
    try:
        path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o600)
    except OSError as exc:
        raise InputError(f"{path}: cannot create the lock of the robot at {address}: "
                         f"{exc.strerror or exc}") from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 512, 0).decode(errors="replace").strip() or "another process"
            raise LeaseRefused(f"the robot at {address} is in use by {holder} (lock {path}); "
                               "wait for it to end, or stop it") from None
        with contextlib.suppress(OSError):  # who holds it, for the refusal's message: best effort
            os.ftruncate(fd, 0)
            os.pwrite(fd, f"{what} (pid {os.getpid()} on host {socket.gethostname()} since "
                          f"{_when(time.time())})\n".encode(), 0)
        yield path
    finally:
        os.close(fd)  # drops the lock; the file stays (removing it would race with a new holder)
