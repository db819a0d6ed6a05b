"""The stopping rule: stop acquiring calibration poses once the fit so far predicts the acceptance.

An end-of-line cell pays for every second of robot time, and a selected design usually has more
calibration poses than an easy arm needs. After each calibration pose (once there are enough points to
fit) the rule identifies the model from the points measured so far (`identify`, the campaign's own
settings: compliance, payload, gravity) and predicts the validation RMS the campaign will measure on
its *planned* validation poses. hil's validation RMS is the RMS of the 3-D residual norms
(`ErrorStats.of`), so per validation pose

    E|r|² = trace(J Σθ Jᵀ) + 3σ²

(the model's prediction error from the parameters' covariance, plus the tracker's and the encoders'
noise at the validation point itself, three axes of σ), and the predicted RMS is the root of the mean
over the poses. Σθ is σ²·(JᵀJ)⁻¹, so both terms scale with σ². The fit's σ̂ is a point estimate from
few residual degrees of freedom early on: a lucky draw would stop the run on an optimistic guess. The
rule therefore uses the upper `CONFIDENCE` bound of σ from the χ² distribution of the residual sum of
squares (σ² ≤ SSR / χ²_{1−c}(dof)), which is several times σ̂ at 3 degrees of freedom and approaches
it as points accumulate — no separate "minimum poses" knob is needed beyond the fit's own minimum.

On a real (or the realistic simulated) arm the residual is mostly what the model cannot hold — the
joints' angle errors, not the tracker's noise — and σ̂ takes it as noise. That is still the right
prediction: a validation pose meets the same unmodelled error, the same size on average, as a
calibration pose's residual (tests/hil/campaign/test_stopping.py measures it: the validation RMS at a
stop was 0.8 × the prediction, median, with σ̂ 45–125 µm against the tracker's 20 µm).

The run stops when that predicted RMS is at most ``stop_margin`` × the acceptance threshold
(`campaign.stop_margin`): the prediction is an expectation, and the validation RMS scatters about it
(see `DEFAULT_MARGIN`). Validation poses are still all measured, and the verdict is still theirs.

Cost: one `identify` on 15–30 synthetic poses took 0.03–0.15 s here (UR5e/UR10e, 27 parameters, or 31
with the compliance), well under a pose's robot time (seconds of motion, settling and measuring), so
the rule checks after every calibration pose from the first one at which a fit is possible — the pose
at which it could first pass.

The verdict depends only on the points fitted (bootstrap and calibration records, in index order) and
the planned validation targets, so a resumed campaign finds the same verdict from the same records.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.stats

from hil.arm.kinematics import Kinematics
from hil.arm.payload import Payload
from hil.calibration.identification import FitResult, IdentificationError, identify
from hil.calibration.measurements import Measurements
from hil.campaign.events import AcquisitionStopped
from hil.campaign.steps import PoseRecord
from hil.errors import InputError

#: One-sided confidence of the upper bound on σ. At 95 % a fit whose residuals happen to be small (1
#: run in 20 is below the 5 % quantile of χ²) still does not stop the run on them.
CONFIDENCE = 0.95

#: Fewest residual degrees of freedom at which the rule may stop. Below them the fit's σ̂ and its
#: covariance (a linearisation) are too uncertain for one look to be trusted, and the rule looks after
#: every pose and stops at the first look that passes. Seen on synthetic stations
#: (tests/hil/campaign/test_stopping.py): a UR10e stopped at 8 degrees of freedom on σ̂ = 4.6 µm against
#: a true 20 µm, another at 14 with a true error of 68 µm against a predicted 54 µm, and both then failed
#: their validation. At 20 the 95 % bound on σ is 1.36 σ̂ and no stop of the 30 stations failed.
MIN_DOF = 20

#: Default `campaign.stop_margin`: stop when the predicted validation RMS is at most 0.7 × the
#: acceptance threshold. The validation RMS of N poses scatters about its expectation: the parameter
#: term is a quadratic form in the ~30 identified parameters' error and is shared by all poses, so its
#: effective degrees of freedom (Satterthwaite, (Σλ)²/Σλ² of the residuals' covariance, the record's
#: `effective_dof`) are only about 20 at a stopping point (median over synthetic UR5e/UR10e stations;
#: 8–30). The 99th percentile of √(χ²_ν/ν) is 1.37 at ν = 20 and 1.52 at ν = 10, so 0.7 covers the
#: scatter of all but about 1 run in 100 — and the rule looks again after every pose and stops at the
#: first look that passes, which favours lucky looks. Measured (random calibration poses, 20 µm noise,
#: acceptance 50–150 µm): of 287 stops at 0.7, 1 then measured a validation RMS above the acceptance
#: (at 1.0: 10 of 349), for about 2.5 poses more than at 1.0 (17.0 vs 14.7 poses on a UR5e).
DEFAULT_MARGIN = 0.7


@dataclass(frozen=True)
class Prediction:
    """What the fit so far predicts for the planned validation poses."""

    rms: float  # predicted validation RMS (m), with σ at its upper confidence bound
    sigma: float  # the fit's point estimate of σ (m, per axis)
    sigma_bound: float  # its upper `CONFIDENCE` bound (m)
    model_rms: float  # the parameters' share: √mean trace(J Σθ Jᵀ) with σ at the bound (m)
    dof: int  # residual degrees of freedom of the fit
    effective_dof: float  # Satterthwaite degrees of freedom of the validation residuals' sum of squares


@dataclass(frozen=True)
class Verdict:
    """One check of the rule: whether to stop, and why (or why not)."""

    stop: bool
    reason: str
    target: float  # margin × acceptance (m)
    fitted: int  # points in the fit (bootstrap and calibration)
    prediction: Prediction | None = None  # None: no fit was possible yet
    fit: FitResult | None = field(default=None, repr=False, compare=False)

    @property
    def predicted_rms(self) -> float | None:
        return None if self.prediction is None else self.prediction.rms


def sigma_upper_bound(sigma: float, dof: int, confidence: float | None = CONFIDENCE) -> float:
    """Upper `confidence` bound on the per-axis noise σ given the fit's estimate from `dof` degrees of
    freedom: SSR = dof·σ̂² is σ²·χ²(dof), so σ² ≤ SSR / χ²_{1−c}(dof) with probability c.
    `confidence` None: the point estimate itself (what the rule must not trust; tests show why)."""
    if dof < 1 or not np.isfinite(sigma):
        return float("inf")
    if confidence is None:
        return float(sigma)
    return float(sigma * np.sqrt(dof / scipy.stats.chi2.ppf(1.0 - confidence, dof)))


def predict_validation(fit: FitResult, validation_q: np.ndarray,
                       confidence: float | None = CONFIDENCE) -> Prediction:
    """The validation RMS `fit` predicts at joints `validation_q` (module docstring)."""
    q = np.atleast_2d(np.asarray(validation_q, dtype=float))
    dof = int(3 * np.count_nonzero(fit.used) - len(fit.indices))
    bound = sigma_upper_bound(fit.sigma, dof, confidence)
    scale = (bound / fit.sigma) ** 2 if fit.sigma > 0 else 0.0
    # the model's predicted points at all poses together: J Σθ Jᵀ (3N × 3N), σ at its bound
    J = Kinematics(fit.geometry).jacobian(q, fit.indices).reshape(-1, len(fit.indices))
    model = J @ (fit.covariance * scale) @ J.T
    mean_trace = float(np.trace(model)) / len(q)
    rms = float(np.sqrt(mean_trace + 3.0 * bound**2))
    # the residuals r = J δθ + ε share δθ across poses: the eigenvalues of their covariance give the
    # effective degrees of freedom of |r|², i.e. how much one campaign's RMS scatters about `rms`
    lam = np.linalg.eigvalsh(model + np.eye(len(model)) * bound**2)
    effective = float(lam.sum() ** 2 / np.sum(lam**2)) if np.all(np.isfinite(lam)) else float("nan")
    return Prediction(rms=rms, sigma=float(fit.sigma), sigma_bound=bound,
                      model_rms=float(np.sqrt(mean_trace)), dof=dof, effective_dof=effective)


class StoppingRule:
    """Judges, from the points measured so far, whether the remaining calibration poses are needed.

    `validation_q`: the planned validation targets (joints, rad); `acceptance`: the campaign's
    validation RMS threshold (m); `margin`: the fraction of it the prediction must reach
    (`campaign.stop_margin`). The fit uses the campaign's `compliance`, `payload` and `gravity`.
    """

    def __init__(self, robot: str, smr_guess: np.ndarray, validation_q: np.ndarray, acceptance: float,
                 margin: float = DEFAULT_MARGIN, *, compliance: bool = False,
                 payload: Payload | None = None, gravity: np.ndarray | None = None,
                 confidence: float | None = CONFIDENCE) -> None:
        if not 0.0 < margin <= 1.0:
            raise ValueError(f"margin must be in (0, 1], got {margin}")
        self.robot, self.smr_guess = robot, np.asarray(smr_guess, dtype=float)
        self.validation_q = np.asarray(validation_q, dtype=float).reshape(-1, 6)
        self.acceptance, self.margin, self.confidence = float(acceptance), float(margin), confidence
        self.compliance, self.payload, self.gravity = compliance, payload, gravity

    @property
    def target(self) -> float:
        """The predicted validation RMS (m) at or below which the rule stops."""
        return self.margin * self.acceptance

    def check(self, fitted: Measurements) -> Verdict:
        """The verdict on the points `fitted` (bootstrap and calibration, as the final fit takes them)."""
        m = len(fitted)
        if len(self.validation_q) == 0:
            return Verdict(False, "no validation poses planned to predict", self.target, m)
        try:
            fit = identify(fitted, self.robot, self.smr_guess, compliance=self.compliance,
                           payload=self.payload, gravity=self.gravity)
        except (InputError, IdentificationError, np.linalg.LinAlgError, ValueError) as exc:
            return Verdict(False, f"no fit yet: {exc}", self.target, m)
        prediction = predict_validation(fit, self.validation_q, self.confidence)
        if prediction.dof < MIN_DOF:
            return Verdict(False, f"{prediction.dof} residual degrees of freedom, the rule needs {MIN_DOF}",
                           self.target, m, prediction, fit)
        reached = prediction.rms <= self.target
        bound = ("σ̂" if self.confidence is None else f"σ ≤ {prediction.sigma_bound * 1e6:.1f} µm at "
                 f"{self.confidence:.0%}")
        words = (f"predicted validation RMS {prediction.rms * 1e3:.4f} mm "
                 f"{'<=' if reached else '>'} {self.margin:g} x acceptance {self.acceptance * 1e3:.4f} mm "
                 f"({bound}, {m} points fitted)")
        return Verdict(reached, words, self.target, m, prediction, fit)

    def record(self, verdict: Verdict, poses_used: int, poses_left: int) -> dict[str, Any]:
        """The JSON-ready record of a stop (the `AcquisitionStopped` event's and the result's
        ``stopping`` block): the verdict's figures, the rule's settings and the poses it saved."""
        p = verdict.prediction
        return {
            "stopped": verdict.stop, "reason": verdict.reason,
            "predicted_rms": None if p is None else p.rms, "target": verdict.target,
            "acceptance": self.acceptance, "margin": self.margin, "confidence": self.confidence,
            "poses_used": poses_used, "poses_left": poses_left, "fitted_points": verdict.fitted,
            "sigma": None if p is None else p.sigma, "sigma_bound": None if p is None else p.sigma_bound,
            "model_rms": None if p is None else p.model_rms,
            "effective_dof": None if p is None else p.effective_dof,
        }


class EarlyStop:
    """The rule as a running campaign applies it (`hil.campaign.calibration_plan.calibration_plan`).

    `rule` None: the rule is off (``campaign.stop_early`` false). `stored`: the record of a stop the
    store already holds (the campaign's `AcquisitionStopped` event): a resumed campaign keeps that
    decision as it was, without fitting again.
    """

    def __init__(self, rule: StoppingRule | None, stored: dict[str, Any] | None = None) -> None:
        self.rule = rule
        self.figures: dict[str, Any] | None = dict(stored) if stored else None
        self.last: Verdict | None = None
        self.calibration_measured = 0

    @property
    def stopped(self) -> bool:
        """The remaining calibration poses are not to be visited."""
        return bool(self.figures and self.figures.get("stopped"))

    def consider(self, campaign: str, fitted: list[PoseRecord], calibration_measured: int,
                 left: list[int]) -> AcquisitionStopped | None:
        """Check the rule on the points `fitted` (bootstrap and calibration records in index order);
        the event to emit when it says stop (`left`: the calibration poses it saves), else None."""
        self.calibration_measured = calibration_measured
        if self.rule is None or self.stopped or not left:
            return None
        meas = Measurements.from_arrays(np.array([r.q for r in fitted]), np.array([r.p for r in fitted]),
                                        f"campaign {campaign} so far",
                                        lines=np.array([r.index for r in fitted], dtype=int))
        self.last = verdict = self.rule.check(meas)
        if not verdict.stop or verdict.predicted_rms is None:
            return None
        self.figures = self.rule.record(verdict, calibration_measured, len(left))
        return AcquisitionStopped(campaign=campaign, reason=verdict.reason,
                                  predicted_rms=verdict.predicted_rms, target=verdict.target,
                                  poses_used=calibration_measured, poses_left=len(left),
                                  skipped=list(left), figures=self.figures)

    def summary(self) -> dict[str, Any] | None:
        """The result's ``stopping`` block: the stop's record, or (rule on, no stop) the last check's
        figures with ``stopped`` false — every planned calibration pose was needed; None: rule off."""
        if self.figures is not None:
            return dict(self.figures)
        if self.rule is None:
            return None
        if self.last is None:
            return {"stopped": False, "reason": "not checked: no calibration pose measured in this run",
                    "target": self.rule.target, "acceptance": self.rule.acceptance,
                    "margin": self.rule.margin, "confidence": self.rule.confidence,
                    "poses_used": self.calibration_measured, "poses_left": 0}
        return self.rule.record(self.last, self.calibration_measured, 0)


def stopped_words(stopping: dict[str, Any] | None) -> str:
    """The summary line's clause for a run the rule stopped ("" otherwise): how many calibration poses
    it measured and saved, and the prediction it stopped on."""
    if not stopping or not stopping.get("stopped"):
        return ""
    used, left = stopping.get("poses_used"), stopping.get("poses_left")
    predicted = stopping.get("predicted_rms")
    said = f", predicted {predicted * 1e3:.4f} mm" if isinstance(predicted, int | float) else ""
    return f"; stopped early after {used} of {int(used or 0) + int(left or 0)} calibration poses{said}"
