"""The UR driver in a child process, so a crash of the ur_rtde client cannot take the caller down.

ur_rtde 1.6.5 can crash its host process when its automatic reconnection runs after a dropped link
(its receive thread segfaults in ``RTDE::isDataAvailable()``; reproduced against the simulator).
An end-of-line cell must not lose its run to a network blip, so the campaign talks to the arm
through this proxy: every call is forwarded to a `URRobot` living in a child process; if that process
dies, the call raises `ConnectionLost`, and `reconnect()` starts a fresh one. `stop()` travels on a
channel of its own, so it interrupts a `move_to` or a `follow` in progress as it does in-process.

Servo streaming (MOVEB) runs in the child too: `follow(Q)` sends the whole trajectory across the pipe
once, the 500 Hz loop runs next to ur_rtde (`URRobot.follow`), and the samples' send times come back
on the system-wide monotonic clock. A call that outlives its timeout stops the arm and ends the child
(its late reply must never be read as the answer to a later call); `reconnect()` starts a new one.

The child never outlives this process: if it dies (even by ``kill -9``), the child notices within
`_PARENT_POLL` seconds, stops the arm and exits within `_STOP_GRACE` more (`_watch_parent`) instead of
finishing the move unsupervised.
"""

from __future__ import annotations

import contextlib
import multiprocessing as mp
import os
import signal
import threading
import time
from collections.abc import Callable
from multiprocessing.connection import Connection
from typing import Any

import numpy as np

from drivers.robot.errors import ConnectionLost, RobotError
from drivers.robot.model import ControllerInfo, FollowResult, JointReading, RobotConfig
from drivers.robot.trajectory import check_trajectory, keep_in_checkpoints

_START_TIMEOUT = 30.0  # seconds for the child to import ur_rtde and answer
_MARGIN = 10.0  # seconds added to the driver's own timeouts before the proxy gives up on a call
_FK_BUDGET = 0.05  # seconds allowed per keep-in FK check of a trajectory (about 4 ms measured)
_SLOWER = 1.5  # a servo loop may run this much slower than the controller rate before time-out
_TERMINAL_SIGNALS = {signal.SIGINT, signal.SIGHUP}  # what a terminal sends its whole process group
_PARENT_POLL = 0.2  # seconds between the child's checks that the process that started it is there
_STOP_GRACE = 2.0  # seconds the child gives stopping the arm after its parent died, before exiting


@contextlib.contextmanager
def _terminal_signals_blocked() -> Any:
    """Block Ctrl-C and SIGHUP in this thread while a child starts, so the child inherits them blocked
    (the mask survives fork and exec) and cannot die of one, with a traceback, before `_serve` makes
    it ignore them. A signal arriving meanwhile is delivered to this process when unblocked.
    (multiprocessing's resource tracker is started the same way.)"""
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _TERMINAL_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _watch_parent(parent: int, on_gone: Callable[[], None]) -> threading.Event:
    """Child side: once the process `parent` is gone, set the returned event, call `on_gone` (at
    most `_STOP_GRACE` s) and end this process.

    The closed command pipe alone is not enough: the child notices it only between calls, so one in
    progress (a two-minute move_to, a follow, ur_rtde blocked on a dead link) would keep the child —
    and the arm — going long after a ``kill -9`` of its parent. PR_SET_PDEATHSIG is no answer: it
    fires when the *thread* that started the child ends, not the process. The parent's pid, passed
    in rather than read here (it may already be gone), is compared with `os.getppid`, which changes
    as soon as an orphan is re-parented.
    """
    gone = threading.Event()

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(_PARENT_POLL)
        gone.set()

        def quietly() -> None:
            with contextlib.suppress(Exception):  # nobody is left to tell
                on_gone()

        stopper = threading.Thread(target=quietly, daemon=True)
        stopper.start()
        stopper.join(_STOP_GRACE)
        os._exit(1)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()
    return gone


def _serve(commands: Connection, stops: Connection, config: RobotConfig,
           parent: int | None = None) -> None:
    """Child process: run calls on a URRobot until the pipe closes or the parent (pid) dies.

    Ctrl-C and a closed terminal signal the whole foreground process group, this child included; it
    ignores them (it started with them blocked, see `_terminal_signals_blocked`): the parent decides
    what an interruption means — it stops the arm through this child and then closes the pipes,
    which ends it. SIGTERM keeps its default (multiprocessing ends daemonic children with it).
    """
    for sig in _TERMINAL_SIGNALS:
        signal.signal(sig, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, _TERMINAL_SIGNALS)
    from drivers.robot.ur import URRobot

    robot = URRobot(config)

    def stop_and_close() -> None:  # the arm first; then the control script, as a close leaves it
        robot.stop()
        robot.close()

    gone = _watch_parent(parent, stop_and_close) if parent is not None else threading.Event()

    def stopper() -> None:
        while True:
            try:
                stops.recv()
            except (EOFError, OSError):
                return
            with contextlib.suppress(Exception):
                robot.stop()

    threading.Thread(target=stopper, daemon=True).start()
    while True:
        try:
            name, args, kwargs = commands.recv()
        except (EOFError, OSError):
            break
        try:
            reply: tuple[str, Any] = ("ok", getattr(robot, name)(*args, **kwargs))
        except Exception as exc:  # every error crosses back to the caller, typed when picklable
            reply = ("err", exc)
        try:
            commands.send(reply)
        except OSError:  # the parent gave up on this call (its timeout) or is gone
            break
        except Exception:  # an unpicklable error: send its text
            commands.send(("err", RobotError(f"{type(reply[1]).__name__}: {reply[1]}")))
    if gone.is_set():
        # the watcher is stopping the arm (the call it aborted is what ended this loop) and ends the
        # process: closing now would stop the control script under its stopJ
        time.sleep(_STOP_GRACE + 1.0)
    with contextlib.suppress(Exception):
        robot.close()


@contextlib.contextmanager
def _real_stderr() -> Any:
    """The process's own stderr while a child starts.

    multiprocessing hands ``sys.stderr.fileno()`` to its resource tracker; under a TUI (Textual
    replaces sys.stderr with an object without a real descriptor) that is not a valid descriptor.
    """
    import sys

    replaced = sys.stderr
    try:
        ok = replaced is not None and replaced.fileno() >= 0
    except (AttributeError, OSError, ValueError):
        ok = False
    if not ok:
        sys.stderr = sys.__stderr__
    try:
        yield
    finally:
        sys.stderr = replaced


class IsolatedURRobot:
    """A `URRobot` in a child process (same methods); no I/O until `open()`."""

    def __init__(self, config: RobotConfig) -> None:
        self.config = config
        self.info: ControllerInfo | None = None
        self._proc: Any = None
        self._cmd: Connection | None = None
        self._stop: Connection | None = None
        self._lock = threading.Lock()

    # --- the child ---------------------------------------------------------------------------
    def _start(self) -> None:
        ctx = mp.get_context("spawn")
        cmd_parent, cmd_child = ctx.Pipe()
        stop_parent, stop_child = ctx.Pipe()
        proc = ctx.Process(target=_serve, args=(cmd_child, stop_child, self.config, os.getpid()),
                           daemon=True,
                           name=f"ur-client-{self.config.host}")
        with _real_stderr(), _terminal_signals_blocked():
            proc.start()
        cmd_child.close()
        stop_child.close()
        self._proc, self._cmd, self._stop = proc, cmd_parent, stop_parent

    def _kill(self) -> None:
        proc, self._proc = self._proc, None
        for conn in (self._cmd, self._stop):
            if conn is not None:
                with contextlib.suppress(OSError):
                    conn.close()
        self._cmd = self._stop = None
        if proc is not None:
            proc.join(2.0)
            if proc.is_alive():
                proc.kill()
                proc.join(2.0)

    def _call(self, name: str, *args: Any, timeout: float, **kwargs: Any) -> Any:
        with self._lock:
            if self._cmd is None or self._proc is None:
                raise ConnectionLost("not connected; call open()")
            try:
                self._cmd.send((name, args, kwargs))
                ready = self._cmd.poll(timeout)
                if not ready:
                    self.stop()  # the arm may still be moving under the unanswered call
                    self._kill()  # its late reply must not answer the next call
                    raise ConnectionLost(f"the robot client did not answer {name}() within "
                                         f"{timeout:.0f} s; reconnect to continue")
                status, value = self._cmd.recv()
            except (EOFError, OSError):
                code = self._proc.exitcode if self._proc is not None else None
                self._kill()
                raise ConnectionLost(f"the robot client process died during {name}() "
                                     f"(exit code {code}); reconnect to continue") from None
            except (KeyboardInterrupt, SystemExit):  # Ctrl-C or a signal handler's exit, mid-call
                self.stop()  # the arm may be moving under the call: stop it now
                self._kill()  # the call's late reply must not answer the next one
                raise
        if status == "err":
            raise value
        return value

    # --- the Robot protocol --------------------------------------------------------------------
    def open(self) -> ControllerInfo:
        """Start the client process and connect (the URRobot pre-flight checks apply)."""
        if self._proc is None:
            self._start()
        try:
            # connect_timeout twice: the RTDE connect, then the primary interface (ControllerInfo.kinematics)
            self.info = self._call("open", timeout=_START_TIMEOUT + 2 * self.config.connect_timeout)
        except BaseException:
            self._kill()
            raise
        return self.info

    def close(self) -> None:
        if self._proc is not None:
            with contextlib.suppress(RobotError, OSError):
                self._call("close", timeout=self.config.connect_timeout + _MARGIN)
        self._kill()

    def reconnect(self) -> ControllerInfo:
        """Recover the link; a dead (or unresponsive) client process is replaced by a new one."""
        if self._proc is not None and self._proc.is_alive():
            try:
                self.info = self._call("reconnect", timeout=3 * self.config.connect_timeout + _MARGIN)
                return self.info
            except ConnectionLost:
                self._kill()
        else:
            self._kill()
        return self.open()

    def check_status(self) -> None:
        self._call("check_status", timeout=self.config.connect_timeout + _MARGIN)

    def move_to(self, q: Any, *, speed: float | None = None, acceleration: float | None = None,
                samples: int = 1) -> JointReading:
        return self._call("move_to", np.asarray(q, dtype=float).tolist(), speed=speed,
                          acceleration=acceleration, samples=samples,
                          timeout=self.config.move_timeout + self.config.settle_timeout + _MARGIN)

    def start_move(self, q: Any, *, speed: float | None = None,
                   acceleration: float | None = None) -> np.ndarray:
        """`URRobot.start_move` in the child: returns once the move is sent (the target checks, the
        keep-in FK checks included, take well under the connect timeout)."""
        return self._call("start_move", np.asarray(q, dtype=float).tolist(), speed=speed,
                          acceleration=acceleration, timeout=self.config.connect_timeout + _MARGIN)

    def wait_move(self, samples: int = 1) -> JointReading:
        """`URRobot.wait_move` in the child; `stop()` interrupts it as it does a `move_to`. The
        child's own move time-out runs from the send, so this call's limit is the move's whole one."""
        return self._call("wait_move", samples,
                          timeout=self.config.move_timeout + self.config.settle_timeout + _MARGIN)

    def follow(self, Q: Any, *, lookahead: float = 0.1, gain: float = 300.0,
               settle: float = 0.0) -> FollowResult:
        """`URRobot.follow` in the child: the servo loop runs next to ur_rtde, not across the pipe.

        `Q` crosses once; the timeout covers the stream (`_SLOWER` x its duration at the controller
        rate), the hold, the keep-in checks and a margin. A child that dies mid-stream (ur_rtde's
        crash on a dropped link) raises ConnectionLost here; this process carries on.
        """
        cfg = self.config
        Qa = check_trajectory(Q, cfg.joint_lower, cfg.joint_upper)  # the child checks it again
        rate = self.info.rate_hz if self.info else 125.0  # unknown: the slower (CB3) rate
        checks = len(keep_in_checkpoints(Qa, cfg.keep_in_spacing)) if cfg.keep_in is not None else 0
        timeout = _SLOWER * (len(Qa) / rate + settle) + checks * _FK_BUDGET + cfg.connect_timeout + _MARGIN
        return self._call("follow", Qa, lookahead=lookahead, gain=gain, settle=settle, timeout=timeout)

    def read_joints(self, samples: int = 1, timeout: float = 2.0) -> JointReading:
        return self._call("read_joints", samples, timeout=timeout + samples / 100.0 + _MARGIN)

    def tcp_pose(self) -> np.ndarray:
        return self._call("tcp_pose", timeout=_MARGIN)

    def joint_temperatures(self) -> np.ndarray:
        return self._call("joint_temperatures", timeout=_MARGIN)

    def validate_target(self, q: Any) -> np.ndarray:
        return self._call("validate_target", np.asarray(q, dtype=float).tolist(), timeout=_MARGIN)

    def stop(self) -> None:
        """Stop the arm now, from any thread, even while a move_to or a follow is running."""
        stop = self._stop
        if stop is not None:
            with contextlib.suppress(OSError):
                stop.send(True)

    def __enter__(self) -> IsolatedURRobot:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
