"""Time-aware selection: the budget is never exceeded, the target is reached faster than method 000's tour,
fixed poses are visited once, and every chosen pose satisfies every constraint of the station."""

from __future__ import annotations

import numpy as np
import pytest

from hil.calibration.selection import SelectionModel
from selector.candidates import CONSTRAINT_NAMES, Constraints, evaluate, generate_candidates
from selector.design import minimum_poses
from selector.errors import SelectorError
from selector.indices import scale_columns
from selector.motion_time import MotionProfile
from selector.order import order_poses
from selector.search import select
from selector.time_aware import time_aware_select

TRACKER = (2.0, 0.3, 0.4)
PROFILE = MotionProfile(0.5, 1.0, (3.14,) * 6)
DWELL = 0.85
START = np.array([0.0, -1.6, 1.4, -1.4, -1.5, 0.0])


@pytest.fixture(scope="module")
def station() -> tuple[SelectionModel, Constraints, np.ndarray, np.ndarray]:
    """2000 UR5e candidates under every constraint of a cell: keep-in box, floor, tracker sight."""
    model = SelectionModel("ur5e", smr=(0.0, 0.0, 0.045), tracker=TRACKER)
    constraints = Constraints(tracker=TRACKER, half_angle_deg=25.0, keep_in_lower=(-0.9, -0.9, 0.05),
                              keep_in_upper=(0.9, 0.9, 1.0), floor=0.05,
                              joint_lower=(-np.pi,) * 6, joint_upper=(np.pi, 0.0, np.pi, np.pi, np.pi, np.pi))
    cands = generate_candidates(model, 2000, constraints, seed=3)
    return model, constraints, scale_columns(cands.jacobian, "expected", model.parameter_scale), cands.q


def _criterion(G: np.ndarray, chosen: np.ndarray) -> float:
    W = np.einsum("nip,niq->pq", G, G) / len(G)
    B = G[chosen].reshape(-1, G.shape[2])
    return float(np.trace(np.linalg.solve(B.T @ B, W)))


def _robot_time(Q: np.ndarray, order: np.ndarray, fixed: np.ndarray) -> float:
    tour = np.array([Q[k] if k >= 0 else fixed[-1 - k] for k in order])
    return PROFILE.tour_time(tour, START) + DWELL * len(tour)


@pytest.mark.parametrize("budget", [80.0, 110.0, 150.0])
def test_the_budget_form_never_exceeds_its_budget(station: tuple, budget: float) -> None:
    _, _, G, Q = station
    fixed = Q[np.random.default_rng(5).choice(len(Q), 8, replace=False)]
    n = G.shape[2]
    for seed in (1, 2):
        r = time_aware_select(G, Q, PROFILE, DWELL, budget=budget, fixed=fixed, start=START,
                              min_count=minimum_poses(n), seed=seed, time_limit=0.5)
        # recomputed independently from the returned tour
        assert _robot_time(Q, r.order, fixed) <= budget + 1e-9
        assert r.total_time == pytest.approx(_robot_time(Q, r.order, fixed))
    # more budget buys at least as much accuracy
    small = time_aware_select(G, Q, PROFILE, DWELL, budget=budget, start=START, min_count=minimum_poses(n),
                              seed=1, time_limit=0.3)
    large = time_aware_select(G, Q, PROFILE, DWELL, budget=2 * budget, start=START,
                              min_count=minimum_poses(n), seed=1, time_limit=0.3)
    assert large.criterion <= small.criterion


def test_the_target_form_reaches_method_000s_accuracy_in_less_time(station: tuple) -> None:
    _, _, G, Q = station
    n = G.shape[2]
    seed_set = select(G, 30, method="tabu", seed=1).chosen
    target = _criterion(G, seed_set)
    _, move = order_poses(Q[seed_set], profile=PROFILE, start=START)
    seed_time = move + DWELL * 30
    r = time_aware_select(G, Q, PROFILE, DWELL, target=target, start=START, min_count=minimum_poses(n),
                          seed=1, time_limit=2.0)
    assert _criterion(G, r.chosen) <= target * (1 + 1e-9)
    assert r.total_time < 0.9 * seed_time
    assert len(set(r.chosen.tolist())) == len(r.chosen) >= minimum_poses(n)


def test_fixed_poses_are_visited_exactly_once_and_inform_nothing(station: tuple) -> None:
    _, _, G, Q = station
    fixed = Q[:6]
    r = time_aware_select(G, Q, PROFILE, DWELL, target=_criterion(G, np.arange(6, 46)), fixed=fixed,
                          start=START, min_count=minimum_poses(G.shape[2]), seed=2, time_limit=0.5)
    assert sorted(int(-1 - k) for k in r.order if k < 0) == list(range(6))
    assert sorted(r.chosen.tolist()) == sorted(int(k) for k in r.order if k >= 0)
    assert r.dwell_time == pytest.approx(DWELL * (len(r.chosen) + 6))


def test_every_chosen_pose_satisfies_every_constraint(station: tuple) -> None:
    model, constraints, G, Q = station
    r = time_aware_select(G, Q, PROFILE, DWELL, budget=120.0, start=START,
                          min_count=minimum_poses(G.shape[2]), seed=4, time_limit=0.5)
    passes, _ = evaluate(model, Q[r.chosen], constraints)
    for name in CONSTRAINT_NAMES:
        assert np.all(passes[name]), name


def test_bad_requests_are_refused(station: tuple) -> None:
    _, _, G, Q = station
    with pytest.raises(SelectorError, match="either"):
        time_aware_select(G, Q, PROFILE, DWELL)
    with pytest.raises(SelectorError, match="budget"):
        time_aware_select(G, Q, PROFILE, DWELL, budget=-1.0)
    with pytest.raises(SelectorError, match="fixed poses alone"):
        time_aware_select(G, Q, PROFILE, DWELL, budget=20.0, fixed=Q[:8], start=START)


@pytest.mark.parametrize("with_start", [False, True])
def test_kept_insertion_costs_equal_trying_every_place(with_start: bool) -> None:
    """The greedy's insertion costs, updated pose by pose, equal the cheapest of all places tried on
    the tour itself (the start fixed or not, fixed poses in the path)."""
    from selector.time_aware import _Insertions, _Tour

    rng = np.random.default_rng(5)
    Q = rng.uniform(-2.0, 2.0, (300, 6))
    tour = _Tour(Q, rng.uniform(-2.0, 2.0, (3, 6)), MotionProfile(0.5, 1.0, (3.14,) * 6),
                 rng.uniform(-2.0, 2.0, 6) if with_start else None)
    nodes = np.array([-1, -2, -3])
    kept = _Insertions(tour, nodes)
    for c in rng.choice(300, 25, replace=False):
        at = kept.position(int(c))
        nodes = np.insert(nodes, at, int(c))
        kept.insert(int(c), at)
        base = tour.move_time(nodes)
        for x in rng.choice(np.setdiff1d(np.arange(300), nodes), 4, replace=False):
            tried = [tour.move_time(np.insert(nodes, p, x)) - base for p in range(len(nodes) + 1)]
            assert kept.cost[x] == pytest.approx(min(tried), abs=1e-9)
            assert tried[kept.position(int(x))] == pytest.approx(min(tried), abs=1e-9)


def test_or_opt_finds_the_best_single_run_move() -> None:
    """Or-opt (all runs and places scored at once) takes the best move of a run of 1-3 poses, as
    trying each one on the path finds it."""
    from selector.order import _or_opt, _path_cost

    rng = np.random.default_rng(11)
    for _ in range(40):
        n = int(rng.integers(4, 14))
        D = rng.uniform(0.0, 5.0, (n, n))
        D = D + D.T
        path, fixed = rng.permutation(n), bool(rng.integers(0, 2))
        out, moved = _or_opt(D, path, fixed)
        best = _path_cost(D, path)
        first = 1 if fixed else 0
        for length in (1, 2, 3):
            for s in range(first, n - length + 1):
                run, rest = path[s:s + length], np.concatenate([path[:s], path[s + length:]])
                for p in range(first, len(rest) + 1):
                    for seg in (run, run[::-1]):
                        best = min(best, _path_cost(D, np.concatenate([rest[:p], seg, rest[p:]])))
        assert moved == (best < _path_cost(D, path) - 1e-12)
        assert _path_cost(D, out) == pytest.approx(best, abs=1e-9)
