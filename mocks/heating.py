"""How warm the simulated arm is: its joints heat while they work, not while the controller is on.

A UR joint is a permanent-magnet servo motor behind a strain-wave gear; what warms it is the motor's
copper loss I²R (Joule heating, with the current I proportional to the torque the joint delivers: a
servo motor's torque constant, e.g. Hughes & Drury, *Electric Motors and Drives*, 5th ed., ch. 9 and
10) and the gear's friction, both while the joint moves. Standing still with its brakes released it
only holds the arm against gravity (a current, so some heat); with the brakes on (robot mode IDLE,
powered off) its motor carries no current at all. UR's own guidance warms a cold arm by *running* a
program, not by leaving it switched on ("Robot start-up in cold environments", universal-robots.com,
Robot care & maintenance). So the simulated arm's temperature rise follows a first-order model driven
by what the arm does,

    dΔT/dt = (rise·u − ΔT) / time_constant,   u = 1 moving, `IDLE_HEAT` holding, 0 braked,

which is the truth's `hil.arm.thermal.Thermal` warm-up (ΔT = rise·(1 − exp(−t/τ))) for an arm that
moves all the time, and keeps an arm that waits (while hil selects its poses, say) at a fraction of it.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable

from hil.arm.thermal import Thermal

#: The heat input of a joint holding its pose with the brakes released, as a fraction of a moving
#: joint's. An assumption, no published figure found: the holding torque (gravity only) is about half a
#: campaign cycle's RMS torque (gravity plus acceleration and the gears' friction), and the copper loss
#: goes with its square: ½² = ¼.
IDLE_HEAT = 0.25


class Heating:
    """The arm's temperature rise ΔT (K) now, integrated from what the arm did since the last query.

    `clock()`: the controller's seconds; `moved()`: the arm's accumulated seconds of joint motion
    (`SimArm.motion_seconds`); `holding()`: whether its brakes are released (robot mode RUNNING). Read
    without the arm's lock (plain attribute reads), so the trackers' threads and the arm's never wait
    on each other. Between two queries the heat input is the fraction of the time the arm moved; the
    queries come many times a second, far inside the minutes of the time constant.
    """

    def __init__(self, thermal: Thermal, clock: Callable[[], float], moved: Callable[[], float],
                 holding: Callable[[], bool], idle: float = IDLE_HEAT, start: float = 0.0) -> None:
        """`start`: ΔT (K) at the start (0: a cold arm; ``thermal.rise``: one that has been working)."""
        self.thermal, self.idle = thermal, float(idle)
        self._clock, self._moved, self._holding = clock, moved, holding
        self._t, self._m, self._rise = float(clock()), float(moved()), float(start)
        self._lock = threading.Lock()

    def rise(self) -> float:
        """ΔT (K) now."""
        with self._lock:
            t, m = float(self._clock()), float(self._moved())
            dt, dm = t - self._t, m - self._m
            if dt > 0:
                moving = min(max(dm / dt, 0.0), 1.0)
                u = moving + (self.idle * (1.0 - moving) if self._holding() else 0.0)
                target = self.thermal.rise * u
                self._rise = target + (self._rise - target) * math.exp(-dt / self.thermal.time_constant)
            self._t, self._m = max(t, self._t), m
            return self._rise
