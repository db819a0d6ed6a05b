"""The two tail probabilities identification's tests need, without importing scipy.

scipy's import (``scipy.special`` alone 0.23 s) was most of ``hil identify``'s start-up
(bench/cli_startup.py), for two numbers per fit: the outlier test's F tail and the cross-validation's
paired t test. Both are the regularized incomplete beta function, evaluated here by its continued
fraction (Abramowitz & Stegun 26.5.8, modified Lentz; the symmetry I_x(a, b) = 1 − I_{1−x}(b, a) keeps
it where it converges fast) — hand-written because numpy has no incomplete beta and this is all that is
needed of scipy. The tests check both against scipy to 1e-12.
"""

from __future__ import annotations

import math

#: The continued fraction stops when a step changes it by less than this (relative), or after
#: `_MAX_TERMS` terms (never reached for the F and t tails identification asks for; a test checks).
_EPSILON = 1e-15
_MAX_TERMS = 10_000
_TINY = 1e-300


def _beta_fraction(x: float, a: float, b: float) -> float:
    """The continued fraction of I_x(a, b) (A&S 26.5.8), by the modified Lentz method."""
    c, d = 1.0, 1.0 - (a + b) * x / (a + 1.0)
    d = 1.0 / (d if abs(d) > _TINY else _TINY)
    h = d
    for m in range(1, _MAX_TERMS):
        for numerator in (m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m)),
                          -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1))):
            d = 1.0 + numerator * d
            d = 1.0 / (d if abs(d) > _TINY else _TINY)
            c = 1.0 + numerator / c
            c = c if abs(c) > _TINY else _TINY
            h *= c * d
        if abs(c * d - 1.0) < _EPSILON:
            return h
    raise ArithmeticError(f"the incomplete beta fraction did not converge (x={x}, a={a}, b={b})")


def regularized_beta(x: float, a: float, b: float) -> float:
    """I_x(a, b), the regularized incomplete beta function, for a, b > 0 and 0 ≤ x ≤ 1."""
    if not (a > 0 and b > 0) or not 0.0 <= x <= 1.0:
        raise ValueError(f"regularized_beta needs a, b > 0 and 0 <= x <= 1, got x={x}, a={a}, b={b}")
    if x in (0.0, 1.0):
        return x
    log_front = a * math.log(x) + b * math.log1p(-x) - (math.lgamma(a) + math.lgamma(b) - math.lgamma(a + b))
    if x < (a + 1.0) / (a + b + 2.0):
        return math.exp(log_front) * _beta_fraction(x, a, b) / a
    return 1.0 - math.exp(log_front) * _beta_fraction(1.0 - x, b, a) / b


def f_sf(f: float, d1: float, d2: float) -> float:
    """P(F > f) for Fisher's F with (d1, d2) degrees of freedom: I_{d2/(d2+d1·f)}(d2/2, d1/2)."""
    if f <= 0.0:
        return 1.0
    return regularized_beta(d2 / (d2 + d1 * f), d2 / 2.0, d1 / 2.0)


def student_t_cdf(t: float, dof: float) -> float:
    """P(T ≤ t) for Student's t with `dof` degrees of freedom: ½·I_{ν/(ν+t²)}(ν/2, ½) in each tail."""
    tail = 0.5 * regularized_beta(dof / (dof + t * t), dof / 2.0, 0.5)
    return tail if t < 0 else 1.0 - tail
