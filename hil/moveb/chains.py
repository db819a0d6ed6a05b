"""The bridge LP solved chain by chain: an exact presolve, a closed form for chains of up to three
bridges, HiGHS for longer ones.

The LP of `hil.moveb.optimise` in units of h: maximise Σ ci·hi (ci > 0) subject to
li ≤ hi ≤ ui and hj + hj+1 ≤ Sj on every segment j (Sj = Lj/arm; hi = li = ui = 0 where there is
no bridge), with li ≤ min(Si−1, Si)/2 (the half-split floor). Its constraint graph is a path, so it
falls apart into independent chains. Planning solves it once per point-error iteration (6–7 times),
and each call into HiGHS costs 0.6–1.5 ms of fixed overhead in scipy's wrappers, more than the
whole rest of an iteration; so only chains that need a solver get one:

* **Implied bounds.** hi ≤ Sj − lk for each neighbour k across segment j (the constraint with the
  neighbour at its floor). Tightening ui to Ui = min(ui, Si−1 − li−1, Si − li+1) leaves the feasible
  set unchanged, so the optimum too. A segment with Uj + Uj+1 ≤ Sj can then never bind and is
  dropped; on the benchmark's paths this leaves almost only chains of one, two or three bridges.
  Ui ≥ li holds exactly: li and the neighbour's floor are each at most Sj/2 (halving is exact).
* **One bridge:** nothing couples it and ci > 0, so hi = Ui.
* **Two or three bridges** have one free variable: pick a pivot x (the first of two, the middle of
  three); given x, each other bridge k is best at hk = min(Uk, Sk − x) (it has no other
  constraint, ck > 0, and hk ≥ lk because x ≤ Ux ≤ Sk − lk). The objective is then concave and
  piecewise linear in x on [lx, Ux], with slope cx minus the weights of the neighbours already
  squeezed (x > Sk − Uk), so its maximum is at the breakpoint where the slope turns negative.
  A zero slope is a tie of the LP (equal weights; HiGHS would return either end); we take the
  middle of that stretch, so mirror-image corners get mirror-image bridges. This is a handful of
  comparisons, checked against HiGHS on random instances in the tests.
* **Four or more** (rare) go to HiGHS (`scipy.optimize.milp` with no integer variable: the same
  solver behind a thinner wrapper than `linprog`'s), all such chains in one call. `ChainCache`
  keeps those answers between iterations: a chain whose data (weights, bounds, capacities) is
  bit-for-bit what it was keeps its answer, which is that same LP's optimum.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.optimize import Bounds, LinearConstraint, milp

#: Longest chain solved in closed form.
CLOSED_FORM = 3


class ChainCache:
    """HiGHS solutions of the chains longer than `CLOSED_FORM`, keyed by their first point."""

    def __init__(self) -> None:
        self._solved: dict[tuple[int, int], tuple[bytes, np.ndarray]] = {}
        self.highs_calls = 0

    def get(self, start: int, key: bytes, size: int) -> np.ndarray | None:
        hit = self._solved.get((start, size))
        return hit[1] if hit is not None and hit[0] == key else None

    def put(self, start: int, key: bytes, x: np.ndarray) -> None:
        self._solved[(start, len(x))] = (key, x)


def implied_upper(lower: np.ndarray, upper: np.ndarray, S: np.ndarray) -> np.ndarray:
    """(n+1,) Ui = min(ui, Si−1 − li−1, Si − li+1) (module docstring)."""
    U = upper.copy()
    np.minimum(U[1:], S - lower[:-1], out=U[1:])
    np.minimum(U[:-1], S - lower[1:], out=U[:-1])
    return U


def one_free_variable(cx: np.ndarray, lx: np.ndarray, Ux: np.ndarray,
                      c1: np.ndarray, U1: np.ndarray, S1: np.ndarray,
                      c2: np.ndarray, U2: np.ndarray, S2: np.ndarray) -> np.ndarray:
    """Optimal pivot x of the problems max cx·x + Σk ck·min(Uk, Sk − x) over lx ≤ x ≤ Ux, each
    with two neighbours k = 1, 2 (all arrays (m,); an absent neighbour has ck = 0, Sk = inf).

    See the module docstring; the neighbours then take hk = min(Uk, Sk − x).
    """
    b1 = np.clip(S1 - U1, lx, Ux)  # beyond bk, neighbour k is squeezed
    b2 = np.clip(S2 - U2, lx, Ux)
    swap = b2 < b1
    lo, hi = np.where(swap, b2, b1), np.where(swap, b1, b2)
    c_lo, c_hi = np.where(swap, c2, c1), np.where(swap, c1, c2)
    # stretches [lx, lo], [lo, hi], [hi, Ux] with falling slopes; the maximum is at the start of
    # the first stretch whose slope is negative, anywhere on one whose slope is zero (a tie: take
    # its middle), and at Ux if every slope is positive
    s1 = cx - c_lo
    s2 = s1 - c_hi
    x = np.where(s2 < 0.0, hi, np.where(s2 == 0.0, 0.5 * (hi + Ux), Ux))
    x = np.where(s1 < 0.0, lo, np.where(s1 == 0.0, 0.5 * (lo + hi), x))
    return np.where(cx < 0.0, lx, np.where(cx == 0.0, 0.5 * (lx + lo), x))


def _small_chains(h: np.ndarray, c: np.ndarray, lower: np.ndarray, U: np.ndarray, S: np.ndarray,
                  first: np.ndarray, size: np.ndarray) -> None:
    """Chains of two (first, first+1) and three (first…first+2) bridges, in place into h."""
    pair = size == 2
    pivot = np.where(pair, first, first + 1)
    left = pivot - 1  # in a pair the pivot's left neighbour is outside the chain: absent
    right = pivot + 1
    x = one_free_variable(c[pivot], lower[pivot], U[pivot],
                          np.where(pair, 0.0, c[left]), U[left], np.where(pair, np.inf, S[left]),
                          c[right], U[right], S[pivot])
    h[pivot] = x
    h[right] = np.minimum(U[right], S[pivot] - x)
    left = left[~pair]
    h[left] = np.minimum(U[left], S[left] - x[~pair])


def _highs(c: np.ndarray, lower: np.ndarray, upper: np.ndarray, S: np.ndarray,
           seg_cols: np.ndarray) -> np.ndarray:
    """max c·h, lower ≤ h ≤ upper, h[a] + h[b] ≤ S per row of seg_cols (m, 2), by HiGHS."""
    rows = np.repeat(np.arange(len(seg_cols)), 2)
    A = sp.csc_array((np.ones(len(rows)), (rows, seg_cols.ravel())), shape=(len(seg_cols), len(c)))
    res = milp(-c, constraints=LinearConstraint(A, -np.inf, S), bounds=Bounds(lower, upper))
    if res.status != 0:  # cannot happen (h = lower is feasible, bounds are finite)
        raise RuntimeError(f"bridge LP failed: {res.message}")
    return np.clip(res.x, lower, upper)


def solve_chain_lp(c: np.ndarray, lower: np.ndarray, upper: np.ndarray, S: np.ndarray,
                   cache: ChainCache | None = None, closed_form: int = CLOSED_FORM) -> np.ndarray:
    """(n+1,) the LP's optimum h (module docstring); c, lower, upper per point, S (n,) per segment.

    `closed_form` (at most `CLOSED_FORM`) is the longest chain solved without HiGHS (the tests
    set 1 to compare).
    """
    U = implied_upper(lower, upper, S)
    h = U.copy()  # single bridges (and points without one, where U = 0)
    binding = U[:-1] + U[1:] > S
    if not binding.any():
        return h
    chain = np.zeros(len(h), int)  # points k and k+1 share a chain iff segment k binds
    np.cumsum(~binding, out=chain[1:])
    size = np.bincount(chain)[chain]
    starts = np.ones(len(h), bool)
    starts[1:] = chain[1:] != chain[:-1]
    first = np.flatnonzero((size > 1) & starts)
    small = size[first] <= min(closed_form, CLOSED_FORM)
    if small.any():
        _small_chains(h, c, lower, U, S, first[small], size[first[small]])
    todo: list[np.ndarray] = []
    keys: list[bytes] = []
    for s0 in first[~small]:
        idx = np.arange(s0, s0 + size[s0])
        key = np.concatenate([c[idx], lower[idx], U[idx], S[idx[:-1]]]).tobytes()
        x = cache.get(int(s0), key, len(idx)) if cache is not None else None
        if x is None:
            todo.append(idx)
            keys.append(key)
        else:
            h[idx] = x
    if todo:
        idx = np.concatenate(todo)
        col = np.full(len(h), -1)
        col[idx] = np.arange(len(idx))
        segs = np.flatnonzero(binding & (col[:-1] >= 0))  # inside those chains only
        h[idx] = _highs(c[idx], lower[idx], U[idx], S[segs], np.column_stack([col[segs], col[segs + 1]]))
        if cache is not None:
            cache.highs_calls += 1
            for chain_idx, key in zip(todo, keys, strict=True):
                cache.put(int(chain_idx[0]), key, h[chain_idx].copy())
    return h
