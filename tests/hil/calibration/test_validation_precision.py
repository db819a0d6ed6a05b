"""The validation RMS's standard error under the validation design
(`hil.calibration.validation_precision`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hil.calibration.validation_precision import (
    campaign_validation_precision,
    describe_precision,
    validation_precision,
)
from selector.cluster_sample import cluster_standard_error, design_effect

UM = 1e-6


def test_a_simple_random_sample_gives_the_hand_computed_standard_error() -> None:
    got = validation_precision(np.array([1, 2, 3, 4]) * UM, [0, 1, 2, 3])
    # by hand, in µm²: e² = 1, 4, 9, 16; mean 7.5; squared deviations 42.25 + 12.25 + 2.25 + 72.25 = 129,
    # s² = 129 / 3 = 43; SE(ms) = √43 / √4; RMS = √7.5; SE(RMS) = SE(ms) / (2 RMS)
    expected = math.sqrt(43) / 2 / (2 * math.sqrt(7.5)) * UM
    assert got == {"design": "simple random", "poses": 4, "clusters": None,
                   "rms_standard_error": pytest.approx(expected, rel=1e-12), "design_effect": None}


def test_a_cluster_sample_uses_the_cluster_standard_error_and_design_effect() -> None:
    rng = np.random.default_rng(4)
    labels = [0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3]  # 4 draws of 3 poses, by validation pose k
    # poses of one draw err alike: a draw's level plus a little of each pose's own
    errors = (np.repeat(rng.uniform(5, 30, 4), 3) + rng.normal(0, 1, 12)) * UM
    order = rng.permutation(12)  # the records in another order than the poses: mapped, not assumed
    got = validation_precision(errors[order], order, labels)
    values = errors**2
    rms = math.sqrt(values.mean())
    assert got["design"] == "clustered" and (got["poses"], got["clusters"]) == (12, 4)
    assert got["rms_standard_error"] == pytest.approx(cluster_standard_error(values, labels) / (2 * rms),
                                                      rel=1e-12)
    assert got["design_effect"] == pytest.approx(design_effect(values, labels), rel=1e-12)
    # alike within a draw: the cluster design is markedly less precise than as many random poses
    srs = validation_precision(errors, range(12))
    assert got["design_effect"] > 2 and got["rms_standard_error"] > srs["rms_standard_error"]


def test_repeated_cycles_are_averaged_per_pose_first() -> None:
    rng = np.random.default_rng(5)
    per_cycle = rng.uniform(5, 30, (3, 6)) * UM  # 3 cycles of 6 poses
    poses = np.tile(np.arange(6), 3)
    got = validation_precision(per_cycle.reshape(-1), poses)
    one_value_per_pose = np.sqrt(np.mean(per_cycle**2, axis=0))
    assert got == validation_precision(one_value_per_pose, range(6))
    assert got["poses"] == 6
    # not the same as taking the 18 measurements as 18 poses (that would be optimistic here)
    assert got != validation_precision(per_cycle.reshape(-1), range(18))


def test_a_cluster_that_lost_a_pose_is_estimated_as_a_ratio() -> None:
    rng = np.random.default_rng(6)
    labels = [0, 0, 1, 1, 2, 2]
    errors = rng.uniform(5, 30, 6) * UM
    kept = [0, 1, 2, 4, 5]  # pose 3 was skipped: draw 1 holds one pose
    got = validation_precision(errors[kept], kept, labels)
    # by hand: draw totals t_i and sizes n_i of e²; ȳ = Σt / Σn; var = k/(k−1)·Σ(t_i − ȳ n_i)² / (Σn)²
    y = errors**2
    t = np.array([y[0] + y[1], y[2], y[4] + y[5]])
    n = np.array([2, 1, 2])
    mean = t.sum() / n.sum()
    se = math.sqrt(3 / 2 * np.sum((t - mean * n) ** 2)) / n.sum()
    assert got["clusters"] == 3 and got["poses"] == 5
    assert got["rms_standard_error"] == pytest.approx(se / (2 * math.sqrt(mean)), rel=1e-12)
    assert got["design_effect"] == pytest.approx(se**2 / (np.var(y[kept], ddof=1) / 5), rel=1e-12)


@pytest.mark.parametrize(("errors", "poses", "labels", "n", "clusters"), [
    ([], [], None, 0, None),  # nothing measured
    ([1e-5], [0], None, 1, None),  # one pose
    ([1e-5, 2e-5, 3e-5], [4, 4, 4], None, 1, None),  # one pose, three cycles
    ([1e-5, 2e-5], [0, 1], [0, 0, 1, 1], 2, 1),  # one draw measured
    ([0.0, 0.0, 0.0], [0, 1, 2], None, 3, None),  # RMS 0: the delta method is undefined
    ([0.0, 0.0, 0.0, 0.0], [0, 1, 2, 3], [0, 0, 1, 1], 4, 2),  # RMS 0, clustered
    ([2e-5, 2e-5, 2e-5, 2e-5], [0, 1, 2, 3], [0, 0, 1, 1], 4, 2),  # no spread: no design effect
])
def test_degenerate_cases_give_none_not_a_crash(errors: list[float], poses: list[int],
                                               labels: list[int] | None, n: int,
                                               clusters: int | None) -> None:
    got = validation_precision(np.array(errors), poses, labels)
    assert (got["poses"], got["clusters"], got["design_effect"]) == (n, clusters, None)
    assert got["rms_standard_error"] in (None, 0.0)
    assert describe_precision(got)  # and it can still be shown


def test_mismatched_inputs_are_a_programming_error() -> None:
    with pytest.raises(ValueError, match="2 errors but 3"):
        validation_precision([1e-5, 2e-5], [0, 1, 2])
    with pytest.raises(ValueError, match="no cluster label"):
        validation_precision([1e-5, 2e-5], [0, 5], [0, 1])


def test_a_campaign_maps_its_records_to_poses_through_the_stored_plan() -> None:
    errors = np.array([10, 12, 30, 11, 13, 29]) * UM  # two cycles of poses 0, 1, 2
    info = {"method": "random", "pose_of_index": {"20": 0, "21": 1, "22": 2, "23": 0, "24": 1, "25": 2}}
    got = campaign_validation_precision(errors, [20, 21, 22, 23, 24, 25], info)
    assert got == validation_precision(errors, [0, 1, 2, 0, 1, 2])
    assert got["poses"] == 3
    clustered = {**info, "method": "clustered", "labels": [0, 0, 1]}
    assert campaign_validation_precision(errors, [20, 21, 22, 23, 24, 25], clustered) == \
        validation_precision(errors, [0, 1, 2, 0, 1, 2], [0, 0, 1])
    with pytest.raises(ValueError, match="pose 26"):
        campaign_validation_precision(errors, [20, 21, 22, 23, 24, 26], info)


def test_an_older_plan_takes_every_record_as_its_own_pose() -> None:
    errors = np.array([10, 12, 30, 11]) * UM
    assert campaign_validation_precision(errors, [7, 8, 9, 10], {"method": "random"}) == \
        validation_precision(errors, range(4))
    assert campaign_validation_precision(errors, [7, 8, 9, 10], None)["design"] == "simple random"
    # a cluster sample's labels cannot be put on the records without the map: said, not guessed
    older = {"method": "clustered", "labels": [0, 0, 1, 1]}
    got = campaign_validation_precision(errors, [7, 8, 9, 10], older)
    assert got == {"design": "clustered", "poses": 4, "clusters": 2, "rms_standard_error": None,
                   "design_effect": None}


def test_the_one_line_says_the_standard_error_and_the_design() -> None:
    assert describe_precision(None) is None
    assert describe_precision({"design": "clustered", "poses": 20, "clusters": 4,
                               "rms_standard_error": 1.84e-6, "design_effect": 2.13}) == \
        "± 1.8 µm (1 s.e., 4 clusters, design effect 2.1)"
    assert describe_precision({"design": "simple random", "poses": 20, "clusters": None,
                               "rms_standard_error": 0.96e-6, "design_effect": None}) == \
        "± 1.0 µm (1 s.e., simple random)"
    assert describe_precision({"design": "simple random", "poses": 1, "clusters": None,
                               "rms_standard_error": None, "design_effect": None}) == \
        "standard error not estimated (simple random, 1 pose)"
