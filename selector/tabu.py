"""The patent method (seed 000): random restarts around a tabu search, with redundant-pose removal.

Steps as the seed describes them, with the gaps (formula (3) and several conditions were lost in
extraction) filled as follows — each choice is what a calibration engineer would expect and is
deterministic for a given seed:

1. **Outer loop** (``outer_iterations`` = nᵢ): start from nₘ = `count` random candidates. Each outer
   iteration runs the tabu search on the current set, keeps the best set seen, removes the redundant
   poses of the tabu result (step 5) and refills the set with new random candidates. When no pose is
   redundant the next tabu run starts from the same set with a fresh random stream.
2. **Tabu search** (``tabu_iterations`` = inᵢ, list length l = 2·nₘ, neighbourhood k = 4·nₘ):
   formula (3) is read as "replace one pose by a new random candidate". Each iteration draws k distinct
   random candidates outside the set; neighbour c replaces the pose whose replacement gives the highest
   index (positions are scored for all k candidates at once with the determinant lemma,
   `DesignState.swap_gain`, so the neighbourhood is k sets but the best position of each is exact).
   The random candidates are not drawn uniformly: among 20 000 candidates a uniform draw of 4·nₘ
   rarely contains one that improves a good set. Candidate c is drawn with probability proportional to
   d_c^β (β = ``sampling_power``, d_c = tr(B_c M⁻¹ B_cᵀ), the information c would add to the current
   set; the same weight the multiplicative D-optimal algorithm uses), refreshed every ``refresh``
   iterations, with a ``uniform_share`` of the draw uniform so every candidate stays reachable.
   The best neighbour whose move is not tabu becomes the current set even if it is worse (that is what
   lets tabu search leave local optima); a tabu move is allowed when it beats the best set so far
   (aspiration). A move (a out, c in) is recorded in the tabu list, and is tabu while the list holds a
   move that removed c or added a, i.e. the reverse of a recent move; the list is cleared when it grows
   past l, as the patent says (not a sliding window).
3. **Redundant-pose removal** (`selector.design.redundant_positions`): a pose whose removal does not
   lower the index is dropped. With O1's 1/√m factor this drops poses that contribute less than an
   average pose — a principled "kick" for the next restart. The output keeps exactly `count` poses
   unless ``prune`` is set, in which case redundant poses of the final set are removed one at a time
   (least useful first) while the count stays identifiable: the patent's "fewer measurement poses".

For O2–O5 the position a candidate replaces is still chosen by the D-criterion (the lemma is cheap and
D-good positions are rarely bad for the others), and the k neighbours are then ranked by their true
index from the eigenvalues of their information matrices.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from selector.design import (
    Selection,
    check_blocks,
    check_count,
    minimum_poses,
    random_fill,
    redundant_positions,
    score,
)
from selector.errors import SelectorError
from selector.indices import index_from_information, parse_index
from selector.information import DesignState


@dataclass(frozen=True)
class TabuSettings:
    """Iteration budget of the patent method (None: the patent's 2·nₘ / 4·nₘ)."""

    outer_iterations: int = 12
    tabu_iterations: int = 60
    tabu_length: int | None = None
    neighbourhood: int | None = None
    prune: bool = False
    sampling_power: float = 4.0
    uniform_share: float = 0.25
    refresh: int = 25

    def __post_init__(self) -> None:
        if not 0.0 <= self.uniform_share <= 1.0 or self.sampling_power < 0:
            raise SelectorError("uniform_share must be in [0, 1] and sampling_power non-negative")
        for name in ("outer_iterations", "tabu_iterations", "refresh"):
            if int(getattr(self, name)) < 1:
                raise SelectorError(f"{name} must be at least 1")
        for name in ("tabu_length", "neighbourhood"):
            value = getattr(self, name)
            if value is not None and int(value) < 1:
                raise SelectorError(f"{name} must be at least 1")


class _Tabu:
    """The tabu list: moves (out, in); a move is tabu if it re-adds a removed or removes an added pose."""

    def __init__(self, n_candidates: int, length: int) -> None:
        self.length = length
        self.moves: list[tuple[int, int]] = []
        self.removed = np.zeros(n_candidates, dtype=bool)
        self.added = np.zeros(n_candidates, dtype=bool)

    def record(self, out: int, into: int) -> None:
        self.moves.append((out, into))
        self.removed[out] = True
        self.added[into] = True
        if len(self.moves) > self.length:
            self.moves.clear()
            self.removed[:] = False
            self.added[:] = False


class _Sampler:
    """Draws the neighbourhood's new candidates: ∝ d_c^β with a uniform share (module docstring)."""

    def __init__(self, settings: TabuSettings, n_candidates: int) -> None:
        self.settings = settings
        self.n = n_candidates
        self.weights: np.ndarray | None = None
        self.age = 0

    def draw(self, state: DesignState, rng: np.random.Generator, k: int) -> np.ndarray:
        free = ~state.in_set
        n_free = int(free.sum())
        k = min(k, n_free)
        s = self.settings
        if s.uniform_share >= 1.0 or s.sampling_power == 0.0:
            return rng.choice(np.flatnonzero(free), size=k, replace=False)
        if self.weights is None or self.age >= s.refresh:
            d = state.variance()
            self.weights = (d / d.max()) ** s.sampling_power
            self.age = 0
        self.age += 1
        w = np.where(free, self.weights, 0.0)
        p = s.uniform_share / n_free * free + (1.0 - s.uniform_share) * w / w.sum()
        cdf = np.cumsum(p)
        draw = np.searchsorted(cdf, rng.random(2 * k) * cdf[-1])
        draw = np.minimum(draw, self.n - 1)
        _, first = np.unique(draw, return_index=True)
        picked = draw[np.sort(first)]
        picked = picked[free[picked]][:k]
        if len(picked) < k:  # top up uniformly (rare: a very peaked distribution)
            rest = np.flatnonzero(free)
            rest = rest[~np.isin(rest, picked)]
            picked = np.concatenate([picked, rng.choice(rest, size=k - len(picked), replace=False)])
        return picked


def _objective(state: DesignState, index: str) -> float:
    """What the search compares: log det for O1 at fixed m (monotone in O1), the index otherwise."""
    return state.logdet if index == "O1" else score(state, index)


def _tabu_run(state: DesignState, index: str, rng: np.random.Generator, iterations: int, length: int,
              k: int, best_value: float, sampler: _Sampler) -> tuple[np.ndarray, float, int]:
    """One tabu search from `state` (modified in place); returns the best set it saw and its objective."""
    tabu = _Tabu(len(state.G), length)
    local_best_set, local_best = state.chosen.copy(), _objective(state, index)
    best = max(best_value, local_best)  # aspiration level: the best objective seen anywhere
    evaluations = 0
    for _ in range(iterations):
        cands = sampler.draw(state, rng, k)
        gains = state.swap_gain(cands)  # (k, m)
        evaluations += gains.size
        pos_tabu = tabu.added[state.chosen]  # removing a recently added pose
        cand_tabu = tabu.removed[cands]  # re-adding a recently removed pose
        if index == "O1":
            values = state.logdet + gains if np.isfinite(state.logdet) else gains
            allowed = ~(cand_tabu[:, None] | pos_tabu[None, :])
            aspire = values > best
            values = np.where(allowed | aspire, values, -np.inf)
            flat = int(np.argmax(values))
            if not np.isfinite(values.flat[flat]) and np.isfinite(state.logdet):
                continue
            c_row, pos = divmod(flat, state.m)
            value = float(values.flat[flat])
        else:
            g = np.where(pos_tabu[None, :], -np.inf, gains)
            g = np.where(np.all(np.isinf(g), axis=1, keepdims=True), gains, g)
            pos_of = np.argmax(g, axis=1)
            Ms = state.swapped_information(cands, pos_of)
            vals = index_from_information(Ms, state.m, index)
            evaluations += len(vals)
            allowed = ~(cand_tabu | pos_tabu[pos_of])
            vals = np.where(allowed | (vals > best), vals, -np.inf)
            c_row = int(np.argmax(vals))
            if not np.isfinite(vals[c_row]):
                continue
            pos, value = int(pos_of[c_row]), float(vals[c_row])
        cand = int(cands[c_row])
        out = state.swap(pos, cand)
        tabu.record(out, cand)
        value = _objective(state, index) if index == "O1" else value
        if value > local_best:
            local_best, local_best_set = value, state.chosen.copy()
        best = max(best, value)
    return local_best_set, local_best, evaluations


def _prune(state: DesignState, index: str) -> DesignState:
    """Drop redundant poses one at a time (the least useful first) while the set stays identifiable."""
    floor = minimum_poses(state.n)
    while state.m > floor:
        redundant = redundant_positions(state, index)
        if redundant.size == 0:
            break
        if index == "O1":
            loss = state.remove_loss()[redundant]
            state.remove(int(redundant[int(np.argmax(loss))]))
        else:
            state.remove(int(redundant[0]))
    return state


def tabu_select(G: np.ndarray, count: int, *, index: str = "O1", seed: int = 0,
                settings: TabuSettings | None = None,
                progress: Callable[[int, int], None] | None = None) -> Selection:
    """Choose `count` of the candidate blocks `G` (N, 3, n) by the patent method (module docstring).

    `progress(done, total)` is called after each of the outer iterations (restarts), if given.
    """
    t0 = time.perf_counter()
    G = check_blocks(G)
    index = parse_index(index)
    settings = settings or TabuSettings()
    check_count(count, len(G), G.shape[2])
    rng = np.random.default_rng(seed)
    length = settings.tabu_length or 2 * count
    k = settings.neighbourhood or 4 * count
    state = DesignState(G, rng.choice(len(G), size=count, replace=False))
    best_set, best = state.chosen.copy(), _objective(state, index)
    evaluations, removed_total = 0, 0
    for outer in range(settings.outer_iterations):
        sampler = _Sampler(settings, len(G))
        run_set, run_value, evals = _tabu_run(state, index, rng, settings.tabu_iterations, length, k, best,
                                              sampler)
        evaluations += evals
        if run_value > best:
            best, best_set = run_value, run_set.copy()
        state = DesignState(G, run_set)
        redundant = redundant_positions(state, index)
        removed_total += len(redundant)
        if redundant.size:
            keep = np.delete(state.chosen, redundant)
            in_set = np.zeros(len(G), dtype=bool)
            in_set[keep] = True
            refill = random_fill(rng, in_set, count - len(keep))
            state = DesignState(G, np.concatenate([keep, refill]))
        if progress is not None:
            progress(outer + 1, settings.outer_iterations)
    final = DesignState(G, best_set)
    if settings.prune:
        final = _prune(final, index)
    return Selection(final.chosen.copy(), index, score(final, index), score(final, "O1"), "tabu",
                     time.perf_counter() - t0, evaluations,
                     {"outer_iterations": settings.outer_iterations,
                      "tabu_iterations": settings.tabu_iterations, "tabu_length": length,
                      "neighbourhood": k, "redundant_removed": removed_total})
