"""The clock of a fast-time simulated station: fast while the host waits on the station, real while it thinks.

A simulated station in fast time (``--speed 40``) runs its physics forty times faster than the wall
clock, so that a campaign's hour of moves, settling and measuring takes minutes. The host's own
computing (choosing poses, fitting, the stopping rule's cross-validation) does not get faster with it:
at a constant forty times, ten seconds of pose selection were 400 seconds of the simulated arm standing
still, cooling or warming, and how many depended on the machine's load (280–3200 simulated s at 40x
for one campaign's selection). A real station's arm stands for the ten seconds the host takes, no more.

So the simulator's clock runs at the station's speed only while the engine executes a step that waits
on the station — a move, a settle, a measurement, a suspension's polling (`PacedClock.busy`) — and at
the wall clock's rate between steps, while the plan computes. The switch is the simulator's control
channel (`mocks.ur.control_channel`, ``pace``), whose reply carries the simulator's time, so the
station seconds this clock counts (`PacedClock.station`) are the simulator's own, not an estimate.

A failing control channel (the simulator killed by a test, a dropped link) does not end the run: the
devices report what really failed; the clock keeps counting on the wall clock at the rate it last set.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Callable, Iterator

#: The simulator's pace switch: takes the simulated seconds per wall second to run at, returns the
#: simulator's time (s) when it switched.
Pace = Callable[[float], float]


class PacedClock:
    """The engine's clock (`hil.campaign.engine.Clock`) on a fast-time simulated station.

    `speed`: simulated seconds per wall second while the host waits on the station; `pace`: switches
    the simulator (`Pace`). The clock starts the simulator at the wall's rate (the plan's first
    computing), and `close` gives the simulator its full speed back (what a simulator runs at when
    nothing paces it).
    """

    def __init__(self, speed: float, pace: Pace) -> None:
        if not speed > 0:
            raise ValueError(f"clock speed must be > 0, got {speed}")
        self._speed, self._pace = float(speed), pace
        self._lock = threading.Lock()
        self._depth = 0
        self._rate = 1.0
        self._wall = time.monotonic()
        self._origin = self._sim = self._switch(1.0, fallback=0.0)

    @property
    def speed(self) -> float:
        """Simulated seconds per wall second while the host waits on the station."""
        return self._speed

    def monotonic(self) -> float:
        """The wall clock (s): what the engine's own statistics are kept in."""
        return time.monotonic()

    def station(self) -> float:
        """Seconds on the station's (the simulator's) clock since this clock was made."""
        with self._lock:
            return self._sim - self._origin + (time.monotonic() - self._wall) * self._rate

    def sleep(self, seconds: float) -> None:
        """Wait `seconds` of station time (the station runs fast through it)."""
        if seconds > 0:
            with self.busy():
                time.sleep(seconds / self._speed)

    @contextlib.contextmanager
    def busy(self) -> Iterator[None]:
        """While inside, the host waits on the station: the simulator runs at `speed`. Nests."""
        with self._lock:
            self._depth += 1
            first = self._depth == 1
        if first:
            self._switch(self._speed)
        try:
            yield
        finally:
            with self._lock:
                self._depth -= 1
                last = self._depth == 0
            if last:
                self._switch(1.0)

    def close(self) -> None:
        """Hand the simulator back its full speed (nothing paces it any more)."""
        self._switch(self._speed)

    def _switch(self, rate: float, fallback: float | None = None) -> float:
        """Set the simulator's rate; the station time is re-based on the simulator's reply."""
        now = time.monotonic()
        try:
            sim = float(self._pace(rate))
        except (OSError, RuntimeError, ValueError):
            # the simulator does not answer (killed, dropped): keep counting on the wall clock
            with self._lock:
                sim = (fallback if fallback is not None
                       else self._sim + (now - self._wall) * self._rate)
        with self._lock:
            self._sim, self._wall, self._rate = sim, time.monotonic(), rate
        return sim


def simulator_pace(simulator: object) -> Pace:
    """The pace switch of a running simulator (`mocks.ur.process.SimProcess`): its control channel's
    ``pace`` command, which answers with the simulator's time."""

    def pace(rate: float) -> float:
        return float(simulator.inject("pace", speed=rate)["time"])  # type: ignore[attr-defined]

    return pace
