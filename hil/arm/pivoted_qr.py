"""QR factorisation with column pivoting (Businger & Golub 1965) in numpy.

The identifiable parameter set and the rank checks of every identification rest on a pivoted QR:
each step takes the column with the largest norm left after projecting out the columns already taken
(the choice LAPACK's ``geqp3`` makes). numpy has no pivoted QR, and scipy's (``scipy.linalg.qr(...,
pivoting=True)``) costs ``hil identify`` about 0.2 s of import (``scipy.linalg`` pulls in scipy's
array-API layer, which imports numpy.testing and numpy.f2py) for a factorisation of a few hundred rows
by tens of columns that takes a millisecond. This one is Gram–Schmidt with the projection done twice
("twice is enough": Giraud, Langou & Rozložník 2005), which keeps Q orthonormal to working precision;
tests/hil/arm/test_pivoted_qr.py checks it picks the same columns and diagonal as scipy's.
"""

from __future__ import annotations

import numpy as np


def pivoted_qr(A: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(Q, |diag R|, pivots) of A·P = Q·R with |R₁₁| ≥ |R₂₂| ≥ … (economic: Q is m × min(m, n)).

    ``A[:, piv[k]]`` is the k-th column taken; ``d[k]`` is the norm of what was left of it after
    projecting out the columns taken before it (zero once the rest lie in their span).
    """
    A = np.array(A, dtype=float)
    m, n = A.shape
    k_max = min(m, n)
    Q = np.zeros((m, k_max))
    d = np.zeros(k_max)
    piv = np.arange(n)
    for k in range(k_max):
        rest = A[:, k:]
        j = k + int(np.argmax(np.einsum("ij,ij->j", rest, rest)))
        if j != k:
            A[:, [k, j]] = A[:, [j, k]]
            piv[[k, j]] = piv[[j, k]]
        v = A[:, k].copy()
        for _ in range(2):  # reorthogonalise against the columns taken
            v -= Q[:, :k] @ (Q[:, :k].T @ v)
        d[k] = float(np.linalg.norm(v))
        if d[k] == 0.0:
            break  # the remaining columns are all zero: the rest of d stays 0
        Q[:, k] = v / d[k]
        A[:, k + 1:] -= np.outer(Q[:, k], Q[:, k] @ A[:, k + 1:])
    return Q, d, piv
