import itertools

import numpy as np
import pytest

from selector.errors import SelectorError
from selector.order import order_poses, time_matrix, travel_time

SPEEDS = np.radians([180, 180, 180, 360, 360, 360])


def test_time_is_the_slowest_joint() -> None:
    Q = np.array([[0, 0, 0, 0, 0, 0], [np.pi, 0, 0, np.pi, 0, 0]], float)
    assert time_matrix(Q, SPEEDS)[0, 1] == pytest.approx(1.0)
    assert travel_time(Q, SPEEDS) == pytest.approx(1.0)
    with pytest.raises(SelectorError):
        time_matrix(Q, np.zeros(6))


@pytest.mark.parametrize("n", [1, 2, 7, 30, 60])
def test_valid_permutation_no_worse_than_unordered(n: int) -> None:
    Q = np.random.default_rng(n).uniform(-np.pi, np.pi, size=(n, 6))
    perm, t = order_poses(Q, SPEEDS)
    assert sorted(perm.tolist()) == list(range(n))
    assert t == pytest.approx(travel_time(Q[perm], SPEEDS))
    assert t <= travel_time(Q, SPEEDS) + 1e-12


def test_near_optimal_on_small_instances() -> None:
    for seed in range(3):
        Q = np.random.default_rng(seed).uniform(-np.pi, np.pi, size=(7, 6))
        best = min(travel_time(Q[list(p)], SPEEDS) for p in itertools.permutations(range(7)))
        assert order_poses(Q, SPEEDS)[1] <= 1.05 * best


def test_fixed_start() -> None:
    Q = np.random.default_rng(9).uniform(-np.pi, np.pi, size=(20, 6))
    start = np.zeros(6)
    perm, t = order_poses(Q, SPEEDS, start)
    assert sorted(perm.tolist()) == list(range(20))
    assert t == pytest.approx(travel_time(Q[perm], SPEEDS, start))
    assert t <= travel_time(Q, SPEEDS, start)
