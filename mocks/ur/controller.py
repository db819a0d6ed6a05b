"""The whole simulated controller: arm model, clock, tick thread and its protocol servers.

`SimController` is the in-process object; `mocks.ur.process` runs one in its own process (the ur_rtde
Python constructors hold the GIL, so client and simulator must never share an interpreter). Faults go
through `inject(name, **args)`, the single entry point shared by tests, ``hil sim`` options and the
JSON-lines control channel:

=========================  ===============================================================
``protective_stop``        safety protective stop (also mid-move); program stops, arm brakes
``emergency_stop``         robot e-stop (``system=True`` for a system e-stop)
``release_emergency_stop`` twist the button out: safety normal, arm powered off
``drop_connection``        close every client link (RTDE, dashboard, script, primary, secondary);
                           ``refuse_s`` seconds of refused reconnects; ``stop_program`` (default
                           True) as an RTDE watchdog would
``stall``                  ``on=True``: stop sending RTDE data (clients time out after 2.5 s) and
                           primary/secondary robot state
``remote_control``         ``on=False``: local control (dashboard refuses, programs refused)
``stop_program``           the program stops (someone pressed stop on the pendant)
``speed_slider``           ``fraction`` in [0, 1]
``power_off`` / ``power_on`` / ``brake_release``
``set_joints``             ``q``: teleport the arm (test setup)
``clear``                  everything back to normal, arm running, program stopped
=========================  ===============================================================

The controller's own kinematic model — nominal DH plus its factory calibration deltas — drives
everything it computes (``actual_TCP_pose``, moveL/servoL targets, FK/IK) and is what its primary and
secondary interfaces publish as KinematicsInfo. It comes from ``SimConfig.controller`` (the JSON
block of docs/design.md, Contracts: the controller's own calibration) or is drawn per
robot from the seed (`mocks.ur.factory_calibration`);
`SimController.set_calibration` swaps it (the simulated station fits one to its truth).
"""

from __future__ import annotations

import importlib
import logging
import threading
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from hil.arm.controller_model import ControllerCalibration
from hil.calibration.synthetic import ENCODER_SIGMA
from mocks.ur.arm import ArmConfig, SimArm
from mocks.ur.clock import SimClock
from mocks.ur.dashboard import DashboardServer
from mocks.ur.factory_calibration import random_factory_calibration
from mocks.ur.hil_model import controller_fk
from mocks.ur.kin import FkFn
from mocks.ur.primary_server import PrimaryServer
from mocks.ur.robot_state import kinematics_info
from mocks.ur.rtde_server import RtdeServer
from mocks.ur.script_server import ScriptServer
from mocks.ur.status import RobotMode, SafetyMode

log = logging.getLogger(__name__)

_CB3 = {"ur3", "ur5", "ur10"}


@dataclass
class SimConfig:
    """Everything needed to build a simulated controller; plain data so it crosses process boundaries."""

    address: str = "127.0.0.1"
    robot: str = "ur5e"
    speed: float = 1.0
    version: tuple[int, int, int, int] | None = None  # None: 5.15 (e-series) or 3.15 (CB3), by robot
    serial: str = "20235500001"
    model: str | None = None  # dashboard "get robot model"; default from `robot`
    rtde_port: int = 30004
    dashboard_port: int = 29999
    script_port: int = 30003
    primary_port: int = 30001  # primary client interface (robot state at 10 Hz); 0 = any free port
    secondary_port: int = 30002  # secondary client interface; 0 = any free port
    control_port: int | None = 0  # JSON-lines fault channel; 0 = any free port, None = off
    rate_hz: float | None = None  # default 500 (e-series) / 125 (CB3)
    encoder_noise: float = ENCODER_SIGMA  # rad, std of actual_q (hil.calibration.synthetic.ENCODER_SIGMA)
    seed: int = 0
    q_home: list[float] | None = None
    lower: list[float] | None = None
    upper: list[float] | None = None
    max_speed: list[float] | None = None
    remote_control: bool = True
    speed_slider: float = 1.0
    # the controller's factory calibration, the JSON block of docs/design.md, Contracts: the
    # controller's own calibration ({"delta_theta": [6], ...});
    # None: drawn for this robot from `seed` (mocks.ur.factory_calibration.random_factory_calibration)
    controller: dict[str, Any] | None = None
    fk_factory: str | None = None  # "module:function"(robot) -> FK callable replacing the controller's
    # own model (tests only: the KinematicsInfo served then does not describe it); None: its own model
    faults: list[dict[str, Any]] = field(default_factory=list)  # injected right after start

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def resolve_calibration(config: SimConfig) -> ControllerCalibration:
    """The controller's factory calibration: the config's block, or one drawn for the robot by seed."""
    if config.controller is not None:
        return ControllerCalibration.from_dict(config.controller, "SimConfig.controller")
    return random_factory_calibration(config.robot.lower(), config.seed)


def resolve_fk(config: SimConfig, calibration: ControllerCalibration | None = None) -> FkFn:
    """The controller's FK: the config's factory if given, else its own calibrated model."""
    if config.fk_factory:
        mod, _, fn = config.fk_factory.partition(":")
        factory = getattr(importlib.import_module(mod), fn)
        return factory(config.robot)
    return controller_fk(config.robot.lower(), calibration or resolve_calibration(config))


class SimController:
    """Arm + clock + RTDE/dashboard/script servers + the tick thread. Use as a context manager."""

    def __init__(self, config: SimConfig, fk: FkFn | None = None, clock: SimClock | None = None) -> None:
        self.config = config
        self.clock = clock if clock is not None else SimClock(config.speed)
        # faults of services in the same process (the tracker): name -> action(**args)
        self.extra_faults: dict[str, Callable[..., Any]] = {}
        # figures of services in the same process, reported by `state` under "services": name -> reader
        self.extra_state: dict[str, Callable[[], Any]] = {}
        robot = config.robot.lower()
        rate = config.rate_hz or (125.0 if robot in _CB3 else 500.0)
        arm_cfg = ArmConfig(robot=robot, rate_hz=rate, encoder_noise=config.encoder_noise, seed=config.seed)
        try:
            from mocks.ur.hil_model import limits

            arm_cfg.lower, arm_cfg.upper, arm_cfg.max_speed = limits(robot)
        except (ImportError, ValueError, KeyError):
            log.debug("no hil catalog entry for %s: default limits", robot)
        if config.q_home is not None:
            arm_cfg.q_home = np.array(config.q_home, dtype=float)
        if config.lower is not None:
            arm_cfg.lower = np.array(config.lower, dtype=float)
        if config.upper is not None:
            arm_cfg.upper = np.array(config.upper, dtype=float)
        if config.max_speed is not None:
            arm_cfg.max_speed = np.array(config.max_speed, dtype=float)
        self.calibration = resolve_calibration(config)
        self._kinematics_info = self._kinematics_package(self.calibration)
        self.arm = SimArm(arm_cfg, fk if fk is not None else resolve_fk(config, self.calibration), self.clock)
        self.arm.remote_control = config.remote_control
        self.arm.speed_slider = config.speed_slider
        model = config.model or robot.upper().rstrip("E")
        version = tuple(config.version) if config.version else (
            (3, 15, 8, 106339) if robot in _CB3 else (5, 15, 0, 12345))
        host = config.address
        self.rtde = RtdeServer(self.arm, host, config.rtde_port, version)  # type: ignore[arg-type]
        self.dashboard = DashboardServer(self.arm, host, config.dashboard_port, model=model,
                                         serial=config.serial, version=version)  # type: ignore[arg-type]
        self.script = ScriptServer(self.arm, host, config.script_port)
        self.primary = PrimaryServer(self.arm, host, config.primary_port, name="primary", version=version,
                                     kinematics=lambda: self._kinematics_info)
        self.secondary = PrimaryServer(self.arm, host, config.secondary_port, name="secondary",
                                       version=version, kinematics=lambda: self._kinematics_info)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.tick_count = 0
        self.late_ticks = 0
        self.max_tick_gap = 0.0  # wall seconds (`_run`)

    @property
    def servers(self) -> tuple[Any, ...]:
        """Every protocol server of the controller (each a `mocks.ur.net.TcpService`)."""
        return (self.rtde, self.dashboard, self.script, self.primary, self.secondary)

    # ----------------------------------------------------------------- its own kinematic model
    def _kinematics_package(self, calibration: ControllerCalibration) -> bytes:
        theta, a, d, alpha = calibration.dh(self.config.robot.lower())
        return kinematics_info(calibration.checksums(), theta, a, d, alpha)

    def set_calibration(self, calibration: ControllerCalibration) -> None:
        """Move, report and solve FK/IK with `calibration` from now on, and publish it (thread-safe).

        The arm's model and the KinematicsInfo served are swapped together under the arm's lock;
        a custom ``fk_factory`` is replaced too (the controller's model is now this calibration).
        """
        fk = controller_fk(self.config.robot.lower(), calibration)
        package = self._kinematics_package(calibration)
        with self.arm.lock:
            self.arm.set_fk(fk)
            self.calibration = calibration
            self._kinematics_info = package

    # ----------------------------------------------------------------- lifecycle
    def start(self) -> SimController:
        """Bind every port (raises OSError on a clash, before anything runs) and start ticking."""
        started = []
        try:
            for srv in self.servers:
                srv.start()
                started.append(srv)
        except OSError:
            for srv in started:
                srv.stop()
            raise
        self._thread = threading.Thread(target=self._run, name="ur-sim-tick", daemon=True)
        self._thread.start()
        for fault in self.config.faults:
            args = dict(fault)
            self.inject(args.pop("name"), **args)
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
        for srv in self.servers:
            srv.stop()

    def __enter__(self) -> SimController:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _run(self) -> None:
        period = 1.0 / self.arm.config.rate_hz
        deadline = time.monotonic()
        last = deadline
        while not self._stop.is_set():
            started = time.monotonic()
            # the longest wall time between two ticks (and so between two RTDE packets): how starved
            # this process has been; ur_rtde drops its link after 2.5 s without data
            self.max_tick_gap = max(self.max_tick_gap, started - last)
            last = started
            self.arm.tick()
            self.rtde.broadcast(self.tick_count)
            self.tick_count += 1
            deadline += period
            delay = deadline - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            elif delay < -period:
                # fell behind (a loaded machine): the next tick steps the motion through every missed
                # cycle (`SimArm.tick`), so bursting ticks to catch up gains nothing and would hold the
                # GIL from the protocol servers and the trackers in this process; yield to them instead
                self.late_ticks += 1
                deadline = time.monotonic()
                time.sleep(0)

    # ----------------------------------------------------------------- readers for other services
    def true_joints(self) -> np.ndarray:
        """The arm's physical joint angles (thread-safe), for a world/tracker simulator."""
        return self.arm.true_joints()

    def joint_directions(self) -> np.ndarray:
        """The sign of each joint's last motion (thread-safe): which side its lost motion lags on."""
        return self.arm.joint_directions()

    def state(self) -> dict[str, Any]:
        """A JSON-friendly summary of the controller (for tests and the control channel)."""
        a = self.arm
        with a.lock:
            return {
                "q": a.q.tolist(),
                "actual_q": a.actual_q.tolist(),
                "moving": a.motion is not None,
                "robot_mode": a.robot_mode.name,
                "safety_mode": a.safety_mode.name,
                "runtime_state": a.runtime_state.name,
                "program": a.program.name if a.program else None,
                "remote_control": a.remote_control,
                "speed_slider": a.speed_slider,
                "tcp": a.tcp.tolist(),
                "time": self.clock.now(),
                "speed": self.clock.speed,
                "last_error": a.last_error,
                "programs_received": self.script.programs_received,
                "rtde_connections": self.rtde.connection_count(),
                "primary_connections": self.primary.connection_count(),
                "secondary_connections": self.secondary.connection_count(),
                "late_ticks": self.late_ticks,
                "max_tick_gap_s": self.max_tick_gap,
                "motion_seconds": a.motion_seconds,
                "joint_moves": a.joint_moves,
                "services": {name: read() for name, read in self.extra_state.items()},
                "controller": self.calibration.to_dict(),
            }

    def pace(self, speed: float) -> dict[str, float]:
        """Run the clock at `speed` simulated seconds per wall second from now (`hil.station.paced_clock`:
        fast while the host waits on the station, the wall's rate while it computes); returns the clock's
        ``time`` at the switch and its ``speed``."""
        if not speed > 0 or speed == float("inf"):
            raise ValueError(f"pace: speed must be a positive number, got {speed}")
        self.clock.speed = speed
        return {"time": self.clock.now(), "speed": self.clock.speed}

    # ----------------------------------------------------------------- faults
    def inject(self, name: str, **args: Any) -> dict[str, Any]:
        """Apply one fault or setup action (see the module docstring); returns the new state."""
        a = self.arm
        if name == "protective_stop":
            a.protective_stop(str(args.get("reason", "injected")))
        elif name == "emergency_stop":
            a.emergency_stop(system=bool(args.get("system", False)))
        elif name == "release_emergency_stop":
            a.release_emergency_stop()
        elif name == "drop_connection":
            # the link goes first; the controller's watchdog then stops the program (as on a real arm)
            refuse = float(args.get("refuse_s", 0.0))
            for srv in self.servers:
                srv.drop(refuse)
            if args.get("stop_program", True):
                a.stop_program(decel=8.0)
        elif name == "stall":
            on = bool(args.get("on", True))
            self.rtde.stalled = self.primary.stalled = self.secondary.stalled = on
        elif name == "remote_control":
            a.set_remote_control(bool(args.get("on", True)))
        elif name == "stop_program":
            a.stop_program()
        elif name == "speed_slider":
            a.set_speed_slider(float(args["fraction"]))
        elif name == "power_off":
            a.power_off()
        elif name == "power_on":
            a.power_on()
        elif name == "brake_release":
            a.brake_release()
        elif name == "set_joints":
            a.set_joints(np.array(args["q"], dtype=float))
        elif name == "set_speed":
            self.clock.speed = float(args["speed"])
        elif name == "dashboard_unresponsive":
            self.dashboard.unresponsive = bool(args.get("on", True))
        elif name == "clear":
            with a.lock:
                a.estop_latched = False
                a.safety_mode = SafetyMode.NORMAL
                a.protective_stop_at = None
                a.robot_mode = RobotMode.RUNNING
                a.remote_control = True
                a.speed_slider = 1.0
                self.rtde.stalled = self.primary.stalled = self.secondary.stalled = False
                self.dashboard.unresponsive = False
        elif name in self.extra_faults:
            self.extra_faults[name](**args)
        else:
            raise ValueError(f"unknown fault {name!r}")
        return self.state()
