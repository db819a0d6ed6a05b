"""What the simulated tracker looks at: an injected source of the true SMR state.

The instrument asks its `TargetSource` for the truth at every measurement, so the simulated robot
(or a test) owns the SMR and the tracker only adds its own errors.
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray


@dataclass(frozen=True)
class TargetState:
    """The true SMR centre in the tracker frame (metres) and whether the beam can reach it."""

    position: NDArray[np.float64]
    visible: bool = True
    reason: str = ""  # why not visible: "faces away (72° > 60° acceptance)", "arm blocks the beam"...

    def __post_init__(self) -> None:
        pos = np.asarray(self.position, dtype=float).reshape(3)
        if not np.all(np.isfinite(pos)):
            raise ValueError("target position must be finite")
        object.__setattr__(self, "position", pos)


@runtime_checkable
class TargetSource(Protocol):
    """Anything that can say where the SMR truly is right now (called from simulator threads)."""

    def target(self) -> TargetState: ...


@dataclass
class StaticTarget:
    """A settable target for tests and the stand-alone simulator (thread-safe)."""

    position: NDArray[np.float64] = field(default_factory=lambda: np.array([1.0, 2.0, 0.5]))
    visible: bool = True
    reason: str = ""

    def __post_init__(self) -> None:
        self._lock = threading.Lock()
        self.position = np.asarray(self.position, dtype=float).reshape(3)

    def set(self, position: ArrayLike, visible: bool = True, reason: str = "") -> None:
        """Move the SMR and/or hide it."""
        with self._lock:
            self.position = np.asarray(position, dtype=float).reshape(3)
            self.visible, self.reason = visible, reason

    def target(self) -> TargetState:
        """The current state."""
        with self._lock:
            return TargetState(self.position.copy(), self.visible, self.reason)
