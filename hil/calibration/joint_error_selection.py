"""Which low-order joint errors the data support: chosen by cross-validated prediction error.

A real joint's link angle differs from its encoder by a few low harmonics of the angle (and lags it by
its lost motion; `hil.arm.joint_errors`). Each harmonic the fit adds costs two parameters, and with a
few dozen poses the residual always falls when a term is added — so the fit's residual cannot say
which terms are real. How well the model predicts poses it never saw can: a term is kept only when it
lowers the k-fold cross-validated RMS by more than that drop's standard error.

**Forward selection.** Starting from the geometry (and compliance) the fit identifies anyway, each
step tries every remaining candidate group — a harmonic of one joint (its cos and sin together: the
phase is unknown) or one joint's lost motion — and adds the one whose model predicts held-out poses
best, while its cross-validated mean squared error falls by more than `SE_FACTOR` (2) standard errors
of the paired per-pose drop (the drop's own standard error, not the error's: both models are judged on
the same poses and folds, so their common scatter cancels). The candidates are orders 1 … 3 of every
joint (`hil.arm.kinematics.identifiable_joint_errors`: all are independent of the geometry on a UR)
and the lost motion of every joint whose approach directions in the data take both signs (approached
from one side it is a constant offset, which the geometry already holds).

**Cheap folds.** The selection's k-fold loop is `hil.calibration.cross_validation`'s (its folds, its one-
step fold fits, the fit's prior), so the error "without" joint errors is the cross-validated error `hil
identify` reports for the geometry. Every fold fit is warm-started at the full-data fit and takes one
Gauss–Newton step there: the fold's solution lies within the noise of the full one, where the model is
linear to far below the noise (the joint-error terms enter the link angle linearly, and a geometry step
of tens of micrometres changes the Jacobian by parts per million), so one step is the fold's fit. The
whole selection is then linear algebra on one Jacobian — milliseconds for 40 poses, against the fit's own
hundreds — and only the chosen model is fitted again, in full.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hil.arm.geometry import Geometry
from hil.arm.joint_error_columns import MAX_FIT_ORDER, term_groups
from hil.arm.kinematics import (
    EXTENDED_PARAMETER_NAMES,
    N_ALL_PARAMETERS,
    Kinematics,
    identifiable_joint_errors,
)
from hil.calibration.cross_validation import fold_of, held_out_residuals
from hil.calibration.identification import FitResult, identify
from hil.calibration.joint_error_request import JointErrorRequest
from hil.calibration.measurements import Measurements

#: A group is added only when the cross-validated mean squared error falls by more than this many
#: standard errors of the paired drop. The one-standard-error rule (Hastie, Tibshirani & Friedman, The
#: Elements of Statistical Learning, 2nd ed., §7.10) judges one model against another; here each step
#: keeps the best of up to 24 candidates, and the best of many spurious drops often exceeds one standard
#: error: measured on rigid UR5e truths with 40 poses (`bench/joint_errors.py`'s stations), one
#: standard error kept a term on 10 of 30 arms, two on 1 of 30 (1 of 20 in the bench's table), while
#: with the bench's assumed joint errors two standard errors kept terms on 15 of 20 arms, every one of
#: them a true order. A spurious group costs little (a few µm of held-out error), but a fit that adds
#: terms to a third of rigid arms would not mean what it says.
SE_FACTOR = 2.0
#: Folds of the selection's cross-validation (fewer when there are fewer poses): ten is the usual
#: compromise between the bias of few folds and the variance of many (ibid. §7.10.1).
FOLDS = 10
#: What `identify_with_joint_errors` does unless told otherwise.
AUTO = JointErrorRequest("auto")


@dataclass(frozen=True)
class Step:
    """One forward-selection step: the best group tried and whether it was kept."""

    group: str
    cv_rms: float  # m, with the group
    drop: float  # m, of the cross-validated RMS
    se: float  # m, standard error of that drop
    kept: bool


@dataclass
class TermChoice:
    """Which joint-error groups the model carries and the cross-validation that chose them."""

    request: str
    groups: tuple[str, ...]
    indices: tuple[int, ...]
    candidates: tuple[str, ...]
    folds: int
    cv_rms_without: float  # m: geometry (and compliance) only
    cv_rms: float  # m: with the chosen groups
    steps: list[Step] = field(default_factory=list)
    seconds: float = 0.0

    def as_dict(self) -> dict[str, Any]:
        """The model file's ``joint_error_selection`` block."""
        return {"request": self.request, "groups": list(self.groups),
                "parameters": [EXTENDED_PARAMETER_NAMES[i] for i in self.indices],
                "candidates": list(self.candidates), "folds": self.folds,
                "cv_rms_without": self.cv_rms_without, "cv_rms": self.cv_rms,
                "rule": f"a group is kept when the {self.folds}-fold cross-validated mean squared "
                        f"error falls by more than {SE_FACTOR:g} standard error(s) of the paired drop",
                "steps": [{"group": s.group, "cv_rms": s.cv_rms, "drop": s.drop, "se": s.se,
                           "kept": s.kept} for s in self.steps],
                "seconds": self.seconds}


def candidate_groups(robot: str, meas: Measurements, *, compliance: bool = False,
                     template: Geometry | None = None,
                     orders: Sequence[int] = tuple(range(1, MAX_FIT_ORDER + 1)),
                     lost_motion: bool = True) -> dict[str, tuple[int, ...]]:
    """The groups a fit of `meas` may add: the harmonics of `orders` independent of the geometry
    (`identifiable_joint_errors`) and, with `lost_motion`, each joint's lost motion where its
    approach directions in `meas` take both signs."""
    payload = None if template is None else template.payload
    gravity = None if template is None else template.gravity
    free = set(identifiable_joint_errors(robot, compliance, payload, gravity).tolist())
    out: dict[str, tuple[int, ...]] = {}
    for name, cols in term_groups().items():
        if not set(cols) <= free:
            continue
        if name.startswith("lost_motion."):
            j = int(name[-1]) - 1
            d = meas.directions
            if not lost_motion or d is None or not (np.any(d[:, j] > 0) and np.any(d[:, j] < 0)):
                continue
        elif int(name.rsplit("k", 1)[1]) not in orders:
            continue
        out[name] = cols
    return out


class _KFold:
    """The k-fold loop of the selection: `hil.calibration.cross_validation`'s, on the same folds and
    with the fit's prior, so "without" is the figure `cross_validate` reports for the fit itself when
    the fit rejected no pose (`cross_validate` also scores the rejected ones; the selection compares
    candidate terms on the poses they are fitted to).

    Every fold's fit is one Gauss–Newton step from the full-data fit (`held_out_residuals`), so a
    model — a set of columns of the Jacobian at that fit — costs a few small solves, not a fit."""

    def __init__(self, J: np.ndarray, r: np.ndarray, fold: np.ndarray, weights: np.ndarray,
                 offset: np.ndarray) -> None:
        self.J, self.r, self.fold = J, r, fold
        self.weights, self.offset = weights, offset  # per column of J: the prior's σ²/τ², θ̂ − θ₀

    def squared_errors(self, cols: Sequence[int]) -> np.ndarray:
        """(m,) each pose's squared held-out error of the model with columns `cols`."""
        c = np.asarray(cols, dtype=int)
        err = held_out_residuals(self.r, self.J[:, :, c], self.fold, self.weights[c], self.offset[c])
        return np.sum(err * err, axis=1)


def choose_terms(fit: FitResult, meas: Measurements, candidates: dict[str, tuple[int, ...]],
                 request: str = "auto", forced: bool = False, folds: int = FOLDS) -> TermChoice:
    """Forward selection of `candidates` over `fit`'s parameters (module docstring); with `forced`
    every candidate is taken and the cross-validation only reports what they do."""
    import time

    t0 = time.perf_counter()
    used = fit.used
    sub = meas.subset(used)
    m = len(sub)
    k = max(2, min(folds, m))
    fold = fold_of(m, k)
    directions = sub.directions
    _, J = Kinematics(fit.geometry).point_and_jacobian(sub.q, fit.with_compliance, directions, True)
    r = fit.residuals[used]
    base = [int(i) for i in fit.indices if i < N_ALL_PARAMETERS]
    weights, offset = np.zeros(J.shape[2]), np.zeros(J.shape[2])
    if fit.prior is not None and fit.prior_weights is not None:  # the fit's MAP prior on its columns
        weights[fit.indices] = fit.prior_weights
        offset[fit.indices] = fit.values - fit.prior.mean
    kfold = _KFold(J, r, fold, weights, offset)
    current = kfold.squared_errors(base)
    without = float(np.sqrt(current.mean()))
    chosen: list[str] = []
    steps: list[Step] = []
    left = dict(candidates)
    cols = list(base)
    if forced:
        chosen = list(left)
        cols += [c for g in chosen for c in left[g]]
        current = kfold.squared_errors(cols)
        left = {}
    # every fold's fit must stay over-determined with 3 residual degrees of freedom, as the fit's own
    # pose count rule (`minimum_poses`) asks of the whole data
    room = 3 * (m - int(np.bincount(fold).max())) - 3
    while left:
        left = {g: c for g, c in left.items() if len(cols) + len(c) <= room}
        if not left:
            break
        trials = {g: kfold.squared_errors(cols + list(c)) for g, c in left.items()}
        best = min(trials, key=lambda g: float(trials[g].mean()))
        drop = current - trials[best]
        se = float(drop.std(ddof=1) / np.sqrt(m)) if m > 1 else float("inf")
        rms_now, rms_new = float(np.sqrt(current.mean())), float(np.sqrt(trials[best].mean()))
        kept = float(drop.mean()) > SE_FACTOR * se
        # the drop's standard error in RMS terms (first order: d√x = dx / 2√x)
        steps.append(Step(best, rms_new, rms_now - rms_new, se / (2.0 * max(rms_now, 1e-30)), kept))
        if not kept:
            break
        chosen.append(best)
        cols += list(left.pop(best))
        current = trials[best]
    indices = tuple(sorted(c for g in chosen for c in candidates[g]))
    return TermChoice(request, tuple(chosen), indices, tuple(candidates), k, without,
                      float(np.sqrt(current.mean())), steps, time.perf_counter() - t0)


def identify_with_joint_errors(meas: Measurements, robot: str, smr_guess: np.ndarray | None = None,
                               *, request: JointErrorRequest = AUTO,
                               **options: Any) -> FitResult:
    """`identify`, with the joint-error terms `request` asks for: none, those cross-validation
    supports ("auto"), or fixed orders; `options` are `identify`'s. The result's
    ``joint_error_choice`` says what was chosen and why (None with "none")."""
    fit = identify(meas, robot, smr_guess, **options)
    if request.mode == "none":
        return fit
    template = Geometry.nominal(robot)
    template.payload = options.get("payload")
    if options.get("gravity") is not None:
        template.gravity = np.asarray(options["gravity"], dtype=float)
    compliance = bool(options.get("compliance", False))
    if request.mode == "orders":
        groups = candidate_groups(robot, meas.subset(fit.used), compliance=compliance, template=template,
                                  orders=request.orders, lost_motion=request.lost_motion)
    else:
        groups = candidate_groups(robot, meas.subset(fit.used), compliance=compliance, template=template)
    choice = choose_terms(fit, meas, groups, str(request), forced=request.mode == "orders")
    if choice.indices:
        seconds = fit.seconds
        fit = identify(meas, robot, smr_guess, joint_errors=choice.indices, **options)
        fit.seconds += seconds + choice.seconds
    else:
        fit.seconds += choice.seconds
    fit.joint_error_choice = choice
    return fit
