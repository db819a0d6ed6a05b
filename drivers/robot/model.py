"""Plain data and the robot protocol the orchestrator programs against.

The protocol is what a campaign engine needs from an arm: open/close, move to joints under limits and
wait until steady, read the joints averaged over samples, stop. `URRobot` implements it over ur_rtde;
tests can substitute any object with the same methods. What only some arms can do is a protocol of its
own, checked with ``isinstance``: `SplitMoves` (send a move and wait for it apart) and
`ReadsJointTemperatures`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

if TYPE_CHECKING:  # numpy only in annotations but one method's: a store reader imports this module
    import numpy as np

    from drivers.robot.kinematics_info import KinematicsInfo

TWO_PI = 2 * math.pi


@dataclass(frozen=True)
class ControllerInfo:
    """What the controller says about itself at connect (`Robot.info`)."""

    model: str  # e.g. "UR5e"
    serial: str
    software_version: str  # e.g. "5.15.0.12345"
    version: tuple[int, int, int, int]
    series: str  # "e" or "cb3"
    rate_hz: float
    # the controller's own kinematic model (primary interface); None when that port did not answer
    kinematics: KinematicsInfo | None = None


@dataclass(frozen=True)
class RobotIdentity:
    """Which arm: the one robot identity the drivers, the store and the reports share.

    ``type`` is the catalog name the arm is driven as (``ur5e``); ``serial``, ``model`` and
    ``software`` are what its controller says of itself (``model`` in the controller's spelling,
    ``UR5e``; "" when unknown). ``serial`` identifies the arm across campaigns.
    """

    type: str
    serial: str = ""
    model: str = ""
    software: str = ""

    @classmethod
    def of(cls, type: str, info: ControllerInfo | None) -> RobotIdentity:
        """The arm of catalog `type` as its controller reported itself (`info`; None: nothing known)."""
        if info is None:
            return cls(type)
        # what it reports (a stand-in robot may report less)
        said = {k: getattr(info, k, "") for k in ("serial", "model", "software_version")}
        return cls(type, *(str(said[k] or "") for k in ("serial", "model", "software_version")))

    @classmethod
    def coerce(cls, value: RobotIdentity | Mapping[str, Any] | str) -> RobotIdentity:
        """A RobotIdentity, a mapping with these keys (others ignored), or just a type name."""
        if isinstance(value, RobotIdentity):
            return value
        if isinstance(value, str):
            return cls(type=value)
        names = {f.name for f in fields(cls)}
        return cls(**{k: str(v) for k, v in value.items() if k in names and v is not None})

    def as_dict(self) -> dict[str, str]:
        return {"type": self.type, "serial": self.serial, "model": self.model, "software": self.software}


@dataclass(frozen=True)
class JointReading:
    """Joint angles averaged over `samples` controller cycles, with their spread (standard deviation)."""

    q: np.ndarray
    spread: np.ndarray
    samples: int
    timestamp: float


@dataclass(frozen=True)
class FollowResult:
    """What a streamed trajectory (`URRobot.follow`) reports.

    `times[i]` is when sample i was sent, on ``time.monotonic()``: CLOCK_MONOTONIC on Linux, one
    clock for the whole system, so a parent process can compare the times sent back by the isolated
    client's child with its own (e.g. the tracker's) timestamps without any offset.
    The period figures cover every loop cycle, the hold at the last target included.
    """

    times: np.ndarray  # (N,) send time of each sample, time.monotonic() seconds
    hold_end: float  # time.monotonic() when the hold at the last target ended
    period_count: int  # loop periods measured (samples + hold cycles - 1)
    period_mean: float  # seconds
    period_max: float  # seconds
    # What the arm did, as the controller reported it each loop cycle (RTDE ``timestamp``: the
    # controller's running time on its own clock, and ``actual_q``), hold included, repeats of one
    # controller cycle dropped: the joint stream a sweep joins with the tracker's. (K,) and (K, 6);
    # None from a driver that does not record it.
    controller_t: np.ndarray | None = None
    actual_q: np.ndarray | None = None
    # (L,) when the loop read a frame, on time.monotonic() (as `times`), and (L,) that frame's
    # controller stamp: ties the controller's clock to the host's, for a first guess of a clock map
    # the data then fix. The loop reads the latest frame once a cycle, so these may miss frames the
    # joint stream above has.
    host_t: np.ndarray | None = None
    host_stamps: np.ndarray | None = None


@dataclass(frozen=True)
class KeepInZone:
    """Axis-aligned box (controller base frame, metres) the TCP must stay inside."""

    lower: tuple[float, float, float]
    upper: tuple[float, float, float]

    def contains(self, p: np.ndarray) -> bool:
        import numpy as np

        return bool(np.all(np.asarray(p[:3]) >= self.lower) and np.all(np.asarray(p[:3]) <= self.upper))


@dataclass(frozen=True)
class RobotConfig:
    """How to reach and drive the arm. Limits are the driver's own, tighter than the controller's."""

    host: str
    speed: float = 0.5  # rad/s of the leading joint
    acceleration: float = 1.0  # rad/s^2
    joint_lower: tuple[float, ...] = (-TWO_PI,) * 6
    joint_upper: tuple[float, ...] = (TWO_PI,) * 6
    keep_in: KeepInZone | None = None
    tcp_offset: tuple[float, ...] = (0.0,) * 6  # pose of the TCP in the flange frame (for the keep-in check)
    keep_in_checks: int = 8  # points along the joint-space path checked against the keep-in zone
    keep_in_spacing: float = 0.02  # rad: largest joint change between keep-in checks of a trajectory
    # rad: the first sample of a streamed trajectory may be this far (largest joint) from the arm.
    # After a move_to the arm is within settle_tolerance; 0.01 rad reached in one lookahead time
    # (>= 30 ms) needs < 0.35 rad/s, a gentle start rather than a jump the servo loop must absorb.
    follow_start_tolerance: float = 0.01
    # rad/s per joint: no streamed sample may ask more of a joint than this (None: not checked)
    max_joint_speed: tuple[float, ...] | None = None
    connect_timeout: float = 5.0
    primary_port: int = 30001  # the controller's primary client interface (its KinematicsInfo)
    move_timeout: float = 120.0  # real seconds for one move_to, settling included
    settle_timeout: float = 5.0  # real seconds to become steady after the profile ends
    settle_tolerance: float = 1e-4  # rad: |actual - target| to call the arm arrived
    steady_velocity: float = 1e-3  # rad/s: below this the arm is steady
    min_speed_fraction: float = 1.0  # speed slider below this raises SpeedSliderReduced
    poll_interval: float = 0.005
    # s: how long a failed ur_rtde call waits for the controller state to say why (see _typed_errors)
    explain_timeout: float = 0.5
    rtde_frequency: float = -1.0  # -1: the controller's rate (500 Hz e-series, 125 Hz CB3)
    allowed_versions: tuple[tuple[int, int], ...] = field(default=((3, 15), (5, 6)))

    def __post_init__(self) -> None:
        if len(self.joint_lower) != 6 or len(self.joint_upper) != 6:
            raise ValueError("joint limits need 6 values each")
        if not 0 < self.speed <= 3.14 or not 0 < self.acceleration <= 40:
            raise ValueError("speed must be in (0, 3.14] rad/s and acceleration in (0, 40] rad/s^2")


@runtime_checkable
class Robot(Protocol):
    """What the orchestrator needs from an arm."""

    info: ControllerInfo | None

    def open(self) -> ControllerInfo: ...

    def close(self) -> None: ...

    def move_to(self, q: np.ndarray, *, speed: float | None = None,
                acceleration: float | None = None) -> JointReading: ...

    def read_joints(self, samples: int = 1) -> JointReading: ...

    def stop(self) -> None: ...


@runtime_checkable
class SplitMoves(Protocol):
    """A robot whose move can be sent and waited for apart (`URRobot.start_move` / `wait_move`), so its
    caller can do something else while the arm travels (the campaign engine commits the last point)."""

    def start_move(self, q: np.ndarray, *, speed: float | None = None,
                   acceleration: float | None = None) -> np.ndarray: ...

    def wait_move(self, samples: int = 1) -> JointReading: ...


@runtime_checkable
class ReadsJointTemperatures(Protocol):
    """A robot that reports its six joints' temperatures (°C; RTDE ``joint_temperatures``)."""

    def joint_temperatures(self) -> np.ndarray: ...


@runtime_checkable
class FollowsPaths(Protocol):
    """A robot that streams a whole joint trajectory at its controller's rate (`URRobot.follow`) and
    reports the controller's record of it (`FollowResult.controller_t`, `actual_q`): a MOVEB run and
    a sweep campaign need it."""

    def follow(self, Q: object, *, lookahead: float = 0.1, gain: float = 300.0,
               settle: float = 0.0) -> FollowResult: ...
