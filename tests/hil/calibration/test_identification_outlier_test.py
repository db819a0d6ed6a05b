"""The outlier test's shortcut: scipy's F distribution is consulted only when the largest F statistic
could be significant, and the bound that decides it is a true lower bound of the F tail."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.special
import scipy.stats

from hil.arm.kinematics import Kinematics
from hil.calibration.identification import _outlier, chi2_3_sf, f_3_sf_lower_bound, identify
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth


@pytest.mark.parametrize("x", [0.0, 0.5, 3.0, 7.8, 11.34, 30.0, 120.0])
def test_the_chi2_tail_is_scipys(x: float) -> None:
    assert chi2_3_sf(x) == pytest.approx(scipy.stats.chi2.sf(x, 3), rel=1e-12, abs=1e-300)


@pytest.mark.parametrize("nu2", [1, 2, 3, 4, 7, 10, 31, 90, 93, 300, 1000, 2997, 10_000, 100_000])
def test_the_bound_is_below_the_f_tail_for_any_residual_dof(nu2: int) -> None:
    f = np.r_[0.0, np.geomspace(1e-3, 1e4, 400)]
    tail = scipy.special.fdtrc(3, nu2, f)
    bound = np.array([f_3_sf_lower_bound(v) for v in f])
    assert np.all(bound <= tail * (1 + 1e-12)), f[bound > tail][:5]


def test_the_bound_is_tight_enough_to_skip_scipy_on_clean_data() -> None:
    """At the Bonferroni level of 40 poses (α = 1 %) the bound's critical F is within a few per cent of
    the F distribution's at 90 residual degrees of freedom: clean data rarely needs scipy."""
    level = 0.01 / 40
    exact = scipy.stats.f.isf(level, 3, 90)
    lo, hi = 0.1, 100.0
    for _ in range(100):  # the F where the bound reaches the level, by bisection
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if f_3_sf_lower_bound(mid) >= level else (lo, mid)
    assert exact * 0.8 < lo < exact


def test_rejections_and_p_values_are_scipys() -> None:
    """With outliers in the data the p-values are scipy's F distribution's, as before the shortcut."""
    rng = np.random.default_rng(11)
    q, p = measure(random_truth("ur5e", rng, rigid=True), random_configurations("ur5e", 40, rng),
                   Noise(20e-6, 0.0), rng)
    p[4] += [0.0, 0.7e-3, 0.0]
    fit = identify(Measurements.from_arrays(q, p), "ur5e")
    assert [r.index for r in fit.rejected] == [4]
    # the pose's statistic as the test saw it: in the fit that still held every pose
    kept = identify(Measurements.from_arrays(q, p), "ur5e", reject_outliers=False)
    Jp = Kinematics(kept.geometry).jacobian(q, kept.indices)
    inv = kept.covariance / kept.sigma ** 2
    worst = _outlier(Jp, kept.residuals, inv, 0.01 / 40)
    assert worst is not None and worst[0] == 4
    assert worst[1] == pytest.approx(fit.rejected[0].p_value, rel=1e-6)
    assert worst[1] < 0.01 / 40
