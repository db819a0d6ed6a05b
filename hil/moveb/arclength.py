"""Arc-length tables of the bridges: arc length from A1 at a fixed grid of parameters u per bridge.

`Curve` needs them for its length, the arc length of every apex (the orientation keys) and to
invert s → u when sampling, so they are built when the plan is, for all bridges at once. For a
long path this was most of the planning time, hence:

* the speed is evaluated from its square, a polynomial of degree 2(p − 1) in each half's t whose
  coefficients are dot products of the hodograph's monomial coefficients (per bridge, cheap), by
  Horner's rule on the (samples × bridges) grid: under half the array passes of summing the
  Bernstein terms coordinate by coordinate;
* the cumulative Simpson rule of `scipy.integrate.cumulative_simpson` is written out for the
  uniform grid (scipy takes its general unequal-interval path when given x).

Element-wise numpy only, in place where the arrays are large: a BLAS product is no faster at these
shapes, and OpenBLAS would run it on several threads, which only costs CPU on a shared 2-core
machine (the benchmark counts the CPU time of every thread of the process).
"""

from __future__ import annotations

import functools
from math import comb

import numpy as np

#: Samples per bridge half in the arc-length table (even: Simpson pairs intervals).
TABLE_SAMPLES = 32


@functools.cache
def table_parameters() -> np.ndarray:
    """(2·TABLE_SAMPLES + 1,) the parameters u of the table's columns, uniform on [0, 1] (shared,
    read-only)."""
    half = np.linspace(0.0, 0.5, TABLE_SAMPLES + 1)
    u = np.r_[half, half[1:] + 0.5]
    u.flags.writeable = False
    return u


@functools.cache
def _to_monomial(n: int) -> np.ndarray:
    """(n+1, n+1) M with Σj Bj,n(t)·Xj = Σk (M @ X)k·t^k (Bernstein to power basis)."""
    M = np.zeros((n + 1, n + 1))
    for k in range(n + 1):
        for j in range(k + 1):
            M[k, j] = comb(n, k) * comb(k, j) * (-1) ** (k - j)
    return M


def squared_speed_coefficients(ctrl: np.ndarray) -> np.ndarray:
    """(2p − 1, nb) power-basis coefficients in t of |dC/dt|² for Bezier curves ctrl (nb, p+1, 3)."""
    p = ctrl.shape[1] - 1
    C = np.ascontiguousarray(ctrl.transpose(1, 2, 0))  # (p+1, 3, nb): contiguous rows per bridge set
    X = p * (C[1:] - C[:-1])  # the hodograph's Bernstein coefficients
    M = _to_monomial(p - 1)
    a = [sum(M[k, j] * X[j] for j in range(k + 1)) for k in range(p)]  # its power-basis coefficients
    g = np.zeros((2 * p - 1, len(ctrl)))
    for k in range(p):
        g[2 * k] += (a[k] * a[k]).sum(axis=0)
        for m in range(k + 1, p):
            g[k + m] += 2.0 * (a[k] * a[m]).sum(axis=0)
    return g


def cumulative_simpson_uniform(f: np.ndarray, dx: float) -> np.ndarray:
    """Cumulative Simpson along axis 0 of samples f on a uniform grid with an even number of
    intervals, initial 0: each interval integrates the parabola through its pair of intervals,
    which is `scipy.integrate.cumulative_simpson`'s rule (the tests compare the two). Written
    in place on whole rows (many curves at once), because temporaries of this size dominate."""
    f0, f1, f2 = f[0:-1:2], f[1::2], f[2::2]
    out = np.empty(f.shape)
    out[0] = 0.0
    even, odd = out[2::2], out[1::2]
    # at the end of each pair: Simpson's dx/3·(f0 + 4f1 + f2), accumulated row by row
    np.multiply(f1, 4.0, out=even)
    even += f0
    even += f2
    even *= dx / 3.0
    for k in range(1, len(even)):
        even[k] += even[k - 1]
    # inside each pair: the parabola's integral over the first interval, dx/12·(5f0 + 8f1 − f2)
    np.multiply(f1, 8.0, out=odd)
    odd += 5.0 * f0
    odd -= f2
    odd *= dx / 12.0
    odd[1:] += even[:-1]
    return out


def arclength_table(ctrl: np.ndarray, degree: int) -> np.ndarray:
    """(nb, 2·TABLE_SAMPLES + 1) arc length from A1 at `table_parameters` of bridges whose control
    points are ctrl (nb, 2p+1, 3): two Bezier halves, u = t/2 on the first and (1 + t)/2 on the
    second. The sample at u = 0.5 is taken from the second half (the speeds agree at Q)."""
    u = table_parameters()
    if not len(ctrl):
        return np.zeros((0, len(u)))
    t = np.linspace(0.0, 1.0, TABLE_SAMPLES + 1)[:, None]
    speed = np.empty((len(u), len(ctrl)))  # rows: the samples u, columns: the bridges
    halves = ((speed[:TABLE_SAMPLES], t[:-1], ctrl[:, : degree + 1]),
              (speed[TABLE_SAMPLES:], t, ctrl[:, degree:]))
    for out, tt, half in halves:
        g = squared_speed_coefficients(half)
        out[...] = g[-1]
        for q in range(len(g) - 2, -1, -1):  # Horner, in place
            out *= tt
            out += g[q]
    np.abs(speed, out=speed)  # a sum of squares; rounding must not make a NaN where it is ~0
    np.sqrt(speed, out=speed)
    speed *= 2.0  # d/du = 2·d/dt on each half
    return np.ascontiguousarray(cumulative_simpson_uniform(speed, float(u[1] - u[0])).T)
