"""Typed errors of the robot driver.

Every failure the caller can act on has its own class, so the campaign engine can map them to
suspenders (protective stop: wait for the operator, then resume) or aborts (e-stop, lost link),
and no error is ever returned as a value.
"""

from __future__ import annotations


class RobotError(Exception):
    """Base of every error the robot driver raises on purpose."""


class RobotConnectionError(RobotError):
    """Problems with the link to the controller."""


class RobotUnreachable(RobotConnectionError):
    """Nothing answers at the address (refused, timed out, or not a UR controller)."""


class ConnectionLost(RobotConnectionError):
    """The link dropped while connected (the arm state is unknown; it may still be moving)."""


class KinematicsInfoUnavailable(RobotConnectionError):
    """The primary interface gave no KinematicsInfo (refused, timed out, closed, or not a UR stream)."""


class UnsupportedVersion(RobotError):
    """The controller software is a version this driver does not support."""


class NotInRemoteControl(RobotError):
    """The teach pendant is in local control: the controller refuses external programs."""


class RobotNotReady(RobotError):
    """Powered off, brakes engaged, or otherwise not in RUNNING mode."""


class SafetyStop(RobotError):
    """The controller's safety system stopped the arm."""


class ProtectiveStop(SafetyStop):
    """A protective stop is (or became) active; unlock it on the pendant or dashboard, then reconnect."""


class EmergencyStop(SafetyStop):
    """An emergency stop is (or became) active."""


class ProgramStopped(RobotError):
    """The control program on the controller is no longer running (stopped from the pendant, ...)."""


class SpeedSliderReduced(RobotError):
    """The speed slider is below the configured minimum: motions would be slower than planned."""


class TargetRejected(RobotError, ValueError):
    """The driver refused a target before moving (never clamped)."""


class JointLimitViolation(TargetRejected):
    """A target joint angle is outside the configured joint limits."""


class KeepInZoneViolation(TargetRejected):
    """The TCP would leave the configured keep-in zone at the target or on the way."""


class StartPositionMismatch(TargetRejected):
    """A streamed trajectory does not start where the arm is: its first servo target would be a jump."""


class MotionTimeout(RobotError, TimeoutError):
    """The arm did not reach the target / become steady in time; it has been stopped."""


class MotionAborted(RobotError):
    """`stop()` was called while a motion (a move_to or a streamed trajectory) was in progress."""
