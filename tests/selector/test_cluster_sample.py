"""The clustered validation sample: self-weighting, compact draws, honest standard errors.

Statistical checks run over many seeds with deterministic seeds (so they never flake) and tolerances
derived from the sampling distribution of what they compare, stated at each assertion.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import binom

from selector.cluster_sample import (
    FIRST_STAGES,
    _merge_small,
    _partition,
    cluster_sample,
    cluster_standard_error,
    default_partition,
    design_effect,
)
from selector.errors import SelectorError

SCALE = np.full(6, 2.0)  # 1 / 0.5 rad/s


def _blobs(n_per: tuple[int, ...], seed: int = 0) -> np.ndarray:
    """Candidates in blobs of very different sizes plus a uniform background (joint radians): the
    clusters k-means finds then differ in size, which is what PPS must correct for."""
    rng = np.random.default_rng(seed)
    centres = rng.uniform(-2.5, 2.5, size=(len(n_per), 6))
    parts = [c + rng.normal(scale=0.3, size=(n, 6)) for c, n in zip(centres, n_per, strict=True)]
    return np.vstack([*parts, rng.uniform(-3, 3, size=(60, 6))])


def _field(q: np.ndarray) -> np.ndarray:
    """A smooth, positive 'squared validation error' over the joints."""
    return (1.0 + 0.6 * np.sin(q[:, 0]) + 0.4 * np.cos(q[:, 1] + q[:, 2]) + 0.2 * np.sin(q[:, 4])) ** 2


def _bonferroni_bounds(trials: int, p: float, n: int, alpha: float = 1e-3) -> tuple[float, float]:
    """Two-sided binomial bounds on each of `n` counts, family-wise false-alarm rate `alpha`."""
    a = alpha / (2 * n)
    return binom.ppf(a, trials, p), binom.isf(a, trials, p)


@pytest.mark.parametrize("first_stage", FIRST_STAGES)
def test_every_candidate_has_the_same_inclusion_probability(first_stage: str) -> None:
    q = _blobs((140, 60, 25, 15))
    n, count, k, seeds = len(q), 12, 3, 1200
    hits = np.zeros(n)
    for s in range(seeds):
        r = cluster_sample(q, count, k, scale=SCALE, seed=s, first_stage=first_stage)
        assert len(np.unique(r.indices)) == count
        hits[r.indices] += 1
    # each candidate's count over independent seeds is Binomial(seeds, count/N) exactly if self-weighting
    lo, hi = _bonferroni_bounds(seeds, count / n, n)
    assert lo <= hits.min() and hits.max() <= hi, (hits.min(), hits.max(), lo, hi)


def test_the_inclusion_check_catches_a_design_that_is_not_self_weighting() -> None:
    """The same check rejects clusters drawn with *equal* probability (not PPS): small clusters' members
    are then over-sampled. Shows the test above has the power to fail."""
    q = _blobs((140, 60, 25, 15))
    n, count, k, seeds = len(q), 12, 3, 1200
    m = count // k
    hits = np.zeros(n)
    for s in range(seeds):
        rng = np.random.default_rng(s)
        x = q * SCALE
        labels, _ = _merge_small(x, _partition(x, default_partition(n, k, m), rng), m)
        ids = np.unique(labels)
        for c in rng.choice(ids, size=k, replace=False):
            hits[rng.choice(np.flatnonzero(labels == c), m, replace=False)] += 1
    lo, hi = _bonferroni_bounds(seeds, count / n, n)
    assert not (lo <= hits.min() and hits.max() <= hi)


def test_a_draw_stays_in_one_cluster_and_its_poses_are_close_together() -> None:
    rng = np.random.default_rng(4)
    q = rng.uniform(-np.pi, np.pi, size=(4000, 6))
    r = cluster_sample(q, 20, 5, scale=SCALE, seed=1, partition=200)
    within = []
    for d in range(r.k):
        rows = r.indices[r.draw == d]
        assert len(rows) == r.m == 4 and len(set(r.cluster[r.draw == d])) == 1
        x = q[rows] * SCALE
        within += [np.linalg.norm(a - b) for i, a in enumerate(x) for b in x[i + 1:]]
    pairs = rng.choice(len(q), size=(500, 2))
    between = np.linalg.norm((q[pairs[:, 0]] - q[pairs[:, 1]]) * SCALE, axis=1)
    # uniform data: a cluster holds 1/200 of the volume, so its linear size is about 200^(-1/6) = 0.41 of
    # the whole; 0.6 leaves room for k-means' uneven cells
    assert np.mean(within) < 0.6 * np.mean(between)


def test_poses_must_split_evenly_over_the_clusters() -> None:
    q = np.random.default_rng(0).uniform(-1, 1, size=(500, 6))
    with pytest.raises(SelectorError, match="divisible") as info:
        cluster_sample(q, 20, 3, scale=SCALE, seed=0)
    assert "\n" not in str(info.value)
    with pytest.raises(SelectorError, match="only 10 candidates"):
        cluster_sample(q[:10], 20, 5, scale=SCALE, seed=0)


@pytest.mark.parametrize("first_stage", FIRST_STAGES)
def test_a_cluster_drawn_more_than_once_gives_distinct_poses_per_draw(first_stage: str) -> None:
    q = np.random.default_rng(1).uniform(-1, 1, size=(200, 6))
    r = cluster_sample(q, 20, 5, scale=SCALE, seed=3, partition=2,  # 5 draws from 2 clusters: repeats
                       first_stage=first_stage)
    assert r.partition == 2 and len(np.unique(r.cluster)) <= 2
    assert len(np.unique(r.indices)) == 20  # distinct rows, even within a repeated cluster
    assert sorted(np.bincount(r.draw)) == [4] * 5 and r.excluded_fraction == 0.0
    repeated = [c for c in np.unique(r.cluster) if len(np.unique(r.draw[r.cluster == c])) > 1]
    assert repeated  # pigeonhole: some cluster was drawn twice, and it counts as several draws
    means = [_field(q[r.indices[r.draw == d]]).mean() for d in range(5)]
    assert cluster_standard_error(_field(q[r.indices]), r.draw) == pytest.approx(
        np.std(means, ddof=1) / np.sqrt(5))


def test_small_clusters_are_merged_or_excluded_and_the_exclusion_is_reported() -> None:
    q = _blobs((140, 60, 25, 15))
    for first_stage, least in (("with-replacement", 20), ("systematic", 4)):
        # ~8 a cluster: many below count = 20, some below m = 4
        merged = cluster_sample(q, 20, 5, scale=SCALE, seed=2, partition=40, first_stage=first_stage)
        assert merged.excluded_fraction == 0.0 and merged.partition < 40
        excluded = cluster_sample(q, 20, 5, scale=SCALE, seed=2, partition=40, small="exclude",
                                  first_stage=first_stage)
        assert 0 < excluded.excluded_fraction < 1 and len(np.unique(excluded.indices)) == 20
        # the candidates left to draw from: every cluster that holds `least`
        x = q * SCALE
        labels = _partition(x, 40, np.random.default_rng(2))
        sizes = np.unique(labels, return_counts=True)[1]
        assert excluded.excluded_fraction == pytest.approx(sizes[sizes < least].sum() / len(q))
    # every cluster too small: nothing left to draw from
    with pytest.raises(SelectorError, match="no cluster"):
        cluster_sample(q, 20, 5, scale=SCALE, seed=2, partition=len(q), small="exclude")


@pytest.mark.parametrize("first_stage", FIRST_STAGES)
def test_the_mean_is_unbiased_and_the_cluster_standard_error_matches_its_spread(first_stage: str) -> None:
    q = _blobs((500, 300, 150, 100), seed=5)
    values = _field(q)
    truth, seeds = values.mean(), 500
    means, var_hat, srs_var = [], [], []
    for s in range(seeds):
        r = cluster_sample(q, 20, 5, scale=SCALE, seed=s, first_stage=first_stage)
        v = values[r.indices]
        means.append(v.mean())
        var_hat.append(cluster_standard_error(v, r.draw) ** 2)
        srs_var.append(np.var(v, ddof=1) / len(v))
    means = np.array(means)
    spread = means.var(ddof=1)
    # unbiased: the average of 500 independent sample means is within 4 standard errors of the truth
    assert abs(means.mean() - truth) < 4 * np.sqrt(spread / seeds)
    # the estimated variance matches the empirical one. Relative sd of the ratio: the empirical variance
    # over 500 seeds ~sqrt(2/499) = 6 %, the mean of 500 estimates with 4 degrees of freedom ~sqrt(2/4)/
    # sqrt(500) = 3 % (more with heavy tails): about 7 % together, so ±25 % is beyond 3 sd. Slightly
    # conservative by design (repeated clusters), never optimistic
    assert 0.8 < np.mean(var_hat) / spread < 1.25
    # and the naive simple-random-sample formula would be optimistic here: the design effect is real
    assert np.mean(srs_var) < 0.6 * spread
    r = cluster_sample(q, 20, 5, scale=SCALE, seed=0)
    assert design_effect(values[r.indices], r.draw) == pytest.approx(
        cluster_standard_error(values[r.indices], r.draw) ** 2 / (np.var(values[r.indices], ddof=1) / 20))


def test_standard_error_needs_draws_not_labels() -> None:
    with pytest.raises(SelectorError, match="at least 2 draws"):
        cluster_standard_error(np.ones(4), np.zeros(4, dtype=int))
    with pytest.raises(SelectorError, match="same number"):
        cluster_standard_error(np.arange(5.0), np.array([0, 0, 1, 1, 1]))

