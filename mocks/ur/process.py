"""Running a simulated controller in its own process, composable with other simulated services.

* `serve(config, services=..., ready=..., stop_event=...)` builds a `SimController` in *this* process,
  starts it plus any extra services (each built by a factory from the controller, so a tracker
  simulator can share its clock and ``true_joints()``), reports the bound ports through `ready`, and
  blocks until stopped (event, SIGTERM or SIGINT).
* `SimProcess` runs `serve` in a child Python process (a fresh interpreter: never fork a process that
  has ur_rtde threads, and no ``__main__`` guard needed in the caller) and talks to it through the
  JSON-lines control channel: ``inject``, ``state``, ``stop``.
  Extra services for the child are named as ``"module:function"`` so they cross the process boundary.
  The child never outlives the process that started it (`_watch_parent`), and its shutdown on a stop,
  SIGTERM or its parent's death is bounded (`_STOP_GRACE`): a service that hangs in ``stop()`` cannot
  leave an orphan simulator holding its ports.
"""

from __future__ import annotations

import importlib
import json
import logging
import os
import selectors
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, Protocol

from hil.arm.blas_threads import limit_blas_threads
from mocks.ur.control_channel import ControlClient, ControlServer
from mocks.ur.controller import SimConfig, SimController

log = logging.getLogger(__name__)


class Service(Protocol):
    """Anything started next to the controller in the same process (e.g. a tracker simulator)."""

    def start(self) -> Any: ...

    def stop(self) -> None: ...


ServiceFactory = Callable[[SimController], Service]


def _import(spec: str) -> Any:
    """A factory from ``"module:function"`` or ``"module:function {json kwargs}"``."""
    target, _, kwargs = spec.partition(" ")
    mod, _, name = target.partition(":")
    fn = getattr(importlib.import_module(mod), name)
    if not kwargs.strip():
        return fn
    options = json.loads(kwargs)
    return lambda controller: fn(controller, **options)


def serve(
    config: SimConfig,
    *,
    services: Sequence[ServiceFactory | str] = (),
    ready: Callable[[dict[str, Any]], None] | None = None,
    stop_event: threading.Event | None = None,
) -> None:
    """Run a simulated controller (and `services`) in this process until `stop_event` or a signal."""
    stop = stop_event or threading.Event()
    controller = SimController(config)
    controller.start()
    running: list[Any] = [controller]
    info: dict[str, Any] = {"address": config.address, "rtde_port": controller.rtde.port,
                            "dashboard_port": controller.dashboard.port,
                            "script_port": controller.script.port, "primary_port": controller.primary.port,
                            "secondary_port": controller.secondary.port, "control_port": None, "services": []}
    try:
        if config.control_port is not None:
            ctl = ControlServer(controller, config.address, config.control_port)
            ctl.start()
            running.append(ctl)
            info["control_port"] = ctl.port
        for factory in services:
            fn = _import(factory) if isinstance(factory, str) else factory
            svc = fn(controller)
            result = svc.start()
            running.append(svc)
            info["services"].append(result if isinstance(result, dict) else repr(svc))
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGTERM, signal.SIGINT):
                signal.signal(sig, lambda *_: stop.set())
        # the controller's own model as it stands once the services are up (a station fits one)
        info["controller"] = controller.calibration.to_dict()
        if ready is not None:
            ready(info)
        while not stop.wait(0.2):
            pass
    finally:
        for svc in reversed(running):
            try:
                svc.stop()
            except Exception:
                log.exception("stopping %r failed", svc)


READY_PREFIX = "UR-SIM-READY "
PARENT_ENV = "UR_SIM_PARENT"  # the pid of the process that started the child (see _watch_parent)
_PARENT_POLL = 0.2  # seconds between the child's checks that its parent is still there
_STOP_GRACE = 2.0  # seconds an orderly shutdown may take before the child exits regardless
#: Starting a simulator is CPU work (imports, a start pose searched among 20 000 configurations): on a
#: loaded machine it takes many times its idle wall time while the child is runnable but not running.
#: `start_timeout` therefore bounds the child's *CPU* time; a child that has had no CPU at all for
#: `_HUNG_S` wall seconds is hung (a starved one still gets its slices), and `_START_WALL_FACTOR` ×
#: `start_timeout` of wall time bounds the whole (where /proc cannot say, that alone applies).
_HUNG_S = 30.0
_START_WALL_FACTOR = 5.0


def _cpu_seconds(pid: int) -> float | None:
    """User + system CPU seconds process `pid` has used (Linux /proc), None where it cannot be read."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


def start_verdict(waited: float, cpu: float | None, idle_for: float, start_timeout: float) -> str | None:
    """Why a simulator still starting after `waited` wall seconds, with `cpu` CPU seconds used (None:
    unknown) and none used for the last `idle_for` wall seconds, has failed; None while it may go on."""
    if cpu is None:
        return f"did not start within {start_timeout:g} s" if waited >= start_timeout else None
    if cpu >= start_timeout:
        return f"used {cpu:g} s of CPU time and did not start within {start_timeout:g} s"
    if idle_for >= _HUNG_S:
        return f"hung while starting (no CPU time for {idle_for:.0f} s)"
    if waited >= _START_WALL_FACTOR * start_timeout:
        return f"did not start within {waited:.0f} s (a machine this loaded cannot run it)"
    return None


def _watch_parent(parent: int, stop: threading.Event) -> None:
    """Child side: set `stop` once the process `parent` is gone, and end this process `_STOP_GRACE`
    seconds after `stop` is set (by this, SIGTERM or SIGINT) if the orderly shutdown has not.

    Not PR_SET_PDEATHSIG: it fires when the *thread* that started the child ends (a short-lived worker
    thread would take the simulator down with it), not the process. The parent's pid comes from the
    environment rather than `os.getppid` at start-up, when the parent may already be gone; an orphan
    is re-parented at once, so a changed `os.getppid` means the parent died, ``kill -9`` included.
    """

    def watch() -> None:
        while os.getppid() == parent and not stop.wait(_PARENT_POLL):
            pass
        stop.set()
        time.sleep(_STOP_GRACE)
        log.warning("shutdown took over %.0f s; exiting regardless", _STOP_GRACE)
        logging.shutdown()
        os._exit(1)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def child_main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the child process: ``python -m mocks.ur CONFIG_JSON [SERVICE...]``.

    Prints one line ``UR-SIM-READY {info json}`` (or ``UR-SIM-READY {"error": ...}``) on stdout.
    """
    args = list(sys.argv[1:] if argv is None else argv)
    limit_blas_threads()  # the controller's 500 Hz loop multiplies 4 x 4 frames: threads only cost
    level = int(os.environ.get("UR_SIM_LOG_LEVEL", logging.WARNING))
    logging.basicConfig(level=level, format="ur-sim %(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    raw = json.loads(args[0])
    raw["version"] = tuple(raw["version"]) if raw.get("version") else None
    config = SimConfig(**raw)

    def ready(info: dict[str, Any]) -> None:
        sys.stdout.write(READY_PREFIX + json.dumps(info) + "\n")
        sys.stdout.flush()

    stop = threading.Event()
    parent = os.environ.get(PARENT_ENV, "")
    if parent.isdigit():
        _watch_parent(int(parent), stop)
    try:
        serve(config, services=args[1:], ready=ready, stop_event=stop)
    except Exception as exc:
        ready({"error": f"{type(exc).__name__}: {exc}"})
        return 1
    return 0


class SimStartError(RuntimeError):
    """The simulator process could not start (e.g. its ports are taken, or a loaded machine).

    For ``hil`` this is a station fault, as a controller that does not boot would be: its CLI maps it to
    exit 3 ("hardware fault"), never to an internal error.
    """


def _project_root() -> str:
    return str(Path(__file__).resolve().parents[2])


class SimProcess:
    """A simulated controller in a child process. ``with SimProcess(cfg) as sim: sim.inject(...)``."""

    def __init__(self, config: SimConfig, services: Sequence[str] = (), *,
                 start_timeout: float = 60.0, log_level: int = logging.WARNING) -> None:
        if config.control_port is None:
            config = replace(config, control_port=0)
        self.config = config
        self.services = list(services)
        self.start_timeout = start_timeout
        self.log_level = log_level
        self.info: dict[str, Any] = {}
        self._proc: subprocess.Popen[str] | None = None
        self._client: ControlClient | None = None

    @property
    def address(self) -> str:
        return self.config.address

    def start(self) -> SimProcess:
        env = dict(os.environ)
        root = _project_root()
        env["PYTHONPATH"] = root + (os.pathsep + env["PYTHONPATH"] if env.get("PYTHONPATH") else "")
        env["UR_SIM_LOG_LEVEL"] = str(self.log_level)
        env[PARENT_ENV] = str(os.getpid())  # the child ends when this process does (_watch_parent)
        cmd = [sys.executable, "-m", "mocks.ur", json.dumps(self.config.to_dict()), *self.services]
        # Its own process group: a controller does not die of the operator's Ctrl-C (or a closed
        # terminal) — the process that started it stops the arm first, then stops the simulator.
        self._proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stdin=subprocess.DEVNULL, text=True,
                                      env=env, cwd=root, process_group=0)
        assert self._proc.stdout is not None
        line = ""
        with selectors.DefaultSelector() as sel:
            sel.register(self._proc.stdout, selectors.EVENT_READ)
            began = time.monotonic()
            last_cpu, last_busy = 0.0, began
            while not line.startswith(READY_PREFIX):
                if not sel.select(1.0):
                    now = time.monotonic()
                    cpu = _cpu_seconds(self._proc.pid)
                    if cpu is not None and cpu > last_cpu:
                        last_cpu, last_busy = cpu, now
                    why = start_verdict(now - began, cpu, now - last_busy, self.start_timeout)
                    if why is not None:
                        self.stop()
                        raise SimStartError(f"simulator on {self.address} {why}")
                    continue
                line = self._proc.stdout.readline()
                if not line:
                    self.stop()
                    raise SimStartError(f"simulator on {self.address} exited during start")
        info = json.loads(line[len(READY_PREFIX):])
        if "error" in info:
            self.stop()
            raise SimStartError(f"simulator on {self.address}: {info['error']}")
        self.info = info
        self._client = ControlClient(self.address, int(info["control_port"]))
        return self

    def inject(self, fault: str, **args: Any) -> dict[str, Any]:
        """Inject a fault (see `mocks.ur.controller`); returns the simulator state after it."""
        assert self._client is not None, "simulator not started"
        return self._client.call(fault, **args)

    def state(self) -> dict[str, Any]:
        assert self._client is not None, "simulator not started"
        return self._client.state()

    def stop(self, timeout: float = 5.0) -> None:
        proc, self._proc = self._proc, None
        if proc is None:
            return
        if proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(timeout)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(timeout)
        if proc.stdout is not None:
            proc.stdout.close()

    def __enter__(self) -> SimProcess:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
