"""The D-optimal approximate-design bound on O1, by the multiplicative algorithm with a certificate.

An exact design of N distinct candidates has O1 = det(Σ BᵀB)^(1/2n)/√N = det(M(w))^(1/2n) with
w = 1/N on its poses and M(w) = Σ w_c B_cᵀB_c. Relaxing w to any probability vector over the candidates
gives a concave problem (maximise log det M(w)) whose optimum bounds O1 of every exact design of every
size from above.

Solver: Silvey–Titterington–Torsney's multiplicative algorithm w_c ← w_c · d_c(w)/n with
d_c(w) = tr(B_c M(w)⁻¹ B_cᵀ), which never lowers log det M. It runs on an *active set* of candidates
(the support of a D-optimal design has few points) and is checked against all candidates; violators
re-enter the active set. This keeps the iterations cheap without affecting validity, because the bound
is certified on the full candidate set:

**Certificate.** For any w, let d̄ = max_c d_c(w) over *all* candidates. H = M(w)⁻¹/d̄ satisfies
tr(B_c H B_cᵀ) ≤ 1 for every c, so for any design w* tr(H M(w*)) ≤ 1 and by the AM–GM inequality
det(H M(w*))^(1/n) ≤ 1/n, i.e. log det M(w*) ≤ log det M(w) + n·log(d̄/n). Hence

    O1(any exact design) ≤ det M(w)^(1/2n) · √(d̄/n),

valid whenever the iteration stops; the iteration only tightens it (at the optimum d̄ = n, Kiefer–
Wolfowitz). The returned `value` is that certified upper bound.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from selector.design import check_blocks
from selector.errors import SelectorError
from selector.information import gram


@dataclass(frozen=True)
class Bound:
    """The certified O1 upper bound and the approximate design that certifies it."""

    value: float  # upper bound on O1 of any exact design from these candidates
    achieved: float  # det M(w)^(1/2n) of the approximate design found (a lower bound of the optimum)
    weights: np.ndarray  # (N,) the approximate design
    gap: float  # value / achieved − 1 (relative)
    iterations: int


def _variances(G: np.ndarray, M: np.ndarray) -> np.ndarray:
    """d_c = tr(B_c M⁻¹ B_cᵀ) = ‖L⁻¹B_cᵀ‖² for blocks `G` (N, 3, n).

    One (3N × n)·(n × n) product rather than N small batched ones: the iterations call this thousands
    of times, and the batched form costs ten times as much.
    """
    L = scipy.linalg.cholesky(M, lower=True)
    Linv, info = scipy.linalg.lapack.dtrtri(L, lower=1)
    if info != 0:
        raise np.linalg.LinAlgError("singular information matrix")
    N, k, n = G.shape
    Z = G.reshape(N * k, n) @ Linv.T  # rows of B_c L⁻ᵀ
    return np.einsum("ij,ij->i", Z, Z).reshape(N, k).sum(axis=1)


def _wynn_step(B: np.ndarray, M: np.ndarray, n: int) -> float:
    """α maximising log det((1 − α)M + α BᵀB) for one candidate block B (3, n), by bisection.

    With λⱼ the eigenvalues of D = BM⁻¹Bᵀ the objective is (n − 3)·log(1 − α) + Σ log(1 − α + αλⱼ),
    concave in α, so its derivative is decreasing and bisection finds the maximiser. The bisection
    runs on plain floats (three eigenvalues): array operations on three numbers cost more than the
    arithmetic.
    """
    L = scipy.linalg.cholesky(M, lower=True)
    Z = scipy.linalg.solve_triangular(L, B.T, lower=True)
    lam = [float(v) for v in np.linalg.eigvalsh(Z.T @ Z)]
    rest = n - len(lam)
    lo, hi = 0.0, 1.0 - 1e-12
    for _ in range(50):
        a = 0.5 * (lo + hi)
        slope = -rest / (1.0 - a) + sum((x - 1.0) / (1.0 - a + a * x) for x in lam)
        lo, hi = (a, hi) if slope > 0 else (lo, a)
    return lo


def _moment(G: np.ndarray, w: np.ndarray) -> np.ndarray:
    return gram(G.reshape(-1, G.shape[2]), np.repeat(w, 3))


def d_optimal_bound(G: np.ndarray, *, tol: float = 1e-3, max_iterations: int = 20000,
                    active_size: int = 400, inner_iterations: int = 3000,
                    progress: Callable[[int, float], None] | None = None) -> Bound:
    """Certified upper bound on O1 for designs drawn from candidate blocks `G` (N, 3, n).

    Iterates until the certified relative gap √(d̄/n) − 1 is at most `tol` (0.1 % by default) or the
    iteration budget is spent (the bound is then valid but looser; `gap` says how much).
    `progress(iterations, gap)` is called after each pass over all candidates, if given.
    """
    G = check_blocks(G)
    N, _, n = G.shape
    w = np.full(N, 1.0 / N)
    M = _moment(G, w)
    if np.linalg.matrix_rank(M) < n:
        raise SelectorError("the candidates cannot identify all parameters (rank-deficient information)")
    iterations = 0
    # A few full-set iterations concentrate the weight, then the active set takes over.
    for _ in range(10):
        d = _variances(G, M)
        w *= d / n
        w /= w.sum()
        M = _moment(G, w)
        iterations += 1
    d = _variances(G, M)
    target = n * (1.0 + tol) ** 2
    inner_target = n * (1.0 + tol / 2) ** 2
    active = np.argsort(-w)[: min(N, max(active_size, 3 * n))]
    while d.max() > target and iterations < max_iterations:
        wa = w[active] + 1e-3 / len(active)  # re-entering candidates start with a small weight
        wa /= wa.sum()
        Ga = G[active]
        for _ in range(inner_iterations):
            Ma = _moment(Ga, wa)
            da = _variances(Ga, Ma)
            iterations += 1
            if da.max() <= inner_target or iterations >= max_iterations:
                break
            wa *= da / n
            wa /= wa.sum()
            # Wynn step: move weight towards the worst-covered candidate with an exact line search.
            Ma = _moment(Ga, wa)
            da = _variances(Ga, Ma)
            c = int(np.argmax(da))
            alpha = _wynn_step(Ga[c], Ma, n)
            wa *= 1.0 - alpha
            wa[c] += alpha
        w = np.zeros(N)
        w[active] = wa
        M = _moment(G, w)
        d = _variances(G, M)
        violators = np.flatnonzero(d > inner_target)
        violators = violators[np.argsort(-d[violators])][:active_size // 2]
        active = np.union1d(active[wa > 1e-9], violators)
        if progress is not None:
            progress(iterations, math.sqrt(max(float(d.max()), n) / n) - 1.0)
    sign, logdet = np.linalg.slogdet(M)
    achieved = math.exp(logdet / (2 * n)) if sign > 0 else 0.0
    value = achieved * math.sqrt(max(float(d.max()), n) / n)
    return Bound(value, achieved, w, value / achieved - 1.0 if achieved > 0 else math.inf, iterations)
