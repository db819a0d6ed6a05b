"""The suspenders that keep a campaign going through the station's faults.

The engine knows nothing of ur_rtde or GeoCOM; the suspenders below map the drivers' typed errors to
what the operator must do and to how the run resumes:

====================  ===========================================  =====================================
kind                  raised by                                    cleared when
====================  ===========================================  =====================================
beam_lost             tracker TargetLost (1285/1292/8710, lock 0)  a re-lock works (else the pose is skipped)
unstable_point        tracker UnstablePoint                        at once (the pose is measured again)
tracker_link          tracker TrackerTimeout / GarbledReply        at once (the driver already resynced)
tracker_unplugged     tracker ConnectionLost                       the link opens again
tracker_not_ready     tracker NotReady (laser warm-up, not init.)  the tracker says it is ready
protective_stop       robot ProtectiveStop                         the safety status is normal again
connection_lost       robot ConnectionLost / ProgramStopped        a reconnect succeeds (with backoff)
====================  ===========================================  =====================================

An emergency stop, a speed slider below 100 %, a refused target or anything else is not suspended:
the run stops with a hardware fault.
"""

from __future__ import annotations

from collections.abc import Callable

from drivers.robot import errors as robot_errors
from drivers.robot.isolated import IsolatedURRobot
from drivers.tracker import errors as tracker_errors
from drivers.tracker.device import Tracker
from hil.campaign.engine import Suspender
from hil.station.devices import Devices


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


def _tracker_ready(tracker: Tracker) -> Callable[[], bool]:
    def check() -> bool:
        try:
            return tracker.ready()
        except tracker_errors.TrackerError:
            return False

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
                  "the tracker's link is gone: check the cable (serial/USB adapter, or the network to "
                  "an emScon tracker); the run resumes when it is back", poll),
        Suspender("tracker_not_ready", _is(tracker_errors.NotReady), _tracker_ready(tracker),
                  "the tracker is not ready to measure (laser warming up or not initialized); the run "
                  "goes on by itself when it is", poll, backoff=2.0),
        Suspender("protective_stop", _is(robot_errors.ProtectiveStop), _robot_ready(robot),
                  "protective stop: clear its cause and unlock it on the teach pendant; the run resumes "
                  "by itself", poll),
        Suspender("connection_lost", _is(robot_errors.ConnectionLost, robot_errors.ProgramStopped),
                  _robot_ready(robot),
                  "lost the link to the robot controller: check the network and that the controller is "
                  "in remote control; reconnecting", poll, backoff=2.0),
    ]
