"""``campaign.plan_cache``: the same question on the next robot of a line gets the same poses without
choosing again; any change the choice depends on asks again; a broken cache only costs time."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from hil.calibration.synthetic import random_truth
from hil.campaign.calibration_plan import CALIBRATION, Choice, SelectionRequest
from hil.campaign.chooser import campaign_chooser
from hil.campaign.engine import RealClock
from hil.campaign.events import EventBus, PlanReady
from hil.campaign.plan_cache import cached_chooser, request_key
from hil.campaign.runner import run_campaign
from hil.errors import InputError
from hil.station.config import default_config
from tests.hil.campaign.fakes import FakeArm, FakeTracker, visible_poses
from tests.hil.campaign.test_clustered_validation import CANDIDATES, _config, _Devices, _request


def _counting(poses: np.ndarray) -> tuple[Any, list[Any]]:
    asked: list[Any] = []

    def choose(request: Any) -> Choice:
        asked.append(request)
        return Choice(poses + len(asked), {"method": "test", "asked": len(asked), "array": np.arange(3)})

    return choose, asked


def test_the_same_question_is_answered_from_the_cache(tmp_path: Path) -> None:
    config = _config(0)
    inner, asked = _counting(np.zeros((4, 6)))
    choose = cached_chooser(inner, config, tmp_path / "plans")
    first = choose(_request(config, seed=3))
    again = choose(_request(config, seed=3))
    assert len(asked) == 1 and np.array_equal(first.poses, again.poses)
    assert first.info["plan_cache"]["reused"] is False and again.info["plan_cache"]["reused"] is True
    assert again.info["asked"] == 1 and again.info["array"] == [0, 1, 2]  # stored as JSON
    # another robot of the line: its own address and the day's weather are not part of the question
    other = config.with_overrides(robot__address="127.0.0.9", tracker__temperature=26.0)
    assert np.array_equal(cached_chooser(inner, other, tmp_path / "plans")(_request(other, 3)).poses,
                          first.poses) and len(asked) == 1


@pytest.mark.parametrize("change", [
    {"robot__speed": 0.4}, {"campaign__search_time": 20.0}, {"campaign__selection": "time-aware"},
    {"tracker__position": [2.0, 0.5, 0.3]}, {"keep_in__max": [1.0, 1.0, 1.1]}, {"robot__type": "ur10e"},
])
def test_anything_the_choice_depends_on_asks_again(tmp_path: Path, change: dict[str, Any]) -> None:
    config = _config(0)
    assert request_key(config, _request(config, 3)) != request_key(config.with_overrides(**change),
                                                                   _request(config, 3))


def test_the_start_pose_counts_to_a_hundredth_of_a_radian() -> None:
    config = _config(0)
    start = np.array([0.1, -1.2, 1.3, -1.5, -1.5, 0.3])
    key = request_key(config, _request(config, 3, start=start))
    assert request_key(config, _request(config, 3, start=start + 1e-4)) == key  # encoder noise
    assert request_key(config, _request(config, 3, start=start + np.array([0.05, 0, 0, 0, 0, 0]))) != key
    assert request_key(config, _request(config, 4, start=start)) != key  # another seed


def test_a_bootstrapped_tracker_a_millimetre_away_asks_the_same_question() -> None:
    import pinocchio as pin

    config = _config(0)
    base = _request(config, 3)
    key = request_key(config, base)

    def moved(by: float) -> Any:
        model = base.model.copy()
        model.tracker = pin.SE3(base.model.tracker.rotation,
                                base.model.tracker.translation + np.array([by, 0.0, 0.0]))
        return SelectionRequest(base.role, base.count, model=model, keep_in=base.keep_in,
                                acceptance_angle=base.acceptance_angle, index=base.index,
                                candidates=base.candidates, seed=base.seed, exclude=base.exclude)

    assert request_key(config, moved(0.001)) == key
    assert request_key(config, moved(0.05)) != key


def test_an_unreadable_entry_is_chosen_again_and_rewritten(tmp_path: Path) -> None:
    config = _config(0)
    inner, asked = _counting(np.zeros((4, 6)))
    choose = cached_chooser(inner, config, tmp_path)
    choose(_request(config, seed=3))
    (entry,) = tmp_path.glob("*.json")
    entry.write_text("{ half a file")
    again = choose(_request(config, seed=3))
    assert len(asked) == 2 and again.info["plan_cache"]["reused"] is False
    assert choose(_request(config, seed=3)).info["plan_cache"]["reused"] is True


def test_a_cache_path_that_is_a_file_is_bad_input(tmp_path: Path) -> None:
    blocker = tmp_path / "plans"
    blocker.write_text("not a directory")
    with pytest.raises(InputError, match=r"campaign\.plan_cache: .*plans"):
        campaign_chooser(_config(0).with_overrides(campaign__plan_cache=str(blocker)))


def test_the_next_campaign_of_the_line_measures_the_same_poses_without_choosing(tmp_path: Path) -> None:
    rng = np.random.default_rng(7)
    truth = random_truth("ur5e", rng, rigid=True)
    config = default_config().with_overrides(
        campaign__calibration_poses=12, campaign__validation_poses=4, campaign__compliance=False,
        campaign__candidates=CANDIDATES, campaign__samples=2, campaign__plan_cache=str(tmp_path / "plans"),
        robot__settle_time=0.0, robot__settle="fixed", robot__joint_samples=2,
        tracker__position=tuple(truth.tracker.translation), smr__offset=tuple(truth.smr),
        warmup__enabled=False, drift__every=0)
    home = visible_poses(truth, 1, rng)[0]
    plans = []
    for robot in range(2):
        arm = FakeArm(home)
        events: list[Any] = []
        bus = EventBus()
        bus.subscribe(events.append, critical=True)
        out = run_campaign(config, campaign_chooser(config), bus=bus, campaign=f"robot-{robot}",
                           devices=_Devices(arm, FakeTracker(arm, truth)), clock=RealClock())
        assert out.status in ("accepted", "rejected"), out.error
        (ready,) = [e for e in events if isinstance(e, PlanReady)]
        plans.append(ready)
    first, second = plans
    assert [p["q"] for p in second.poses] == [p["q"] for p in first.poses]
    for role in ("calibration", "validation"):
        assert first.selection[role]["plan_cache"]["reused"] is False
        assert second.selection[role]["plan_cache"]["reused"] is True
        assert second.selection[role]["method"] == first.selection[role]["method"]


def test_calibration_requests_carry_their_fixed_poses_into_the_key() -> None:
    config = _config(0)
    base = _request(config, 3)
    ask = dict(model=base.model, keep_in=base.keep_in, acceptance_angle=base.acceptance_angle,
               index=base.index, candidates=base.candidates, seed=1, exclude=np.zeros((0, 6)))
    a = SelectionRequest(CALIBRATION, 14, fixed=np.zeros((2, 6)), **ask)
    b = SelectionRequest(CALIBRATION, 14, fixed=np.ones((2, 6)), **ask)
    assert request_key(config, a) != request_key(config, b)
