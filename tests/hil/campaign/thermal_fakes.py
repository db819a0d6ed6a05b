"""A fake station whose arm grows as it warms up, on a virtual clock, for warm-up and drift tests.

The clock is the station's: moves, settling and measuring advance it (no wall-clock time passes), so a
40-minute warm-up runs in a fraction of a second. The tracker sees the true arm at the clock's time,
`Geometry.warmed(t)` (docs/design.md, Contracts: non-geometric errors); the arm reports its joint
temperatures as the simulator does (ambient + ΔT(t)).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from tests.hil.campaign.fakes import FakeArm, FakeTracker, Point

#: The lab's air (°C) the fake joints start at.
AMBIENT = 25.0


class VirtualClock:
    """The engine's clock, advanced only by what the station does (moves, settling, measuring)."""

    def __init__(self) -> None:
        self.now = 0.0

    def monotonic(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.now += max(0.0, float(seconds))


@dataclass
class WarmingArm(FakeArm):
    """`FakeArm` whose moves take time (the largest joint travel at 1 rad/s, plus half a second)."""

    clock: VirtualClock = field(default_factory=VirtualClock)
    truth: Geometry | None = None

    def move_to(self, q, *, speed=None, acceleration=None):
        travel = float(np.max(np.abs(np.asarray(q, float) - self.q)))
        reading = super().move_to(q, speed=speed, acceleration=acceleration)
        self.clock.sleep(travel / 1.0 + 0.5)
        return reading

    def joint_temperatures(self):
        rise = self.truth.thermal.rise_at(self.clock.now) if self.truth and self.truth.thermal else 0.0
        return [AMBIENT + rise] * 6


@dataclass
class WarmingTracker(FakeTracker):
    """`FakeTracker` that measures the arm as grown at the clock's time; a measurement takes 0.2 s
    per sample."""

    clock: VirtualClock = field(default_factory=VirtualClock)

    def measure_point(self, samples: int = 1):
        if self.lose_beam > 0:
            return super().measure_point(samples)
        self.measurements += 1
        p = Kinematics(self.truth.warmed(self.clock.now)).points(self.arm.q)[0]
        s = p + self.rng.normal(0, self.sigma, (samples, 3))
        self.clock.sleep(0.2 * samples)
        return Point(s.mean(0), s.std(0), samples)


class Devices:
    """`hil.station.devices.Devices` made of the fakes."""

    def __init__(self, arm, tracker) -> None:
        self.robot, self.tracker = arm, tracker

    def close(self) -> None:
        pass
