"""Controller status codes as the RTDE guide and the dashboard server report them."""

from __future__ import annotations

from enum import IntEnum


class RobotMode(IntEnum):
    """RTDE ``robot_mode``."""

    NO_CONTROLLER = -1
    DISCONNECTED = 0
    CONFIRM_SAFETY = 1
    BOOTING = 2
    POWER_OFF = 3
    POWER_ON = 4
    IDLE = 5
    BACKDRIVE = 6
    RUNNING = 7
    UPDATING_FIRMWARE = 8


class SafetyMode(IntEnum):
    """RTDE ``safety_mode``."""

    NORMAL = 1
    REDUCED = 2
    PROTECTIVE_STOP = 3
    RECOVERY = 4
    SAFEGUARD_STOP = 5
    SYSTEM_EMERGENCY_STOP = 6
    ROBOT_EMERGENCY_STOP = 7
    VIOLATION = 8
    FAULT = 9


class SafetyBit(IntEnum):
    """Bit positions of RTDE ``safety_status_bits``."""

    NORMAL_MODE = 0
    REDUCED_MODE = 1
    PROTECTIVE_STOPPED = 2
    RECOVERY_MODE = 3
    SAFEGUARD_STOPPED = 4
    SYSTEM_EMERGENCY_STOPPED = 5
    ROBOT_EMERGENCY_STOPPED = 6
    EMERGENCY_STOPPED = 7
    VIOLATION = 8
    FAULT = 9
    STOPPED_DUE_TO_SAFETY = 10


class RobotBit(IntEnum):
    """Bit positions of RTDE ``robot_status_bits``."""

    POWER_ON = 0
    PROGRAM_RUNNING = 1
    TEACH_BUTTON = 2
    POWER_BUTTON = 3


class RuntimeState(IntEnum):
    """RTDE ``runtime_state`` (the program's state)."""

    STOPPING = 0
    STOPPED = 1
    PLAYING = 2
    PAUSING = 3
    PAUSED = 4
    RESUMING = 5
