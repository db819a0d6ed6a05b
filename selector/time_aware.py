"""Time-aware selection: the poses *and* their visiting order that buy the most accuracy per second.

Method 000 (`selector.tabu`) maximises an observability index for a fixed number of poses and the
visiting order is found afterwards (`selector.order`). An end-of-line cell pays for robot time, and the
poses that are best for the index lie far apart in joint space: most of a campaign is travel. Here the
set and the tour are chosen together.

**What is optimised.** The accuracy a calibration buys is the error of its predictions on the poses the
robot will work in. With M the information matrix of the chosen poses (their stacked Jacobian blocks G,
M = Σ GᵢᵀGᵢ) and W = mean over the workspace of GᵀG (the candidates are a sample of the constrained
workspace), the expected squared prediction error per unit of measurement variance is

    f(S) = tr(W M⁻¹)            (I-optimality; it does not depend on how the columns are scaled),

so equal f means equal expected truth error on held-out poses. Time is the tour's move times under the
driver's motion profile (`selector.motion_time.MotionProfile`) plus a dwell per pose.

**Two forms.**

* *target*: reach f ≤ `target` (by default the f of the N poses method 000 chooses: "the accuracy of
  today's N poses") in the least robot time — the number of poses is free (at least the minimum);
* *budget*: the smallest f whose tour fits in `budget` seconds.

**How.** Cost-benefit greedy insertion builds a first tour: every step adds the candidate with the best
ratio of accuracy gained (a rank-3 Woodbury update, batched over all candidates) to time added (its
cheapest insertion into the current tour plus the dwell). Then a ruin-and-recreate search (large
neighbourhood search, as for orienteering problems): remove a random run of the tour, re-order the rest
(2-opt/Or-opt, `selector.order`), insert greedily again until the target (or budget) is met, keep the
result if it is better. *Fixed* poses (the validation poses, which the tour must visit but which give the
fit nothing) are part of the tour from the start, so calibration poses come to lie near them.

Written here because no library solves this problem: orienteering/prize-collecting TSP solvers take
additive prizes, and the value of a pose set is not additive (a pose is worth less next to a similar one).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from selector.errors import SelectorError
from selector.information import inv3
from selector.motion_time import MotionProfile
from selector.order import order_poses, refine_order

#: Regularisation of M while the set cannot identify every parameter yet (relative to W's diagonal):
#: small enough that a full-rank set's f is unaffected to 1e-6, large enough to keep M⁻¹ finite.
RIDGE = 1e-9

#: A recreate step inserts one of this many best-ratio candidates at random (a deterministic greedy
#: would rebuild what the ruin removed).
EXPLORE = 3

#: Relative tolerance of "f reaches the target" (two computations of f differ by rounding).
TOLERANCE = 1e-9

#: Candidates scored per insertion step: this many of the cheapest to insert, and as many at random.
SHORTLIST = 800


@dataclass
class TimedSelection:
    """A tour of chosen poses and what it costs and buys."""

    chosen: np.ndarray  # candidate indices, in visiting order (fixed poses not included)
    order: np.ndarray  # the whole tour: candidate indices, and fixed poses as -1 - k
    move_time: float  # s, the tour's moves (from the start pose if one was given)
    dwell_time: float  # s, dwell × poses visited (fixed ones too)
    criterion: float  # f = tr(W M⁻¹)
    logdet: float
    seconds: float  # compute time
    form: str
    details: dict[str, Any] = field(default_factory=dict)

    @property
    def total_time(self) -> float:
        return self.move_time + self.dwell_time


class _Design:
    """f, M⁻¹ and batched add/remove scores for one pose set (regularised while rank-deficient)."""

    def __init__(self, G: np.ndarray, W: np.ndarray) -> None:
        self.G = G
        self.W = W
        self.p = G.shape[2]
        self.ridge = RIDGE * float(np.mean(np.diag(W))) * np.eye(self.p)

    def matrix(self, chosen: np.ndarray) -> np.ndarray:
        B = self.G[np.asarray(chosen, dtype=int)].reshape(-1, self.p)
        return B.T @ B + self.ridge

    def criterion(self, chosen: np.ndarray) -> float:
        M = self.matrix(chosen)
        return float(np.trace(np.linalg.solve(M, self.W)))

    def add_gains(self, chosen: np.ndarray, idx: np.ndarray) -> tuple[float, np.ndarray]:
        """(f(S), f(S) − f(S + c) for every candidate c in `idx`)."""
        Minv = np.linalg.inv(self.matrix(chosen))
        f = float(np.sum(Minv * self.W))
        _, C, E = self._blocks(self.G[idx], Minv)
        return f, np.einsum("nij,nji->n", inv3(C + np.eye(3)), E)

    def _blocks(self, Gc: np.ndarray, Minv: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """A = Gc M⁻¹, C = Gc M⁻¹ Gcᵀ and E = Gc M⁻¹ W M⁻¹ Gcᵀ, as batched matrix products."""
        n = len(Gc)
        A = (Gc.reshape(-1, self.p) @ Minv).reshape(n, 3, self.p)
        At = A.transpose(0, 2, 1)
        C = np.matmul(Gc, At)
        E = np.matmul((A.reshape(-1, self.p) @ self.W).reshape(n, 3, self.p), At)
        return A, C, E

    def remove_losses(self, chosen: np.ndarray) -> np.ndarray:
        """f(S − i) − f(S) for every pose i of the set (inf when removing it loses a parameter)."""
        Minv = np.linalg.inv(self.matrix(chosen))
        _, C, E = self._blocks(self.G[np.asarray(chosen, dtype=int)], Minv)
        with np.errstate(divide="ignore", invalid="ignore"):
            out = np.einsum("nij,nji->n", inv3(np.eye(3) - C), E)
        return np.where(np.isfinite(out) & (out >= 0), out, np.inf)


class _Insertions:
    """The cheapest insertion of every candidate into a path, kept up to date as poses are inserted.

    The path is framed by a head (the start, or a virtual node 0 s from everything when the tour may
    begin anywhere) and a virtual tail (0 s from everything: appending costs the move from the last
    node), so every insertion is "into a leg (u, v)", costing t(u, x) + t(x, v) − t(u, v). A full
    computation is (legs × candidates); inserting a pose replaces one leg by two, so only those two are
    new for every candidate, and only the candidates whose best leg was the replaced one need all legs
    again: a greedy fill of k poses costs about k × candidates instead of k × legs × candidates.
    """

    HEAD = -(10**9)  # the key of the head (node keys are candidate indices ≥ 0 and fixed poses < 0)

    def __init__(self, tour: _Tour, nodes: np.ndarray) -> None:
        self.tour = tour
        self.keys = [self.HEAD] + [int(n) for n in nodes]  # the left ends of the legs, in path order
        self.rows = [tour.row(None)] + [tour.row(int(n)) for n in nodes] + [tour.zero_row()]
        # leg i runs from path entry i to i + 1; a leg from or to a virtual end costs nothing
        q = [self._q(i) for i in range(len(self.rows))]
        self.legs = [self._time(q[i], q[i + 1]) for i in range(len(q) - 1)]
        self.cost, self.left = self._over(np.arange(len(tour.Q)))

    def _over(self, cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(cheapest cost, the key of that leg's left end) over every leg, for candidates `cols`."""
        R = np.stack([r[cols] for r in self.rows])
        mid = R[:-1]
        mid += R[1:]
        mid -= np.asarray(self.legs)[:, None]
        j = np.argmin(mid, axis=0)
        return mid[j, np.arange(len(cols))], np.asarray(self.keys, dtype=np.int64)[j]

    def position(self, candidate: int) -> int:
        """Where `candidate` goes in the nodes array: right after the node its cheapest leg starts at
        (the head's leg: first)."""
        return self.keys.index(int(self.left[candidate]))

    def _q(self, i: int) -> np.ndarray | None:
        """The configuration of path entry `i` (None: the virtual head or tail)."""
        if i == 0:
            return self.tour.start
        if i == len(self.rows) - 1:
            return None
        return self.tour.q(np.array([self.keys[i]]))[0]

    def _time(self, a: np.ndarray | None, b: np.ndarray | None) -> float:
        if a is None or b is None:
            return 0.0
        return float(self.tour.profile.move_times(a[None], b[None])[0])

    def insert(self, node: int, position: int) -> None:
        """`node` inserted at `position` of the nodes array, i.e. into leg `position` of the path."""
        i = position
        row = self.tour.row(node)
        u, v = self.rows[i], self.rows[i + 1]
        q_c = self.tour.q(np.array([node]))[0]
        t_uc, t_cv = self._time(self._q(i), q_c), self._time(q_c, self._q(i + 1))
        old_left = self.keys[i]
        self.keys.insert(i + 1, node)
        self.rows.insert(i + 1, row)
        self.legs[i:i + 1] = [t_uc, t_cv]
        stale = self.left == old_left  # their best leg is gone: all legs again
        a = u + row - t_uc
        b = row + v - t_cv
        new = np.minimum(a, b)
        better = new < self.cost
        self.cost = np.where(better, new, self.cost)
        self.left = np.where(better, np.where(a <= b, old_left, node), self.left)
        cols = np.flatnonzero(stale)
        if len(cols):
            self.cost[cols], self.left[cols] = self._over(cols)


class _Tour:
    """The tour being built: nodes are candidate indices (≥ 0) and fixed poses (−1 − k)."""

    def __init__(self, Q: np.ndarray, fixed: np.ndarray, profile: MotionProfile,
                 start: np.ndarray | None) -> None:
        self.Q, self.fixed, self.profile = Q, fixed, profile
        self.start = None if start is None else np.asarray(start, dtype=float)
        # move times between every candidate and each node met so far, one column per node (the start
        # first), computed once: a tour changes a few nodes at a time
        self._column: dict[int, int] = {}
        self._times = np.empty((64, len(Q)))
        self._zero: np.ndarray | None = None

    def _col(self, node: int | None) -> int:
        key = -(10**9) if node is None else int(node)
        if key not in self._column:
            j = len(self._column)
            if j == len(self._times):
                self._times = np.vstack([self._times, np.empty_like(self._times)])
            q = self.start if node is None else self.q(np.array([node]))[0]
            self._times[j] = self.profile.move_times(self.Q, q[None, :])
            self._column[key] = j
        return self._column[key]

    def row(self, node: int | None) -> np.ndarray:
        """(N,) move times between a node (None: the start; none given: a virtual head, 0 s from
        every candidate) and every candidate."""
        if node is None and self.start is None:
            return self.zero_row()
        j = self._col(node)  # first: it may grow the table
        return self._times[j]

    def zero_row(self) -> np.ndarray:
        if self._zero is None:
            self._zero = np.zeros(len(self.Q))
        return self._zero

    def q(self, nodes: np.ndarray) -> np.ndarray:
        nodes = np.asarray(nodes, dtype=int)
        out = np.empty((len(nodes), 6))
        cand = nodes >= 0
        out[cand] = self.Q[nodes[cand]]
        out[~cand] = self.fixed[-1 - nodes[~cand]]
        return out

    def path_q(self, nodes: np.ndarray) -> np.ndarray:
        """Configurations along the path, the start first when there is one."""
        q = self.q(nodes)
        return q if self.start is None else np.vstack([self.start[None], q])

    def move_time(self, nodes: np.ndarray) -> float:
        return self.profile.tour_time(self.q(nodes), self.start)

    def reorder(self, nodes: np.ndarray, thorough: bool = False, quick: bool = False) -> np.ndarray:
        """The nodes in a short visiting order: built from scratch (`thorough`) or the current one
        improved (2-opt, Or-opt), which is what a search that changes a few poses at a time needs."""
        nodes = np.asarray(nodes, dtype=int)
        if len(nodes) < 2:
            return nodes
        if thorough:
            perm, _ = order_poses(self.q(nodes), profile=self.profile, start=self.start)
        else:
            perm, _ = refine_order(self.q(nodes), np.arange(len(nodes)), profile=self.profile,
                                   start=self.start, or_opt=not quick)
        return nodes[perm]


def time_aware_select(G: np.ndarray, Q: np.ndarray, profile: MotionProfile, dwell: float, *,
                      target: float | None = None, budget: float | None = None,
                      fixed: np.ndarray | None = None, start: np.ndarray | None = None,
                      min_count: int = 1, max_count: int | None = None, seed: int = 0,
                      time_limit: float = 5.0, workspace: np.ndarray | None = None) -> TimedSelection:
    """Choose and order poses among candidates (G (N, 3, n) scaled Jacobian blocks, Q (N, 6) joints).

    Exactly one of `target` (reach f ≤ target in the least time) and `budget` (least f within budget
    seconds, moves plus `dwell` per pose visited) must be given. `fixed` (F, 6): poses the tour visits
    anyway (validation), `start`: the arm's configuration before the first move. `workspace`: the
    weight W (n, n); default the mean GᵀG over the candidates. `min_count`: fewest poses that identify
    the parameters. The search stops improving after `time_limit` seconds.
    """
    t0 = time.perf_counter()
    G = np.asarray(G, dtype=float)
    Q = np.asarray(Q, dtype=float)
    if G.ndim != 3 or G.shape[1] != 3 or len(G) != len(Q):
        raise SelectorError("time-aware selection needs (N, 3, n) blocks and (N, 6) configurations")
    if (target is None) == (budget is None):
        raise SelectorError("give either a target accuracy or a time budget")
    if budget is not None and not budget > 0:
        raise SelectorError(f"the time budget must be positive, got {budget}")
    if target is not None and not target > 0:
        raise SelectorError(f"the target must be positive, got {target}")
    fixed = np.zeros((0, 6)) if fixed is None else np.asarray(fixed, dtype=float).reshape(-1, 6)
    max_count = len(Q) if max_count is None else min(int(max_count), len(Q))
    if min_count > max_count:
        raise SelectorError(f"{min_count} poses needed, only {max_count} candidates")
    W = (np.einsum("nip,niq->pq", G, G) / len(G)) if workspace is None else np.asarray(workspace, float)
    design = _Design(G, W)
    tour = _Tour(Q, fixed, profile, start)
    rng = np.random.default_rng(seed)
    fixed_nodes = -1 - np.arange(len(fixed))

    def total(nodes: np.ndarray) -> float:
        return tour.move_time(nodes) + dwell * len(nodes)

    def fill(nodes: np.ndarray, explore: bool = False) -> np.ndarray:
        """Greedy cost-benefit insertion until the target is met (or nothing more fits the budget)."""
        nodes = np.asarray(nodes, dtype=int)
        in_set = np.zeros(len(Q), dtype=bool)
        in_set[nodes[nodes >= 0]] = True
        insertions = _Insertions(tour, nodes)
        while True:
            chosen = nodes[nodes >= 0]
            if len(chosen) >= max_count:
                return nodes
            cost = insertions.cost + dwell
            ok = ~in_set
            if budget is not None:
                ok &= total(nodes) + cost <= budget + 1e-9
            # scored: the cheapest insertions and a random sample of the rest (far poses win only by
            # their gain, and a sample finds such gains as well as all of them would)
            idx = np.flatnonzero(ok)
            if len(idx) > 2 * SHORTLIST:
                near = idx[np.argpartition(cost[idx], SHORTLIST)[:SHORTLIST]]
                idx = np.union1d(near, rng.choice(idx, SHORTLIST, replace=False))
            f, gain = design.add_gains(chosen, idx)
            if target is not None and f <= target and len(chosen) >= min_count:
                return nodes
            if not len(idx):
                return nodes
            ratio = gain / np.maximum(cost[idx], 1e-6)
            if explore and len(ratio) > EXPLORE:  # a recreate step: one of the few best, at random
                top = np.argpartition(-ratio, EXPLORE)[:EXPLORE]
                k = int(rng.choice(top))
            else:
                k = int(np.argmax(ratio))
            c = int(idx[k])
            at = insertions.position(c)
            nodes = np.insert(nodes, at, c)
            insertions.insert(c, at)
            in_set[c] = True

    def objective(nodes: np.ndarray) -> tuple[float, float]:
        """What is minimised, lexicographically: (shortfall, time) for a target, (f, time) for a budget."""
        chosen = nodes[nodes >= 0]
        f = design.criterion(chosen)
        short = 0.0 if len(chosen) >= min_count else float(min_count - len(chosen))
        if target is not None:
            # (the greedy's f and this one are computed differently: equal within rounding)
            return (short + max(0.0, f / target - 1.0 - TOLERANCE), total(nodes))
        return (short + f, total(nodes))

    nodes = tour.reorder(fixed_nodes, thorough=True)
    if budget is not None and total(nodes) > budget:
        raise SelectorError(f"the {len(fixed)} fixed poses alone take {total(nodes):.1f} s, over the "
                            f"budget of {budget:g} s")
    nodes = tour.reorder(fill(nodes), thorough=True)
    nodes = tour.reorder(fill(nodes))
    best, best_obj = nodes, objective(nodes)
    iterations = accepted = 0
    while time.perf_counter() - t0 < time_limit and (best >= 0).sum() > 1:
        iterations += 1
        cand = best[_ruin(best, design, tour, rng)]
        cand = tour.reorder(fill(tour.reorder(cand, quick=True), explore=True), quick=True)
        if budget is not None and total(cand) > budget + 1e-9:
            continue
        if target is not None:  # a refill can leave poses the target no longer needs
            cand = _prune(cand, design, tour, target, min_count, dwell, quick=True)
        if total(cand) < 1.03 * best_obj[1]:  # close: worth the full reordering before judging
            cand = tour.reorder(cand)
        obj = objective(cand)
        if obj < best_obj:
            best, best_obj = tour.reorder(cand), obj
            best_obj = objective(best)
            accepted += 1
    if target is not None:  # drop poses the target does not need, cheapest-to-keep last
        best = _prune(best, design, tour, target, min_count, dwell)
    rebuilt = tour.reorder(best, thorough=True)
    if total(rebuilt) < total(best):
        best = rebuilt
    chosen = best[best >= 0]
    f = design.criterion(chosen)
    sign, logdet = np.linalg.slogdet(design.matrix(chosen) - design.ridge)
    move = tour.move_time(best)
    return TimedSelection(
        chosen=chosen, order=best, move_time=move, dwell_time=dwell * len(best), criterion=f,
        logdet=float(logdet) if sign > 0 else -np.inf, seconds=time.perf_counter() - t0,
        form="target" if target is not None else "budget",
        details={"iterations": iterations, "accepted": accepted, "target": target, "budget": budget,
                 "dwell": dwell, "fixed": len(fixed)})


def _ruin(nodes: np.ndarray, design: _Design, tour: _Tour, rng: np.random.Generator) -> np.ndarray:
    """Which nodes to keep in one ruin-and-recreate step (fixed poses always stay).

    Half the time a random run of the tour goes (a region visited badly), half the time a few poses
    chosen with probability rising with the time their removal saves per unit of accuracy lost (the
    expensive detours)."""
    n = len(nodes)
    keep = np.ones(n, dtype=bool)
    sel = np.flatnonzero(nodes >= 0)
    if rng.random() < 0.5:
        run = int(rng.integers(1, max(2, n // 4) + 1))
        first = int(rng.integers(0, n))
        keep[[(first + k) % n for k in range(run)]] = False
    else:
        loss = design.remove_losses(nodes[sel])
        q = tour.path_q(nodes)  # the start first, if any: node i is q[i + off]
        off = 1 if tour.start is not None else 0
        legs = np.concatenate([[0.0], tour.profile.move_times(q[:-1], q[1:]), [0.0]])
        at = np.arange(n) + off
        prev, nxt = legs[at], legs[at + 1]  # the legs into and out of each node (0: none)
        inner = (at >= 1) & (at <= len(q) - 2)
        bypass = np.zeros(n)
        bypass[inner] = tour.profile.move_times(q[at[inner] - 1], q[at[inner] + 1])
        saving = (prev + nxt - bypass)[sel]
        weight = np.where(np.isfinite(loss), np.maximum(saving, 1e-3) / np.maximum(loss, 1e-12), 0.0)
        if weight.sum() <= 0:
            return keep
        k = int(rng.integers(1, min(4, len(sel)) + 1))
        drop = rng.choice(sel, size=min(k, int(np.count_nonzero(weight))), replace=False,
                          p=weight / weight.sum())
        keep[drop] = False
    keep |= nodes < 0
    return keep


def _prune(nodes: np.ndarray, design: _Design, tour: _Tour, target: float, min_count: int,
           dwell: float, quick: bool = False) -> np.ndarray:
    """Remove, one at a time, the pose whose removal saves the most time while f stays ≤ target."""
    while True:
        chosen = nodes[nodes >= 0]
        if len(chosen) <= min_count:
            return nodes
        f = design.criterion(chosen)
        loss = design.remove_losses(chosen)
        ok = np.flatnonzero(f + loss <= target * (1 + TOLERANCE))
        if not len(ok):
            return nodes
        pos = np.flatnonzero(nodes >= 0)
        base = tour.move_time(nodes)
        saving = [base - tour.move_time(np.delete(nodes, pos[i])) for i in ok]
        i = ok[int(np.argmax(saving))]
        nodes = tour.reorder(np.delete(nodes, pos[i]), quick=quick)
