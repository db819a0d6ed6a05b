"""A simulated clock that can run faster than real time.

Every simulator in one process (the robot controller and, later, the tracker) reads the same clock so
that "3 s of settling" means the same thing to both. With ``speed=F`` one real second is F simulated
seconds: long campaigns run in seconds while every duration the simulators model (motion profiles,
the 5 s protective-stop unlock delay, timestamps) stays consistent in simulated time.
"""

from __future__ import annotations

import threading
import time


class SimClock:
    """Thread-safe simulated time: ``now()`` advances ``speed`` times faster than ``time.monotonic``."""

    def __init__(self, speed: float = 1.0, start: float = 0.0) -> None:
        if not speed > 0:
            raise ValueError(f"clock speed must be > 0, got {speed}")
        self._lock = threading.Lock()
        self._speed = float(speed)
        self._t0_real = time.monotonic()
        self._t0_sim = float(start)

    @property
    def speed(self) -> float:
        """Simulated seconds per real second."""
        return self._speed

    @speed.setter
    def speed(self, value: float) -> None:
        if not value > 0:
            raise ValueError(f"clock speed must be > 0, got {value}")
        with self._lock:
            now_real = time.monotonic()
            self._t0_sim = self._t0_sim + (now_real - self._t0_real) * self._speed
            self._t0_real = now_real
            self._speed = float(value)

    def now(self) -> float:
        """Simulated seconds since the clock started."""
        with self._lock:
            return self._t0_sim + (time.monotonic() - self._t0_real) * self._speed

    def real_seconds(self, sim_seconds: float) -> float:
        """How long `sim_seconds` of simulated time takes in real time."""
        return sim_seconds / self._speed

    def sleep(self, sim_seconds: float) -> None:
        """Block for `sim_seconds` of simulated time."""
        if sim_seconds > 0:
            time.sleep(sim_seconds / self._speed)
