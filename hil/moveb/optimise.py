"""The bridge parameters h: a linear programme, and the seed's point-error iteration around it.

**The LP** (seed 001, formulas (1)–(5)). For the working points W0…Wn with segment lengths Lj and
turn half-angles θi, a bridge uses ``arm·h`` of each neighbouring segment (`BridgeShape.arm`) and
its chord error is |WiQi| = h·sinθi. Maximise Σ hi subject to

* non-overlap: arm·h(j) + arm·h(j+1) ≤ Lj on every segment (the first and last segments carry one
  bridge only);
* chord error: hi·sinθi ≤ di;
* hi ≥ ĥi = min(di/sinθi, L(i−1)/(2·arm), Li/(2·arm)), the bridge's share under the classic
  half-segment split.

The last bound is ours. Σh alone starves a corner between two others on short segments (h1 + h2 ≤ c,
h2 + h3 ≤ c is maximised by h2 = 0: a sharp kink, infinite curvature); with the floor every bridge is
at least as flat as the half-split gives, the floor is always feasible, and Σh spreads the rest.

The peak curvature of a bridge is ∝ 1/h, so a larger Σh is a flatter path. Σh alone is degenerate
when two bridges share a segment that limits both (any split has the same sum), and HiGHS would pick
an arbitrary vertex, possibly handing the shared length to a nearly straight corner that does not
need it. The objective therefore adds a tie-break of 1e-3·sinθi/max sinθ: among the seed's optima,
sharper corners get the room. Solved with `scipy.optimize.linprog` (HiGHS) on a sparse matrix.

**The point-error iteration** (the update formulas are lost; this is our reading). Q lies on the
curve, so |PiQi| bounds the distance from the original point to the curve. While some |PiQi| > Ei:

* the working point moves by Wi ← Wi + (Pi − Qi)·(1 − Ei'/|PiQi|), which puts Q on the sphere of
  radius Ei' = 0.99·Ei about Pi when h and the directions hold (once moved, a point follows that
  sphere both ways, so the iteration settles instead of ratcheting outward);
* the working chord threshold becomes di = Di + Ei: Q may sit Ei inside the original corner and the
  working point up to Di outside it, so the curve stays within Di of the original polyline (its
  straight parts lie on working segments whose ends moved at most Di).

A shift that would exceed Di is pulled back to 0.99·Di and lowers that di by the overshoot. Where
Ei ≥ Di the unshifted bridge already meets Ei, so di = Di from the start; elsewhere the first solve
already uses Di + Ei' (the seed's initial threshold is lost; this saves one LP). The loop stops
when every point is within E (and every shift within D); if it has not after `max_iterations`,
the plan falls back to the unshifted points with di = min(Di, Ei)·(1 − margin), which honours
both thresholds by construction.
Straight input (θ = 0 everywhere) has no bridges and no shifts, so it stays exactly straight.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.optimize import linprog

from hil.moveb.bridge import STRAIGHT, BridgeShape, Curve, control_points

MARGIN = 1e-2
TIE_BREAK = 1e-3


@dataclass(frozen=True)
class Solution:
    """The planned curve and how it was found."""

    curve: Curve
    iterations: int
    point_error: np.ndarray  # (n+1,) |P Q| per point, mm (0 at the ends and straight points)
    shift: np.ndarray  # (n+1,) |W − P| per point, mm
    fallback: bool


def _directions(W: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    seg = np.diff(W, axis=0)
    L = np.linalg.norm(seg, axis=1)
    return seg / L[:, None], L


def half_angles(W: np.ndarray) -> np.ndarray:
    """(n+1,) half of the turn at each point (0 at the ends)."""
    T, _ = _directions(W)
    # atan2 of |cross| and dot: accurate near 0 (arccos of a rounded cosine would see a 1e-8 turn
    # in collinear input)
    turn = np.arctan2(np.linalg.norm(np.cross(T[:-1], T[1:]), axis=1), np.einsum("ij,ij->i", T[:-1], T[1:]))
    return np.r_[0.0, 0.5 * turn, 0.0]


def solve_lp(W: np.ndarray, d: np.ndarray, shape: BridgeShape, previous: np.ndarray | None = None,
             changed: np.ndarray | None = None) -> np.ndarray:
    """(n+1,) bridge parameters h maximising Σh under non-overlap and |WQ| ≤ d (0 where straight).

    With `previous` (the last solution) and `changed` (a mask of points whose position or threshold
    changed since), only the chains of coupled bridges that contain a changed point (or a neighbour
    of one: its turn changed) are solved again; the others keep their previous optimum, which is
    still optimal because their constraints did not change.
    """
    _, L = _directions(W)
    theta = half_angles(W)
    corners = np.flatnonzero(theta > STRAIGHT)
    h = np.zeros(len(W))
    if not corners.size:
        return h
    sin = np.sin(theta[corners])
    upper = np.zeros(len(W))
    upper[corners] = d[corners] / sin
    # presolve: a segment whose two bridges fit at their chord bounds can never bind; a corner whose
    # two segments cannot bind takes its bound. Only the coupled rest goes to HiGHS (this keeps the
    # repeated solves of the point-error iteration cheap; HiGHS' own presolve runs after the wrapper).
    # the floor: no bridge smaller than its share under the classic half-segment split
    floor = np.minimum(upper, np.minimum(np.r_[np.inf, L], np.r_[L, np.inf]) / (2.0 * shape.arm))
    floor[[0, -1]] = 0.0
    coupled = shape.arm * (upper[:-1] + upper[1:]) > L
    free = np.zeros(len(W), bool)
    free[corners] = ~coupled[corners - 1] & ~coupled[corners]
    h[free] = upper[free]
    var = corners[~free[corners]]
    if previous is not None and changed is not None and var.size:
        touched = changed.copy()
        touched[1:] |= changed[:-1]
        touched[:-1] |= changed[1:]
        chain = np.r_[0, np.cumsum(~coupled)]  # points k and k+1 share a chain iff segment k is coupled
        redo = np.isin(chain[var], np.unique(chain[touched]))
        keep = var[~redo]
        h[keep] = np.clip(previous[keep], floor[keep], upper[keep])
        var = var[redo]
    if var.size:
        m = len(var)
        col = np.full(len(W), -1)
        col[var] = np.arange(m)
        segs = np.flatnonzero(coupled)
        left, right = col[segs], col[segs + 1]  # segment j joins points j and j+1
        rows = np.r_[np.flatnonzero(left >= 0), np.flatnonzero(right >= 0)]
        cols = np.r_[left[left >= 0], right[right >= 0]]
        A = sp.csc_array((np.full(len(rows), shape.arm), (rows, cols)), shape=(len(segs), m))
        w = np.sin(theta[var])
        cost = -(1.0 + TIE_BREAK * w / w.max())
        res = linprog(cost, A_ub=A, b_ub=L[segs], bounds=np.c_[floor[var], upper[var]], method="highs")
        if res.status != 0:  # cannot happen for this LP (h = 0 is feasible, bounds are finite)
            raise RuntimeError(f"bridge LP failed: {res.message}")
        h[var] = np.clip(res.x, 0.0, upper[var])
    # keep the non-overlap exact despite the solver's feasibility tolerance
    need = shape.arm * (h[:-1] + h[1:])
    scale = np.minimum(1.0, L / np.maximum(need, 1e-300))
    h[1:-1] *= np.minimum(scale[:-1], scale[1:])
    return h


def apexes(W: np.ndarray, h: np.ndarray, shape: BridgeShape) -> np.ndarray:
    """(n+1, 3) the bridge apex Q at every bridged point, the working point elsewhere."""
    T, _ = _directions(W)
    Q = W.copy()
    i = np.flatnonzero(h > 0)
    if i.size:
        Q[i] = control_points(W[i], T[i - 1], T[i], h[i], shape)[:, shape.degree]
    return Q


def plan_positions(P: np.ndarray, D: np.ndarray, E: np.ndarray, shape: BridgeShape,
                   max_iterations: int = 40) -> Solution:
    """Bridges through the points P (n+1, 3, mm) honouring D and E per point (see module docstring)."""
    P = np.asarray(P, float)
    D = np.broadcast_to(np.asarray(D, float), (len(P),)).copy()
    E = np.broadcast_to(np.asarray(E, float), (len(P),)).copy()
    target = (1.0 - MARGIN) * E
    limit = (1.0 - MARGIN) * D  # largest shift of a working point
    cap = (1.0 - MARGIN) * (D + target)  # working chord threshold where points may move
    # where E >= D the unshifted bridge already meets E (|PQ| <= D), so its threshold is just D
    d = np.where(E < D, cap, limit)
    W = P.copy()
    h: np.ndarray | None = None
    changed: np.ndarray | None = None
    for it in range(1, max_iterations + 1):
        h = solve_lp(W, d, shape, h, changed)
        Q = apexes(W, h, shape)
        err = np.linalg.norm(P - Q, axis=1)
        shift = np.linalg.norm(W - P, axis=1)
        if np.all(err <= E) and np.all(shift <= D):
            return Solution(Curve(W, h, shape), it, err, shift, False)
        W_before, d_before = W.copy(), d.copy()
        # move Q onto the sphere of radius E' about P (both ways once a point has moved)
        # (a dead band below E leaves settled points alone, so later solves stay small)
        active = (err > E) | ((shift > 0) & (err < (1.0 - 3.0 * MARGIN) * E))
        move = np.where(active, 1.0 - target / np.maximum(err, 1e-300), 0.0)
        W = W + (P - Q) * move[:, None]
        W[0], W[-1] = P[0], P[-1]
        # a shift beyond D is pulled back, and that point's chord threshold shrinks to match
        shift = np.linalg.norm(W - P, axis=1)
        over = shift > limit
        if over.any():
            W[over] = P[over] + (W[over] - P[over]) * (limit[over] / shift[over])[:, None]
            cap = np.where(over, cap - (shift - limit), cap)
        d = np.where(E < D, np.maximum(cap, 1e-9), limit)
        changed = np.any(W_before != W, axis=1) | (d != d_before)
    d = (1.0 - MARGIN) * np.minimum(D, E)
    h = solve_lp(P, d, shape)
    Q = apexes(P, h, shape)
    return Solution(Curve(P.copy(), h, shape), max_iterations, np.linalg.norm(P - Q, axis=1),
                    np.zeros(len(P)), True)
