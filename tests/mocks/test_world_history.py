"""The world says where the SMR was at any recorded time, not only where it is now (issue 29)."""

from __future__ import annotations

import numpy as np

from hil.calibration.synthetic import random_truth
from mocks.ur.history import JointHistory
from mocks.world import World

Q_A = np.array([0.3, -1.2, 1.4, -1.5, -1.3, 0.2])
Q_B = Q_A + np.array([0.2, 0.1, -0.1, 0.05, 0.1, -0.2])


def test_positions_at_recorded_times_are_the_arm_there() -> None:
    truth = random_truth("ur5e", np.random.default_rng(3))  # the realistic arm: joint errors, lost motion
    history = JointHistory()
    for k in range(11):  # 10 cycles from Q_A to Q_B, the last joints moving backwards
        q = Q_A + (Q_B - Q_A) * k / 10
        history.append(1.0 + 0.002 * k, q, np.sign(Q_B - Q_A))
    now = {"q": Q_B}
    world = World(truth, lambda: now["q"], directions=lambda: np.sign(Q_B - Q_A), joints_at=history.at,
                  known_until=lambda: history.span()[1])
    got = world.positions_at(np.array([1.0, 1.01, 1.02]))
    for p, q in zip(got, (Q_A, Q_A + (Q_B - Q_A) / 2, Q_B), strict=True):
        now["q"] = q
        np.testing.assert_allclose(p, world.target().position, atol=1e-12)
    assert np.linalg.norm(got[0] - got[2]) > 0.01  # the arm did move between them
