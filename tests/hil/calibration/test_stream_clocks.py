"""The clock truth: stamps, their inverse, the true map between two clocks, and the JSON block."""

import numpy as np
import pytest

from hil.calibration.stream_clocks import ClockMap, InstrumentClock, StationClocks
from hil.errors import InputError


def test_the_true_map_takes_a_tracker_stamp_to_the_controller_stamp_of_the_same_instant():
    clocks = StationClocks.realistic()
    t = np.linspace(0.0, 600.0, 50)
    s_trk, s_ctrl = clocks.tracker.stamps(t), clocks.controller.stamps(t)
    np.testing.assert_allclose(clocks.controller_from_tracker()(s_trk), s_ctrl, rtol=0, atol=1e-9)
    np.testing.assert_allclose(clocks.tracker.true_time(s_trk), t, atol=1e-9)
    assert clocks.controller_from_tracker().drift_ppm == pytest.approx(35.0, abs=1e-3)


def test_jitter_is_drawn_only_with_a_generator_and_ideal_clocks_are_the_true_time():
    clock = InstrumentClock(offset_s=3.0, drift_ppm=10.0, jitter_s=1e-5, latency_s=1e-3)
    t = np.linspace(0, 1, 20001)
    jittered = clock.stamps(t, np.random.default_rng(0)) - clock.stamps(t)
    assert jittered.std() == pytest.approx(1e-5, rel=0.05)
    ideal = StationClocks.ideal()
    np.testing.assert_array_equal(ideal.tracker.stamps(t, np.random.default_rng(0)), t)
    assert ideal.controller_from_tracker() == ClockMap(0.0, 0.0)


def test_the_block_round_trips_and_a_bad_field_is_named():
    clocks = StationClocks.realistic()
    assert StationClocks.from_dict(clocks.to_dict()) == clocks
    with pytest.raises(InputError, match=r"clocks.tracker: unknown field 'drift'"):
        StationClocks.from_dict({"tracker": {"drift": 1.0}})
    with pytest.raises(InputError, match=r"clocks.controller:.*out of range"):
        StationClocks.from_dict({"controller": {"drift_ppm": 5000}})
