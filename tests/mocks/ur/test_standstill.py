"""The simulated arm's repeatability: every movej stops off its target by a fresh error of the
configured σ, which the encoders see and the command does not (`mocks.ur.arm`,
`ArmConfig.standstill_sigma`)."""

from __future__ import annotations

import numpy as np
import pytest

from mocks.ur.arm import ArmConfig, SimArm

TARGET = np.array([0.3, -1.2, 1.1, -1.4, -1.5, 0.2])
BELOW = TARGET - 0.005  # the campaign's approach: every joint comes up to the target


class ManualClock:
    """Simulated seconds moved by the test alone."""

    speed = 1.0

    def __init__(self) -> None:
        self.t = 0.0

    def now(self) -> float:
        return self.t


def _arm(sigma: float) -> tuple[SimArm, ManualClock]:
    clock = ManualClock()
    arm = SimArm(ArmConfig(encoder_noise=0.0, standstill_sigma=sigma, seed=4), lambda q: np.eye(4), clock)
    return arm, clock


def _move(arm: SimArm, clock: ManualClock, q: np.ndarray) -> dict:
    """movej to `q` and run the controller until the arm stands; the snapshot seen mid-move."""
    assert arm.start_movej(q, 1.0, 1.4) is not None
    clock.t += 0.002
    arm.tick()
    during = dict(arm.snapshot)
    while arm.motion is not None:
        clock.t += 0.05
        arm.tick()
    return during


def test_stops_scatter_by_sigma_around_the_target_and_the_encoders_see_them() -> None:
    sigma = 2e-5
    arm, clock = _arm(sigma)
    stops = []
    for _ in range(300):
        _move(arm, clock, BELOW)
        during = _move(arm, clock, TARGET)
        assert during["target_q"] == pytest.approx(TARGET.tolist(), abs=0)  # the command, not the stop
        stops.append(arm.q - TARGET)
        # the reading is where the joint stands (no encoder noise here), not where it was sent
        assert np.array(arm.snapshot["actual_q"]) == pytest.approx(arm.q, abs=1e-15)
        # the stop error never turns a joint that came up to its target (no lost-motion flip)
        assert arm.joint_directions().tolist() == [1.0] * 6
    e = np.array(stops)
    assert np.abs(e.mean(axis=0)).max() < 4 * sigma / np.sqrt(len(e))
    assert e.std(axis=0) == pytest.approx(np.full(6, sigma), rel=0.15)
    assert np.abs(np.corrcoef(e.T) - np.eye(6)).max() < 0.25  # independent joints


def test_without_standstill_error_the_joints_stop_on_the_target() -> None:
    arm, clock = _arm(0.0)
    for _ in range(3):
        _move(arm, clock, BELOW)
        _move(arm, clock, TARGET)
        assert arm.q.tolist() == TARGET.tolist()


def test_a_negative_standstill_error_is_refused() -> None:
    arm, _ = _arm(0.0)
    with pytest.raises(ValueError, match="standstill"):
        arm.set_standstill(-1e-5)
