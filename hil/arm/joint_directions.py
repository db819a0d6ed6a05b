"""Which way each joint last moved: the side its lost motion lags to.

A joint's link lags its encoder by its lost motion in the direction of the joint's last motion
(docs/design.md, Contracts: non-geometric errors), standing or moving. The simulated arm follows that
direction cycle by cycle (`mocks.ur.arm`), and a sweep's fit reads it off the recorded joint stream
(`directions_along`, `hil.calibration.sweep_fit`): both by the one rule here, the contract's.

A direction turns only once a joint has come back more than `threshold` from the furthest point of
its current motion, so a joint that stands still (or the small jitter of a stream of joint readings)
never flips it; a joint that has never moved has direction 0 (no lost motion applied). Written here:
a hysteresis on a sequence of readings is a loop no array library offers in one call.
"""

from __future__ import annotations

import numpy as np

#: Radians a joint must travel back from the extreme of its motion before its direction turns: ten
#: standard deviations of a UR joint reading's noise (5 µrad, `hil.calibration.synthetic.ENCODER_SIGMA`,
#: which this package may not import), so reading jitter never turns it, and a hundredth of the
#: 0.005 rad the campaign engine approaches every pose by (`hil.campaign.steps.APPROACH`).
DIRECTION_THRESHOLD = 10 * 5e-6


class JointDirections:
    """Each joint's last direction of motion (−1, 0, +1), from a stream of joint angles."""

    def __init__(self, q: np.ndarray, threshold: float = DIRECTION_THRESHOLD,
                 signs: np.ndarray | None = None) -> None:
        if not (np.isfinite(threshold) and threshold >= 0):
            raise ValueError(f"threshold must be a non-negative number of radians, got {threshold!r}")
        self.threshold = float(threshold)
        self._extreme = np.array(q, dtype=float).reshape(6)
        self._sign = np.zeros(6) if signs is None else np.sign(np.asarray(signs, dtype=float).reshape(6))

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


def directions_along(q: np.ndarray, threshold: float = DIRECTION_THRESHOLD,
                     signs: np.ndarray | None = None) -> np.ndarray:
    """(N, 6) each joint's direction after each of the readings `q` (N, 6), in order, starting from
    `signs` (default: none known, 0). A jump between two readings (an unrecorded move between two
    recorded stretches) turns a joint as the move did."""
    q = np.asarray(q, dtype=float).reshape(-1, 6)
    out = np.zeros_like(q)
    if not len(q):
        return out
    follow = JointDirections(q[0], threshold, signs)
    out[0] = follow.signs
    for k in range(1, len(q)):
        out[k] = follow.update(q[k])
    return out
