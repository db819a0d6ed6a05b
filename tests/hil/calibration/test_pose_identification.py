"""The 6-D and several-reflector fit (`hil.calibration.pose_identification`) and its cross-validation
(`hil.calibration.pose_cross_validation`) on synthetic data from a known truth."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from hil.arm import tool_frame as tf
from hil.calibration.measurements import read_measurements
from hil.calibration.pose_cross_validation import cross_validate_pose
from hil.calibration.pose_identification import identify_pose, uses_tool
from hil.calibration.synthetic import random_configurations
from hil.calibration.synthetic_tool import measure_tool
from tests.hil.calibration.sixd_data import (
    ORIENTATION_NOISE,
    POSITION_NOISE,
    SIXD_CSV,
    sixd_set,
    write_sixd_csv,
)


def _fit(meas, **kw):
    return identify_pose(meas, "ur10e", position_noise=POSITION_NOISE, orientation_noise=ORIENTATION_NOISE,
                         prior=False, **kw)


def _z(fit, names, error):
    k = [fit.names.index(n) for n in names]
    return np.asarray(error) / fit.std[k]


def _prediction_z(truth, fit, rng) -> float:
    """RMS over fresh poses of the model's position error over its predicted standard deviation."""
    q = random_configurations("ur10e", 200, rng)
    p_true, _ = tf.predict(truth, q)
    p_fit, _ = tf.predict(fit.geometry, q)
    _, _, J = tf.frame_and_jacobian(fit.geometry, q, fit.pose_fit.orientation)
    Jp = J[:, : 3 * fit.pose_fit.reflectors][:, :, fit.pose_fit.local]
    var = np.einsum("nij,jk,nik->ni", Jp, fit.covariance, Jp)
    return float(np.sqrt(np.mean((p_true - p_fit).reshape(len(q), -1) ** 2 / var)))


@pytest.mark.parametrize("seed", [1, 2])
def test_a_6d_fit_recovers_the_tool_rotation_and_geometry_to_their_std(seed: int) -> None:
    truth, meas = sixd_set(seed=seed, poses=40)
    fit = _fit(meas)
    assert len(fit.indices) == 30 and not fit.rejected
    z = _z(fit, tf.TOOL_ROTATION_NAMES, pin.log3(truth.tool_rotation.T @ fit.geometry.tool_rotation))
    assert np.all(np.abs(z) < 4.0), z
    assert 0.5 < fit.pose_fit.scale < 1.5  # the stated noises are the true ones
    assert 0.4 < _prediction_z(truth, fit, np.random.default_rng(seed + 100)) < 2.0
    rms = fit.pose_fit.as_dict(fit.used)["orientation_rms"]
    assert rms == pytest.approx(np.sqrt(3) * ORIENTATION_NOISE, rel=0.35)


def test_a_several_reflector_fit_recovers_each_offset() -> None:
    truth, meas = sixd_set(seed=5, poses=30, reflectors=3, orientation=False)
    assert uses_tool(meas) and meas.rotation is None
    fit = _fit(meas)
    assert len(fit.indices) == 33
    for k in range(3):
        names = ["smr.x", "smr.y", "smr.z"] if k == 0 else [f"reflector{k + 1}.{a}" for a in "xyz"]
        z = _z(fit, names, fit.geometry.reflectors[k] - truth.reflectors[k])
        assert np.all(np.abs(z) < 4.0), (k, z)
    assert 0.4 < _prediction_z(truth, fit, np.random.default_rng(9)) < 2.0


def test_cross_validation_of_a_6d_fit_predicts_fresh_poses() -> None:
    truth, meas = sixd_set(seed=3, poses=40)
    fit = identify_pose(meas, "ur10e", position_noise=POSITION_NOISE, orientation_noise=ORIENTATION_NOISE)
    cv = cross_validate_pose(meas, fit)
    assert cv.folds == 10 and cv.better_than_nominal
    assert cv.calibrated.rms < cv.nominal.rms
    assert cv.orientation["calibrated"].rms < cv.orientation["nominal"].rms
    rng = np.random.default_rng(33)
    q = random_configurations("ur10e", 300, rng)
    fresh = measure_tool(truth, q, rng, POSITION_NOISE, ORIENTATION_NOISE)
    p, R = tf.predict(fit.geometry, fresh.q)
    measured_p = float(np.sqrt(np.mean(np.sum((fresh.p - p[:, 0]) ** 2, axis=1))))
    measured_o = float(np.sqrt(np.mean(np.sum(tf.rotation_residuals(fresh.rotation, R) ** 2, axis=1))))
    assert 0.7 < cv.calibrated.rms / measured_p < 1.4
    assert 0.7 < cv.orientation["calibrated"].rms / measured_o < 1.4
    block = cv.as_dict()
    assert block["orientation"]["calibrated"]["rms"] == cv.orientation["calibrated"].rms
    assert "mrad" in cv.verdict()


def test_a_hopeless_6d_set_is_not_called_better() -> None:
    # an arm exactly as drawn, a dozen noisy poses: there is nothing a fit could improve on the nominal
    for seed in (4, 6, 7):
        _, meas = sixd_set(seed=seed, poses=12, position_noise=3e-3, orientation_noise=3e-3, placement=0.0)
        fit = identify_pose(meas, "ur10e", position_noise=3e-3, orientation_noise=3e-3)
        assert not cross_validate_pose(meas, fit).better_than_nominal, seed


def test_the_committed_file_is_the_known_truth_s_and_reads_as_6d(tmp_path) -> None:
    again = tmp_path / "again.csv"
    write_sixd_csv(again)
    assert again.read_text() == SIXD_CSV.read_text()
    meas = read_measurements(SIXD_CSV)
    _, memory = sixd_set()
    np.testing.assert_allclose(meas.rotation, memory.rotation, atol=1e-12)
    np.testing.assert_allclose(meas.p, memory.p, atol=1e-15)
