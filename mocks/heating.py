"""How warm the simulated arm is: its joints heat while they move, not while the controller is on.

A UR joint is a permanent-magnet servo motor behind a strain-wave gear; what warms it is the motor's
copper loss I²R (Joule heating, with the current I proportional to the torque the joint delivers: a
servo motor's torque constant, e.g. Hughes & Drury, *Electric Motors and Drives*, 5th ed., ch. 9 and
10) and the gear's friction, both while the joint moves. UR's own guidance warms a cold arm by
*running* a program, not by leaving it switched on ("Robot start-up in cold environments",
universal-robots.com, Robot care & maintenance). So the simulated arm's temperature rise is a
first-order response to its *motion*: over m seconds of joint motion

    dΔT/dm = (rise − ΔT) / time_constant,

which is the truth's `hil.arm.thermal.Thermal` warm-up (ΔT = rise·(1 − exp(−t/τ))) for an arm that
moves all the time. Standing still, the arm keeps its temperature.

Why standing still counts for nothing, where a joint holding the arm with its brakes released does
draw a current (about a quarter of a moving joint's heat, half its torque squared; before, the
simulator warmed a holding arm by that share and cooled a braked one): in fast time every standstill
lasts as long as the *host* takes. A campaign's client computes while the arm waits (selecting its
poses: 17–80 wall seconds, 700–3200 simulated seconds at 40x, the more the busier the machine), and
the simulated arm warmed or cooled through all of it, so what the tracker saw depended on the host:
at a load average of 16 a warm-up whose temperatures dipped with every slow stretch never converged,
and the beam-lost campaign's validation poses, measured on an arm 0.25 K warmer than its calibration
poses, were rejected. On a real station those waits are seconds against the warm-up's quarter of an
hour: over them a joint's temperature changes by a fraction of a percent of what it has still to
go. Motion durations are exact in simulated time (the controller's profiles), so heat that follows
motion is the same whatever the host's pace. The cost, an assumption: a long real pause (an operator
away for many minutes, a robot left powered overnight) does not cool the simulated arm.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable

from hil.arm.thermal import Thermal


class Heating:
    """The arm's temperature rise ΔT (K) now, integrated over the joint motion since the last query.

    `moved()`: the arm's accumulated seconds of joint motion (`SimArm.motion_seconds`), read without
    the arm's lock (a plain attribute read), so the trackers' threads and the arm's never wait on each
    other. The response to m seconds of motion is exact whatever the queries' spacing.
    """

    def __init__(self, thermal: Thermal, moved: Callable[[], float], start: float = 0.0) -> None:
        """`start`: ΔT (K) before any motion (0: a cold arm; ``thermal.rise``: one warmed up)."""
        self.thermal = thermal
        self._moved = moved
        self._m, self._rise = float(moved()), float(start)
        self._lock = threading.Lock()

    def rise(self) -> float:
        """ΔT (K) now."""
        with self._lock:
            m = float(self._moved())
            dm = m - self._m
            if dm > 0:
                target = self.thermal.rise
                self._rise = target + (self._rise - target) * math.exp(-dm / self.thermal.time_constant)
                self._m = m
            return self._rise
