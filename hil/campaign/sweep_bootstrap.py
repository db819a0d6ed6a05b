"""A sweep campaign's bootstrap, swept: the arm goes through the bootstrap poses on one streamed path
and each pose is read off the hold the path makes there.

Stop-and-go's bootstrap visits its poses (`hil.campaign.calibration_plan.bootstrap_targets`: small
moves of the arm and turns of the wrist around the start) one by one at the station's movej, each
approached from below, settled and read: on the simulated UR5e about a fifth of a sweep campaign's
robot time (bench/sweep_campaign.py, 33 s of 147 s), most of it moves at ``robot.speed``. A sweep
campaign streams both instruments anyway, so here each bootstrap pose ends a segment of a streamed
path (`bootstrap_segments`): from the pose before, within the sweep's limits (`sweep_limits`), coming
up the last ``campaign.approach`` in every joint and holding (`hil.campaign.sweep_rests`), and the
hold's stream is the pose's reading. The poses are then what stop-and-go's bootstrap gives — still
points approached from below, the same `PointMeasured` in the store — and locate the tracker the
same way; the segments' streams join the sweep's fit with the tour's.

Nothing here knows where the tracker is (that is what the bootstrap finds): a segment is checked for
the joint limits, the speeds and the keep-in box, not for the tracker's sight, as the stop-and-go
bootstrap's moves are not. A pose whose segment is refused, or whose hold is not still, is visited
the stop-and-go way. Bootstrap segments are numbered from `BOOTSTRAP_SEGMENTS` in the campaign's
sweep records, apart from the tour's (0, 1, …), so a resumed campaign finds both.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from hil.arm.catalog import RobotSpec
from hil.arm.geometry import Geometry
from hil.campaign.events import BOOTSTRAP_SEGMENTS
from hil.campaign.steps import SweepSegment
from hil.campaign.sweep_plan import CONTROLLER_RATE_HZ, sweep_limits
from hil.campaign.sweep_rests import approach_knots, ends_from_below, with_dwell


def bootstrap_segments(targets: np.ndarray, config: Any, spec: RobotSpec, check_model: Geometry,
                       limit_model: Geometry | None = None, rate_hz: float = CONTROLLER_RATE_HZ
                       ) -> list[SweepSegment | None]:
    """For each bootstrap pose of `targets` (n, 6), the segment that arrives there and holds (the
    first comes from just below the first pose, where the arm stands at the start), or None where
    that segment is refused (the joint limits, the sweep's speed and acceleration, the keep-in box
    with `check_model`) or would not end coming up in every joint: that pose is visited still."""
    from hil.calibration.sweep_path import SweepRefused, check_sweep, plan_leg

    targets = np.asarray(targets, dtype=float).reshape(-1, 6)
    keep_in = (np.asarray(config.keep_in["min"], float), np.asarray(config.keep_in["max"], float))
    speed, accel = sweep_limits(config, spec, targets, limit_model)
    approach = float(config.campaign.get("approach", 0.0) or 0.0)
    out: list[SweepSegment | None] = []
    for k, q in enumerate(targets):
        knots = approach_knots(np.vstack([targets[k - 1] if k else q, q]), approach)
        try:
            leg = plan_leg(knots, max_speed=speed, max_acceleration=accel, rate_hz=rate_hz)
            check_sweep(leg, max_speed=speed, max_acceleration=accel, spec=spec, keep_in=keep_in,
                        model=check_model)
        except (SweepRefused, ValueError):  # refused, or no motion to plan (a pose twice, no approach)
            out.append(None)
            continue
        path = np.asarray(leg.q, float)
        if approach > 0 and not ends_from_below(path):
            out.append(None)
            continue
        path, hold = with_dwell(path, rate_hz)
        out.append(SweepSegment(BOOTSTRAP_SEGMENTS + k, path, float(rate_hz), knots, hold))
    return out
