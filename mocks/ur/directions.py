"""Which way each simulated joint last moved: what a joint's lost motion depends on.

A joint's link lags its encoder by its lost motion in the direction of the joint's last motion
(docs/design.md, Contracts: non-geometric errors), so the simulated world must know that direction at
every reading. `JointDirections` follows the joint stream cycle by cycle (`SimArm.tick`), so a move
that goes up and comes back down between two tracker readings leaves the direction of its last leg.
A direction turns only once a joint has come back more than `threshold` from the furthest point of
its current motion, so a joint that stands still (or the small jitter of a stream of joint readings)
never flips it; a joint that has never moved has direction 0 (no lost motion applied).
"""

from __future__ import annotations

import numpy as np

from hil.calibration.synthetic import ENCODER_SIGMA

#: Radians a joint must travel back from the extreme of its motion before its direction turns: ten
#: standard deviations of a UR joint reading's noise (`ENCODER_SIGMA`), so reading jitter never turns
#: it, and under a tenth of the 0.01 rad the campaign engine approaches every pose by.
DIRECTION_THRESHOLD = 10 * ENCODER_SIGMA


class JointDirections:
    """Each joint's last direction of motion (−1, 0, +1), from a stream of joint angles."""

    def __init__(self, q: np.ndarray, threshold: float = DIRECTION_THRESHOLD) -> None:
        if not (np.isfinite(threshold) and threshold >= 0):
            raise ValueError(f"threshold must be a non-negative number of radians, got {threshold!r}")
        self.threshold = float(threshold)
        self._extreme = np.array(q, dtype=float).reshape(6)
        self._sign = np.zeros(6)

    @property
    def signs(self) -> np.ndarray:
        """(6,) the direction of each joint's last motion (a copy)."""
        return self._sign.copy()

    def update(self, q: np.ndarray) -> np.ndarray:
        """Take the joints' next angles; returns the directions after them."""
        q = np.asarray(q, dtype=float).reshape(6)
        d = q - self._extreme
        further = d * self._sign > 0  # still going the same way: the extreme follows
        turned = (np.abs(d) > self.threshold) & ~further
        self._sign = np.where(turned, np.sign(d), self._sign)
        self._extreme = np.where(further | turned, q, self._extreme)
        return self._sign.copy()
