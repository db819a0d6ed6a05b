"""How precise a validation RMS is, under the design that chose the validation poses.

A campaign is accepted when its validation RMS is at most ``campaign.acceptance``. That RMS is an
estimate, from a sample of validation poses, of the RMS over the whole constrained workspace, so it
has a standard error; an engineer comparing 19 µm with an acceptance of 20 µm needs it. The sample is
either a simple random sample of the candidates (``campaign.validation_clusters = 0``) or a two-stage
cluster sample (`selector.cluster_sample`): the same RMS, but poses of one cluster err alike, so it is
less precise than as many random poses would be, and the standard error must follow the design.

*The sampling unit is the pose.* With ``validation_cycles > 1`` each pose is measured several times;
those repeats share the pose's geometric error and are not more samples of the workspace. The squared
errors are therefore averaged per pose first (the repeat noise stays inside each pose's value).

*Mean square, then RMS.* Both designs are self-weighting, so the plain mean of the per-pose squared
errors is the unbiased estimate of the workspace's mean square (ms) and its standard error is known:
s(e²)/√n for a simple random sample (no finite-population correction: the candidates are thousands),
`selector.cluster_standard_error` (the between-draw variance of the draw means / k) for the cluster
sample. The RMS is √ms; by the delta method (first-order Taylor expansion of g(ms) = √ms, g' = 1/(2√ms))
SE(RMS) ≈ SE(ms) / (2·RMS). That holds while SE(ms) is small against ms, which is the case worth
quoting; with a handful of poses it is only a guide.

*Design effect* = the cluster design's variance of the mean over that of a simple random sample of the
same number of poses (`selector.cluster_sample.design_effect`): 3 means the n clustered poses tell as
much as about n/3 random ones. It is estimated only for the cluster design (``None`` otherwise).

Pure computation: nothing here reads files or the store.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from selector.cluster_sample import cluster_standard_error, design_effect
from selector.errors import SelectorError

SIMPLE_RANDOM, CLUSTERED = "simple random", "clustered"


def validation_precision(errors: np.ndarray | Sequence[float], poses: np.ndarray | Sequence[int],
                         labels: Sequence[int] | None = None) -> dict[str, Any]:
    """Standard error of the validation RMS under its sampling design.

    `errors`: the 3-D distance (m) of each validation measurement; `poses`: the validation pose (its
    index k in the validation Choice) each measurement belongs to, so repeated cycles are averaged per
    pose; `labels`: the first-stage draw of each validation pose, indexed by k (the clustered chooser's
    ``labels``), or None for a simple random sample.

    Returns ``{"design": "simple random" | "clustered", "poses": n, "clusters": k | None,
    "rms_standard_error": m | None, "design_effect": float | None}``. What cannot be estimated is None,
    never an error: one pose (or one draw) has no spread to estimate from, and an RMS of 0 leaves the
    delta method undefined. Mismatched inputs are a programming error (ValueError).
    """
    e = np.asarray(errors, dtype=float).reshape(-1)
    k_of = np.asarray(poses).reshape(-1)
    if e.shape != k_of.shape:
        raise ValueError(f"validation precision: {len(e)} errors but {len(k_of)} pose indices")
    ids, inverse = np.unique(k_of.astype(int), return_inverse=True)
    n = len(ids)
    # per-pose mean square (repeated cycles of one pose are one sample of the workspace)
    counts = np.maximum(np.bincount(inverse, minlength=n), 1)
    values = np.bincount(inverse, weights=e**2, minlength=n) / counts
    out: dict[str, Any] = {"design": SIMPLE_RANDOM if labels is None else CLUSTERED, "poses": int(n),
                           "clusters": None, "rms_standard_error": None, "design_effect": None}
    se_ms: float | None = None
    if labels is None:
        if n >= 2:
            se_ms = float(np.std(values, ddof=1) / math.sqrt(n))
    else:
        if n and (ids.min() < 0 or ids.max() >= len(labels)):
            raise ValueError(f"validation precision: pose index {int(ids.max())} has no cluster label "
                             f"({len(labels)} labels)")
        draws = np.array([int(labels[int(k)]) for k in ids], dtype=int)
        out["clusters"] = len(np.unique(draws)) if n else None
        if n and out["clusters"] >= 2:
            se_ms, deff = _clustered(values, draws)
            out["design_effect"] = deff
    rms = math.sqrt(float(values.mean())) if n else 0.0
    if se_ms is not None and math.isfinite(se_ms) and rms > 0:
        out["rms_standard_error"] = se_ms / (2.0 * rms)
    return out


def _clustered(values: np.ndarray, draws: np.ndarray) -> tuple[float, float | None]:
    """(SE of the mean of `values`, design effect) under the two-stage design.

    Every draw complete (the self-weighting design as drawn): `cluster_standard_error` and
    `design_effect`. A draw that lost poses (skipped: out of sight, beam lost) makes the mean a ratio
    of the draw totals to the draw sizes; its with-replacement linearised variance,
    k/(k−1)·Σ(t_i − ȳ·n_i)² / (Σn_i)² (Lohr, *Sampling: Design and Analysis*, §9.1 linearization of a
    ratio, with the ultimate-cluster variance of §6.4), is exactly the former when all n_i are equal.
    """
    try:
        se = cluster_standard_error(values, draws)
        deff = design_effect(values, draws)
    except SelectorError:  # unequal draw sizes: poses were skipped
        ids, inverse = np.unique(draws, return_inverse=True)
        k = len(ids)
        totals, sizes = np.bincount(inverse, weights=values), np.bincount(inverse).astype(float)
        mean = totals.sum() / sizes.sum()
        se = float(math.sqrt(k / (k - 1) * np.sum((totals - mean * sizes) ** 2)) / sizes.sum())
        srs = float(np.var(values, ddof=1) / len(values))
        deff = se * se / srs if srs > 0 else math.nan
    return se, (float(deff) if math.isfinite(deff) else None)


def campaign_validation_precision(errors: np.ndarray | Sequence[float], indices: Sequence[int],
                                  info: Mapping[str, Any] | None) -> dict[str, Any]:
    """`validation_precision` of a campaign's validation records, their poses and labels read from the
    plan's validation selection info (``selection["validation"]``, stored with the plan).

    `indices` are the records' campaign pose numbers, in the order of `errors`. The plan maps each
    planned validation entry to its validation pose (``pose_of_index``: {str(index): k}), so repeated
    cycles fall on one pose and a resumed run, reading the stored plan, maps them alike. A plan stored
    by an older hil has no such map: every record is then taken as its own pose (right for one cycle;
    with repeated cycles the standard error comes out somewhat optimistic), and a cluster sample's
    labels cannot be attached to the records, so its standard error is not estimated (None).
    """
    info = info or {}
    labels = info.get("labels")
    labels = [int(v) for v in labels] if isinstance(labels, list) else None
    pose_of = info.get("pose_of_index")
    if isinstance(pose_of, Mapping):
        missing = [i for i in indices if str(int(i)) not in pose_of]
        if missing:
            raise ValueError(f"validation precision: pose {missing[0]} is not a planned validation pose")
        poses = [int(pose_of[str(int(i))]) for i in indices]
    else:  # an older plan: no map, every record is its own pose
        poses = list(range(len(indices)))
        if labels is not None:
            unmapped = validation_precision(errors, poses)
            unmapped.update(design=CLUSTERED, clusters=len(set(labels)), rms_standard_error=None)
            return unmapped
    return validation_precision(errors, poses, labels)


def _number(v: Any) -> bool:
    return isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)


def describe_precision(block: Mapping[str, Any] | None) -> str | None:
    """A precision block (`validation_precision`, or a result's ``validation.precision``) as one line,
    e.g. "± 1.8 µm (1 s.e., 4 clusters, design effect 2.1)"; None without a block. The HTML report
    and the terminal show the same words."""
    if block is None:
        return None
    design = (f"{block.get('clusters')} clusters" if block.get("design") == CLUSTERED
              else str(block.get("design") or "unknown design"))
    deff = block.get("design_effect")
    if _number(deff):
        design += f", design effect {deff:.2g}"
    se = block.get("rms_standard_error")
    if not _number(se):
        poses = block.get("poses")
        return f"standard error not estimated ({design}, {poses} pose{'' if poses == 1 else 's'})"
    return f"± {se * 1e6:.1f} µm (1 s.e., {design})"
