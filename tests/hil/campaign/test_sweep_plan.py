"""The sweep's tour as the plan builds it: segments rest to rest between the waypoints, within the
station's speed and acceleration, checked before anything moves; its verdict on still poses."""

from __future__ import annotations

from itertools import pairwise

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.campaign.sweep_plan import sweep_tour, sweep_verdict
from hil.errors import InputError
from hil.station.config import default_config

POSE = np.array([0.0, -1.2, 1.4, -1.8, -1.57, 0.0])


def swing(angle: float) -> np.ndarray:
    q = POSE.copy()
    q[0] = angle
    return q


def test_segments_run_rest_to_rest_through_the_waypoints_within_the_stations_limits():
    config = default_config()
    waypoints = np.array([swing(-0.3), swing(0.2), swing(0.5)])
    segs = sweep_tour(waypoints, config, get_robot("ur5e"), Geometry.nominal("ur5e"))
    assert [s.index for s in segs] == [0, 1]
    for seg, (a, b) in zip(segs, pairwise(waypoints), strict=True):
        assert np.allclose(seg.q[0], a) and np.allclose(seg.q[-1], b)
        speed = np.abs(np.diff(seg.q, axis=0)) * seg.rate_hz
        assert speed.max() <= config.robot["speed"] * (1 + 1e-9)
        assert np.allclose(seg.q[1] - seg.q[0], 0, atol=1e-4)  # starts (and ends) at rest


def test_a_tour_leaving_the_keep_in_box_is_refused_before_anything_moves():
    """Joint 1 from -45° to +45°: both ends inside the box, the arc between them bulges out past its
    x limit. The segment and the first sample outside are named; no segment is returned."""
    model = Geometry.nominal("ur5e")
    a, b = swing(-np.pi / 4), swing(np.pi / 4)
    ends = Kinematics(model).points(np.array([a, b]), frame="base")
    lo = ends.min(axis=0) - 0.02
    hi = ends.max(axis=0) + 0.02
    config = default_config().with_overrides(keep_in__min=list(map(float, lo)),
                                             keep_in__max=list(map(float, hi)))
    with pytest.raises(InputError, match=r"sweep segment 1 of 1 refused before the sweep moved: sweep "
                                         r"sample \d+ .* outside the keep-in box"):
        sweep_tour(np.array([a, b]), config, get_robot("ur5e"), model)


def test_the_verdict_needs_the_model_better_than_the_nominal_arm_then_the_bound():
    assert sweep_verdict(0.1e-3, 0.8e-3, "ur5e", None).passed
    worse = sweep_verdict(0.9e-3, 0.8e-3, "ur5e", None)
    assert not worse.passed and "not better than the nominal" in worse.reason
    assert not sweep_verdict(0.2e-3, 0.8e-3, "ur5e", 0.1e-3).passed
