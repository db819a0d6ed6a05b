"""The simulated arm keeps its true state cycle by cycle, also through a stalled tick (issue 29).

On a loaded machine the arm's tick thread can be starved for tenths of a second. A real controller
steps its motion every 2 ms regardless, so the simulated arm must move through the stall as if it had
ticked (sub-stepped) and record every cycle, for the tracker to read the truth at its samples' times.
"""

from __future__ import annotations

import numpy as np
import pytest

from mocks.ur.arm import ArmConfig, SimArm
from mocks.ur.history import JointHistory
from mocks.ur.motion import JointMove, ServoTracker


class HandClock:
    """A simulated clock moved by the test."""

    speed = 1.0

    def __init__(self) -> None:
        self.t = 0.0

    def now(self) -> float:
        return self.t


def _arm() -> tuple[SimArm, HandClock]:
    clock = HandClock()
    arm = SimArm(ArmConfig(encoder_noise=0.0), lambda q: np.eye(4), clock)  # type: ignore[arg-type]
    return arm, clock


Q0 = np.array([0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0])
Q1 = Q0 + np.array([0.4, -0.2, 0.3, 0.1, -0.3, 0.5])


def _start(arm: SimArm, kind: str) -> None:
    vmax = arm.config.max_speed
    arm.motion = (ServoTracker(Q1, 0.05, 1000.0, vmax) if kind == "servo"
                  else JointMove(arm.q, Q1, 1.0, 3.0, vmax))


@pytest.mark.parametrize("kind", ["servo", "movej"])
def test_a_stalled_tick_moves_the_arm_as_ticking_every_cycle_would(kind: str) -> None:
    reference, rclock = _arm()
    stalled, sclock = _arm()
    for arm in (reference, stalled):
        _start(arm, kind)
    period = 1.0 / reference.config.rate_hz
    for k in range(1, 251):  # 0.5 s of ticks every controller period
        rclock.t = k * period
        reference.tick()
    sclock.t = 250 * period  # one tick after a 0.5 s stall
    stalled.tick()
    times = np.linspace(0.01, 0.49, 25)
    q_ref, _ = reference.true_joints_at(times)
    q_stalled, _ = stalled.true_joints_at(times)
    np.testing.assert_allclose(q_stalled, q_ref, atol=1e-9)
    # and the motion really happened in between (not a history that holds one state)
    far = np.max(np.abs(q_stalled - Q0), axis=1) > 0.05
    between = far & (np.max(np.abs(q_stalled - Q1), axis=1) > 1e-3)
    assert between.any()
    np.testing.assert_allclose(stalled.true_joints(), reference.true_joints(), atol=1e-9)
    assert stalled.history_end() == pytest.approx(0.5)


def test_history_interpolates_between_cycles_and_keeps_the_last_capacity() -> None:
    h = JointHistory(capacity=4)
    with pytest.raises(LookupError):
        h.at([0.0])
    for k in range(10):
        h.append(float(k), np.full(6, 10.0 * k), np.full(6, float(k % 2)))
    assert h.span() == (6.0, 9.0)  # the last four cycles
    q, d = h.at(np.array([6.25, 8.5, 9.0, 20.0, 0.0]))
    np.testing.assert_allclose(q[:, 0], [62.5, 85.0, 90.0, 90.0, 60.0])
    np.testing.assert_allclose(d[:, 0], [0.0, 0.0, 1.0, 1.0, 0.0])  # the cycle at or before
    with pytest.raises(ValueError):
        h.append(5.0, np.zeros(6), np.zeros(6))
