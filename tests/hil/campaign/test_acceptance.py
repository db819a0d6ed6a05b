"""The campaign's verdict (`hil.campaign.acceptance`): better than nominal and the controller's model by
cross-validation, always; then the user's threshold, or the cross-validated floor and the robot class's
bound. And a campaign carries the cross-validation into its model, result, report."""

from __future__ import annotations

from html import escape as html_escape
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
from scipy.stats import f as scipy_f

from hil.calibration.synthetic import Noise, measure, random_truth
from hil.campaign.acceptance import (
    CLASS_MARGIN,
    FLOOR_FACTOR,
    FLOOR_QUANTILE,
    REAL_UR5_CALIBRATED,
    class_bound,
    floor_factor,
    judge,
    threshold,
)
from hil.campaign.calibration_plan import Choice, calibration_plan
from hil.campaign.steps import Acquire, PoseRecord, dry_run
from hil.report import mes_result
from hil.report.data import report_data_from_result
from hil.report.render import render_html
from hil.station.config import default_config
from tests.hil.campaign.fakes import visible_poses


def cv(calibrated: float, better: bool = True) -> Any:
    return SimpleNamespace(calibrated=SimpleNamespace(rms=calibrated), better_than_nominal=better,
                           verdict=lambda: "the calibrated model does not predict held-out poses better "
                                           "than the nominal model (...)")


def test_the_class_bound_is_the_real_ur5_figure_with_margin_scaled_by_reach() -> None:
    assert class_bound("ur5e") == pytest.approx(CLASS_MARGIN * REAL_UR5_CALIBRATED)
    assert class_bound("ur10e") == pytest.approx(class_bound("ur5e") * 1.3 / 0.85)
    # a real, well-calibrated UR5 at 0.2 mm passes; its nominal model at 1.41 mm does not
    assert 0.2e-3 < class_bound("ur5") < 1.41e-3
    assert threshold(None, "ur5e") == class_bound("ur5e") and threshold(0.3e-3, "ur5e") == 0.3e-3


def test_the_automatic_verdict() -> None:
    real = judge(0.21e-3, cv(0.19e-3), "ur5")  # a real UR5: accepted, where 0.1 mm rejected it
    assert real.passed and real.rule == "auto" and real.threshold == pytest.approx(FLOOR_FACTOR * 0.19e-3)
    drifted = judge(0.5e-3, cv(0.02e-3), "ur5e")  # validation far above what the fit predicts
    assert not drifted.passed and "cross-validated" in drifted.reason
    bad_arm = judge(0.9e-3, cv(0.8e-3), "ur5e")  # within the floor, beyond the class
    assert not bad_arm.passed and "class bound" in bad_arm.reason


def test_a_campaign_the_stopping_rule_ended_is_judged_against_the_prediction_it_stopped_on() -> None:
    # the simulated run stopped at 14 poses: cross-validated 0.021 mm, predicted 0.0755 mm, validation
    # 0.0656 mm — what the campaign said it would measure; rejected against 2 x 0.021 mm before
    stopped = judge(0.0656e-3, cv(0.021e-3), "ur5e", predicted=0.0755e-3)
    assert stopped.passed and stopped.threshold == pytest.approx(FLOOR_FACTOR * 0.0755e-3)
    assert "predicted 0.0755 mm" in stopped.reason and "cross-validated 0.0210 mm" in stopped.reason
    assert not judge(0.0656e-3, cv(0.021e-3), "ur5e").passed  # not stopped early: the floor is the CV's
    # a validation far beyond the prediction is still rejected; a prediction below the CV changes nothing
    assert not judge(0.2e-3, cv(0.021e-3), "ur5e", predicted=0.0755e-3).passed
    low = judge(0.03e-3, cv(0.021e-3), "ur5e", predicted=0.01e-3)
    assert low.threshold == pytest.approx(FLOOR_FACTOR * 0.021e-3) and "predicted" not in low.reason
    # neither lifts the class bound, nor rescues a model worse than nominal
    assert not judge(0.6e-3, cv(0.3e-3), "ur5e", predicted=0.4e-3).passed
    assert not judge(0.01e-3, cv(0.01e-3, better=False), "ur5e", predicted=0.05e-3).passed


def test_not_better_than_nominal_is_rejected_whatever_the_threshold() -> None:
    for acceptance in (None, 5e-3):
        verdict = judge(0.01e-3, cv(0.01e-3, better=False), "ur5e", acceptance)
        assert not verdict.passed and "does not predict held-out poses better" in verdict.reason
    user = judge(0.15e-3, cv(0.01e-3), "ur5e", 0.2e-3)  # the user's threshold replaces floor and bound
    assert user.passed and user.rule == "threshold" and user.threshold == 0.2e-3


def test_a_campaign_carries_its_cross_validation_into_model_result_and_report() -> None:
    rng = np.random.default_rng(12)
    truth = random_truth("ur5e", rng)

    def respond(step: Any) -> Any:
        if isinstance(step, Acquire):
            q = np.array(step.steps[0].q)
            q_read, points = measure(truth, q[None], Noise(), rng)
            return PoseRecord(step.index, step.role, q, q_read[0], np.zeros(6), points[0], np.zeros(3), 1)
        return None

    config = default_config().with_overrides(
        campaign__calibration_poses=24, campaign__validation_poses=8, robot__settle_time=0.0,
        smr__offset=tuple(truth.smr + 0.003), tracker__position=tuple(truth.tracker.translation + 0.05),
        warmup__enabled=False, drift__every=0)
    assert config.campaign["acceptance"] is None  # the default: the automatic verdict
    choose = lambda request: Choice(visible_poses(request.model, request.count, rng), {})  # noqa: E731
    _, result = dry_run(calibration_plan(config, choose, "c1"), respond)
    assert result.cross_validation is not None and result.verdict is not None
    assert result.model["better_than_nominal"] is True
    assert result.model["cross_validation"]["calibrated"]["rms"] == result.cross_validation.calibrated.rms
    assert result.passed == result.verdict.passed and result.verdict.rule == "auto"
    assert result.passed, result.verdict.reason

    from hil.report.result import report_data

    outcome = SimpleNamespace(result=result, campaign="c1", robot_info={}, timing=None)
    doc = mes_result(report_data(outcome, config, [], 0.0))
    assert doc["better_than_nominal"] is True and doc["cross_validation"]["folds"] == 10
    assert doc["verdict"]["rule"] == "auto" and doc["accept_rms"] == pytest.approx(result.verdict.threshold)
    html = render_html(report_data_from_result(doc))
    assert "10-fold cross-validation (held-out RMS)" in html
    assert html_escape(result.verdict.reason, quote=False) in html


def test_few_validation_poses_get_the_f_test_bound_not_a_fixed_factor() -> None:
    """With one or two validation poses the RMS ratio of one error distribution scatters beyond 2:
    the factor is then the 99.9 % bound of F(3n, 3N); from three poses on it is `FLOOR_FACTOR`."""
    assert floor_factor(1, 24) == pytest.approx(np.sqrt(scipy_f.ppf(FLOOR_QUANTILE, 3, 72)))
    assert floor_factor(1, 24) > floor_factor(2, 24) > FLOOR_FACTOR
    assert floor_factor(4, 24) == floor_factor(None, 24) == FLOOR_FACTOR
    fit = SimpleNamespace(calibrated=SimpleNamespace(rms=0.01e-3), better_than_nominal=True, poses=24,
                          verdict=lambda: "")
    one = judge(0.022e-3, fit, "ur5e", validation_poses=1)  # 2.2 x: within one pose's scatter
    assert one.passed and one.floor_factor == pytest.approx(floor_factor(1, 24))
    assert "2.46 x the cross-validated" in one.reason and one.as_dict()["floor_factor"] == one.floor_factor
    assert not judge(0.022e-3, fit, "ur5e", validation_poses=4).passed


def test_the_f_bound_holds_for_gaussian_errors() -> None:
    """Validation and cross-validation RMS of the same Gaussian point errors: one validation pose
    against 24 is beyond the bound in about one draw in a thousand, and beyond a fixed 2 in several."""
    rng = np.random.default_rng(4)
    val = np.sqrt(np.mean(rng.normal(size=(20000, 1, 3)) ** 2, axis=(1, 2)))
    cvr = np.sqrt(np.mean(rng.normal(size=(20000, 24, 3)) ** 2, axis=(1, 2)))
    ratio = val / cvr
    assert np.mean(ratio > floor_factor(1, 24)) < 0.002
    assert np.mean(ratio > FLOOR_FACTOR) > 0.004
