"""Each simulated joint's last direction of motion: what its lost motion lags by."""

import numpy as np
import pytest

from mocks.ur.directions import DIRECTION_THRESHOLD, JointDirections


def test_a_joint_that_never_moved_has_no_direction():
    d = JointDirections(np.zeros(6))
    assert d.signs.tolist() == [0.0] * 6


def test_up_then_down_turns_the_direction_once_past_the_threshold():
    d = JointDirections(np.zeros(6))
    for x in np.linspace(0.0, 0.1, 50):  # joint 2 goes up in small steps
        d.update(np.r_[0.0, x, 0, 0, 0, 0])
    assert d.signs[1] == 1.0 and d.signs[0] == 0.0
    # coming back less than the threshold keeps the side; more turns it
    d.update(np.r_[0.0, 0.1 - 0.5 * DIRECTION_THRESHOLD, 0, 0, 0, 0])
    assert d.signs[1] == 1.0
    d.update(np.r_[0.0, 0.1 - 2 * DIRECTION_THRESHOLD, 0, 0, 0, 0])
    assert d.signs[1] == -1.0


def test_reading_jitter_never_turns_a_standing_joint(rng):
    d = JointDirections(np.zeros(6))
    d.update(np.full(6, 0.05))  # every joint came up
    for _ in range(2000):  # then stands, read with a UR joint's noise (`ENCODER_SIGMA`, 5 µrad)
        d.update(0.05 + rng.normal(0.0, 5e-6, 6))
    assert d.signs.tolist() == [1.0] * 6


def test_a_negative_threshold_is_refused():
    with pytest.raises(ValueError, match="threshold"):
        JointDirections(np.zeros(6), threshold=-1.0)


def test_the_threshold_is_ten_encoder_sigmas():
    from hil.calibration.synthetic import ENCODER_SIGMA

    assert DIRECTION_THRESHOLD == 10 * ENCODER_SIGMA
