"""Two classic ways to smooth a polyline, for the benchmark against MOVEB.

* `arc_blend` — circular-arc corner blending (the tolerance blend of most robot controllers, G1):
  at each corner an arc tangent to both segments, as large as the tolerance allows, with its tangent
  length at most half of each neighbouring segment (the classic rule, so blends never overlap).
  With half-turn θ and radius r, the arc misses the corner by r·(1 − cosθ)/cosθ; that must stay within
  min(D, E), because the corner point is both the chord-height and the point-error reference.
  Curvature jumps from 0 to 1/r where an arc starts.
* `cubic_spline` — an interpolating cubic B-spline through all points (chord-length parameters,
  not-a-knot ends, `scipy.interpolate.make_interp_spline`): C2 and through every point, but its
  deviation from the straight segments is not controlled.

Both return a `Profile`: dense arc lengths, positions and curvature, so the same timing and metrics
apply to all three methods.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_simpson
from scipy.interpolate import make_interp_spline


@dataclass(frozen=True)
class Profile:
    """A sampled smoothed path: s (mm), positions (mm), curvature (1/mm), and what it cost."""

    s: np.ndarray
    position: np.ndarray
    curvature: np.ndarray
    seconds: float  # computing the curve (not sampling it)
    junctions: np.ndarray  # arc lengths where curvature may jump (piece boundaries)


def arc_blend(P: np.ndarray, tolerance: float, step: float = 0.05) -> Profile:
    """Circular-arc corner blending of the polyline P (mm) with corner tolerance `tolerance` (mm)."""
    t0 = time.perf_counter()
    seg = np.diff(P, axis=0)
    L = np.linalg.norm(seg, axis=1)
    T = seg / L[:, None]
    cross = np.linalg.norm(np.cross(T[:-1], T[1:]), axis=1)
    phi = np.arctan2(cross, np.einsum("ij,ij->i", T[:-1], T[1:]))  # turn at interior points
    theta = phi / 2
    with np.errstate(divide="ignore", invalid="ignore"):
        r_tol = np.where(phi > 1e-9, tolerance * np.cos(theta) / (1 - np.cos(theta)), np.inf)
        t = np.minimum(np.minimum(L[:-1], L[1:]) / 2, r_tol * np.tan(theta))
        r = np.where(phi > 1e-9, t / np.tan(theta), np.inf)
    t = np.where(phi > 1e-9, t, 0.0)
    arc_len = np.where(phi > 1e-9, r * phi, 0.0)
    line_len = L - np.r_[0.0, t] - np.r_[t, 0.0]
    seconds = time.perf_counter() - t0
    # pieces: line0, arc1, line1, arc2, ...
    lengths = np.empty(2 * len(L) - 1)
    lengths[0::2], lengths[1::2] = line_len, arc_len
    kappa_piece = np.zeros_like(lengths)
    kappa_piece[1::2] = np.where(phi > 1e-9, 1.0 / r, 0.0)
    edges = np.r_[0.0, np.cumsum(lengths)]
    arcs = (edges[1:-1:2, None] + lengths[1::2, None] * np.linspace(0.0, 1.0, 65)[None, :]).ravel()
    s = np.unique(np.r_[np.arange(0.0, edges[-1], step), edges, arcs])  # 64 samples per arc too
    piece = np.clip(np.searchsorted(edges, s, side="right") - 1, 0, len(lengths) - 1)
    # positions (for deviation metrics): lines exactly, arcs by rotation about their centres
    pos = np.empty((len(s), 3))
    local = s - edges[piece]
    for k in range(len(lengths)):
        m = piece == k
        if not m.any():
            continue
        j = k // 2
        if k % 2 == 0:
            start = P[j] + T[j] * (t[j - 1] if j > 0 else 0.0)
            pos[m] = start + T[j] * local[m, None]
        else:
            i = j  # arc at interior point i+1, between segments i and i+1
            a, b = T[i], T[i + 1]
            n = b - (a @ b) * a
            nn = np.linalg.norm(n)
            if nn < 1e-15 or not np.isfinite(r[i]):
                pos[m] = P[i + 1]
                continue
            n /= nn
            start = P[i + 1] - a * t[i]
            ang = local[m] / r[i]
            pos[m] = start + r[i] * (np.sin(ang)[:, None] * a + (1 - np.cos(ang))[:, None] * n)
    return Profile(s, pos, kappa_piece[piece], seconds, edges[1:-1])


def cubic_spline(P: np.ndarray, per_segment: int = 64) -> Profile:
    """Interpolating cubic spline through every point of P (chord-length parameters)."""
    t0 = time.perf_counter()
    u = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(P, axis=0), axis=1))]
    spline = make_interp_spline(u, P, k=3)
    seconds = time.perf_counter() - t0
    frac = np.linspace(0.0, 1.0, per_segment + 1)[:-1]
    uu = np.r_[(u[:-1, None] + np.diff(u)[:, None] * frac[None, :]).ravel(), u[-1]]
    d1, d2 = spline(uu, 1), spline(uu, 2)
    speed = np.linalg.norm(d1, axis=1)
    kappa = np.linalg.norm(np.cross(d1, d2), axis=1) / speed ** 3
    s = cumulative_simpson(speed, x=uu, initial=0.0)
    return Profile(s, spline(uu), kappa, seconds, s[::per_segment][1:-1])
