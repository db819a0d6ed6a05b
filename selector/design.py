"""What every selection method shares: the result type, the count check, scoring, redundancy.

A selection works on candidate Jacobian blocks `G` (N, 3, n), already restricted to the identifiable
parameters and column-scaled (`selector.indices.scale_columns`), and returns indices into them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from selector.errors import CountError, SelectorError
from selector.indices import index_from_information, o1_from_logdet, observability
from selector.information import DesignState


@dataclass(frozen=True)
class Selection:
    """The chosen poses (indices into the candidates) and how good and how costly they are."""

    chosen: np.ndarray
    index: str
    value: float  # the requested index of the chosen set
    o1: float  # O1 of the chosen set (what the bound bounds)
    method: str
    seconds: float
    evaluations: int = 0  # swap/add/remove scores computed
    details: dict[str, float | int] = field(default_factory=dict)


def minimum_poses(n_parameters: int) -> int:
    """Fewest poses that identify `n_parameters` from 3 coordinates each and leave 3 residual DOF.

    The same rule as identification's design check, so a selection is never refused by the fit.
    """
    return -(-(n_parameters + 3) // 3)


def check_count(count: int, n_candidates: int, n_parameters: int) -> None:
    """CountError unless `count` poses can identify the parameters and exist among the candidates."""
    need = minimum_poses(n_parameters)
    if count < need:
        raise CountError(f"--count {count} is too small: identifying {n_parameters} parameters from 3 "
                         f"coordinates per pose needs at least {need} poses")
    if count > n_candidates:
        raise CountError(f"--count {count} exceeds the {n_candidates} feasible candidates")


def check_blocks(G: np.ndarray) -> np.ndarray:
    G = np.asarray(G, dtype=float)
    if G.ndim != 3 or G.shape[1] != 3 or G.shape[2] < 1:
        raise SelectorError(f"candidate Jacobians must be (N, 3, n), got shape {G.shape}")
    if not np.all(np.isfinite(G)):
        raise SelectorError("candidate Jacobians contain non-finite values")
    return G


def score(state: DesignState, index: str) -> float:
    """The index of the state's set: O1 from the maintained log-determinant, others from eigenvalues."""
    if index == "O1":
        return float(o1_from_logdet(state.logdet, state.n, state.m))
    return float(index_from_information(state.M, state.m, index))


def score_sets(G: np.ndarray, sets: np.ndarray, index: str) -> np.ndarray:
    """Index of several pose sets at once (rows of `sets`), by direct SVD (used by tests and baselines)."""
    return np.array([observability(G[s], index) for s in np.atleast_2d(sets)])


def redundant_positions(state: DesignState, index: str) -> np.ndarray:
    """Positions of poses whose removal does not lower the index (patent step 5).

    Every pose is tested against the full set (leave-one-out), as the patent's loop does, not
    sequentially. For O1 the leave-one-out value comes from the determinant lemma; note O1's 1/√m
    factor: a pose is redundant when det(I − E) ≥ ((m − 1)/m)ⁿ, i.e. when it adds less information
    than an average pose's share.
    """
    m, n = state.m, state.n
    if m <= 1 or state.logdet == -np.inf:
        return np.zeros(0, dtype=int)
    current = score(state, index)
    if index == "O1":
        without = o1_from_logdet(state.logdet + state.remove_loss(), n, m - 1)
    else:
        A = state.G[state.chosen]
        Ms = state.M[None] - np.einsum("kai,kaj->kij", A, A)
        without = index_from_information(Ms, m - 1, index)
    return np.flatnonzero(np.asarray(without) >= current)


def random_fill(rng: np.random.Generator, in_set: np.ndarray, k: int) -> np.ndarray:
    """`k` distinct random candidates not in the set (boolean mask `in_set`)."""
    free = np.flatnonzero(~in_set)
    if k > len(free):
        raise CountError(f"cannot draw {k} more candidates from {len(free)} unused ones")
    return rng.choice(free, size=k, replace=False)


def o1_of(G: np.ndarray, chosen: np.ndarray) -> float:
    """O1 of a set from the Cholesky factor of its information matrix (a quick reporting helper)."""
    state = DesignState(G, chosen)
    return float(o1_from_logdet(state.logdet, state.n, state.m)) if math.isfinite(state.logdet) else 0.0
