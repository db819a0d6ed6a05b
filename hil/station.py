"""A station: the real drivers built from the configuration, and the suspenders that keep a run going.

This is where hil meets the hardware. The engine knows nothing of ur_rtde or GeoCOM; the suspenders
below map the drivers' typed errors to what the operator must do and to how the run resumes:

====================  ===========================================  =====================================
kind                  raised by                                    cleared when
====================  ===========================================  =====================================
beam_lost             tracker TargetLost (1285/1292/8710, lock 0)  a re-lock works (else the pose is skipped)
unstable_point        tracker UnstablePoint                        at once (the pose is measured again)
tracker_link          tracker TrackerTimeout / GarbledReply        at once (the driver already resynced)
tracker_unplugged     tracker ConnectionLost                       the link opens again
protective_stop       robot ProtectiveStop                         the safety status is normal again
connection_lost       robot ConnectionLost / ProgramStopped        a reconnect succeeds (with backoff)
====================  ===========================================  =====================================

An emergency stop, a speed slider below 100 %, a refused target or anything else is not suspended:
the run stops with a hardware fault.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from drivers.robot import errors as robot_errors
from drivers.robot.isolated import IsolatedURRobot
from drivers.robot.model import KeepInZone, RobotConfig
from drivers.tracker import errors as tracker_errors
from drivers.tracker.measurement import Atmosphere, Tracker, TrackerConfig
from drivers.tracker.transport import SerialConfig
from hil.config import StationConfig
from hil.engine import Suspender
from hil.errors import InputError
from hil.robots import get_robot

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


def tracker_config(config: StationConfig) -> TrackerConfig:
    """The tracker driver's settings (serial line, atmosphere, stability threshold)."""
    t = config.tracker
    if not t["url"]:
        raise InputError(f"{config.source}: tracker.url: the tracker's serial device or URL is required")
    try:
        serial = SerialConfig(url=t["url"], baudrate=t["baudrate"], parity=t["parity"])
    except ValueError as exc:
        raise InputError(f"{config.source}: tracker: {exc}") from None
    return TrackerConfig(serial=serial, timeout=t["timeout"],
                         atmosphere=Atmosphere(temperature_c=t["temperature"], pressure_mbar=t["pressure"]),
                         stability_threshold_m=config.campaign["stability"])


@dataclass
class Devices:
    """The opened robot and tracker of a station.

    The robot is driven through `IsolatedURRobot` (ur_rtde in a child process): a crash of the client
    library on a dropped link becomes a `ConnectionLost` the engine recovers from. That includes MOVEB's
    500 Hz servo streaming, whose loop runs in the child (`follow`).
    """

    robot: IsolatedURRobot
    tracker: Tracker

    def close(self) -> None:
        for close in (self.robot.close, self.tracker.close):
            with contextlib.suppress(Exception):  # best effort; both must be attempted
                close()


def open_devices(config: StationConfig) -> Devices:
    """Connect to the robot (through `IsolatedURRobot`) and the tracker (typed driver errors on failure;
    nothing left open)."""
    robot = IsolatedURRobot(robot_config(config))
    tracker = Tracker(tracker_config(config))
    robot.open()
    try:
        tracker.open()
    except BaseException:
        robot.close()
        raise
    return Devices(robot, tracker)


def _is(*kinds: type[BaseException]) -> Callable[[BaseException], bool]:
    return lambda exc: isinstance(exc, kinds)


def _robot_ready(robot: IsolatedURRobot) -> Callable[[], bool]:
    """True once the controller is running normally again; reconnects after the program stopped."""

    def check() -> bool:
        try:
            robot.check_status()
            return True
        except (robot_errors.ProtectiveStop, robot_errors.EmergencyStop):
            return False
        except robot_errors.RobotError:
            robot.reconnect()  # raises while the controller is still not ready: "not clear yet"
            return True

    return check


def _tracker_reopened(tracker: Tracker) -> Callable[[], bool]:
    def check() -> bool:
        tracker.close()
        tracker.open()
        return True

    return check


def suspenders(devices: Devices, poll: float = 0.5, relock_timeout: float = 30.0) -> list[Suspender]:
    """The suspenders of a real (or simulated) station; see the module docstring.

    A beam that does not come back within `relock_timeout` skips the pose: the SMR may simply not be
    visible there (the tracker position was only estimated), and no operator action fixes that.
    """
    robot, tracker = devices.robot, devices.tracker
    return [
        Suspender("beam_lost", _is(tracker_errors.TargetLost), tracker.relock,
                  "the tracker lost the SMR: clear the line of sight (the run re-locks by itself)", poll,
                  timeout=relock_timeout, on_timeout="skip"),
        Suspender("unstable_point", _is(tracker_errors.UnstablePoint), lambda: True,
                  "the SMR reading was not stable; measuring the pose again", poll),
        Suspender("tracker_link", _is(tracker_errors.LinkError), lambda: True,
                  "the tracker's reply was garbled or late; asking again", poll),
        Suspender("tracker_unplugged", _is(tracker_errors.ConnectionLost), _tracker_reopened(tracker),
                  "the tracker's serial link is gone: check the cable and the USB adapter; the run "
                  "resumes when it is back", poll),
        Suspender("protective_stop", _is(robot_errors.ProtectiveStop), _robot_ready(robot),
                  "protective stop: clear its cause and unlock it on the teach pendant; the run resumes "
                  "by itself", poll),
        Suspender("connection_lost", _is(robot_errors.ConnectionLost, robot_errors.ProgramStopped),
                  _robot_ready(robot),
                  "lost the link to the robot controller: check the network and that the controller is "
                  "in remote control; reconnecting", poll, backoff=2.0),
    ]


def joints_now(devices: Devices) -> np.ndarray:
    """The arm's current joint angles (for the visiting order of the first pose)."""
    return np.asarray(devices.robot.read_joints(1).q, dtype=float)
