"""Observability indices of a stacked identification Jacobian, and the column scaling they need.

With J the (3m × n) Jacobian of m poses and σ1 ≥ … ≥ σn its singular values (Borm & Menq 1991;
Nahvi & Hollerbach 1996):

* O1 = (σ1·σ2·…·σn)^(1/n) / √m — the patent's index (formula (2) was lost in extraction; this is the
  reading the seeds README gives). It is det(JᵀJ)^(1/2n)/√m, so it ranks designs identically under any
  column scaling (scaling multiplies it by a constant) and it is the D-criterion in disguise;
* O2 = σn / σ1 — the inverse condition number;
* O3 = σn — the minimum singular value (E-optimality);
* O4 = σn² / σ1 — the noise amplification index;
* O5 = 1 / Σ 1/σi — a harmonic mean flavour (related to A-optimality).

O2–O5 depend on the units of the parameters (metres for translations, radians for rotations), so the
columns are scaled explicitly before they are computed (`scale_columns`):

* ``"expected"`` (default): column j is multiplied by the expected magnitude of parameter j's error
  (e.g. 0.5 mm, 1 mrad; supplied by the model). J·diag(s) then maps "one typical error of every
  parameter" to metres at the SMR, which is what an engineer means by "this parameter is visible";
* ``"unit"``: every column gets unit RMS norm *per pose* over the candidate set. The scale is fixed by
  the candidate set, not by the design being scored, so different designs stay comparable;
* ``"none"``: the raw Jacobian (metres per metre, metres per radian).

The same scaled Jacobian is used for all indices, O1 included (where it only changes a constant).
"""

from __future__ import annotations

import math

import numpy as np

from selector.errors import SelectorError, UnknownIndexError
from selector.names import INDEX_NAMES, SCALINGS


def parse_index(name: str) -> str:
    """Canonical index name ("o1" → "O1"); UnknownIndexError for anything else."""
    key = str(name).strip().upper()
    if key not in INDEX_NAMES:
        raise UnknownIndexError(
            f"unknown observability index {name!r}: choose one of {', '.join(INDEX_NAMES)}")
    return key


def index_from_singular_values(s: np.ndarray, m: int, index: str = "O1") -> float:
    """The index `index` from singular values `s` (any order) of the Jacobian of `m` poses."""
    index = parse_index(index)
    s = np.sort(np.asarray(s, dtype=float))[::-1]
    if s.size == 0 or s[-1] <= 0.0:
        return 0.0
    if index == "O1":
        return float(np.exp(np.mean(np.log(s))) / math.sqrt(m))
    if index == "O2":
        return float(s[-1] / s[0])
    if index == "O3":
        return float(s[-1])
    if index == "O4":
        return float(s[-1] ** 2 / s[0])
    return float(1.0 / np.sum(1.0 / s))


def observability(J: np.ndarray, index: str = "O1") -> float:
    """Index of a Jacobian by a direct SVD: `J` is (m, 3, n) per pose, or (rows, n) with 3 rows a pose.

    This is the reference implementation the fast paths are tested against; the search never calls it
    inside its loops.
    """
    J = np.asarray(J, dtype=float)
    if J.ndim == 3:
        m = J.shape[0]
        J = J.reshape(-1, J.shape[2])
    elif J.ndim == 2:
        m = J.shape[0] // 3
    else:
        raise SelectorError(f"a Jacobian must be (m, 3, n) or (rows, n), got shape {J.shape}")
    if J.shape[0] < J.shape[1]:
        return 0.0
    return index_from_singular_values(np.linalg.svd(J, compute_uv=False), m, index)


def index_from_information(M: np.ndarray, m: int, index: str = "O1") -> np.ndarray:
    """Index of designs given their information matrices M = JᵀJ, batched over leading axes.

    σi = √λi(M); eigenvalues of the n × n matrix are far cheaper than an SVD of the 3m × n stack and
    this is used only for the O2–O5 scoring of a handful of neighbours at a time.
    """
    index = parse_index(index)
    lam = np.linalg.eigvalsh(np.asarray(M, dtype=float))
    lam = np.clip(lam, 0.0, None)
    s = np.sqrt(lam)  # ascending
    smin, smax = s[..., 0], s[..., -1]
    with np.errstate(divide="ignore", invalid="ignore"):
        if index == "O1":
            out = np.exp(np.mean(np.log(s), axis=-1)) / math.sqrt(m)
        elif index == "O2":
            out = smin / smax
        elif index == "O3":
            out = smin
        elif index == "O4":
            out = smin**2 / smax
        else:
            out = 1.0 / np.sum(1.0 / s, axis=-1)
    return np.where(smin > 0, out, 0.0)


def o1_from_logdet(logdet: float | np.ndarray, n: int, m: int) -> np.ndarray | float:
    """O1 from log det(JᵀJ) of `n` parameters and `m` poses: exp(logdet / 2n) / √m."""
    return np.exp(np.asarray(logdet) / (2.0 * n)) / math.sqrt(m)


def column_scale(G: np.ndarray, scaling: str, expected: np.ndarray | None = None) -> np.ndarray:
    """Per-column factors (n,) for candidate Jacobians `G` (N, 3, n) under `scaling` (see module doc)."""
    n = G.shape[-1]
    if scaling == "none":
        return np.ones(n)
    if scaling == "expected":
        if expected is None:
            raise SelectorError("scaling 'expected' needs the expected parameter error magnitudes")
        s = np.asarray(expected, dtype=float).reshape(-1)
        if s.shape != (n,) or np.any(s <= 0) or not np.all(np.isfinite(s)):
            raise SelectorError(f"expected parameter magnitudes must be {n} positive numbers")
        return s
    if scaling == "unit":
        rms = np.sqrt(np.mean(np.sum(G**2, axis=1), axis=0))
        return 1.0 / np.where(rms > 0, rms, 1.0)
    raise SelectorError(f"unknown column scaling {scaling!r}: choose one of {', '.join(SCALINGS)}")


def scale_columns(G: np.ndarray, scaling: str = "expected", expected: np.ndarray | None = None
                  ) -> np.ndarray:
    """`G` (N, 3, n) with its columns multiplied by `column_scale`."""
    return np.asarray(G, dtype=float) * column_scale(G, scaling, expected)
