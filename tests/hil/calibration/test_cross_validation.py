"""Cross-validation (`hil.calibration.cross_validation`): folds, the linearised folds against refitting,
its estimate against the truth on synthetic stations, and the better-than-nominal verdict."""

from __future__ import annotations

import numpy as np
import pytest

from hil.arm.kinematics import Kinematics
from hil.calibration.cross_validation import (
    MAX_FOLDS,
    CrossValidation,
    cross_validate,
    default_folds,
    fold_of,
    held_out_residuals,
    paired_p_value,
)
from hil.calibration.identification import ErrorStats, identify, register
from hil.calibration.joint_error_selection import identify_with_joint_errors
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth, true_points


def station(robot: str, poses: int, sigma: float, seed: int, rigid: bool = True, ideal: bool = True):
    rng = np.random.default_rng(seed)
    truth = random_truth(robot, rng, rigid=rigid, ideal=ideal)
    q, p = measure(truth, random_configurations(robot, poses, rng), Noise(sigma), rng)
    return truth, Measurements(q, p, np.arange(poses) + 2, f"{robot}-{seed}.csv"), rng


def test_folds_are_interleaved_ten_at_most_and_leave_one_out_for_few_poses() -> None:
    assert default_folds(40) == MAX_FOLDS == 10 and default_folds(7) == 7
    assert fold_of(12).tolist() == [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0, 1]
    assert sorted(fold_of(7).tolist()) == list(range(7))  # leave-one-out
    with pytest.raises(ValueError, match="2..5 folds"):
        fold_of(5, 6)


def test_the_linear_step_is_exact_for_a_linear_model() -> None:
    """On a linear least-squares problem one step from the full fit is the fold's own fit."""
    rng = np.random.default_rng(3)
    J = rng.normal(size=(20, 3, 4))
    theta = rng.normal(size=4)
    y = J.reshape(60, 4) @ theta + rng.normal(0, 0.1, 60)
    full = np.linalg.lstsq(J.reshape(60, 4), y, rcond=None)[0]
    r = (y - J.reshape(60, 4) @ full).reshape(20, 3)
    fold = fold_of(20, 5)
    got = held_out_residuals(r, J, fold)
    for f in range(5):
        train = np.repeat(fold != f, 3)
        own = np.linalg.lstsq(J.reshape(60, 4)[train], y[train], rcond=None)[0]
        expect = (y - J.reshape(60, 4) @ own).reshape(20, 3)[fold == f]
        np.testing.assert_allclose(got[fold == f], expect, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize(("robot", "poses", "sigma", "seed"), [
    ("ur5e", 30, 20e-6, 0), ("ur10e", 25, 1e-3, 1), ("ur5e", 12, 3e-3, 2)])
def test_linearised_folds_agree_with_refitting_each_fold(robot, poses, sigma, seed) -> None:
    _, meas, _ = station(robot, poses, sigma, seed)
    fit = identify(meas, robot, reject_outliers=False)
    cv = cross_validate(meas, fit)
    fold = fold_of(poses)
    cal, nom = np.empty((poses, 3)), np.empty((poses, 3))
    for f in range(cv.folds):
        train, test = fold != f, fold == f
        part = Measurements(meas.q[train], meas.p[train], meas.lines[train], "train")
        own = identify(part, robot, reject_outliers=False)
        cal[test] = meas.p[test] - Kinematics(own.geometry).points(meas.q[test])
        nom[test] = meas.p[test] - Kinematics(register(part, robot)).points(meas.q[test])
    # a refit moves each fold's σ̂ and so its prior's weight a little; the step does not
    assert cv.calibrated.rms == pytest.approx(ErrorStats.of(cal).rms, rel=0.1)
    assert cv.nominal.rms == pytest.approx(ErrorStats.of(nom).rms, rel=1e-3)


def _cv_against_fresh_poses(seed: int, ideal: bool):
    """(cv, fit, fresh points, fresh joints, CV RMS / fresh RMS) of a 30-pose fit on a compliant arm
    (UR5e for even seeds, UR10e for odd), against 1000 fresh measured poses (20 µm)."""
    robot = ("ur5e", "ur10e")[seed % 2]
    truth, meas, rng = station(robot, 30, 20e-6, seed, rigid=False, ideal=ideal)
    fit = identify(meas, robot)
    cv = cross_validate(meas, fit)
    q_fresh, p_fresh = measure(truth, random_configurations(robot, 1000, rng), Noise(20e-6), rng)
    fresh = ErrorStats.of(p_fresh - Kinematics(fit.geometry).points(q_fresh))
    return cv, fit, p_fresh, q_fresh, cv.calibrated.rms / fresh.rms


def test_the_estimate_agrees_with_the_truth_on_fresh_poses() -> None:
    """CV's RMS against the RMS of 1000 fresh measured poses (the model's error plus the tracker's
    noise: what a validation measures), over synthetic stations of both arms: within a factor 1.3.

    Measured (30 poses, 20 µm, ideal arms — compliance, payload, warm-up — fitted without compliance):
    CV/fresh 0.95-1.17 for seeds 0-5, 0.83-1.17 for seeds 0-11."""
    ratios = []
    for seed in range(6):
        cv, fit, p_fresh, q_fresh, ratio = _cv_against_fresh_poses(seed, ideal=True)
        ratios.append(ratio)
        nominal_fresh = ErrorStats.of(p_fresh - Kinematics(fit.baseline).points(q_fresh))
        assert cv.nominal.rms / nominal_fresh.rms == pytest.approx(1.0, abs=0.5)
        assert cv.better_than_nominal
    assert min(ratios) > 1 / 1.3 and max(ratios) < 1.3, ratios


def test_on_the_realistic_arm_the_estimate_stays_within_its_measured_spread() -> None:
    """On the realistic arm (joint errors and their high-frequency part, `hil.arm.joint_physics`) what
    is left after the fit is structured, not noise, and 30-40 poses estimate it less surely: CV/fresh
    measured 0.65-1.16 over seeds 0-11 (30 poses, geometry only; 0.70-1.16 with compliance; 40 poses
    0.65-1.17). CV tends to be optimistic there, never by more than a factor 1.6."""
    ratios = [_cv_against_fresh_poses(seed, ideal=False)[-1] for seed in range(6)]
    assert min(ratios) > 1 / 1.6 and max(ratios) < 1.3, ratios


def test_a_hopeless_data_set_is_not_called_better() -> None:
    """12 poses with 3 mm noise (a camera's, on a tracker's job): the fit cannot beat the nominal."""
    refused = 0
    for seed in range(6):
        _, meas, _ = station("ur5e", 12, 3e-3, seed)
        cv = cross_validate(meas, identify(meas, "ur5e"))
        refused += not cv.better_than_nominal
        if not cv.better_than_nominal:
            assert "does not predict held-out poses better than the nominal model" in cv.verdict()
            assert cv.as_dict()["better_than_nominal"] is False
    assert refused >= 5


#: Bad-data stations of `bench/bad_data.py` (seed 0) that the naive paired t test (per-pose variance)
#: exported although the truth says the model is worse than nominal: robot, seed, poses, σ (m), outliers.
WORSE_BUT_EXPORTED_BEFORE = [("ur5e", 1341434675, 10, 1.016e-3, 0), ("ur10e", 588053791, 14, 1.938e-3, 2),
                             ("ur10e", 1487200420, 11, 1.695e-3, 2), ("ur5e", 1263536663, 14, 1.589e-3, 0),
                             ("ur10e", 641890153, 11, 1.733e-3, 0), ("ur10e", 1667716326, 15, 1.575e-3, 0)]


@pytest.mark.parametrize(("robot", "seed", "poses", "sigma", "outliers"), WORSE_BUT_EXPORTED_BEFORE)
def test_a_bad_data_model_worse_than_nominal_is_not_called_better(robot, seed, poses, sigma,
                                                                  outliers) -> None:
    """The realistic arm, few poses approached from below, a camera's noise, maybe outliers, fitted as
    `hil identify` does: the truth over 500 fresh poses says the model is worse than the nominal, and
    the folds' corrected test no longer calls it better (the naive one did, at p 0.009-0.04)."""
    cv = _worse_bad_station(robot, seed, poses, sigma, outliers)
    naive = cv.nominal.errors**2 - cv.calibrated.errors**2
    assert naive.mean() > 1.8 * naive.std(ddof=1) / np.sqrt(len(naive))  # the naive test said better
    assert not cv.better_than_nominal, cv.verdict()


def _worse_bad_station(robot: str, seed: int, poses: int, sigma: float, outliers: int) -> CrossValidation:
    """A `bench/bad_data.py` station fitted and cross-validated as `hil identify` does, after checking
    that the truth over 500 fresh poses says its model is worse than the nominal."""
    rng = np.random.default_rng(seed)
    truth = random_truth(robot, rng, ideal=False)
    up = np.ones(6)

    def upper_arm_up(count: int) -> np.ndarray:
        q = random_configurations(robot, count, rng)
        q[:, 1] = rng.uniform(-np.pi, 0.0, count)
        return q

    q, p = measure(truth, upper_arm_up(poses), Noise(sigma), rng, directions=up)
    for i in rng.choice(poses, outliers, replace=False):
        direction = rng.normal(size=3)
        p[i] += rng.uniform(5e-3, 20e-3) * direction / np.linalg.norm(direction)
    meas = Measurements.from_arrays(q, p, directions=np.broadcast_to(up, q.shape))
    fit = identify_with_joint_errors(meas, robot)
    cv = cross_validate(meas, fit)
    qv = upper_arm_up(500)
    actual = true_points(truth, qv, directions=up)
    nominal = register(meas.subset(fit.used), robot)
    worse = (np.linalg.norm(Kinematics(fit.geometry).points(qv, directions=np.broadcast_to(up, qv.shape))
                            - actual, axis=1) ** 2).mean()
    assert worse > (np.linalg.norm(Kinematics(nominal).points(qv) - actual, axis=1) ** 2).mean()
    return cv


#: Bad-data stations of `bench/bad_data.py` (seed 1) that the corrected paired test on the differences of
#: squared errors still exported at 5 % (p 0.015-0.022) although the truth says the model is worse than
#: nominal: robot, seed, poses, σ (m), outliers.
WORSE_BUT_EXPORTED_BY_THE_DIFFERENCE_TEST = [("ur5e", 1897149461, 15, 1.4482e-3, 0),
                                             ("ur10e", 74845286, 10, 1.9230e-3, 0)]


@pytest.mark.parametrize(("robot", "seed", "poses", "sigma", "outliers"),
                         WORSE_BUT_EXPORTED_BY_THE_DIFFERENCE_TEST)
def test_the_log_ratio_test_refuses_what_the_difference_test_exported(robot, seed, poses, sigma,
                                                                      outliers) -> None:
    """The stations above, fitted as `hil identify` does: the truth says worse; the difference test on
    the folds' mean differences (the previous verdict at 5 %) said better; the verdict's log-ratio test
    at 0.5 % does not."""
    cv = _worse_bad_station(robot, seed, poses, sigma, outliers)
    assert paired_p_value(cv.nominal.errors**2 - cv.calibrated.errors**2, cv.folds) < 0.05  # said better
    assert not cv.better_than_nominal, cv.verdict()


def test_the_controller_model_counts() -> None:
    """A controller's model as good as the fit's (the truth's own geometry) is not beaten."""
    truth, meas, _ = station("ur5e", 30, 20e-6, 4)
    fit = identify(meas, "ur5e")
    cv = cross_validate(meas, fit, controller=truth)
    assert cv.controller is not None and cv.controller.rms < 0.1e-3
    assert cv.better_than_controller is False and not cv.better_than_nominal
    assert "controller's own model" in cv.verdict()
    block = cv.as_dict()
    assert block["controller"]["rms"] == cv.controller.rms and block["better_than_controller"] is False


def test_better_needs_evidence_not_a_lower_rms() -> None:
    e = np.array([1.0, 1.0, 1.0, 1.0])
    tied = CrossValidation(4, 4, ErrorStats.of(np.c_[e * 0.99, 0 * e, 0 * e]),
                           ErrorStats.of(np.c_[e * np.array([0.5, 1.5, 0.6, 1.4]), 0 * e, 0 * e]))
    assert tied.calibrated.rms < tied.nominal.rms and not tied.better_than_nominal

