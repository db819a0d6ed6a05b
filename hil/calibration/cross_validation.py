"""k-fold cross-validation of a fit: how well each model predicts poses it never saw.

A fit's own RMS says how well it matches the poses it was fitted to, which a model with 27–31 free
parameters always does well, however little it has learnt about the arm. What a user needs is how well
it predicts *other* poses, beside what they would get without it: the **nominal** model (tracker pose
and SMR offset fitted, the arm as drawn: `register`) and, when known, the **controller's own** model
(its factory calibration, registered the same way). All three are judged on the same folds.

**Folds.** Pose i (in the order of the file or the campaign's records, counting every pose, the ones the
fit rejected as outliers included) is in fold ``i mod k``, k = `default_folds` = min(10, poses).
Deterministic, so the same data give the same figure every time; interleaved rather than in blocks
because poses come in visiting order — a tour's neighbours are neighbours in the workspace and in time —
so a block would hold out one region and one stretch of the session (an extrapolation and a drift test,
not a prediction test), while every interleaved fold spans the whole. Ten folds is the usual compromise
between the bias of few folds (each training set much smaller than the fit's) and the variance of many
(Kohavi, IJCAI 1995; Hastie, Tibshirani & Friedman, *The Elements of Statistical Learning*, §7.10); with
ten poses or fewer it is leave-one-out.

**Rejected poses are scored, never dropped** (a fit must not silently make the arm worse).
The poses the fit rejected as outliers (an F test on its own residuals) are exactly those it explains
worst; scoring only the kept ones flattered the calibrated model (the shared UR10e camera file: 3.25
against 4.27 mm, "better", on 20 of 23 poses; 3.95 against 4.35 mm, not better, with every pose kept).
A rejected pose trains no fit, neither the full one nor any fold's (the full fit's choice stands: no
rejection inside the folds), so each model's prediction of it from *all* the poses it was fitted to is
already a held-out prediction: the calibrated model's is the full fit's residual, the nominal's and the
controller's the one-step registration on the kept poses (`held_out_residuals` with its ``train``
mask). Those errors enter every model's figures and the test, each rejected pose in its fold by the
same rule, so the corrected-variance test below still sees k folds of interleaved poses.

**Each fold's fit is one Gauss–Newton step warm-started from the full fit**: with the full fit's
residuals r and Jacobian J (and the MAP fit's prior weights W and offset θ̂ − θ₀), the fold's
parameters move by δ = (J_Tᵀ J_T + W)⁻¹ (J_Tᵀ r_T − W (θ̂ − θ₀)) over its training poses T, and the
held-out poses' errors are r_F − J_F δ. The full fit already sits at the minimum over all poses, and
leaving a tenth out moves it by a small step in which the model is linear to second order, so one step
is the refit (the tests compare it with fitting each fold from scratch). It costs one Jacobian per
model and k small solves: a few milliseconds where a refit per fold would cost k fits. The nominal's and
the controller's folds are the same step in their registration parameters (tracker pose, SMR offset).

**Better or not.** The calibrated model counts as better than another only when the held-out poses show
it: a one-sided t test on the k folds' log ratios log(Σ other² / Σ calibrated²) at `SIGNIFICANCE`
(`ratio_p_value`). A lower RMS alone is not enough: on a dozen noisy poses the two RMS figures scatter by
more than their difference.

*The test's variance is the corrected resampled one* (Nadeau & Bengio, "Inference for the
Generalization Error", Machine Learning 52:239–281, 2003; for k-fold cross-validation Bouckaert &
Frank, PAKDD 2004): t = mean / √((1/k + n_test/n_train)·s²) over the k fold statistics, k − 1 degrees
of freedom. Every fold's poses are judged by one fold fit, and any two fold fits share most of their
training poses, so the per-pose figures are not independent; the naive test over poses exported 7 of
200 worse-than-nominal models on `bench/bad_data.py` (seed 0).

*Why log ratios at 0.5 %, not mean differences at 5 %.* With the differences of squared errors
(other² − calibrated²) the test's power is set by the spread of the nominal's errors from pose to pose,
not by the gain: good data (25–40 poses, tracker noise, a gain of twenty) reached only p 0.002–0.006,
so the level could not be lowered below 5 %, and at 5 % bad data (10–15 poses, 0.5–2 mm) exported 6
models worse than nominal over 400 stations (seeds 0 and 1) — the CV gain of a dozen noisy poses
scatters far more than the corrected variance assumes at k ≤ 10 folds. The fold's log ratio is
scale-free (a tenfold gain is the same figure wherever the nominal errs much or little) and the log of
a sum of squares has a nearly constant variance (Bartlett & Kendall 1946), so good data reach p ≤ 5e-7
and the level can be the strict 0.5 % that Benjamin et al. (2018) propose for claiming a new effect:
handing out a worse model harms the arm, refusing a better one costs a re-measurement. Measured with
`bench/bad_data.py --bad 200 --good 40` on seeds 0 and 1 (docs/design.md, Identification:
cross-validation): no bad-data model worse than nominal exported, every good-data model exported.

Any fit can be judged this way: `held_out_residuals` takes the residuals, Jacobian and prior of any
linearised least-squares or MAP fit (joint-error terms included), so a choice between models by
cross-validated prediction error calls it with each candidate's columns.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from hil.arm.geometry import Geometry
from hil.arm.kinematics import N_PARAMETERS, SMR_SLICE, TRACKER_SLICE, Kinematics, parameter_layout
from hil.calibration.distributions import student_t_cdf
from hil.calibration.identification import ErrorStats, FitResult, register
from hil.calibration.measurements import Measurements

#: Most folds: ten (module docstring); fewer poses give leave-one-out.
MAX_FOLDS = 10
#: The rule in words, as results state it.
FOLD_RULE = ("pose i (in input order, every pose, rejected ones included) in fold i mod k, "
             "k = min(10, poses); a rejected pose is predicted by each model fitted to every kept pose")
#: One-sided level of the test that says the calibrated model predicts better than another (module
#: docstring, "Better or not"): 0.5 %, the level Benjamin et al. (Nature Human Behaviour 2:6-10, 2018)
#: propose for a claim of a new effect, since handing out a worse model harms the arm while refusing a
#: better one costs a re-measurement; on data that can calibrate an arm the test's p-value is 1e-6 or less.
SIGNIFICANCE = 0.005
#: The registration parameters: what "nominal" and "controller" models fit in each fold.
REGISTRATION = np.r_[np.arange(N_PARAMETERS)[TRACKER_SLICE], np.arange(N_PARAMETERS)[SMR_SLICE]]


def default_folds(count: int) -> int:
    """k for `count` poses: min(`MAX_FOLDS`, count), so ten poses or fewer are left out one at a time."""
    return max(1, min(MAX_FOLDS, int(count)))


def fold_of(count: int, folds: int | None = None) -> np.ndarray:
    """(count,) fold number of each pose: pose i in fold i mod k (module docstring)."""
    k = default_folds(count) if folds is None else int(folds)
    if not 2 <= k <= count:
        raise ValueError(f"cross-validation needs 2..{count} folds for {count} poses, not {k}")
    return np.arange(count) % k


def held_out_residuals(residuals: np.ndarray, jacobian: np.ndarray, fold: np.ndarray,
                       weights: np.ndarray | None = None,
                       offset: np.ndarray | None = None,
                       train: np.ndarray | None = None) -> np.ndarray:
    """(m, b) each pose's error when its fold is left out of the fit (module docstring).

    `residuals` (m, b) measured − modelled at the full fit (b = 3 for a point; a 6-D or several-reflector
    fit's whitened rows, `hil.calibration.pose_cross_validation`); `jacobian` (m, b, n) of the modelled points
    in the fitted parameters; `fold` (m,) fold numbers; `weights` (n,) a MAP fit's prior weights σ²/τ²
    and `offset` (n,) its θ̂ − θ₀ (None: plain least squares). A training set that cannot determine
    every parameter on its own (no prior, few poses) takes the least-norm step (a pseudo-inverse).
    `train` (m,) bool: the poses a fit may use (None: all). A pose outside it (a rejected outlier) is in
    no fold's training set and is predicted by the step over *every* training pose — the model fitted
    to all the poses it was given, which never saw this one (module docstring, "Rejected poses").
    """
    J = np.asarray(jacobian, dtype=float)
    m, b, n = J.shape
    r = np.asarray(residuals, dtype=float).reshape(m, b)
    Jf = J.reshape(b * m, n)
    rf = r.ravel()
    w = np.zeros(n) if weights is None else np.asarray(weights, dtype=float)
    prior_gradient = np.zeros(n) if offset is None else w * np.asarray(offset, dtype=float)
    fold = np.asarray(fold)
    fits = np.ones(m, dtype=bool) if train is None else np.asarray(train, dtype=bool)
    rows = np.repeat(fold, b)
    fitted_rows = np.repeat(fits, b)
    Jt, rt = Jf[fitted_rows], rf[fitted_rows]
    A_all = Jt.T @ Jt
    g_all = Jt.T @ rt
    norms = np.sqrt(np.maximum(np.diag(A_all) + w, 1e-300))  # column scaling for the solves

    def step_without(leave: np.ndarray) -> np.ndarray:
        """The one Gauss–Newton step of the fit over the training rows not in `leave`."""
        Jh, rh = Jf[leave & fitted_rows], rf[leave & fitted_rows]
        A = (A_all - Jh.T @ Jh + np.diag(w)) / np.outer(norms, norms)
        g = (g_all - Jh.T @ rh - prior_gradient) / norms
        try:  # numpy's solve, not scipy's: `hil identify` of clean data imports no scipy (its start-up)
            step = np.linalg.solve(A, g)
            if not np.all(np.isfinite(step)):
                raise np.linalg.LinAlgError
        except np.linalg.LinAlgError:
            step = np.linalg.pinv(A, rcond=1e-10) @ g
        return step / norms

    out = np.empty_like(r)
    for f in sorted(set(fold[fits].tolist())):  # not np.unique: numpy 2.4's imports numpy.ma
        held = (rows == f) & fitted_rows
        out[(fold == f) & fits] = (rf[held] - Jf[held] @ step_without(rows == f)).reshape(-1, b)
    if not fits.all():
        rest = ~fitted_rows
        out[~fits] = (rf[rest] - Jf[rest] @ step_without(np.zeros_like(rows, dtype=bool))).reshape(-1, b)
    return out


def _corrected_t_p_value(per_fold: np.ndarray, n: int) -> float:
    """One-sided p-value of "the fold statistics `per_fold` are positive on average" for k folds of
    `n` poses: the t test with the corrected resampled variance (1/k + n_test/n_train)·s² on k − 1
    degrees of freedom of the module docstring."""
    k = len(per_fold)
    spread = float(np.var(per_fold, ddof=1)) * (1.0 / k + (n / k) / (n - n / k))
    mean = float(np.mean(per_fold))
    if spread == 0.0:
        return 0.0 if mean > 0 else 1.0
    return float(student_t_cdf(-mean / np.sqrt(spread), k - 1))


def paired_p_value(d: np.ndarray, folds: int) -> float:
    """One-sided p-value of "the per-pose differences `d` (other − calibrated) are positive on
    average", with pose i in fold i mod `folds`, on the fold means (`_corrected_t_p_value`), since
    poses of one fold share a fit and the folds share most of their training poses."""
    d = np.asarray(d, dtype=float)
    n = len(d)
    k = min(folds, n)
    if k < 2:
        return 1.0
    return _corrected_t_p_value(np.array([d[f::k].mean() for f in range(k)]), n)


def ratio_p_value(other: np.ndarray, calibrated: np.ndarray, folds: int) -> float:
    """One-sided p-value of "the calibrated model's held-out squared errors are smaller than the
    other's", on each fold's log ratio log(Σ other / Σ calibrated) (pose i in fold i mod `folds`;
    `other` and `calibrated` are per-pose squared errors), with the corrected variance
    (`_corrected_t_p_value`). The verdict's test (module docstring, "Better or not"): the log ratio is
    scale-free, so a station whose nominal errors are large in some poses and small in others does
    not drown a tenfold gain in the spread of the differences, and the log of a sum of squares has a
    nearly constant variance (Bartlett & Kendall, JRSS Suppl. 8:128-138, 1946)."""
    a = np.asarray(other, dtype=float)
    b = np.asarray(calibrated, dtype=float)
    n = len(a)
    k = min(folds, n)
    if k < 2:
        return 1.0
    tiny = np.finfo(float).tiny
    per_fold = np.array([np.log(max(a[f::k].sum(), tiny) / max(b[f::k].sum(), tiny)) for f in range(k)])
    return _corrected_t_p_value(per_fold, n)


@dataclass(frozen=True)
class CrossValidation:
    """Held-out errors of the calibrated, nominal and (when known) controller's models on the same folds."""

    folds: int
    poses: int  # poses scored held out: every pose of the input, the rejected ones included
    calibrated: ErrorStats
    nominal: ErrorStats
    controller: ErrorStats | None = None
    seconds: float = 0.0
    rejected: int = 0  # of `poses`, those the fit rejected as outliers (scored all the same)

    def p_value(self, other: ErrorStats) -> float:
        """One-sided p-value of "the calibrated model predicts better than `other`": the folds' log
        ratios of squared held-out errors with the corrected variance (`ratio_p_value`, module
        docstring)."""
        return ratio_p_value(other.errors**2, self.calibrated.errors**2, self.folds)

    @property
    def better_than_controller(self) -> bool | None:
        """Whether the held-out poses show the calibrated model better than the controller's (None:
        the controller's model is not known)."""
        return None if self.controller is None else self.p_value(self.controller) < SIGNIFICANCE

    @property
    def better_than_nominal(self) -> bool:
        """Whether the held-out poses show the calibrated model better than the nominal model *and*
        than the controller's own model when that is known. False: using it may make the arm worse."""
        return self.p_value(self.nominal) < SIGNIFICANCE and self.better_than_controller is not False

    def verdict(self) -> str:
        """One line: the models' held-out RMS and, when the calibrated one is not shown better, so."""
        figures = (f"calibrated {self.calibrated.rms * 1e3:.4f} mm, nominal {self.nominal.rms * 1e3:.4f} mm"
                   + ("" if self.controller is None
                      else f", controller's model {self.controller.rms * 1e3:.4f} mm"))
        if self.better_than_nominal:
            return f"{self.folds}-fold cross-validation RMS: {figures}"
        other = ("the nominal model" if self.p_value(self.nominal) >= SIGNIFICANCE
                 else "the controller's own model")
        return (f"the calibrated model does not predict held-out poses better than {other} "
                f"({self.folds}-fold cross-validation RMS: {figures}): it may make the arm worse")

    def as_dict(self) -> dict[str, Any]:
        """The ``cross_validation`` block of a model and a result (docs/design.md)."""
        return {
            "folds": self.folds, "rule": FOLD_RULE, "poses": self.poses,
            "fitted": self.poses - self.rejected, "rejected": self.rejected, "rejected_scored": True,
            "calibrated": self.calibrated.as_dict(), "nominal": self.nominal.as_dict(),
            "controller": None if self.controller is None else self.controller.as_dict(),
            "better_than_nominal": self.better_than_nominal,
            "better_than_controller": self.better_than_controller,
            "p_value_nominal": self.p_value(self.nominal),
            "p_value_controller": None if self.controller is None else self.p_value(self.controller),
            "significance": SIGNIFICANCE,
            "seconds": self.seconds,
        }


def _registered(geometry: Geometry, q: np.ndarray, p: np.ndarray,
                fold: np.ndarray, train: np.ndarray) -> ErrorStats:
    """Held-out errors of a model whose tracker pose and SMR offset are refitted in each fold on the
    `train` poses (the poses outside it predicted by the registration on all of them)."""
    model, J = Kinematics(geometry).point_and_jacobian(q)
    registration = parameter_layout(len(geometry.joints)).registration
    return ErrorStats.of(held_out_residuals(p - model, J[:, :, registration], fold, train=train))


def cross_validate(meas: Measurements, fit: FitResult, *, controller: Geometry | None = None,
                   folds: int | None = None, smr_guess: np.ndarray | None = None,
                   jacobian: np.ndarray | None = None) -> CrossValidation:
    """Cross-validate `fit` (made from `meas`) beside the nominal and the controller's models.

    Every pose of `meas` is scored, those the fit rejected included (`score_folds`, module docstring).
    `controller`: the controller's own arm (`ControllerCalibration.geometry`), registered on the fit's
    used poses like the nominal. `jacobian` (every pose, 3, n): the fit's Jacobian when its columns are
    not `Kinematics.jacobian`'s for ``fit.indices`` (a fit with further terms). Fewer than two used
    poses cannot be split: ValueError.
    """
    import time

    t0 = time.perf_counter()
    used, fold = score_folds(fit.used, folds)
    q, p = meas.q, meas.p
    if jacobian is None:
        jacobian = Kinematics(fit.geometry).jacobian(q, fit.indices, meas.directions)
    offset = None
    if fit.prior is not None and fit.prior_weights is not None:
        offset = fit.values - fit.prior.mean
    calibrated = ErrorStats.of(held_out_residuals(fit.residuals, jacobian, fold,
                                                  fit.prior_weights, offset, used))
    baseline = fit.baseline if fit.baseline is not None else register(meas, fit.robot, smr_guess)
    nominal = _registered(baseline, q, p, fold, used)
    theirs = None
    if controller is not None:
        located = register(Measurements(q[used], p[used], meas.lines[used], meas.source), fit.robot,
                           fit.geometry.smr if smr_guess is None else smr_guess, arm=controller)
        theirs = _registered(located, q, p, fold, used)
    return CrossValidation(int(fold.max()) + 1, len(q), calibrated, nominal, theirs,
                           time.perf_counter() - t0, int((~used).sum()))


def score_folds(used: np.ndarray, folds: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(used (m,) bool, fold (m,)) of a fit's cross-validation: every pose, the rejected ones included,
    in fold i mod k with k from the count of *all* poses (module docstring, "Rejected poses"), the
    one rule of the position and the 6-D paths. Fewer than two used poses cannot be split: ValueError."""
    used = np.asarray(used, dtype=bool)
    if used.sum() < 2:
        raise ValueError(f"cross-validation needs at least 2 fitted poses, not {int(used.sum())}")
    fold = fold_of(len(used), folds)
    return used, fold
