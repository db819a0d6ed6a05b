"""The simulated arm's recent true states in simulated time, for instruments that sample the past.

A real tracker samples the SMR where it truly is at each sample's instant, and a real controller
moves the arm on a hard real-time cycle. The simulators are Python threads that a loaded machine can
starve for tenths of a second: a tracker that looked at the arm's *current* joints whenever its
thread happened to run would put the samples of a stall on a chord between two looks (a weld seam's
corner cut by millimetres), a measurement artefact of the simulator that no real
instrument has. So the arm records every controller cycle's true joints and joint directions here
(sub-stepped through a stall by `SimArm.tick`), and an instrument asks `at` for the truth at its
samples' own times.

The buffer holds the last `capacity` cycles (at 500 Hz, 8192 cycles are 16 s of simulated time at
real speed: far longer than any stall or any batch of samples waiting to be sent). Thread-safe.
"""

from __future__ import annotations

import threading

import numpy as np

#: Cycles kept (see the module docstring).
CAPACITY = 8192


class JointHistory:
    """(time, joints, joint directions) of the last `capacity` controller cycles, oldest first."""

    def __init__(self, capacity: int = CAPACITY) -> None:
        if capacity < 2:
            raise ValueError(f"capacity must be at least 2, got {capacity}")
        self.capacity = int(capacity)
        # twice the capacity, so the kept window is always one contiguous slice (moved down when full)
        self._t = np.empty(2 * self.capacity)
        self._q = np.empty((2 * self.capacity, 6))
        self._d = np.empty((2 * self.capacity, 6))
        self._end = 0
        self._lock = threading.Lock()

    def append(self, t: float, q: np.ndarray, directions: np.ndarray) -> None:
        """Record the state at simulated time `t` (not earlier than the last one recorded)."""
        with self._lock:
            if self._end and t < self._t[self._end - 1]:
                raise ValueError(f"history time went back: {t} < {self._t[self._end - 1]}")
            if self._end == 2 * self.capacity:
                keep = slice(self.capacity, 2 * self.capacity)
                self._t[:self.capacity] = self._t[keep]
                self._q[:self.capacity] = self._q[keep]
                self._d[:self.capacity] = self._d[keep]
                self._end = self.capacity
            self._t[self._end] = t
            self._q[self._end] = q
            self._d[self._end] = directions
            self._end += 1

    def clear(self) -> None:
        """Forget the past (the arm was teleported: nothing before it is a motion it made)."""
        with self._lock:
            self._end = 0

    def span(self) -> tuple[float, float] | None:
        """(oldest, newest) simulated time recorded; None when empty."""
        with self._lock:
            if not self._end:
                return None
            return float(self._t[max(self._end - self.capacity, 0)]), float(self._t[self._end - 1])

    def at(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(joints (n, 6), directions (n, 6)) at simulated `times`: joints linear between the two
        recorded cycles around each time (a cycle is 2 ms: the motion is straight at that scale),
        directions those of the cycle at or before it. Times outside the record take its end."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        with self._lock:
            if not self._end:
                raise LookupError("no joint history recorded yet")
            lo = max(self._end - self.capacity, 0)
            T, Q, D = self._t[lo:self._end], self._q[lo:self._end], self._d[lo:self._end]
            j = np.clip(np.searchsorted(T, times, side="right"), 1, max(len(T) - 1, 1))
            if len(T) == 1:
                return np.repeat(Q, len(times), axis=0), np.repeat(D, len(times), axis=0)
            t0, t1 = T[j - 1], T[j]
            w = np.clip(np.divide(times - t0, t1 - t0, out=np.zeros_like(times), where=t1 > t0), 0.0, 1.0)
            q = Q[j - 1] + w[:, None] * (Q[j] - Q[j - 1])
            before = np.where(times >= t1, j, j - 1)
            return q, D[before].copy()
