"""The station's devices: the real drivers built from the configuration, opened and closed together.

This is where hil meets the hardware: the robot (ur_rtde, in its own process) and the tracker
(GeoCOM over a serial line, or Leica's emScon TPI over TCP, as `tracker.protocol` says), typed by the
drivers' own errors (`HARDWARE_ERRORS`).
What a campaign does when one of them fails is `hil.campaign.suspenders`.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass, field

import numpy as np

from drivers.robot import errors as robot_errors
from drivers.robot.isolated import IsolatedURRobot
from drivers.robot.model import ControllerInfo, KeepInZone, RobotConfig
from drivers.robot.probe import ask_controller as ask_dashboard
from drivers.tracker import errors as tracker_errors
from drivers.tracker.device import Atmosphere, Tracker
from drivers.tracker.emscon import EmsconConfig, EmsconTracker, TcpConfig
from drivers.tracker.geocom import GeoComTracker, SerialConfig, TrackerConfig
from hil.arm.catalog import get_robot
from hil.errors import InputError
from hil.station.config import StationConfig

HARDWARE_ERRORS: tuple[type[BaseException], ...] = (robot_errors.RobotError, tracker_errors.TrackerError)


def robot_config(config: StationConfig) -> RobotConfig:
    """The robot driver's settings: the catalog's joint limits, and the keep-in box for the SMR.

    The driver checks its keep-in zone with the controller's own (nominal) kinematics at the TCP; the
    TCP offset is set to the SMR guess so the box means the same thing to the driver as to the plan.
    """
    spec = get_robot(config.robot["type"])
    smr = config.smr["offset"]
    return RobotConfig(
        host=config.robot["address"], speed=config.robot["speed"],
        acceleration=config.robot["acceleration"],
        joint_lower=tuple(spec.lower), joint_upper=tuple(spec.upper),
        max_joint_speed=tuple(float(v) for v in spec.max_joint_speed),
        keep_in=KeepInZone(tuple(config.keep_in["min"]), tuple(config.keep_in["max"])),
        tcp_offset=(smr[0], smr[1], smr[2], 0.0, 0.0, 0.0),
        connect_timeout=config.timeouts["connect"], move_timeout=config.timeouts["move"])


def tracker_config(config: StationConfig) -> TrackerConfig | EmsconConfig:
    """The tracker driver's settings for the configured protocol (GeoCOM line or emScon TCP)."""
    t = config.tracker
    if not t["url"]:
        raise InputError(f"{config.source}: tracker.url: the tracker's serial device or URL is required")
    atmosphere = Atmosphere(temperature_c=t["temperature"], pressure_mbar=t["pressure"],
                            humidity_percent=t["humidity"])
    stability = config.campaign["stability"]
    if t["protocol"] == "emscon":
        try:
            tcp = TcpConfig(t["url"], connect_timeout=config.timeouts["connect"])
            return EmsconConfig(tcp, timeout=t["timeout"], atmosphere=atmosphere,
                                reflector=t["reflector"] or None,
                                measure_time_ms=max(1, round(t["measure_time"] * 1000)),
                                warmup_timeout=t["warmup"], stability_threshold_m=stability,
                                bird_bath_on_loss=t["bird_bath"])
        except ValueError as exc:
            raise InputError(f"{config.source}: tracker: {exc}") from None
    try:
        serial = SerialConfig(url=t["url"], baudrate=t["baudrate"], parity=t["parity"])
    except ValueError as exc:
        raise InputError(f"{config.source}: tracker: {exc}") from None
    return TrackerConfig(serial=serial, timeout=t["timeout"], atmosphere=atmosphere,
                         stability_threshold_m=stability)


def make_tracker(config: StationConfig) -> Tracker:
    """The configured tracker driver, not yet opened."""
    settings = tracker_config(config)
    if isinstance(settings, EmsconConfig):
        return EmsconTracker(settings)
    return GeoComTracker(settings)


@dataclass
class Devices:
    """The opened robot and tracker of a station.

    The robot is driven through `IsolatedURRobot` (ur_rtde in a child process): a crash of the client
    library on a dropped link becomes a `ConnectionLost` the engine recovers from. That includes MOVEB's
    500 Hz servo streaming, whose loop runs in the child (`follow`).
    """

    robot: IsolatedURRobot
    tracker: Tracker
    closed: bool = field(default=False, init=False, repr=False)

    def close(self) -> None:
        """Close both, once: a run closes them as it ends and the station that opened them on its way
        out (`hil.jobs.station.take_station`); the second close does nothing."""
        if self.closed:
            return
        self.closed = True
        for close in (self.robot.close, self.tracker.close):
            with contextlib.suppress(Exception):  # best effort; both must be attempted
                close()


def ask_controller(config: StationConfig) -> ControllerInfo:
    """Who the station's controller is (model, serial, software), asked before the devices are opened.

    The robot type is checked against this answer (`hil.jobs.station.take_station`), so a controller
    of another robot is refused in milliseconds: opening the driver starts a client process, uploads
    the control script and opens the tracker, and closing them again takes seconds (stopping the
    script). Read-only: nothing is uploaded, started or moved; bounded by ``timeouts.connect``.
    A controller that does not answer is `drivers.robot.errors.RobotUnreachable`, as at open.
    """
    return ask_dashboard(config.robot["address"], config.timeouts["connect"])


def open_devices(config: StationConfig) -> Devices:
    """Connect to the robot (through `IsolatedURRobot`) and the tracker (typed driver errors on failure;
    nothing left open)."""
    robot = IsolatedURRobot(robot_config(config))
    tracker = make_tracker(config)
    robot.open()
    try:
        tracker.open()
    except BaseException:
        robot.close()
        raise
    return Devices(robot, tracker)


def joints_now(devices: Devices) -> np.ndarray:
    """The arm's current joint angles (for the visiting order of the first pose)."""
    return np.asarray(devices.robot.read_joints(1).q, dtype=float)
