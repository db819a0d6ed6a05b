"""Cross-validation scores the poses the fit rejected as outliers (`hil.calibration.cross_validation`,
"Rejected poses are scored"; issue 30): they are held out by construction, so leaving them out of the
figures would flatter the calibrated model, which explains them worst."""

from __future__ import annotations

import dataclasses

import numpy as np

from hil.calibration.cross_validation import cross_validate, fold_of, held_out_residuals, score_folds
from hil.calibration.identification import identify
from hil.calibration.measurements import Measurements
from hil.calibration.pose_cross_validation import cross_validate_pose
from hil.calibration.pose_identification import identify_pose
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from tests.hil.calibration.sixd_data import ORIENTATION_NOISE, POSITION_NOISE, sixd_set


def _push(p: np.ndarray, rows: list[int], rng: np.random.Generator, size: float) -> np.ndarray:
    """`p` with the points of `rows` moved by `size` (m) in random directions: gross outliers."""
    out = p.copy()
    for i in rows:
        d = rng.normal(size=3)
        out[i] += size * d / np.linalg.norm(d)
    return out


def test_a_pose_outside_the_training_set_is_predicted_by_the_fit_on_every_training_pose() -> None:
    """On a linear problem (where one step is the fit): the excluded poses' errors are those of the
    least-squares fit to all training poses, and each fold's poses those of the fit to the training
    poses outside the fold — the excluded ones never train anything."""
    rng = np.random.default_rng(7)
    J = rng.normal(size=(23, 3, 4))
    A = J.reshape(69, 4)
    y = A @ rng.normal(size=4) + rng.normal(0, 0.1, 69)
    train = np.ones(23, dtype=bool)
    train[[3, 11, 17]] = False
    y[np.repeat(~train, 3)] += 5.0  # gross outliers that must not pull any fit
    rows = np.repeat(train, 3)
    full = np.linalg.lstsq(A[rows], y[rows], rcond=None)[0]
    r = (y - A @ full).reshape(23, 3)
    fold = fold_of(23, 10)
    got = held_out_residuals(r, J, fold, train=train)
    np.testing.assert_allclose(got[~train], r[~train], rtol=1e-9, atol=1e-12)
    for f in range(10):
        fit_rows = np.repeat(train & (fold != f), 3)
        own = np.linalg.lstsq(A[fit_rows], y[fit_rows], rcond=None)[0]
        expect = (y - A @ own).reshape(23, 3)[train & (fold == f)]
        np.testing.assert_allclose(got[train & (fold == f)], expect, rtol=1e-9, atol=1e-12)


def test_the_folds_span_every_pose_and_need_two_fitted_ones() -> None:
    used = np.ones(12, dtype=bool)
    used[[0, 5]] = False
    kept, fold = score_folds(used)
    assert fold.tolist() == [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0, 1] and kept.sum() == 10
    try:
        score_folds(np.array([True, False, False]))
    except ValueError as e:
        assert "at least 2 fitted poses" in str(e)
    else:
        raise AssertionError("one fitted pose cannot be cross-validated")


def test_rejected_positions_enter_both_models_held_out_figures() -> None:
    """30 tracker-grade poses, 3 pushed 5 mm: the fit rejects them, and every model's held-out figures
    count all 30 — the calibrated model's error on a rejected pose is the full fit's residual there (the
    fit never saw it), the nominal's the registration on the kept poses, both millimetres."""
    rng = np.random.default_rng(11)
    truth = random_truth("ur5e", rng)
    q, p = measure(truth, random_configurations("ur5e", 30, rng), Noise(20e-6), rng)
    bad = [4, 13, 22]
    meas = Measurements(q, _push(p, bad, rng, 5e-3), np.arange(30) + 2, "outliers.csv")
    fit = identify(meas, "ur5e")
    assert sorted(r.index for r in fit.rejected) == bad
    cv = cross_validate(meas, fit)
    assert (cv.poses, cv.rejected, cv.calibrated.count, cv.nominal.count) == (30, 3, 30, 30)
    np.testing.assert_allclose(cv.calibrated.errors[bad], np.linalg.norm(fit.residuals[bad], axis=1))
    assert cv.calibrated.errors[bad].min() > 3e-3 and cv.nominal.errors[bad].min() > 1e-3
    kept = np.setdiff1d(np.arange(30), bad)
    assert cv.calibrated.rms > 3 * np.sqrt(np.mean(cv.calibrated.errors[kept] ** 2))  # they count
    block = cv.as_dict()
    assert (block["poses"], block["fitted"], block["rejected"], block["rejected_scored"]) == (30, 27, 3, True)
    # the verdict still stands: the same outliers weigh on both models
    assert cv.better_than_nominal


def test_rejected_6d_poses_enter_both_models_held_out_figures_and_scores() -> None:
    _, meas = sixd_set(seed=5, poses=30)
    rng = np.random.default_rng(5)
    bad = [2, 19]
    meas = dataclasses.replace(meas, p=_push(meas.p, bad, rng, 20 * POSITION_NOISE), reflectors=None)
    fit = identify_pose(meas, "ur10e", position_noise=POSITION_NOISE, orientation_noise=ORIENTATION_NOISE)
    assert sorted(r.index for r in fit.rejected) == bad
    cv = cross_validate_pose(meas, fit)
    assert (cv.poses, cv.rejected, cv.calibrated.count, cv.nominal.count) == (30, 2, 30, 30)
    assert cv.orientation["calibrated"].count == cv.orientation["nominal"].count == 30
    assert len(cv.scores["calibrated"]) == len(cv.scores["nominal"]) == 30
    assert cv.calibrated.errors[bad].min() > 5 * POSITION_NOISE
    assert cv.scores["calibrated"][bad].min() > 20 * np.median(cv.scores["calibrated"])
    assert cv.as_dict()["rejected"] == 2
