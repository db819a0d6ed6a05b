"""The UR robot driver (over ur_rtde) and the robot protocol the orchestrator programs against."""

from typing import TYPE_CHECKING

from drivers.robot.errors import (
    ConnectionLost,
    EmergencyStop,
    JointLimitViolation,
    KeepInZoneViolation,
    KinematicsInfoUnavailable,
    MotionAborted,
    MotionTimeout,
    NotInRemoteControl,
    ProgramStopped,
    ProtectiveStop,
    RobotConnectionError,
    RobotError,
    RobotNotReady,
    RobotUnreachable,
    SafetyStop,
    SpeedSliderReduced,
    StartPositionMismatch,
    TargetRejected,
    UnsupportedVersion,
)

if TYPE_CHECKING:
    from drivers.robot.kinematics_info import KinematicsInfo, read_kinematics_info
    from drivers.robot.model import (
        ControllerInfo,
        FollowResult,
        JointReading,
        KeepInZone,
        Robot,
        RobotConfig,
        RobotIdentity,
    )
    from drivers.robot.ur import ServoStream, URRobot

#: The names below the errors, by the module that defines them, imported when first asked for: a
#: reader of the store needs `RobotIdentity` and nothing of ur_rtde's driver or numpy (``hil history``'s
#: start-up; bench/cli_startup.py).
_LAZY = {
    "KinematicsInfo": "kinematics_info", "read_kinematics_info": "kinematics_info",
    "ControllerInfo": "model", "FollowResult": "model", "JointReading": "model", "KeepInZone": "model",
    "Robot": "model", "RobotConfig": "model", "RobotIdentity": "model",
    "ServoStream": "ur", "URRobot": "ur",
}


def __getattr__(name: str) -> object:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
    globals()[name] = value
    return value


__all__ = [
    "ConnectionLost",
    "ControllerInfo",
    "EmergencyStop",
    "FollowResult",
    "JointLimitViolation",
    "JointReading",
    "KeepInZone",
    "KeepInZoneViolation",
    "KinematicsInfo",
    "KinematicsInfoUnavailable",
    "MotionAborted",
    "MotionTimeout",
    "NotInRemoteControl",
    "ProgramStopped",
    "ProtectiveStop",
    "Robot",
    "RobotConfig",
    "RobotConnectionError",
    "RobotError",
    "RobotIdentity",
    "RobotNotReady",
    "RobotUnreachable",
    "SafetyStop",
    "ServoStream",
    "SpeedSliderReduced",
    "StartPositionMismatch",
    "TargetRejected",
    "URRobot",
    "UnsupportedVersion",
    "read_kinematics_info",
]
