"""RTDE's timestamp is the controller's running time read on its own clock (the station's truth)."""

from __future__ import annotations

import numpy as np
import pytest

from hil.calibration.stream_clocks import InstrumentClock
from mocks.ur.arm import ArmConfig, SimArm
from tests.mocks.ur.test_history import HandClock, _arm


def test_the_timestamp_is_the_running_time_on_the_controllers_clock() -> None:
    arm, clock = _arm()
    clock.t = 12.5
    arm.tick()
    assert arm.snapshot["timestamp"] == pytest.approx(12.5, abs=1e-12)  # a perfect clock by default
    arm.controller_clock = InstrumentClock(drift_ppm=20.0, latency_s=1e-3)
    clock.t = 100.0
    arm.tick()
    assert arm.snapshot["timestamp"] == pytest.approx((1 + 20e-6) * (100.0 + 1e-3), abs=1e-12)
    assert arm.timestamp == pytest.approx(100.0)  # the running time itself (temperatures, durations)


def test_jitter_draws_from_its_own_generator() -> None:
    clock, twin_clock = HandClock(), HandClock()
    arm = SimArm(ArmConfig(), lambda q: np.eye(4), clock)  # type: ignore[arg-type]  # encoder noise on
    twin = SimArm(ArmConfig(), lambda q: np.eye(4), twin_clock)  # type: ignore[arg-type]
    arm.controller_clock = InstrumentClock(jitter_s=1e-4)
    stamps, noise, twin_noise = [], [], []
    for k in range(1, 400):
        clock.t = twin_clock.t = 0.002 * k
        arm.tick()
        twin.tick()
        stamps.append(arm.snapshot["timestamp"] - arm.timestamp)
        noise.append(arm.actual_q.copy())
        twin_noise.append(twin.actual_q.copy())
    assert np.std(stamps) == pytest.approx(1e-4, rel=0.15)
    assert np.std(np.diff(noise, axis=0)) > 0  # the encoders are noisy here, and their noise is
    np.testing.assert_array_equal(noise, twin_noise)  # as without jitter
