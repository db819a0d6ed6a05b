"""A fault-free campaign plans no pose the tracker cannot see.

The calibration plan is dry-run against a true world (the simulator's own visibility model): every
bootstrap and pose visit is answered with the true SMR point plus Leica-class noise, and every pose the
plan chooses must be visible in that world — the SMR facing the tracker and the beam clear of the arm.
The seed is one where locating the tracker against the SMR *guess* alone planned a hidden pose (so did
seeds 3 and 4; every seed of 1-12 plans none now).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from hil.calibration.synthetic import Noise, measure, random_truth
from hil.campaign.calibration_plan import BOOTSTRAP, calibration_plan
from hil.campaign.chooser import campaign_chooser
from hil.campaign.events import PlanReady
from hil.campaign.steps import Acquire, Emit, PoseRecord, ReadJoints, dry_run
from hil.station.config import default_config
from mocks.world import World
from tests.hil.campaign.fakes import Reading


class PlanReadyReached(Exception):
    """Stop the dry run once the poses are chosen (measuring them adds nothing here)."""


@pytest.mark.parametrize("seed", [5])
def test_no_planned_pose_is_hidden_from_the_tracker(seed: int) -> None:
    rng = np.random.default_rng(seed)
    truth = random_truth("ur5e", rng, ideal=True)
    world = World(truth, lambda: np.zeros(6))
    home = world.home_pose(rng)
    config = default_config().with_overrides(campaign__calibration_poses=30, campaign__validation_poses=20,
                                             campaign__candidates=3000, campaign__seed=seed,
                                             warmup__enabled=False, drift__every=0)  # a dry run of poses
    plan = calibration_plan(config, campaign_chooser(config), "test")
    chosen: list[PlanReady] = []

    def respond(step: Any) -> Any:
        if isinstance(step, ReadJoints):
            return Reading(home.copy(), np.zeros(6), step.samples)
        if isinstance(step, Acquire):
            assert step.role == BOOTSTRAP, "measuring starts after the plan is ready"
            q = np.array(step.steps[0].q)
            _p, angle = world.state(q)
            assert angle <= 30 and not world.blocked_by_arm(q), f"bootstrap pose {step.index} is hidden"
            q_read, points = measure(truth, q[None], Noise(), rng)
            return PoseRecord(step.index, step.role, q, q_read[0], np.zeros(6), points[0], np.zeros(3), 1)
        if isinstance(step, Emit) and isinstance(step.event, PlanReady):
            chosen.append(step.event)
            raise PlanReadyReached
        return None

    with pytest.raises(PlanReadyReached):
        dry_run(plan, respond)
    (ready,) = chosen
    hidden = []
    for pose in ready.poses:
        q = np.array(pose["q"])
        angle = world.state(q)[1]
        if angle > world.acceptance_deg or world.blocked_by_arm(q):
            hidden.append((pose["index"], pose["role"], round(angle, 1), world.blocked_by_arm(q)))
    assert not hidden, hidden
    located = np.array(ready.tracker["xyz"])
    assert np.linalg.norm(located - truth.tracker.translation) < 0.03  # the tracker found to cm


def test_a_planned_pose_the_tracker_would_not_see_is_skipped_without_moving_there() -> None:
    """The poses are checked again during the run with the tracker and SMR fitted to the points so far;
    one that faces away is skipped at once with the reason, not driven to and waited on for 30 s."""
    from hil.calibration.selection import hidden_reason
    from hil.campaign.calibration_plan import Choice
    from hil.campaign.events import PoseSkipped
    from tests.hil.campaign.fakes import visible_poses

    rng = np.random.default_rng(8)
    truth = random_truth("ur5e", rng, ideal=True)
    world = World(truth, lambda: np.zeros(6))
    config = default_config().with_overrides(campaign__calibration_poses=14, campaign__validation_poses=4,
                                             tracker__position=tuple(truth.tracker.translation + 0.04),
                                             smr__offset=tuple(truth.smr + 0.003),
                                             warmup__enabled=False, drift__every=0)  # a dry run of poses

    def seen(q: np.ndarray) -> bool:
        return world.state(q)[1] <= 25 and not world.blocked_by_arm(q)

    def choose(request: Any) -> Choice:
        poses = [q for q in visible_poses(truth, 200, rng, half_angle_deg=25) if seen(q)][: request.count]
        if request.role == "calibration":
            away = poses[10].copy()
            away[4] += 1.2  # the wrist turned: the SMR faces 60-70° off the tracker
            assert not seen(away)
            poses[10] = away
        return Choice(np.array(poses), {"method": "test"})

    choose.hidden = hidden_reason  # type: ignore[attr-defined]
    visited: list[int] = []
    skipped: list[PoseSkipped] = []

    def respond(step: Any) -> Any:
        if isinstance(step, Acquire):
            q = np.array(step.steps[0].q)
            assert seen(q), f"the plan drove to pose {step.index}, which the tracker cannot see"
            visited.append(step.index)
            q_read, points = measure(truth, q[None], Noise(), rng)
            return PoseRecord(step.index, step.role, q, q_read[0], np.zeros(6), points[0], np.zeros(3), 1)
        if isinstance(step, Emit) and isinstance(step.event, PoseSkipped):
            skipped.append(step.event)
        return None

    _, result = dry_run(calibration_plan(config, choose, "test"), respond)
    assert [s.index for s in skipped] == [10] and "face away" in skipped[0].reason
    assert 10 not in visited and len(visited) == 17 and result.passed
