import itertools

import numpy as np
import pytest

from selector.bound import d_optimal_bound
from selector.design import minimum_poses, redundant_positions
from selector.errors import CountError, SelectorError
from selector.exchange import exchange_select
from selector.indices import observability
from selector.information import DesignState
from selector.random_selection import random_select
from selector.search import select
from selector.tabu import TabuSettings, tabu_select

FAST = TabuSettings(outer_iterations=3, tabu_iterations=30)


def test_minimum_poses_leaves_three_residual_dof() -> None:
    assert minimum_poses(27) == 10
    assert minimum_poses(9) == 4


@pytest.mark.parametrize("method", ["tabu", "exchange", "random"])
def test_deterministic_for_a_seed(blocks: np.ndarray, method: str) -> None:
    opts = {"settings": FAST} if method == "tabu" else {}
    a = select(blocks, 8, method=method, seed=5, **opts)
    b = select(blocks, 8, method=method, seed=5, **opts)
    assert np.array_equal(a.chosen, b.chosen) and a.value == b.value
    assert len(np.unique(a.chosen)) == 8


def test_reported_value_is_the_direct_svd_value(blocks: np.ndarray) -> None:
    s = tabu_select(blocks, 8, seed=1, settings=FAST)
    assert s.value == pytest.approx(observability(blocks[s.chosen]), rel=1e-9)
    assert s.o1 == s.value


def test_tabu_beats_random_and_matches_exchange(ur5e_blocks: np.ndarray) -> None:
    G = ur5e_blocks
    tabu = tabu_select(G, 15, seed=2, settings=TabuSettings(outer_iterations=6, tabu_iterations=40))
    rand = max(random_select(G, 15, seed=s).o1 for s in range(5))
    exch = exchange_select(G, 15, seed=2)
    assert tabu.o1 > rand
    assert tabu.o1 >= 0.995 * exch.o1


def test_bound_is_above_every_selection(ur5e_blocks: np.ndarray) -> None:
    G = ur5e_blocks
    b = d_optimal_bound(G)
    assert b.gap < 0.01
    for sel in (tabu_select(G, 15, seed=0, settings=FAST), exchange_select(G, 15, seed=0),
                random_select(G, 15, seed=0), random_select(G, 60, seed=0)):
        assert sel.o1 <= b.value
    assert b.achieved <= b.value
    assert b.weights.sum() == pytest.approx(1.0)


def test_bound_is_above_the_exhaustive_optimum() -> None:
    G = np.random.default_rng(7).normal(size=(12, 3, 4))
    best = max(observability(G[list(c)]) for c in itertools.combinations(range(12), 3))
    b = d_optimal_bound(G, tol=1e-4)
    assert best <= b.value
    assert best >= 0.8 * b.value  # and not absurdly loose


def test_other_indices_are_optimised_too(blocks: np.ndarray) -> None:
    for index in ("O2", "O3", "O4", "O5"):
        s = tabu_select(blocks, 8, index=index, seed=0, settings=FAST)
        r = random_select(blocks, 8, index=index, seed=0)
        assert s.value == pytest.approx(observability(blocks[s.chosen], index), rel=1e-8)
        assert s.value > r.value


def test_redundant_pose_removal(blocks: np.ndarray) -> None:
    # A duplicated direction adds little: the copy of a pose scaled down to almost nothing is redundant.
    G = blocks[:30].copy()
    G[29] = 1e-4 * G[0]
    state = DesignState(G, np.arange(30))
    assert 29 in state.chosen[redundant_positions(state, "O1")]
    pruned = tabu_select(blocks, 30, seed=0, settings=TabuSettings(2, 20, prune=True))
    assert minimum_poses(9) <= len(pruned.chosen) < 30


def test_count_errors(blocks: np.ndarray) -> None:
    with pytest.raises(CountError, match="at least 4"):
        tabu_select(blocks, 3)
    with pytest.raises(CountError, match="exceeds"):
        exchange_select(blocks[:5], 6)
    with pytest.raises(SelectorError, match="method"):
        select(blocks, 8, method="annealing")
    with pytest.raises(SelectorError):
        TabuSettings(outer_iterations=0)
