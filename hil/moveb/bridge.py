"""The bridging B-splines of seed 001 and the piecewise curve they make with the straight segments.

At an interior point P with incoming unit direction T0 and outgoing T2, a bridge of degree p has the
2p+1 control points A1…Ap, Q, Bp…B1 and the knots {0, 0.5, 1} with multiplicities p+1, p, p+1, i.e.
two Bezier curves meeting at Q (the curve passes through Q). Ap = P − h·T0 and Bp = P + h·T2, so
T1 = (T0+T2)/|T0+T2|, θ (the angle of T0 and T1) is half the turn, and Q = P − h·T0 + h·cosθ·T1 =
P + h·(T2 − T0)/2 is the midpoint of ApBp; |PQ| = h·sinθ is the chord error.

* G2 (cubic): A2 = A3 − h·T0, A1 = A2 − β·h·T0. A1, A2, A3 are collinear with the segment, so the
  curvature is zero where the bridge leaves the line; mirror symmetry makes it continuous at Q.
* G3 (quartic): A3 = A4 − α·h·T0, A2 = A3 − h·T0 (the seed's formula for A2 is lost; this is the
  reading the seed's README proposes), A1 = A2 − β·h·T0. A1…A4 collinear give zero curvature *and*
  zero curvature derivative at A1. At Q the mirror symmetry makes dκ/ds antisymmetric, so G3 needs
  dκ/ds(Q) = 0. Writing the end derivatives of the Bezier half (Δ0 = A4−Q, Δ1 = A3−A4 = αΔ2) into
  dκ/dt ∝ (r'×r''')|r'|² − 3(r'×r'')(r'·r'') gives 2(1/α − 2) = 9(α − 1), i.e.
  9α² − 5α − 2 = 0 and α = (5 + √97)/18 ≈ 0.8249, independent of h and θ — consistent with the
  seed's "α ≥ 0.7" and the lost formula it summarised. `ALPHA_G3` is that root.
* β ∈ (0, 0.5] only lengthens the run-in from the line. It does not change the peak curvature
  (κ(Q) = (2/3)·sinθ/(h·cos²θ) for G2, (3/4)·α·sinθ/(h·cos²θ) for G3), so it is a fixed shape
  parameter (default 0.5, the gentlest run-in the seed allows) and the optimisation is linear in h.

Evaluation is batched over bridges with Bernstein polynomials (every bridge shares one knot vector,
so the B-spline is two Bezier halves); `Bridge.spline` returns the same bridge as a
`scipy.interpolate.BSpline`, which the tests use as the reference.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from math import comb

import numpy as np
from scipy.interpolate import BSpline

from hil.moveb.arclength import TABLE_SAMPLES, arclength_table, table_parameters

ALPHA_G3 = (5.0 + math.sqrt(97.0)) / 18.0
DEFAULT_BETA = 0.5
#: Turns below this (radians) are straight: no bridge, the curve runs through the point.
STRAIGHT = 1e-9


@dataclass(frozen=True)
class BridgeShape:
    """Degree and fixed shape parameters of the bridges of one curve."""

    continuity: str = "G2"  # "G2" (cubic) or "G3" (quartic)
    beta: float = DEFAULT_BETA
    alpha: float = ALPHA_G3

    def __post_init__(self) -> None:
        if self.continuity not in ("G2", "G3"):
            raise ValueError(f"continuity must be 'G2' or 'G3', not {self.continuity!r}")
        if not 0.0 < self.beta <= 0.5:
            raise ValueError(f"beta must be in (0, 0.5], got {self.beta}")
        if self.alpha < 0.7:
            raise ValueError(f"alpha must be at least 0.7, got {self.alpha}")

    @property
    def degree(self) -> int:
        return 3 if self.continuity == "G2" else 4

    @property
    def offsets(self) -> np.ndarray:
        """Distances |Aj P| / h for A1…Ap (the B side mirrors them)."""
        if self.continuity == "G2":
            return np.array([2.0 + self.beta, 2.0, 1.0])
        a = self.alpha
        return np.array([2.0 + a + self.beta, 2.0 + a, 1.0 + a, 1.0])

    @property
    def arm(self) -> float:
        """|A1 P| / h: how much of each neighbouring segment a bridge uses per unit of h."""
        return float(self.offsets[0])

    def knots(self) -> np.ndarray:
        p = self.degree
        return np.r_[np.zeros(p + 1), np.full(p, 0.5), np.ones(p + 1)]


def control_points(P: np.ndarray, T0: np.ndarray, T2: np.ndarray, h: np.ndarray,
                   shape: BridgeShape) -> np.ndarray:
    """(nb, 2p+1, 3) control points A1…Ap, Q, Bp…B1 of bridges at P (nb, 3) with parameters h (nb,)."""
    P, T0, T2 = (np.atleast_2d(np.asarray(v, float)) for v in (P, T0, T2))
    h = np.atleast_1d(np.asarray(h, float))
    off = shape.offsets  # A1..Ap
    A = P[:, None, :] - (off[None, :, None] * h[:, None, None]) * T0[:, None, :]
    B = P[:, None, :] + (off[::-1][None, :, None] * h[:, None, None]) * T2[:, None, :]  # Bp..B1
    Q = P + 0.5 * h[:, None] * (T2 - T0)
    return np.concatenate([A, Q[:, None, :], B], axis=1)


@dataclass(frozen=True)
class Bridge:
    """One bridge, for inspection and as a scipy B-spline."""

    control: np.ndarray  # (2p+1, 3)
    shape: BridgeShape

    def spline(self) -> BSpline:
        return BSpline(self.shape.knots(), self.control, self.shape.degree)


def _bernstein(n: int, t: np.ndarray) -> np.ndarray:
    """(len(t), n+1) Bernstein basis of degree n."""
    t = t[:, None]
    i = np.arange(n + 1)[None, :]
    coef = np.array([comb(n, k) for k in range(n + 1)], float)[None, :]
    return coef * t ** i * (1.0 - t) ** (n - i)


def bezier_derivatives(R: np.ndarray, t: np.ndarray, order: int = 3) -> list[np.ndarray]:
    """[C, C', …] (each (N, 3)) of Bezier curves with per-sample control points R (N, n+1, 3) at t."""
    n = R.shape[1] - 1
    out = []
    D = R
    factor = 1.0
    for k in range(order + 1):
        m = n - k
        if m < 0:
            out.append(np.zeros((len(t), 3)))
            continue
        out.append(factor * np.einsum("nj,njc->nc", _bernstein(m, t), D))
        factor *= m
        D = D[:, 1:] - D[:, :-1]
    return out


def bridge_derivatives(ctrl: np.ndarray, u: np.ndarray, degree: int,
                       order: int = 3) -> list[np.ndarray]:
    """[C, dC/du, …] of bridges with control points ctrl (N, 2p+1, 3) at parameters u (N,) in [0, 1]."""
    u = np.asarray(u, float)
    second = u >= 0.5
    t = np.where(second, 2.0 * u - 1.0, 2.0 * u)
    idx = np.where(second[:, None], np.arange(degree, 2 * degree + 1)[None, :],
                   np.arange(degree + 1)[None, :])
    R = np.take_along_axis(ctrl, idx[:, :, None], axis=1)
    ders = bezier_derivatives(R, t, order)
    return [d * 2.0 ** k for k, d in enumerate(ders)]


def curvature_terms(d1: np.ndarray, d2: np.ndarray, d3: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Curvature κ and its arc-length derivative dκ/ds from the first three parameter derivatives."""
    c = np.cross(d1, d2)
    cn = np.linalg.norm(c, axis=1)
    sp = np.linalg.norm(d1, axis=1)
    kappa = cn / sp ** 3
    with np.errstate(invalid="ignore", divide="ignore"):
        dcn = np.where(cn > 1e-300, np.einsum("ij,ij->i", c, np.cross(d1, d3)) / cn, 0.0)
    dk_dt = dcn / sp ** 3 - 3.0 * cn * np.einsum("ij,ij->i", d1, d2) / sp ** 5
    return kappa, dk_dt / sp


@dataclass
class Curve:
    """The planned position curve: straight segments on the working polyline joined by bridges.

    ``working`` are the (possibly shifted) points the bridges are built on, ``h`` the bridge
    parameter per point (0 at the ends and at straight points). Built once; sampling is vectorised.
    """

    working: np.ndarray  # (n+1, 3) mm
    h: np.ndarray  # (n+1,)
    shape: BridgeShape

    def __post_init__(self) -> None:
        W = self.working
        seg = np.diff(W, axis=0)
        T = seg / np.linalg.norm(seg, axis=1)[:, None]
        self.bridged = np.flatnonzero(self.h > 0)
        i = self.bridged
        self.control = control_points(W[i], T[i - 1], T[i], self.h[i], self.shape)
        # arc-length table of each bridge on a shared parameter grid
        self._u = table_parameters()
        self._table = arclength_table(self.control, self.shape.degree)
        # pieces in order: line 0, bridge at 1 (if any), line 1, ...; line k−1 runs from point k−1
        # (or the B1 of its bridge) to point k (or the A1 of its bridge)
        n = len(W) - 1
        line_at = np.arange(n) + np.cumsum(self.h > 0)[:-1]  # piece index of line k−1, k = 1…n
        self._kinds = np.zeros(n + len(i), int)
        self._refs = np.empty(n + len(i), int)
        self._refs[line_at] = np.arange(n)
        self._kinds[line_at[i - 1] + 1] = 1
        self._refs[line_at[i - 1] + 1] = np.arange(len(i))
        self._a = np.empty((n + len(i), 3))
        self._b = np.empty((n + len(i), 3))
        self._a[line_at] = W[:-1]
        self._b[line_at] = W[1:]
        if len(i):
            self._a[line_at[i - 1] + 1] = self._b[line_at[i - 1]] = self.control[:, 0]
            self._b[line_at[i - 1] + 1] = self._a[line_at[i]] = self.control[:, -1]
        lengths = np.where(self._kinds == 0, np.linalg.norm(self._b - self._a, axis=1), 0.0)
        lengths[self._kinds == 1] = self._table[self._refs[self._kinds == 1], -1]
        self._s0 = np.r_[0.0, np.cumsum(lengths)[:-1]]
        self.length = float(np.sum(lengths))
        self._piece_len = lengths
        bridge_start = np.empty(len(i))
        bridge_start[self._refs[self._kinds == 1]] = self._s0[self._kinds == 1]
        self._bridge_start = bridge_start
        self._S_glob = (bridge_start[:, None] + self._table).ravel()
        self._U_glob = (np.arange(len(i))[:, None] + self._u[None, :]).ravel()

    # ------------------------------------------------------------------ queries
    def bridge(self, point: int) -> Bridge:
        """The bridge at program point `point` (KeyError if that point has none)."""
        j = np.flatnonzero(self.bridged == point)
        if not j.size:
            raise KeyError(point)
        return Bridge(self.control[int(j[0])], self.shape)

    def apex(self) -> np.ndarray:
        """(n+1, 3): the curve's point for each program point (Q at bridges, the point elsewhere)."""
        out = self.working.copy()
        out[self.bridged] = self.control[:, self.shape.degree]
        return out

    def point_arclength(self) -> np.ndarray:
        """(n+1,) arc length of `apex` for each program point (keys of the orientation spline)."""
        out = np.empty(len(self.working))
        out[0], out[-1] = 0.0, self.length
        lines = np.flatnonzero(self._kinds == 0)  # line k-1 is the (k-1)-th line piece
        k = np.arange(1, len(self.working) - 1)
        p = lines[k - 1]
        out[k] = self._s0[p] + self._piece_len[p]  # the point itself where there is no bridge
        b = self.h[k] > 0
        j = p[b] + 1  # the bridge right after line k-1; its apex is half-way through its table
        out[k[b]] = self._s0[j] + self._table[self._refs[j], TABLE_SAMPLES]
        return out

    def evaluate(self, s: np.ndarray) -> dict[str, np.ndarray]:
        """Position, unit tangent, curvature κ and dκ/ds at arc lengths `s` (clipped to [0, L])."""
        s = np.clip(np.asarray(s, float), 0.0, self.length)
        piece = np.clip(np.searchsorted(self._s0, s, side="right") - 1, 0, len(self._s0) - 1)
        local = s - self._s0[piece]
        n = len(s)
        pos, tan = np.empty((n, 3)), np.empty((n, 3))
        kappa, dkappa = np.zeros(n), np.zeros(n)
        line = self._kinds[piece] == 0
        if np.any(line):
            pl = piece[line]
            a, b = self._a[pl], self._b[pl]
            L = np.linalg.norm(b - a, axis=1)
            d = np.divide(b - a, L[:, None], out=np.zeros_like(a), where=L[:, None] > 0)
            pos[line] = a + d * local[line, None]
            tan[line] = d
        br = ~line
        if np.any(br):
            refs = self._refs[piece[br]]
            # invert the arc-length tables of all bridges at once: along the curve, (s, b + u) is
            # non-decreasing over the concatenated tables
            U = np.interp(s[br], self._S_glob, self._U_glob)
            u = np.clip(U - refs, 0.0, 1.0)
            C, d1, d2, d3 = bridge_derivatives(self.control[refs], u, self.shape.degree, order=3)
            pos[br] = C
            tan[br] = d1 / np.linalg.norm(d1, axis=1)[:, None]
            kappa[br], dkappa[br] = curvature_terms(d1, d2, d3)
        return {"s": s, "position": pos, "tangent": tan, "curvature": kappa, "dcurvature": dkappa}

    def bridge_arclengths(self, per_bridge: int = 64) -> np.ndarray:
        """Arc lengths of `per_bridge` parameter-uniform samples through every bridge."""
        if not len(self.bridged):
            return np.zeros(0)
        f = np.interp(np.linspace(0.0, 1.0, per_bridge + 1), self._u, np.arange(len(self._u)))
        lo = np.minimum(np.floor(f).astype(int), len(self._u) - 2)
        w = f - lo
        table = self._table[:, lo] * (1.0 - w) + self._table[:, lo + 1] * w
        return (self._bridge_start[:, None] + table).ravel()

    def arclength_grid(self, ds: float) -> np.ndarray:
        """Arc lengths every `ds` (the last one at the end) and at every piece boundary."""
        n = max(math.ceil(self.length / ds), 1)
        return np.unique(np.r_[np.linspace(0.0, self.length, n + 1), self._s0])
