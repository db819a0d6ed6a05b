"""Visiting order: the sequence of chosen poses that minimises the robot's travel time.

Travel time between two configurations is the slowest joint's time at its maximum speed,
t(a, b) = maxⱼ |aⱼ − bⱼ| / vⱼ (joint-space moves, as movej with synchronised joints; acceleration
phases add roughly the same overhead to every move, so they do not change the best order and are left
out). The route is an open path (a campaign does not return to its first pose), optionally starting at
a fixed configuration (the robot's current one).

Heuristic: nearest neighbour from every possible first pose, each improved by 2-opt and Or-opt
(moving runs of 1–3 poses) to a local optimum, keeping the best. For the 15–60 poses of a calibration
this is milliseconds and typically within a few percent of optimal.
"""

from __future__ import annotations

import numpy as np

from selector.errors import SelectorError
from selector.motion_time import MotionProfile


def time_matrix(Q: np.ndarray, speeds: np.ndarray) -> np.ndarray:
    """(N, N) travel times between configurations `Q` (N, 6) at per-joint `speeds` (rad/s)."""
    Q = np.asarray(Q, dtype=float)
    v = np.asarray(speeds, dtype=float)
    if np.any(v <= 0):
        raise SelectorError("joint speeds must be positive")
    return np.max(np.abs(Q[:, None, :] - Q[None, :, :]) / v, axis=2)


def travel_time(Q: np.ndarray, speeds: np.ndarray, start: np.ndarray | None = None) -> float:
    """Total time to visit `Q` in the given order (from `start` if given)."""
    Q = np.asarray(Q, dtype=float)
    if start is not None:
        Q = np.vstack([np.asarray(start, float)[None], Q])
    if len(Q) < 2:
        return 0.0
    return float(np.sum(np.max(np.abs(np.diff(Q, axis=0)) / np.asarray(speeds, float), axis=1)))


def _path_cost(D: np.ndarray, path: np.ndarray) -> float:
    return float(D[path[:-1], path[1:]].sum())


def _two_opt(D: np.ndarray, path: np.ndarray, fixed_first: bool) -> np.ndarray:
    """Best-improvement 2-opt on an open path (segment reversal, vectorised over all pairs)."""
    n = len(path)
    first = 1 if fixed_first else 0
    while True:
        p = path
        # Reversing p[i..j] replaces edges (p[i-1], p[i]) and (p[j], p[j+1]).
        i = np.arange(first, n)[:, None]
        j = np.arange(n)[None, :]
        valid = j > i
        prev = np.where(i > 0, p[np.maximum(i - 1, 0)], -1)
        nxt = np.where(j < n - 1, p[np.minimum(j + 1, n - 1)], -1)
        pi, pj = p[i], p[j]
        pv, nv = np.maximum(prev, 0), np.maximum(nxt, 0)
        old = np.where(prev >= 0, D[pv, pi], 0) + np.where(nxt >= 0, D[pj, nv], 0)
        new = np.where(prev >= 0, D[pv, pj], 0) + np.where(nxt >= 0, D[pi, nv], 0)
        delta = np.where(valid, new - old, 0.0)
        k = int(np.argmin(delta))
        if delta.flat[k] > -1e-12:
            return path
        a, b = divmod(k, n)
        a += first
        path = np.concatenate([p[:a], p[a:b + 1][::-1], p[b + 1:]])


def _or_opt(D: np.ndarray, path: np.ndarray, fixed_first: bool) -> tuple[np.ndarray, bool]:
    """The best move of a run of 1–3 poses to another place (either direction), if it improves.

    Every run and every insertion point of it is scored at once from edge differences (no path is
    rebuilt): for a run at s of length L, the rest of the path is path[:s] + path[s + L:], and its
    insertion point k sits between rest[k − 1] and rest[k].
    """
    n = len(path)
    first = 1 if fixed_first else 0
    best_delta, best_path = -1e-12, None
    pad = np.concatenate([path, [-1]])  # index −1 (and n): no node there

    def at(i: np.ndarray) -> np.ndarray:
        return np.where((i >= 0) & (i < n), pad[np.clip(i, 0, n)], -1)

    def edge(u: np.ndarray, v: np.ndarray) -> np.ndarray:
        return np.where((u >= 0) & (v >= 0), D[np.maximum(u, 0), np.maximum(v, 0)], 0.0)

    for length in (1, 2, 3):
        if n - length < 1 or n - length + 1 <= first:
            break
        s = np.arange(first, n - length + 1)[:, None]  # run starts
        k = np.arange(first, n - length + 1)[None, :]  # insertion points in the rest
        prev, nxt = at(s - 1), at(s + length)
        removed = edge(prev, path[s]) + edge(path[s + length - 1], nxt) - edge(prev, nxt)
        left = at(np.where(k - 1 < s, k - 1, k - 1 + length))
        right = at(np.where(k < s, k, k + length))
        joined = edge(left, right)
        delta = np.empty((s.shape[0], 2, k.shape[1]))
        for o, (head, tail) in enumerate(((path[s], path[s + length - 1]),
                                          (path[s + length - 1], path[s]))):
            delta[:, o, :] = edge(left, head) + edge(tail, right) - joined - removed
        delta[np.broadcast_to((k == s)[:, None, :], delta.shape)] = np.inf  # back where it was
        m = int(np.argmin(delta))
        if delta.flat[m] < best_delta:
            best_delta = float(delta.flat[m])
            i, o, j = np.unravel_index(m, delta.shape)
            start, pos = int(s[i, 0]), int(k[0, j])
            run = path[start:start + length]
            rest = np.concatenate([path[:start], path[start + length:]])
            best_path = np.concatenate([rest[:pos], run if o == 0 else run[::-1], rest[pos:]])
    return (path, False) if best_path is None else (best_path, True)


def _nearest_neighbour(D: np.ndarray, first: int) -> np.ndarray:
    n = len(D)
    seen = np.zeros(n, dtype=bool)
    path = [first]
    seen[first] = True
    for _ in range(n - 1):
        d = np.where(seen, np.inf, D[path[-1]])
        nxt = int(np.argmin(d))
        path.append(nxt)
        seen[nxt] = True
    return np.array(path)


def order_poses(Q: np.ndarray, speeds: np.ndarray | None = None, start: np.ndarray | None = None,
                max_starts: int = 16, *, profile: MotionProfile | None = None) -> tuple[np.ndarray, float]:
    """A permutation of `Q`'s rows with a short total travel time, and that time (s).

    With `start` the route begins at that configuration (not part of the returned permutation). Travel
    times are the driver's motion `profile` (`selector.motion_time`) when given, else the slowest
    joint at its maximum speed (`speeds`).
    """
    Q = np.asarray(Q, dtype=float)
    n = len(Q)
    if n == 0:
        return np.zeros(0, dtype=int), 0.0
    if profile is None and speeds is None:
        raise SelectorError("order_poses needs joint speeds or a motion profile")
    pts = Q if start is None else np.vstack([np.asarray(start, float)[None], Q])
    D = profile.matrix(pts) if profile is not None else time_matrix(pts, speeds)
    if n <= 2 and start is None:
        perm = np.arange(n)
        return perm, _path_cost(D, perm) if n == 2 else 0.0
    fixed = start is not None
    firsts = [0] if fixed else list(range(min(n, max_starts)))
    best_path, best_cost = None, np.inf
    for f in firsts:
        path = _two_opt(D, _nearest_neighbour(D, f), fixed)
        improved = True
        while improved:
            path, improved = _or_opt(D, path, fixed)
            if improved:
                path = _two_opt(D, path, fixed)
        cost = _path_cost(D, path)
        if cost < best_cost - 1e-12:
            best_path, best_cost = path, cost
    assert best_path is not None
    perm = best_path[1:] - 1 if fixed else best_path
    return perm.astype(int), float(best_cost)


def refine_order(Q: np.ndarray, perm: np.ndarray, *, profile: MotionProfile,
                 start: np.ndarray | None = None, or_opt: bool = True) -> tuple[np.ndarray, float]:
    """`perm` (a visiting order of `Q`'s rows) improved by 2-opt and Or-opt to a local optimum.

    The warm start of a search that changes a few poses of a tour at a time: far cheaper than
    `order_poses`, which builds tours from every first pose.
    """
    Q = np.asarray(Q, dtype=float)
    perm = np.asarray(perm, dtype=int)
    if len(perm) < 2:
        return perm, profile.tour_time(Q[perm], start) if len(perm) else 0.0
    fixed = start is not None
    pts = Q if start is None else np.vstack([np.asarray(start, float)[None], Q])
    D = profile.matrix(pts)
    path = np.concatenate([[0], perm + 1]) if fixed else perm.copy()
    path = _two_opt(D, path, fixed)
    improved = or_opt
    while improved:
        path, improved = _or_opt(D, path, fixed)
        if improved:
            path = _two_opt(D, path, fixed)
    out = path[1:] - 1 if fixed else path
    return out.astype(int), _path_cost(D, path)
