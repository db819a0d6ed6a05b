"""The chain-by-chain bridge LP agrees with HiGHS on the whole LP; the arc-length and orientation
shortcuts agree with the scipy routines they replace."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson
from scipy.interpolate import make_interp_spline
from scipy.optimize import linprog

from hil.moveb.arclength import arclength_table, cumulative_simpson_uniform, table_parameters
from hil.moveb.bridge import Bridge, BridgeShape, control_points
from hil.moveb.chains import ChainCache, solve_chain_lp
from hil.moveb.orientation import axis_splines


def instance(rng: np.random.Generator, n: int, weights: str) -> tuple[np.ndarray, ...]:
    """A random chain LP shaped like the bridge LP: c > 0, 0 ≤ l ≤ u, l ≤ half of either segment."""
    S = rng.uniform(1.0, 3.0, n)
    upper = np.zeros(n + 1)
    upper[1:-1] = rng.uniform(0.2, 2.5, n - 1) * np.minimum(S[:-1], S[1:])
    upper[1:-1][rng.random(n - 1) < 0.1] = 0.0  # a straight point now and then
    floor = np.minimum(upper, np.minimum(np.r_[np.inf, S], np.r_[S, np.inf]) / 2.0)
    lower = np.where(rng.random(n + 1) < 0.5, floor, floor * rng.random(n + 1))
    # "tie-break": the planner's weights, 1 + 1e-3·sinθ/max sinθ
    c = 1.0 + 1e-3 * rng.random(n + 1) if weights == "tie-break" else rng.uniform(0.3, 3.0, n + 1)
    return c, lower, upper, S


def highs_reference(c: np.ndarray, lower: np.ndarray, upper: np.ndarray, S: np.ndarray) -> np.ndarray:
    """The whole LP (every segment, no presolve) by HiGHS."""
    n = len(S)
    A = np.zeros((n, n + 1))
    A[np.arange(n), np.arange(n)] = 1.0
    A[np.arange(n), np.arange(n) + 1] = 1.0
    res = linprog(-c, A_ub=A, b_ub=S, bounds=np.c_[lower, upper], method="highs")
    assert res.status == 0
    return res.x


@pytest.mark.parametrize("weights", ["tie-break", "general"])
@pytest.mark.parametrize("closed_form", [3, 1])
def test_chain_lp_matches_highs_on_the_whole_lp(weights: str, closed_form: int) -> None:
    rng = np.random.default_rng(11)
    sizes: set[int] = set()
    for _ in range(300):
        c, lower, upper, S = instance(rng, int(rng.integers(2, 12)), weights)
        ours = solve_chain_lp(c, lower, upper, S, closed_form=closed_form)
        ref = highs_reference(c, lower, upper, S)
        # feasible, same optimum; distinct random weights make the optimum unique, so same h
        assert np.all(ours >= lower - 1e-12) and np.all(ours <= upper + 1e-12)
        assert np.all(ours[:-1] + ours[1:] <= S * (1 + 1e-12))
        assert c @ ours == pytest.approx(c @ ref, rel=1e-12, abs=1e-12)
        assert np.abs(ours - ref).max() < 1e-9
        U = np.minimum(upper, np.minimum(np.r_[np.inf, S - lower[:-1]], np.r_[S - lower[1:], np.inf]))
        binding = U[:-1] + U[1:] > S
        sizes.update(np.bincount(np.r_[0, np.cumsum(~binding)]).tolist())
    assert {1, 2, 3, 4} <= sizes  # every path of the solver was exercised


def test_a_tie_is_split_down_the_middle() -> None:
    # two equally sharp corners sharing a segment too short for both: mirror-image bridges
    c = np.array([1.0, 1.0005, 1.0005, 1.0])
    S = np.array([10.0, 3.0, 10.0])
    upper = np.array([0.0, 2.5, 2.5, 0.0])
    lower = np.array([0.0, 0.5, 0.5, 0.0])
    h = solve_chain_lp(c, lower, upper, S)
    assert h[1] == h[2] == 1.5
    # three equal corners: the middle one's stretch of optimal values is split the same way
    c = np.array([1.0, 1.0, 2.0, 1.0, 1.0])
    S = np.array([10.0, 3.0, 3.0, 10.0])
    upper = np.array([0.0, 2.5, 2.5, 2.5, 0.0])
    lower = np.array([0.0, 0.5, 0.5, 0.5, 0.0])
    h = solve_chain_lp(c, lower, upper, S)
    ref = highs_reference(c, lower, upper, S)
    assert c @ h == pytest.approx(c @ ref, rel=1e-12)
    assert h[1] == h[3] == h[2] == 1.5  # the middle of [0.5, 2.5]


def test_the_cache_reuses_only_unchanged_chains() -> None:
    c = np.r_[1.0, np.full(5, 1.0003), 1.0]
    c[2] = 1.0009  # a chain of five with an interior favourite: HiGHS
    S = np.full(6, 2.0)
    upper = np.r_[0.0, np.full(5, 1.8), 0.0]
    lower = np.r_[0.0, np.full(5, 0.4), 0.0]
    cache = ChainCache()
    first = solve_chain_lp(c, lower, upper, S, cache)
    assert cache.highs_calls == 1
    again = solve_chain_lp(c, lower, upper, S, cache)
    assert cache.highs_calls == 1 and np.array_equal(first, again)
    S2 = S.copy()
    S2[3] = 1.9
    moved = solve_chain_lp(c, lower, upper, S2, cache)
    assert cache.highs_calls == 2
    assert np.abs(moved - highs_reference(c, lower, upper, S2)).max() < 1e-9


def test_cumulative_simpson_matches_scipy() -> None:
    u = table_parameters()
    f = np.random.default_rng(1).random((len(u), 7))
    ours = cumulative_simpson_uniform(f, float(u[1] - u[0]))
    assert np.abs(ours - cumulative_simpson(f, x=u, axis=0, initial=0.0)).max() < 1e-14


@pytest.mark.parametrize("continuity", ["G2", "G3"])
def test_arclength_table_matches_simpson_on_the_scipy_spline(continuity: str) -> None:
    shape = BridgeShape(continuity)
    rng = np.random.default_rng(2)
    T0 = rng.normal(size=(20, 3))
    T2 = rng.normal(size=(20, 3))
    T0 /= np.linalg.norm(T0, axis=1)[:, None]
    T2 /= np.linalg.norm(T2, axis=1)[:, None]
    ctrl = control_points(rng.normal(size=(20, 3)) * 100, T0, T2, rng.uniform(0.1, 5.0, 20), shape)
    table = arclength_table(ctrl, shape.degree)
    u = table_parameters()
    for k in range(len(ctrl)):
        spline = Bridge(ctrl[k], shape).spline()
        speed = np.linalg.norm(spline(u, nu=1), axis=1)
        ref = cumulative_simpson(speed, x=u, initial=0.0)
        assert np.abs(table[k] - ref).max() < 1e-12 * ref[-1]


@pytest.mark.parametrize("continuity", ["G2", "G3"])
@pytest.mark.parametrize("n", [2, 3, 4, 6, 50])
def test_axis_splines_match_separate_interpolation(continuity: str, n: int) -> None:
    rng = np.random.default_rng(n)
    s = np.cumsum(rng.uniform(0.1, 5.0, n))
    z, x = rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    zs, xs = axis_splines(s, z, x, continuity)
    k = min({"G2": 3, "G3": 5}[continuity], n - 1)
    q = np.linspace(s[0] - 1.0, s[-1] + 1.0, 501)
    assert np.array_equal(zs(q), make_interp_spline(s, z, k=k)(q))
    assert np.array_equal(xs(q), make_interp_spline(s, x, k=k)(q))
