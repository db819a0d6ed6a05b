"""The F and t tails identification uses, against scipy's (which hil no longer imports for them)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.special

from hil.calibration.distributions import f_sf, regularized_beta, student_t_cdf


def test_f_tail_is_scipys_over_the_outlier_tests_range() -> None:
    for d2 in [*range(1, 60), 97, 100, 333, 1000, 5000, 100_000]:
        for f in np.r_[np.linspace(0.0, 10.0, 41), 20.0, 50.0, 100.0, 1000.0]:
            want = float(scipy.special.fdtrc(3, d2, f))
            got = f_sf(float(f), 3.0, float(d2))
            assert abs(got - want) < 1e-9 and (want < 1e-200 or abs(got / want - 1) < 1e-6), (d2, f)


def test_t_cdf_is_scipys() -> None:
    for nu in [*range(1, 40), 99, 100, 999]:
        for t in np.linspace(-9.0, 9.0, 37):
            assert abs(student_t_cdf(float(t), nu) - float(scipy.special.stdtr(nu, t))) < 1e-12


def test_regularized_beta_is_scipys_and_refuses_bad_arguments() -> None:
    for a, b in [(0.5, 0.5), (1.5, 20.0), (50.0, 1.5), (3.0, 3.0)]:
        for x in np.linspace(0.0, 1.0, 21):
            assert regularized_beta(float(x), a, b) == pytest.approx(float(scipy.special.betainc(a, b, x)),
                                                                     abs=1e-13)
    with pytest.raises(ValueError):
        regularized_beta(1.5, 1.0, 1.0)
