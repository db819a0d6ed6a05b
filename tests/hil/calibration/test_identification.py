import numpy as np
import pytest
import scipy.stats

from hil.arm.kinematics import Kinematics
from hil.calibration.identification import check_design, identify, minimum_poses, validate
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.errors import InputError


def station(rng, poses, noise=20e-6, robot="ur5e"):
    # the geometry alone, read by exact encoders: the compliant arm is test_identification_compliance's
    truth = random_truth(robot, rng, rigid=True)
    q, p = measure(truth, random_configurations(robot, poses, rng), Noise(noise, 0.0), rng)
    return truth, Measurements.from_arrays(q, p, "sim.csv")


def true_error(truth, geometry, q):
    return np.linalg.norm(Kinematics(geometry).points(q) - Kinematics(truth).points(q), axis=1)


@pytest.mark.parametrize("robot", ["ur5e", "ur10e", "ur3"])
def test_noise_free_data_recovers_the_truth_exactly(robot, rng):
    truth, meas = station(rng, 30, noise=0.0, robot=robot)
    fit = identify(meas, robot)
    held_out = random_configurations(robot, 200, rng)
    assert true_error(truth, fit.geometry, held_out).max() < 1e-9
    assert fit.rms < 1e-9
    assert fit.initial_rms > 1e-3  # the start really was wrong
    assert len(fit.indices) == 27


def test_noisy_fit_reaches_the_cramer_rao_level(rng):
    truth, meas = station(rng, 50)
    fit = identify(meas, "ur5e")
    held_out = random_configurations("ur5e", 300, rng)
    err = true_error(truth, fit.geometry, held_out)
    predicted = np.sqrt(np.mean(np.trace(fit.prediction_covariance(held_out), axis1=1, axis2=2)))
    rms = np.sqrt(np.mean(err**2))
    assert 0.4 * predicted < rms < 2.0 * predicted
    assert 15e-6 < fit.sigma < 25e-6  # the noise level is estimated
    assert rms < 40e-6
    before = true_error(truth, fit.baseline, held_out)
    assert np.sqrt(np.mean(before**2)) > 20 * rms  # calibration mattered


def test_standard_deviations_are_honest(rng):
    """Coverage: predicted-position errors normalised by the reported covariance follow χ²(3)."""
    truth = random_truth("ur5e", rng, rigid=True)
    held_out = random_configurations("ur5e", 4, rng)
    stats = []
    for _ in range(50):
        q, p = measure(truth, random_configurations("ur5e", 30, rng), Noise(20e-6, 0.0), rng)
        fit = identify(Measurements.from_arrays(q, p), "ur5e", reject_outliers=False)
        e = Kinematics(fit.geometry).points(held_out) - Kinematics(truth).points(held_out)
        C = fit.prediction_covariance(held_out)
        stats += [float(ei @ np.linalg.solve(Ci, ei)) for ei, Ci in zip(e, C, strict=True)]
    stats = np.array(stats)
    inside = np.mean(stats < scipy.stats.chi2.ppf(0.95, 3))
    assert 0.88 < inside <= 1.0
    assert 2.3 < stats.mean() < 3.8  # χ²(3) has mean 3; over- or under-stated σ moves it


def test_outliers_are_rejected_and_named(rng):
    _truth, meas = station(rng, 40)
    p = meas.p.copy()
    p[7] += [1.0e-3, 0, 0]
    p[23] += [0, -0.6e-3, 0.5e-3]
    bad = Measurements(meas.q, p, meas.lines, "bad.csv", "x")
    fit = identify(bad, "ur5e")
    assert sorted(r.index for r in fit.rejected) == [7, 23]
    assert sorted(r.line for r in fit.rejected) == [9, 25]
    assert not fit.used[7] and not fit.used[23]
    assert fit.rms < 45e-6
    kept = identify(bad, "ur5e", reject_outliers=False)
    assert kept.rejected == [] and kept.rms > 2 * fit.rms


@pytest.mark.parametrize("seed", [1, 2, 3, 4, 5])
def test_clean_data_keeps_every_pose(seed):
    _, meas = station(np.random.default_rng(seed), 30)
    assert identify(meas, "ur5e").rejected == []


def test_correlated_pairs_reported_and_smr_guess_used(rng):
    truth, meas = station(rng, 30)
    guess = truth.smr + 0.01
    fit = identify(meas, "ur5e", smr_guess=guess)
    # the SMR offset also absorbs the flange's and joint 6's placement errors (≲ 2 mm here)
    assert np.linalg.norm(fit.geometry.smr - truth.smr) < 2e-3 < np.linalg.norm(guess - truth.smr)
    assert all(abs(c.rho) >= 0.95 for c in fit.correlated)
    assert fit.condition > 1 and fit.iterations > 0
    assert fit.std.shape == (27,) and np.all(fit.std > 0)


def test_validation_statistics(rng):
    truth, meas = station(rng, 30)
    stats = validate(truth, meas)
    assert stats.count == 30
    assert 20e-6 < stats.rms < 50e-6  # pure noise: √3·20 µm
    assert stats.max >= stats.rms >= stats.mean * 0.99


def test_too_few_poses(rng):
    _, meas = station(rng, minimum_poses(27) - 1)
    with pytest.raises(InputError, match=r"sim.csv: 9 poses, .* at least 10"):
        check_design(meas, "ur5e")


def test_joint_that_never_moves(rng):
    _, meas = station(rng, 30)
    q = meas.q.copy()
    q[:, 3] = 0.4
    with pytest.raises(InputError, match=r"column\(s\) q4 never change"):
        identify(Measurements(q, meas.p, meas.lines, "sim.csv"), "ur5e")


def test_all_poses_alike(rng):
    _, meas = station(rng, 12)
    q = np.tile(meas.q[0], (12, 1))
    with pytest.raises(InputError, match="all 12 poses are the same"):
        identify(Measurements(q, meas.p, meas.lines, "sim.csv"), "ur5e")


def test_degenerate_pose_set_names_what_is_lost(rng):
    _, meas = station(rng, 12)
    q = np.where((np.arange(12) % 2 == 0)[:, None], meas.q[0], meas.q[1])  # two poses, repeated
    with pytest.raises(InputError, match="degenerate pose set: the poses cannot identify"):
        identify(Measurements(q, meas.p, meas.lines, "sim.csv"), "ur5e")


def test_the_prior_shrinks_few_noisy_poses_toward_nominal_and_leaves_good_data_alone() -> None:
    """MAP fit (`hil.calibration.prior`): 12 poses with 3 mm noise chase the noise without the prior
    (true error several times the nominal's) and stay near nominal with it; 40 tracker-grade poses give
    the same model either way. Posterior standard deviations are below the tolerances."""
    from hil.calibration.prior import ROTATION_TOLERANCE, TRANSLATION_TOLERANCE
    from hil.calibration.synthetic import true_points

    for poses, sigma in ((12, 3e-3), (40, 20e-6)):
        rng = np.random.default_rng(5)
        truth = random_truth("ur5e", rng, rigid=True)
        q, p = measure(truth, random_configurations("ur5e", poses, rng), Noise(sigma), rng)
        meas = Measurements(q, p, np.arange(poses) + 2, "x.csv")
        q_fresh = random_configurations("ur5e", 500, rng)
        fresh = true_points(truth, q_fresh)

        def error(geometry, q_fresh=q_fresh, fresh=fresh) -> float:
            return float(np.sqrt(np.mean(np.sum((Kinematics(geometry).points(q_fresh) - fresh) ** 2, 1))))

        plain = identify(meas, "ur5e", prior=False)
        shrunk = identify(meas, "ur5e")
        assert plain.prior is None and shrunk.prior is not None
        if sigma > 1e-3:
            assert error(plain.geometry) > 1.5 * error(shrunk.geometry)
            assert error(shrunk.geometry) < 1.3 * error(shrunk.baseline)
            joints = [k for k, n in enumerate(shrunk.names) if n.startswith("joint")]
            tol = np.where([shrunk.names[k].split(".")[1][0] == "t" for k in joints],
                           TRANSLATION_TOLERANCE, ROTATION_TOLERANCE)
            assert np.all(shrunk.std[joints] < 1.05 * tol)  # the data add to the prior, never less
            assert np.all(np.abs(shrunk.values[joints]) < 3 * tol)
        else:
            assert error(shrunk.geometry) == pytest.approx(error(plain.geometry), rel=0.05)
            assert shrunk.rms == pytest.approx(plain.rms, rel=0.01)
