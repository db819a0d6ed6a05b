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
sharper corners get the room (max sinθ is taken once per plan, over the program's points, so an
unchanged part of the path keeps an unchanged objective across the iteration).

The LP is solved by `hil.moveb.chains`: its constraint graph is a path, an exact bound-tightening
presolve splits it into independent chains, chains of up to three bridges have a closed-form
optimum, and longer ones (rare) go to HiGHS. The iteration below solves it 6–7 times per plan, so
the per-call overhead of scipy's HiGHS wrappers (0.6–1.5 ms) used to be most of the planning time.

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

from hil.moveb.bridge import STRAIGHT, BridgeShape, Curve
from hil.moveb.chains import ChainCache, solve_chain_lp

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
    return _half_angles(_directions(W)[0])


def _half_angles(T: np.ndarray) -> np.ndarray:
    # atan2 of |cross| and dot: accurate near 0 (arccos of a rounded cosine would see a 1e-8 turn
    # in collinear input)
    turn = np.arctan2(np.linalg.norm(np.cross(T[:-1], T[1:]), axis=1), np.einsum("ij,ij->i", T[:-1], T[1:]))
    out = np.zeros(len(T) + 1)
    out[1:-1] = 0.5 * turn
    return out


def solve_lp(W: np.ndarray, d: np.ndarray, shape: BridgeShape, cache: ChainCache | None = None,
             sin_scale: float | None = None) -> np.ndarray:
    """(n+1,) bridge parameters h maximising Σh under non-overlap and |WQ| ≤ d (0 where straight).

    The LP is solved chain by chain (`hil.moveb.chains`: exact presolve, closed forms for up to
    three coupled bridges, HiGHS for longer chains). `cache` carries the HiGHS answers across the
    point-error iteration; `sin_scale` is the tie-break's normaliser (default: the largest sinθ of
    W), fixed by the caller so that an unchanged chain keeps an unchanged objective.
    """
    return _solve_lp(*_directions(W), d, shape, cache, sin_scale)


def _solve_lp(T: np.ndarray, L: np.ndarray, d: np.ndarray, shape: BridgeShape, cache: ChainCache | None,
              sin_scale: float | None) -> np.ndarray:
    theta = _half_angles(T)
    corner = theta > STRAIGHT
    if not corner.any():
        return np.zeros(len(d))
    sin = np.sin(theta)
    upper = np.zeros(len(d))
    upper[corner] = d[corner] / sin[corner]
    # the floor: no bridge smaller than its share under the classic half-segment split
    shorter = np.full(len(d), np.inf)  # the shorter neighbouring segment
    shorter[:-1] = L
    np.minimum(shorter[1:], L, out=shorter[1:])
    floor = np.minimum(upper, shorter / (2.0 * shape.arm))
    scale = sin_scale if sin_scale is not None else float(sin[corner].max())
    cost = 1.0 + TIE_BREAK * sin / scale
    h = solve_chain_lp(cost, floor, upper, L / shape.arm, cache)
    h[~corner] = 0.0
    # keep the non-overlap exact despite rounding (and the solver's feasibility tolerance)
    need = shape.arm * (h[:-1] + h[1:])
    scale_back = np.minimum(1.0, L / np.maximum(need, 1e-300))
    h[1:-1] *= np.minimum(scale_back[:-1], scale_back[1:])
    return h


def apexes(W: np.ndarray, h: np.ndarray) -> np.ndarray:
    """(n+1, 3) the bridge apex Q = W + h·(T2 − T0)/2 at every bridged point, W elsewhere."""
    return _apexes(W, _directions(W)[0], h)


def _apexes(W: np.ndarray, T: np.ndarray, h: np.ndarray) -> np.ndarray:
    Q = W.copy()
    i = np.flatnonzero(h > 0)
    if i.size:
        Q[i] = W[i] + 0.5 * h[i, None] * (T[i] - T[i - 1])  # the middle control point (bridge.py)
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
    cache = ChainCache()
    theta = half_angles(P)
    sin_scale = float(np.sin(theta).max()) or 1.0
    for it in range(1, max_iterations + 1):
        T, L = _directions(W)
        h = _solve_lp(T, L, d, shape, cache, sin_scale)
        Q = _apexes(W, T, h)
        err = np.linalg.norm(P - Q, axis=1)
        shift = np.linalg.norm(W - P, axis=1)
        if np.all(err <= E) and np.all(shift <= D):
            return Solution(Curve(W, h, shape), it, err, shift, False)
        # move Q onto the sphere of radius E' about P (both ways once a point has moved)
        # (a dead band below E leaves settled points alone, so their chains keep their optimum)
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
    d = (1.0 - MARGIN) * np.minimum(D, E)
    h = solve_lp(P, d, shape, sin_scale=sin_scale)
    Q = apexes(P, h)
    return Solution(Curve(P.copy(), h, shape), max_iterations, np.linalg.norm(P - Q, axis=1),
                    np.zeros(len(P)), True)
