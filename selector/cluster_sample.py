"""Validation poses as a two-stage, self-weighting cluster sample of the candidate configurations.

Why: a simple random sample of the workspace spreads the validation poses everywhere, so the arm spends
most of a validation run travelling between them. A two-stage cluster sample keeps validation an
unbiased sample of the workspace while the arm visits only a few places:

1. *Partition* the N candidates into K clusters of nearby configurations (k-means on joint angles scaled
   by 1/joint speed, so that distance is roughly travel time).
2. *First stage*: draw k clusters with probability proportional to size (PPS).
3. *Second stage*: inside each drawn cluster draw m = count / k poses uniformly, without replacement; a
   cluster drawn r times gives r·m distinct poses (split into r draws of m).

If E[r_c] = k·N_c / N (PPS), a candidate of cluster c is included with probability
E[r_c]·m / N_c = k·m / N = count / N, the same for every candidate (a *self-weighting* design), so the
plain mean of the validation values (e.g. squared errors) is an unbiased estimate of the workspace mean.
The price is variance: poses of one draw are close together, so their errors are correlated;
`cluster_standard_error` estimates the standard error of that mean honestly (the between-draw variance of
the draw means / k, the "ultimate cluster" estimator; Lohr, *Sampling: Design and Analysis*, §6.4-6.5;
Cochran, *Sampling Techniques*, §11.9) and `design_effect` says how many times a simple random sample's
variance that is.

Two first stages, both with E[r_c] = k·N_c / N exactly:

* ``"with-replacement"``: k independent PPS draws (Hansen-Hurwitz). A cluster may come up r times and
  must then hold r·m distinct candidates, for any r ≤ k: every cluster needs at least count = k·m
  candidates, so small clusters are merged (or excluded) up to `count`. That forces big, loose clusters.
* ``"systematic"`` (default): PPS systematic sampling over the clusters in random order (Madow): one
  uniform start, k equally spaced points on the cumulated sizes; a cluster is drawn once per point that
  falls in it. A cluster smaller than the spacing N/k is drawn at most once, so clusters need only m
  candidates and can be small and compact: about half the travel time of the with-replacement form on
  a UR5e's candidates (measured). There is no unbiased variance estimator for it; the
  with-replacement one above, applied to it, errs on the safe side (Särndal, Swensson & Wretman,
  *Model Assisted Survey Sampling*, §3.6: the random-order systematic πps design is close to one with
  replacement, which over-states the variance by a factor of about 1 / (1 − k/K)).

Small clusters: a cluster below the first stage's need (``count`` or ``m``) is merged into the cluster
with the nearest centroid by default (``small="merge"``): the partition changes, the inclusion
probabilities do not (the argument above holds for any partition), so nothing is lost. With
``small="exclude"`` such clusters are dropped from the draw instead: the design is then self-weighting
over the *remaining* candidates only (the excluded ones have inclusion probability 0), a coverage loss
reported as `ClusterSample.excluded_fraction`.

Pure numpy/scipy: nothing here imports `hil`.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy.cluster.vq import kmeans2

from selector.errors import SelectorError

#: Candidates per cluster of the default partition, in poses per draw (m). 5m leaves room for k-means'
#: uneven cell sizes above the m a systematic draw needs, while keeping clusters compact: on 20,000 UR5e
#: candidates (example station, 20 poses in 5 clusters) the ordered tour took 53 s with ~100 candidates
#: per cluster, 46 s with ~20 (5m), 44 s with ~8 (k-means then takes 5 s), against 86 s at random.
CANDIDATES_PER_CLUSTER_PER_POSE = 5

#: Clusters per drawn cluster at least, whatever N: with K ≥ 4k the first stage still has room to spread
#: the k draws over the workspace.
MIN_CLUSTERS_PER_DRAW = 4

FIRST_STAGES = ("systematic", "with-replacement")


@dataclass(frozen=True)
class ClusterSample:
    """A two-stage cluster sample of candidate rows.

    `indices` are rows of the candidate array (distinct), `cluster` the partition label of each chosen
    row and `draw` its first-stage draw (0..k-1): a cluster drawn twice is two draws. Standard errors
    need `draw`, not `cluster` (`cluster_standard_error`).
    """

    indices: np.ndarray  # (count,) rows of q
    cluster: np.ndarray  # (count,) partition label per chosen row
    draw: np.ndarray  # (count,) first-stage draw id per chosen row, 0..k-1
    k: int  # clusters drawn (with replacement)
    m: int  # poses per draw
    partition: int  # clusters the candidates were partitioned into (after merging / excluding)
    excluded_fraction: float  # share of candidates in clusters left out of the draw (0 when merging)
    first_stage: str = "systematic"  # how the clusters were drawn (`FIRST_STAGES`)


def default_partition(n: int, clusters: int, per_cluster: int) -> int:
    """K for `n` candidates, `clusters` draws of `per_cluster` poses: about
    `CANDIDATES_PER_CLUSTER_PER_POSE` × `per_cluster` candidates per cluster, at least
    `MIN_CLUSTERS_PER_DRAW` clusters per draw, at most `n`."""
    size = CANDIDATES_PER_CLUSTER_PER_POSE * max(1, per_cluster)
    return int(min(n, max(MIN_CLUSTERS_PER_DRAW * clusters, round(n / size))))


def cluster_sample(q: np.ndarray, count: int, clusters: int, *, scale: np.ndarray, seed: int,
                   partition: int | None = None, small: str = "merge",
                   first_stage: str = "systematic") -> ClusterSample:
    """Draw `count` rows of `q` (N, d) as `clusters` PPS draws of m = count / clusters nearby rows.

    `scale` (d,) weights each joint before clustering (1 / joint speed: distance then reads as the time
    the slowest joint needs); `partition` is K (default `default_partition`); `small` says what happens to
    clusters too small for `first_stage` ("merge" into the nearest, or "exclude" from the draw).
    """
    q = np.asarray(q, dtype=float)
    scale = np.asarray(scale, dtype=float)
    if q.ndim != 2 or len(q) == 0:
        raise SelectorError(f"cluster sample: need an (N, d) array of candidates, got shape {q.shape}")
    if scale.shape != (q.shape[1],) or not np.all(np.isfinite(scale)) or np.any(scale <= 0):
        raise SelectorError(f"cluster sample: scale must be {q.shape[1]} positive weights")
    if clusters < 1 or count < 1:
        raise SelectorError(f"cluster sample: count ({count}) and clusters ({clusters}) must be positive")
    if count % clusters:
        raise SelectorError(f"cluster sample: {count} poses cannot be split evenly over {clusters} clusters "
                            "(count must be divisible by clusters)")
    if small not in ("merge", "exclude"):
        raise SelectorError(f"cluster sample: small must be 'merge' or 'exclude', got {small!r}")
    if first_stage not in FIRST_STAGES:
        raise SelectorError(f"cluster sample: first_stage must be one of {FIRST_STAGES}, got {first_stage!r}")
    n = len(q)
    if n < count:
        raise SelectorError(f"cluster sample: only {n} candidates for {count} poses")
    m = count // clusters
    K = default_partition(n, clusters, m) if partition is None else int(partition)
    if not 1 <= K <= n:
        raise SelectorError(f"cluster sample: partition must be between 1 and {n} clusters, got {K}")

    rng = np.random.default_rng(seed)
    x = q * scale
    least = m if first_stage == "systematic" else count
    labels = _partition(x, K, rng)
    labels, excluded = (_merge_small(x, labels, least) if small == "merge"
                        else _exclude_small(labels, least))
    ids, sizes = np.unique(labels[labels >= 0], return_counts=True)
    if len(ids) == 0:
        raise SelectorError(f"cluster sample: no cluster of {len(q)} candidates holds {least} poses "
                            "(fewer clusters, or small='merge')")
    drawn = (_systematic(sizes, clusters, rng) if first_stage == "systematic"
             else rng.choice(len(ids), size=clusters, replace=True, p=sizes / sizes.sum()))

    # second stage: r·m distinct rows of a cluster drawn r times, split into its r draws
    indices = np.empty(count, dtype=int)
    draw = np.empty(count, dtype=int)
    pos = 0
    for c in np.unique(drawn):
        draws = np.flatnonzero(drawn == c)
        members = np.flatnonzero(labels == ids[c])
        need = len(draws) * m
        if need > len(members):  # systematic: only with fewer than 2·count candidates in all
            raise SelectorError(f"cluster sample: a cluster of {len(members)} candidates drawn "
                                f"{len(draws)} times cannot give {need} distinct poses (too few candidates "
                                f"for {clusters} clusters of {m})")
        picked = rng.choice(members, size=need, replace=False)
        indices[pos:pos + need] = picked
        draw[pos:pos + need] = np.repeat(draws, m)
        pos += need
    order = np.argsort(draw, kind="stable")
    indices, draw = indices[order], draw[order]
    return ClusterSample(indices=indices, cluster=labels[indices].copy(), draw=draw, k=int(clusters),
                         m=int(m), partition=len(ids), excluded_fraction=float(excluded),
                         first_stage=first_stage)


def _systematic(sizes: np.ndarray, k: int, rng: np.random.Generator) -> np.ndarray:
    """k PPS systematic draws (cluster positions in `sizes`) over the clusters in random order: cluster c
    is drawn once per point u + j·N/k (u uniform in [0, N/k)) inside its stretch of the cumulated sizes,
    so E[draws of c] = k·N_c/N exactly and a cluster smaller than N/k is drawn at most once. A cluster
    of N_c ≥ N/k is drawn r ≤ N_c·k/N + 1 times, and r·m ≤ N_c holds whenever N ≥ 2·count."""
    order = rng.permutation(len(sizes))
    ends = np.cumsum(sizes[order])
    step = ends[-1] / k
    points = rng.uniform(0.0, step) + step * np.arange(k)
    return order[np.minimum(np.searchsorted(ends, points, side="right"), len(sizes) - 1)]


def _partition(x: np.ndarray, K: int, rng: np.random.Generator) -> np.ndarray:
    """k-means labels of the rows of `x` into at most K clusters, from a k-means++ start (labels of
    clusters emptied on the way simply do not occur)."""
    if K == 1:
        return np.zeros(len(x), dtype=int)
    with warnings.catch_warnings():  # an emptied cluster is harmless here: its label just never occurs
        warnings.filterwarnings("ignore", "One of the clusters is empty", UserWarning)
        _, labels = kmeans2(x, _plus_plus(x, K, rng), minit="matrix", missing="warn")
    return np.asarray(labels, dtype=int)


def _plus_plus(x: np.ndarray, K: int, rng: np.random.Generator) -> np.ndarray:
    """K k-means++ seeds (Arthur & Vassilvitskii 2007: each next seed drawn with probability ∝ squared
    distance to the nearest seed so far). The same rule as scipy's ``minit="++"``, but keeping each row's
    nearest-seed distance from one seed to the next: O(N·K) instead of scipy's recomputation against all
    seeds at every step, which took 6 s for K = 200 and 90 s for K = 1000 on 20,000 candidates."""
    seeds = np.empty((K, x.shape[1]))
    seeds[0] = x[rng.integers(len(x))]
    d2 = np.sum((x - seeds[0]) ** 2, axis=1)
    for j in range(1, K):
        cum = np.cumsum(d2)
        i = (min(int(np.searchsorted(cum, rng.random() * cum[-1], side="right")), len(x) - 1)
             if cum[-1] > 0 else int(rng.integers(len(x))))
        seeds[j] = x[i]
        np.minimum(d2, np.sum((x - seeds[j]) ** 2, axis=1), out=d2)
    return seeds


def _merge_small(x: np.ndarray, labels: np.ndarray, least: int) -> tuple[np.ndarray, float]:
    """Merge, smallest first, every cluster with fewer than `least` rows into the cluster whose centroid
    is nearest its own, until none is left (one cluster of everything at worst). Excludes nothing."""
    ids, labels = np.unique(labels, return_inverse=True)
    sizes = np.bincount(labels).astype(float)
    sums = np.zeros((len(ids), x.shape[1]))
    np.add.at(sums, labels, x)
    target = np.arange(len(ids))  # where each original cluster's rows end up
    alive = sizes > 0
    while alive.sum() > 1:
        live = np.flatnonzero(alive)
        small = live[np.argmin(sizes[live])]
        if sizes[small] >= least:
            break
        centroids = sums[live] / sizes[live, None]
        d = np.linalg.norm(centroids - sums[small] / sizes[small], axis=1)
        d[live == small] = np.inf
        into = live[int(np.argmin(d))]
        sizes[into] += sizes[small]
        sums[into] += sums[small]
        sizes[small], alive[small] = 0.0, False
        target[target == small] = into
    return target[labels], 0.0


def _exclude_small(labels: np.ndarray, least: int) -> tuple[np.ndarray, float]:
    """Label -1 (never drawn) for the rows of clusters with fewer than `least` rows."""
    ids, sizes = np.unique(labels, return_counts=True)
    out = labels.copy()
    out[np.isin(labels, ids[sizes < least])] = -1
    return out, float(np.mean(out < 0))


def _draw_means(values: np.ndarray, draws: np.ndarray) -> np.ndarray:
    values = np.asarray(values, dtype=float)
    draws = np.asarray(draws)
    if values.shape != draws.shape or values.ndim != 1:
        raise SelectorError("cluster standard error: values and draws must be 1-D and of equal length")
    ids, sizes = np.unique(draws, return_counts=True)
    if len(ids) < 2:
        raise SelectorError("cluster standard error: needs at least 2 draws")
    if np.any(sizes != sizes[0]):
        raise SelectorError("cluster standard error: every draw must hold the same number of values "
                            "(the self-weighting design)")
    return np.array([values[draws == i].mean() for i in ids])


def cluster_standard_error(values: np.ndarray, draws: np.ndarray) -> float:
    """Standard error of ``values.mean()`` under the two-stage design: √(s²_b / k), s²_b the sample
    variance of the k draw means.

    `draws` is the first-stage draw of each value (`ClusterSample.draw`), not its cluster: a cluster
    drawn twice contributes two draw means, as the with-replacement estimator requires. This single
    term estimates both stages' variance (the second stage's is inside the spread of the draw means).
    Exact in expectation for the with-replacement first stage with independent subsamples; here a
    cluster drawn twice gives its two subsamples jointly without replacement (slightly negatively
    correlated), and the systematic first stage draws without replacement: both make the estimate a
    little conservative, never optimistic (module docstring).
    """
    means = _draw_means(values, draws)
    return float(np.sqrt(np.var(means, ddof=1) / len(means)))


def design_effect(values: np.ndarray, draws: np.ndarray) -> float:
    """Variance of the mean under the cluster design over that of a simple random sample of the same size
    (s² / n, no finite-population correction): how many times fewer poses a simple random sample would
    need for the same precision. NaN when the values do not vary."""
    values = np.asarray(values, dtype=float)
    srs = float(np.var(values, ddof=1) / len(values)) if len(values) > 1 else 0.0
    se = cluster_standard_error(values, draws)
    return se * se / srs if srs > 0 else float("nan")
