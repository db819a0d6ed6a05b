"""k-fold cross-validation of a fit: how well each model predicts poses it never saw.

A fit's own RMS says how well it matches the poses it was fitted to, which a model with 27–31 free
parameters always does well, however little it has learnt about the arm. What a user needs is how well
it predicts *other* poses, beside what they would get without it: the **nominal** model (tracker pose
and SMR offset fitted, the arm as drawn: `register`) and, when known, the **controller's own** model
(its factory calibration, registered the same way). All three are judged on the same folds.

**Folds.** Pose i (in the order of the file or the campaign's records, counting only the poses the fit
used) is in fold ``i mod k``, k = `default_folds` = min(10, poses). Deterministic, so the same data give
the same figure every time; interleaved rather than in blocks because poses come in visiting order —
a tour's neighbours are neighbours in the workspace and in time — so a block would hold out one region
and one stretch of the session (an extrapolation and a drift test, not a prediction test), while every
interleaved fold spans the whole. Ten folds is the usual compromise between the bias of few folds (each
training set much smaller than the fit's) and the variance of many (Kohavi, IJCAI 1995; Hastie,
Tibshirani & Friedman, *The Elements of Statistical Learning*, §7.10); with ten poses or fewer it is
leave-one-out. Poses the fit rejected as outliers are left out of the folds too (no rejection inside
the folds: the full fit's choice stands), and of the figures of all three models alike.

**Each fold's fit is one Gauss–Newton step warm-started from the full fit**: with the full fit's
residuals r and Jacobian J (and the MAP fit's prior weights W and offset θ̂ − θ₀), the fold's
parameters move by δ = (J_Tᵀ J_T + W)⁻¹ (J_Tᵀ r_T − W (θ̂ − θ₀)) over its training poses T, and the
held-out poses' errors are r_F − J_F δ. The full fit already sits at the minimum over all poses, and
leaving a tenth out moves it by a small step in which the model is linear to second order, so one step
is the refit (the tests compare it with fitting each fold from scratch). It costs one Jacobian per
model and k small solves: a few milliseconds where a refit per fold would cost k fits. The nominal's and
the controller's folds are the same step in their registration parameters (tracker pose, SMR offset).

**Better or not.** The calibrated model counts as better than another only when the held-out poses show
it: a one-sided paired t test on the per-pose differences of squared errors (other² − calibrated²) at
`SIGNIFICANCE`. A lower RMS alone is not enough: on a dozen noisy poses the two RMS figures scatter by
more than their difference, and a coin toss would hand out a model that makes the arm worse about half
the time (the tests draw such stations). On data that can calibrate an arm the improvement is tens of
times the scatter and the test passes at any level.

Any fit can be judged this way: `held_out_residuals` takes the residuals, Jacobian and prior of any
linearised least-squares or MAP fit (joint-error terms included), so a choice between models by
cross-validated prediction error calls it with each candidate's columns.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from hil.arm.geometry import Geometry
from hil.arm.kinematics import N_PARAMETERS, SMR_SLICE, TRACKER_SLICE, Kinematics
from hil.calibration.distributions import student_t_cdf
from hil.calibration.identification import ErrorStats, FitResult, register
from hil.calibration.measurements import Measurements

#: Most folds: ten (module docstring); fewer poses give leave-one-out.
MAX_FOLDS = 10
#: The rule in words, as results state it.
FOLD_RULE = "pose i (in input order, fitted poses only) in fold i mod k, k = min(10, poses)"
#: One-sided level of the paired test that says the calibrated model predicts better than another (module
#: docstring): 5 %, so a fit that improves nothing is handed out as better at most 1 time in 20.
SIGNIFICANCE = 0.05
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
                       offset: np.ndarray | None = None) -> np.ndarray:
    """(m, 3) each pose's error when its fold is left out of the fit (module docstring).

    `residuals` (m, 3) measured − modelled at the full fit; `jacobian` (m, 3, n) of the modelled points
    in the fitted parameters; `fold` (m,) fold numbers; `weights` (n,) a MAP fit's prior weights σ²/τ²
    and `offset` (n,) its θ̂ − θ₀ (None: plain least squares). A training set that cannot determine
    every parameter on its own (no prior, few poses) takes the least-norm step (a pseudo-inverse).
    """
    r = np.asarray(residuals, dtype=float).reshape(-1, 3)
    J = np.asarray(jacobian, dtype=float)
    m, n = len(r), J.shape[2]
    Jf = J.reshape(3 * m, n)
    rf = r.ravel()
    w = np.zeros(n) if weights is None else np.asarray(weights, dtype=float)
    prior_gradient = np.zeros(n) if offset is None else w * np.asarray(offset, dtype=float)
    rows = np.repeat(np.asarray(fold), 3)
    A_all = Jf.T @ Jf
    g_all = Jf.T @ rf
    norms = np.sqrt(np.maximum(np.diag(A_all) + w, 1e-300))  # column scaling for the solves
    out = np.empty_like(r)
    for f in sorted(set(np.asarray(fold).tolist())):  # not np.unique: numpy 2.4's imports numpy.ma
        held = rows == f
        Jh = Jf[held]
        A = A_all - Jh.T @ Jh + np.diag(w)
        g = g_all - Jh.T @ rf[held] - prior_gradient
        As = A / np.outer(norms, norms)
        try:  # numpy's solve, not scipy's: `hil identify` of clean data imports no scipy (its start-up)
            step = np.linalg.solve(As, g / norms)
            if not np.all(np.isfinite(step)):
                raise np.linalg.LinAlgError
        except np.linalg.LinAlgError:
            step = np.linalg.pinv(As, rcond=1e-10) @ (g / norms)
        step = step / norms
        out[np.asarray(fold) == f] = (rf[held] - Jh @ step).reshape(-1, 3)
    return out


@dataclass(frozen=True)
class CrossValidation:
    """Held-out errors of the calibrated, nominal and (when known) controller's models on the same folds."""

    folds: int
    poses: int  # poses in the folds (the fit's used poses)
    calibrated: ErrorStats
    nominal: ErrorStats
    controller: ErrorStats | None = None
    seconds: float = 0.0

    def p_value(self, other: ErrorStats) -> float:
        """One-sided p-value of "the calibrated model predicts better than `other`" (paired t test on
        the per-pose differences of squared held-out errors; module docstring)."""
        d = other.errors**2 - self.calibrated.errors**2
        if len(d) < 2:
            return 1.0
        sd = float(np.std(d, ddof=1))
        mean = float(np.mean(d))
        if sd == 0.0:
            return 0.0 if mean > 0 else 1.0
        return float(student_t_cdf(float(-mean / (sd / np.sqrt(len(d)))), len(d) - 1))

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
                fold: np.ndarray) -> ErrorStats:
    """Held-out errors of a model whose tracker pose and SMR offset are refitted in each fold."""
    model, J = Kinematics(geometry).point_and_jacobian(q)
    return ErrorStats.of(held_out_residuals(p - model, J[:, :, REGISTRATION], fold))


def cross_validate(meas: Measurements, fit: FitResult, *, controller: Geometry | None = None,
                   folds: int | None = None, smr_guess: np.ndarray | None = None,
                   jacobian: np.ndarray | None = None) -> CrossValidation:
    """Cross-validate `fit` (made from `meas`) beside the nominal and the controller's models.

    `controller`: the controller's own arm (`ControllerCalibration.geometry`), registered on the fit's
    poses like the nominal. `jacobian` (used poses, 3, n): the fit's Jacobian when its columns are not
    `Kinematics.jacobian`'s for ``fit.indices`` (a fit with further terms). Fewer than two used poses
    cannot be split: ValueError.
    """
    import time

    t0 = time.perf_counter()
    used = np.asarray(fit.used, dtype=bool)
    q, p = meas.q[used], meas.p[used]
    fold = fold_of(len(q), folds)
    if jacobian is None:
        directions = None if meas.directions is None else meas.directions[used]
        jacobian = Kinematics(fit.geometry).jacobian(q, fit.indices, directions)
    offset = None
    if fit.prior is not None and fit.prior_weights is not None:
        offset = fit.values - fit.prior.mean
    calibrated = ErrorStats.of(held_out_residuals(fit.residuals[used], jacobian, fold,
                                                  fit.prior_weights, offset))
    baseline = fit.baseline if fit.baseline is not None else register(meas, fit.robot, smr_guess)
    nominal = _registered(baseline, q, p, fold)
    theirs = None
    if controller is not None:
        located = register(Measurements(q, p, meas.lines[used], meas.source), fit.robot,
                           fit.geometry.smr if smr_guess is None else smr_guess, arm=controller)
        theirs = _registered(located, q, p, fold)
    return CrossValidation(int(fold.max()) + 1, len(q), calibrated, nominal, theirs,
                           time.perf_counter() - t0)
