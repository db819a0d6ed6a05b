"""The naive baseline: a pose set drawn uniformly at random (what the tabu search is measured against)."""

from __future__ import annotations

import time

import numpy as np

from selector.design import Selection, check_blocks, check_count, score
from selector.indices import parse_index
from selector.information import DesignState


def random_select(G: np.ndarray, count: int, *, index: str = "O1", seed: int = 0) -> Selection:
    """The naive baseline: `count` distinct candidates drawn uniformly at random."""
    t0 = time.perf_counter()
    G = check_blocks(G)
    index = parse_index(index)
    check_count(count, len(G), G.shape[2])
    rng = np.random.default_rng(seed)
    state = DesignState(G, np.sort(rng.choice(len(G), size=count, replace=False)))
    return Selection(state.chosen.copy(), index, score(state, index), score(state, "O1"), "random",
                     time.perf_counter() - t0)
