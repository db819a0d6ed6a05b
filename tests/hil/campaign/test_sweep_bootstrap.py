"""A sweep campaign's bootstrap as one streamed path: each bootstrap pose ends a segment that comes up
to it from below and holds; a segment that may not be swept leaves its pose to a still visit."""

from __future__ import annotations

import numpy as np

from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry
from hil.arm.joint_directions import directions_along
from hil.arm.kinematics import Kinematics
from hil.campaign.calibration_plan import bootstrap_targets
from hil.campaign.events import BOOTSTRAP_SEGMENTS, is_bootstrap_segment
from hil.campaign.sweep_bootstrap import bootstrap_segments
from hil.station.config import default_config

START = np.array([0.0, -1.2, 1.4, -1.8, -1.5708, 0.0])


def _config(**over):
    return default_config().with_overrides(tracker__protocol="emscon", tracker__url="tcp://127.0.0.1:700",
                                           campaign__mode="sweep", **over)


def test_each_bootstrap_pose_ends_a_segment_from_the_one_before_coming_up_and_holding():
    config, model = _config(), Geometry.nominal("ur5e", (0.0, 0.0, 0.045))
    targets = bootstrap_targets(START, 6)
    segments = bootstrap_segments(targets, config, get_robot("ur5e"), model, model)
    assert len(segments) == len(targets) and all(s is not None for s in segments)
    for k, (segment, q) in enumerate(zip(segments, targets, strict=True)):
        assert segment.index == BOOTSTRAP_SEGMENTS + k and is_bootstrap_segment(segment.index)
        np.testing.assert_allclose(segment.q[0], targets[k - 1] if k else q, atol=1e-12)
        np.testing.assert_allclose(segment.q[-segment.dwell - 1:], np.repeat(q[None], segment.dwell + 1, 0))
        assert np.all(directions_along(segment.q)[-1] == 1.0)  # lags as a stop-and-go pose does
        assert np.max(np.abs(np.diff(segment.q, axis=0))) * 500 <= 0.5 + 1e-9  # robot.speed
    assert not is_bootstrap_segment(0) and not is_bootstrap_segment(BOOTSTRAP_SEGMENTS - 1)


def test_a_pose_whose_segment_may_not_be_swept_is_left_to_a_still_visit():
    model = Geometry.nominal("ur5e", (0.0, 0.0, 0.045))
    targets = bootstrap_targets(START, 6)
    base = Geometry.nominal("ur5e", (0.0, 0.0, 0.045))
    tips = Kinematics(base).points(targets, frame="base")
    # a keep-in box that ends just short of the farthest pose's SMR in x: the paths into it and out
    # of it leave the box
    far = int(np.argmax(tips[:, 0]))
    lo, hi = tips.min(axis=0) - 0.3, tips.max(axis=0) + 0.3
    hi[0] = tips[far, 0] - 1e-3
    config = _config(keep_in__min=lo.tolist(), keep_in__max=hi.tolist())
    segments = bootstrap_segments(targets, config, get_robot("ur5e"), model, model)
    refused = {far, far + 1} & set(range(len(targets)))
    assert {k for k, s in enumerate(segments) if s is None} == refused
    # without an approach the first pose, where the arm stands, is no motion to sweep
    plain = bootstrap_segments(targets, _config(campaign__approach=0.0), get_robot("ur5e"), model, model)
    assert plain[0] is None and all(s is not None and s.dwell > 0 for s in plain[1:])
