"""In-process stand-ins for the robot and the tracker, driven by a hidden truth, for engine tests.

They satisfy the drivers' protocols the engine holds (`drivers.robot.model.Robot`,
`drivers.tracker.device.Tracker`) and answer with the drivers' own data (`JointReading`,
`TrackerPoint`), and can be told to fail: a protective stop on a given move, a lost beam for a number
of measurements, a dead connection. The arm moves in one call (no `SplitMoves`) and reports no joint
temperatures; subclasses add either.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from drivers.robot.model import ControllerInfo, JointReading
from drivers.tracker.device import Identity, PointStatus, StreamSample, TrackerPoint
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics


class FakeProtectiveStop(Exception):
    pass


class FakeBeamLost(Exception):
    pass


class FakeHardwareFault(Exception):
    pass


@dataclass(frozen=True)
class Reading(JointReading):
    """The driver's joint reading with the fakes' defaults: one sample, no timestamp."""

    samples: int = 1
    timestamp: float = 0.0


@dataclass(frozen=True)
class Point(TrackerPoint):
    """The driver's tracker point from arrays (position, spread), its status OK."""

    status: PointStatus = PointStatus.OK

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", tuple(float(v) for v in self.position))
        object.__setattr__(self, "spread", tuple(float(v) for v in self.spread))


class RobotParts:
    """What `Robot` asks beyond moving, reading and stopping: an in-process arm has nothing to open."""

    info: ControllerInfo | None = None

    def open(self) -> ControllerInfo | None:
        return self.info

    def close(self) -> None:
        pass


class TrackerParts:
    """What `Tracker` asks beyond `measure_point` and `relock`: nothing to open, always ready, no
    stream; `sample` is a one-sample measurement (its beam losses included)."""

    identity: Identity | None = None

    def measure_point(self, samples: int = 1) -> TrackerPoint:
        raise NotImplementedError

    def sample(self) -> TrackerPoint:
        return self.measure_point(1)

    def ready(self) -> bool:
        return True

    def lock_status(self) -> str:
        return "locked in"

    def open(self) -> Any:
        return self

    def close(self) -> None:
        pass

    def __enter__(self) -> Any:
        return self.open()

    def __exit__(self, *exc: object) -> None:
        self.close()

    def stream(self, rate_hz: float, **kwargs: Any) -> Iterator[StreamSample]:
        raise NotImplementedError("the fake tracker takes points, it does not stream")


@dataclass
class FakeArm(RobotParts):
    start: np.ndarray
    encoder_sigma: float = 1e-6
    seed: int = 0
    protective_stop_on_moves: set[int] = field(default_factory=set)  # 1-based move numbers
    fail_on_move: int | None = None
    safety_clear_after_checks: int = 2

    def __post_init__(self) -> None:
        self.q = np.asarray(self.start, float).copy()
        self.moves = 0
        self.stops = 0
        self.in_protective_stop = False
        self._checks = 0
        self.rng = np.random.default_rng(self.seed)
        self.targets: list[np.ndarray] = []

    def move_to(self, q, *, speed=None, acceleration=None):
        self.moves += 1
        if self.fail_on_move == self.moves:
            raise FakeHardwareFault("motor fault")
        if self.moves in self.protective_stop_on_moves:
            self.q = (self.q + np.asarray(q)) / 2  # stopped half way
            self.in_protective_stop = True
            self._checks = 0
            raise FakeProtectiveStop("protective stop")
        self.targets.append(np.asarray(q, float))
        self.q = np.asarray(q, float).copy()
        return Reading(self.q.copy(), np.zeros(6))

    def read_joints(self, samples: int = 1):
        noise = self.rng.normal(0, self.encoder_sigma, (samples, 6))
        return Reading(self.q + noise.mean(0), noise.std(0), samples)

    def stop(self):
        self.stops += 1

    def safety_normal(self) -> bool:
        """The operator clears the stop on the pendant after a few polls."""
        self._checks += 1
        if self._checks >= self.safety_clear_after_checks:
            self.in_protective_stop = False
        return not self.in_protective_stop


@dataclass
class FakeTracker(TrackerParts):
    arm: FakeArm
    truth: Geometry
    sigma: float = 20e-6
    seed: int = 1
    lose_beam: int = 0  # the next N measurements raise FakeBeamLost

    def __post_init__(self) -> None:
        self.kin = Kinematics(self.truth)
        self.rng = np.random.default_rng(self.seed)
        self.measurements = 0
        self.relocks = 0

    def measure_point(self, samples: int = 1):
        if self.lose_beam > 0:
            self.lose_beam -= 1
            raise FakeBeamLost("target lost")
        self.measurements += 1
        p = self.kin.points(self.arm.q)[0]
        s = p + self.rng.normal(0, self.sigma, (samples, 3))
        return Point(s.mean(0), s.std(0), samples)

    def relock(self) -> bool:
        """Each attempt brings the beam back a little closer (after `lose_beam` events in all)."""
        self.relocks += 1
        self.lose_beam = max(0, self.lose_beam - 1)
        return self.lose_beam == 0


def visible_poses(model: Geometry, count: int, rng: np.random.Generator, half_angle_deg: float = 30.0,
                  exclude: np.ndarray | None = None) -> np.ndarray:
    """Random joint vectors whose SMR faces the model's tracker within the acceptance angle."""
    out = []
    kin = Kinematics(model)
    while len(out) < count:
        q = rng.uniform(-np.pi, np.pi, (4000, 6))
        q[:, 2] = rng.uniform(-2.5, 2.5, 4000)
        F = kin.flange_poses(q)
        p = kin.points(q, frame="base")
        to_tracker = model.tracker.translation - p
        to_tracker /= np.linalg.norm(to_tracker, axis=1)[:, None]
        cos = np.einsum("ni,ni->n", F[:, :3, 2], to_tracker)
        ok = (cos > np.cos(np.radians(half_angle_deg))) & (p[:, 2] > 0.05)
        out.extend(q[ok])
    return np.array(out[:count])
