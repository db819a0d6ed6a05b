"""The exchange baseline: Mitchell's DETMAX (1974) with excursions.

From a random start of `count` candidates, an excursion of depth d adds the d candidates that raise
det M the most (one at a time, greedily, the add-gain of every unused candidate from one triangular
solve) and then removes the d poses that lower it the least; it is accepted when det M grew, and the
depth grows (up to `max_depth`) while excursions fail. It stops when an excursion of the maximum depth
fails. Depth 1 is exactly the Wynn–Mitchell / Fedorov "best in, worst out" exchange.

DETMAX maximises the D-criterion, i.e. O1. For O2–O5 it still optimises O1 and only reports the
requested index: the baseline is a baseline, not a second O2–O5 optimiser.
"""

from __future__ import annotations

import time

import numpy as np

from selector.design import Selection, check_blocks, check_count, score
from selector.indices import parse_index
from selector.information import DesignState


def _excursion(state: DesignState, depth: int) -> tuple[DesignState, int]:
    """Add `depth` best candidates, then remove `depth` least useful poses; returns the new state."""
    trial = DesignState(state.G, state.chosen)
    evaluations = 0
    for _ in range(depth):
        free = np.flatnonzero(~trial.in_set)
        gain = trial.add_gain(free)
        evaluations += len(free)
        trial.add(int(free[int(np.argmax(gain))]))
    for _ in range(depth):
        loss = trial.remove_loss()
        evaluations += trial.m
        trial.remove(int(np.argmax(loss)))
    return trial, evaluations


def exchange_select(G: np.ndarray, count: int, *, index: str = "O1", seed: int = 0, max_depth: int = 3,
                    max_excursions: int = 2000) -> Selection:
    """Choose `count` of the candidate blocks `G` (N, 3, n) by DETMAX from a seeded random start."""
    t0 = time.perf_counter()
    G = check_blocks(G)
    index = parse_index(index)
    check_count(count, len(G), G.shape[2])
    rng = np.random.default_rng(seed)
    state = DesignState(G, rng.choice(len(G), size=count, replace=False))
    depth, evaluations, excursions = 1, 0, 0
    while excursions < max_excursions:
        excursions += 1
        trial, evals = _excursion(state, depth)
        evaluations += evals
        if trial.logdet > state.logdet + 1e-10 or (np.isinf(state.logdet) and np.isfinite(trial.logdet)):
            state, depth = trial, 1
        elif depth < max_depth:
            depth += 1
        else:
            break
    return Selection(state.chosen.copy(), index, score(state, index), score(state, "O1"), "exchange",
                     time.perf_counter() - t0, evaluations,
                     {"excursions": excursions, "max_depth": max_depth})
