"""The information matrix of a pose set, and low-rank scores for adding, removing and swapping poses.

A pose contributes a 3 × n block B (its rows of the Jacobian), the set the information matrix
M = Σ BᵢᵀBᵢ. With L the Cholesky factor of M (M = LLᵀ), W = L⁻¹Bᵀ and the determinant lemma:

* adding c:       det(M + BcᵀBc) / det M = det(I₃ + Dc),  Dc = BcM⁻¹Bcᵀ = WcᵀWc;
* removing i:     det(M − AᵢᵀAᵢ) / det M = det(I₃ − Eᵢ), Eᵢ = AᵢM⁻¹Aᵢᵀ;
* swapping i → c: det(I₃ + Dc) · det(I₃ − Eᵢ + XᵢcᵀSc Xᵢc), Xᵢc = BcM⁻¹Aᵢᵀ = WcᵀVᵢ, Sc = (I₃ + Dc)⁻¹,
  which is the lemma applied twice (add c, then remove i from M + BcᵀBc by Woodbury).

Everything is 3 × 3 algebra batched over candidates and positions after one triangular solve of the
stacked blocks, so scoring k candidates against m positions costs O(k·n² + k·m·n) — no SVD, no
refactorisation. Only an accepted move rebuilds M (from the set's rows, so no drift) and its Cholesky
factor, O(m·n² + n³), negligible at n = 27.
"""

from __future__ import annotations

import numpy as np

from selector.errors import SelectorError


def det3(A: np.ndarray) -> np.ndarray:
    """Determinants of a batch (..., 3, 3) in closed form (several times faster than LAPACK per call)."""
    a = A
    return (a[..., 0, 0] * (a[..., 1, 1] * a[..., 2, 2] - a[..., 1, 2] * a[..., 2, 1])
            - a[..., 0, 1] * (a[..., 1, 0] * a[..., 2, 2] - a[..., 1, 2] * a[..., 2, 0])
            + a[..., 0, 2] * (a[..., 1, 0] * a[..., 2, 1] - a[..., 1, 1] * a[..., 2, 0]))


def inv3(A: np.ndarray) -> np.ndarray:
    """Inverses of a batch (..., 3, 3) by the adjugate."""
    a = A
    adj = np.empty_like(a)
    adj[..., 0, 0] = a[..., 1, 1] * a[..., 2, 2] - a[..., 1, 2] * a[..., 2, 1]
    adj[..., 0, 1] = a[..., 0, 2] * a[..., 2, 1] - a[..., 0, 1] * a[..., 2, 2]
    adj[..., 0, 2] = a[..., 0, 1] * a[..., 1, 2] - a[..., 0, 2] * a[..., 1, 1]
    adj[..., 1, 0] = a[..., 1, 2] * a[..., 2, 0] - a[..., 1, 0] * a[..., 2, 2]
    adj[..., 1, 1] = a[..., 0, 0] * a[..., 2, 2] - a[..., 0, 2] * a[..., 2, 0]
    adj[..., 1, 2] = a[..., 0, 2] * a[..., 1, 0] - a[..., 0, 0] * a[..., 1, 2]
    adj[..., 2, 0] = a[..., 1, 0] * a[..., 2, 1] - a[..., 1, 1] * a[..., 2, 0]
    adj[..., 2, 1] = a[..., 0, 1] * a[..., 2, 0] - a[..., 0, 0] * a[..., 2, 1]
    adj[..., 2, 2] = a[..., 0, 0] * a[..., 1, 1] - a[..., 0, 1] * a[..., 1, 0]
    return adj / det3(a)[..., None, None]


#: Largest M·N·K of one matrix product in the search loop: OpenBLAS goes multi-threaded above about
#: 262 144 and its thread wake-ups then cost more than the product itself.
_GEMM_CHUNK = 200_000


def _safe_log(x: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(x > 0, np.log(np.where(x > 0, x, 1.0)), -np.inf)


def gram(X: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """XᵀX (or Xᵀ diag(weights) X) of a tall (rows, n) matrix, summed over row chunks.

    Chunks keep every product below OpenBLAS's threading threshold (`_GEMM_CHUNK`); a single wide
    product would wake the BLAS threads on each call of a tight loop.
    """
    rows, n = X.shape
    step = max(1, _GEMM_CHUNK // (n * n))
    out = np.zeros((n, n))
    for r in range(0, rows, step):
        x = X[r:r + step]
        out += x.T @ (x if weights is None else x * weights[r:r + step, None])
    return out


def information(G: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """M = Σ BᵀB over the chosen candidates' blocks of `G` (N, 3, n)."""
    return gram(G[np.asarray(chosen, dtype=int)].reshape(-1, G.shape[2]))


class DesignState:
    """A pose set (indices into the candidate blocks `G`) with its information matrix and Cholesky factor.

    `logdet` is −inf while M is singular (fewer independent rows than parameters); the scores then use a
    tiny ridge so that the search can still climb out of a singular start.
    """

    RIDGE = 1e-12

    def __init__(self, G: np.ndarray, chosen: np.ndarray) -> None:
        self.G = G
        self.n = G.shape[2]
        self.chosen = np.array(chosen, dtype=int)
        if len(np.unique(self.chosen)) != len(self.chosen):
            raise SelectorError("a pose set must not repeat a candidate")
        self.in_set = np.zeros(len(G), dtype=bool)
        self.in_set[self.chosen] = True
        self._refresh()

    @property
    def m(self) -> int:
        return len(self.chosen)

    def _refresh(self) -> None:
        # imported here, not with the module: a command that only asks `selector.design.minimum_poses`
        # (a pose count refused before the station is taken) need not load scipy.linalg (0.25 s cold)
        import scipy.linalg

        self.M = information(self.G, self.chosen)
        scale = max(float(np.trace(self.M)) / self.n, 1e-300)
        try:
            self.L = scipy.linalg.cholesky(self.M, lower=True)
            self.logdet = float(2.0 * np.sum(np.log(np.diag(self.L))))
            self.singular = bool(np.min(np.diag(self.L)) ** 2 <= 1e-13 * scale)
        except np.linalg.LinAlgError:
            self.singular = True
        if self.singular:
            self.L = scipy.linalg.cholesky(self.M + self.RIDGE * scale * np.eye(self.n), lower=True)
            self.logdet = -np.inf
        self.Linv = scipy.linalg.solve_triangular(self.L, np.eye(self.n), lower=True)
        self._V: np.ndarray | None = None  # whitened blocks of the set, computed on demand

    def _set_whitened(self) -> tuple[np.ndarray, np.ndarray]:
        """V = L⁻¹Aᵀ of the set's blocks (m, n, 3) and E = VᵀV (m, 3, 3), cached until the set changes."""
        if self._V is None:
            self._V = self.whiten(self.chosen)
            self._E = self._V.transpose(0, 2, 1) @ self._V
        return self._V, self._E

    def whiten(self, idx: np.ndarray) -> np.ndarray:
        """W = L⁻¹Bᵀ for the blocks `idx`, as (len(idx), n, 3).

        A stack of small products (n × n by n × 3) rather than one wide triangular solve: per-slice
        work stays below the size at which OpenBLAS wakes its threads, whose wake-up latency (up to
        milliseconds on a loaded 2-core machine) would otherwise dominate the search loop.
        """
        B = self.G[np.asarray(idx, dtype=int)]  # (k, 3, n)
        return np.matmul(self.Linv, B.transpose(0, 2, 1))

    def variance(self, idx: np.ndarray | None = None) -> np.ndarray:
        """d_c = tr(B_c M⁻¹ B_cᵀ) of candidates `idx` (all when None): how much each would add."""
        W = self.whiten(np.arange(len(self.G)) if idx is None else idx)
        return np.einsum("kni,kni->k", W, W)

    def add_gain(self, idx: np.ndarray) -> np.ndarray:
        """log det(M + BᵀB) − log det M for each candidate in `idx`."""
        W = self.whiten(idx)
        return _safe_log(det3(np.eye(3) + W.transpose(0, 2, 1) @ W))

    def remove_loss(self) -> np.ndarray:
        """log det(M − AᵢᵀAᵢ) − log det M for each pose of the set (−inf: the pose is indispensable)."""
        _, E = self._set_whitened()
        return _safe_log(det3(np.eye(3) - E))

    def swap_gain(self, idx: np.ndarray) -> np.ndarray:
        """(len(idx), m) log det ratios of replacing pose position i by candidate idx[k].

        With S = (I + D)⁻¹ = RRᵀ (Cholesky per candidate) the quadratic term XᵀSX is YᵀY with
        Y = (WR)ᵀV, so all k·m pairs come from one (3k × n)·(n × 3m) product (cut into row chunks small
        enough to stay single-threaded in OpenBLAS) and 3 × 3 arithmetic on whole (k, m) planes.
        """
        W = self.whiten(idx)  # (k, n, 3)
        V, E = self._set_whitened()  # (m, n, 3), (m, 3, 3)
        k, m, n = len(W), len(V), self.n
        Dp = np.eye(3) + W.transpose(0, 2, 1) @ W
        R = np.linalg.cholesky(inv3(Dp))
        Wr = (W @ R).transpose(0, 2, 1).reshape(3 * k, n)
        Vf = V.transpose(1, 0, 2).reshape(n, 3 * m)
        rows = max(3, (_GEMM_CHUNK // max(1, 3 * m * n)) // 3 * 3)
        Y = np.concatenate([Wr[r:r + rows] @ Vf for r in range(0, 3 * k, rows)])
        Yc = Y.reshape(k, 3, m, 3).transpose(1, 3, 0, 2)  # (a, i, k, m)
        c = [[None] * 3 for _ in range(3)]
        for i in range(3):
            for j in range(i, 3):
                q = Yc[0, i] * Yc[0, j] + Yc[1, i] * Yc[1, j] + Yc[2, i] * Yc[2, j]
                c[i][j] = c[j][i] = q - E[:, i, j] + (1.0 if i == j else 0.0)
        det_inner = (c[0][0] * (c[1][1] * c[2][2] - c[1][2] * c[1][2])
                     - c[0][1] * (c[0][1] * c[2][2] - c[1][2] * c[0][2])
                     + c[0][2] * (c[0][1] * c[1][2] - c[1][1] * c[0][2]))
        return _safe_log(det3(Dp))[:, None] + _safe_log(det_inner)

    def swapped_information(self, idx: np.ndarray, pos: np.ndarray) -> np.ndarray:
        """(k, n, n) information matrices after replacing positions `pos` by candidates `idx` (pairwise)."""
        B = self.G[np.asarray(idx, dtype=int)]
        A = self.G[self.chosen[np.asarray(pos, dtype=int)]]
        return (self.M[None] + np.einsum("kai,kaj->kij", B, B) - np.einsum("kai,kaj->kij", A, A))

    def swap(self, pos: int, cand: int) -> int:
        """Replace the pose at position `pos` by candidate `cand`; returns the candidate removed."""
        if self.in_set[cand]:
            raise SelectorError(f"candidate {cand} is already in the set")
        old = int(self.chosen[pos])
        self.chosen[pos] = cand
        self.in_set[old] = False
        self.in_set[cand] = True
        self._refresh()
        return old

    def add(self, cand: int) -> None:
        if self.in_set[cand]:
            raise SelectorError(f"candidate {cand} is already in the set")
        self.chosen = np.append(self.chosen, cand)
        self.in_set[cand] = True
        self._refresh()

    def remove(self, pos: int) -> int:
        old = int(self.chosen[pos])
        self.chosen = np.delete(self.chosen, pos)
        self.in_set[old] = False
        self._refresh()
        return old
