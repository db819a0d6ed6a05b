"""A campaign's verdict: accepted only if the calibration helps the arm and reaches what it can reach.

The old default (validation RMS ≤ 0.1 mm) was a simulator's floor: a real, well-calibrated UR5 reaches
about 0.2 mm held-out (docs/design.md, Facts: what real arms reach) and would be rejected. The verdict
now asks what the arm and the instrument can give:

1. **Better than what the arm already has**: cross-validation (`hil.calibration.cross_validation`) shows
   the calibrated model predicting held-out poses better than the nominal model and, when the controller
   reported its own, better than that. Always required, whatever the threshold: a model that may make the
   arm worse is never accepted.
2. **The validation agrees with the cross-validated floor**: the validation RMS is at most
   `floor_factor` × the cross-validated RMS of the calibrated model (`FLOOR_FACTOR`, more for very few
   validation poses: below). Cross-validation on the fitted poses
   predicts what validation will measure (both are measured points, noise included); a validation far
   above it says something changed between the two (the arm warmed, the tracker or the base moved, a
   pose set that covers the workspace badly), which the fit cannot vouch for. When the stopping rule
   ended the acquisition early (`hil.campaign.stopping`), the campaign stopped on its own prediction of
   the validation RMS (the parameters' covariance at the validation poses, σ at its upper bound), so that
   prediction is the floor when it is the larger: with few poses, leave-one-fold-out refits sit close
   to their neighbours and cross-validation reads optimistic (a simulated run stopped at 14 poses:
   cross-validated 0.021 mm, predicted 0.076 mm, validation 0.066 mm — as predicted, and rejected
   against 2 × 0.021 mm before).
3. **An absolute bound for the robot class**: validation RMS ≤ `class_bound` of the robot.

A threshold the user sets (``campaign.acceptance``, ``hil calibrate --accept``) replaces 2 and 3 by
"validation RMS ≤ threshold" as before; 1 still holds.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from hil.arm.catalog import get_robot

#: Held-out RMS a calibrated real UR5 (CB3, 0.85 m reach) reaches: 0.19–0.21 mm by 13-fold
#: cross-validation of 39 Leica-tracker poses (the shared real data; docs/design.md, Facts: what real
#: arms reach).
REAL_UR5_CALIBRATED = 0.21e-3  # m
REAL_UR5_REACH = 0.85  # m (UR5 datasheet)
#: The class bound is this many times the real UR5's figure, scaled by reach: hil's assumption. One
#: measured arm is not a distribution; 2.5× leaves room for a worse arm, a shorter session and a
#: position-only SMR on a larger payload, and still rejects a calibration that failed (a UR5's nominal
#: model is at 1.4 mm, 2.8 times the bound).
CLASS_MARGIN = 2.5
#: Validation RMS allowed above the cross-validated RMS: the validation RMS of N poses scatters about
#: its expectation by up to ~1.4× at 20 effective degrees of freedom (99th percentile of √(χ²_ν/ν);
#: `hil.campaign.stopping.DEFAULT_MARGIN`), and the cross-validated figure has a scatter of its own
#: (0.83–1.17 of the error on 1000 fresh poses over 12 synthetic stations, as in
#: tests/hil/calibration/test_cross_validation.py).
#: Measured on 24 realistic synthetic UR5e/UR10e stations (30 random calibration poses, compliance fitted,
#: 20 µm): validation RMS / cross-validated RMS 0.53–1.30 with 4 validation poses, 0.64–1.50 with 10.
FLOOR_FACTOR = 2.0
#: Few validation poses make the comparison noisy: with n validation poses and N cross-validated ones,
#: (validation RMS / cross-validated RMS)² of one error distribution is F-distributed with (3n, 3N)
#: degrees of freedom (three coordinates a pose; Gaussian errors). The factor applied is at least the
#: square root of that ratio's `FLOOR_QUANTILE` quantile, so that noise alone rejects at most one sound
#: campaign in a thousand: it exceeds `FLOOR_FACTOR` only below three validation poses (1 pose against
#: 24: 2.45; 2: 2.05; 4: 1.73, so 2.0 holds).
FLOOR_QUANTILE = 0.999


def floor_factor(validation_poses: int | None, cross_validated_poses: int | None) -> float:
    """The factor the validation RMS may exceed the cross-validated RMS by (module docstring):
    `FLOOR_FACTOR`, or the F-test bound for these pose counts when that is larger. Unknown counts:
    `FLOOR_FACTOR`."""
    if not validation_poses or not cross_validated_poses:
        return FLOOR_FACTOR
    from scipy.stats import f  # on first use: the CLI's help and listings import this module

    bound = float(np.sqrt(f.ppf(FLOOR_QUANTILE, 3 * int(validation_poses), 3 * int(cross_validated_poses))))
    return max(FLOOR_FACTOR, bound)


def class_bound(robot: str) -> float:
    """Absolute bound (m) on a calibrated arm's validation RMS for `robot`'s class (module docstring)."""
    return CLASS_MARGIN * REAL_UR5_CALIBRATED * max(get_robot(robot).reach / REAL_UR5_REACH, 1.0)


def threshold(acceptance: float | None, robot: str) -> float:
    """The RMS threshold a campaign works to before it has a fit: the user's, else the class bound.

    The stopping rule and the live colours use it; the verdict may end tighter (`judge`)."""
    return float(acceptance) if acceptance is not None else class_bound(robot)


@dataclass(frozen=True)
class Verdict:
    """A campaign's verdict and its reason, one line."""

    passed: bool
    threshold: float  # the validation RMS threshold applied (m): the user's, or min(floor, class bound)
    reason: str
    rule: str  # "threshold" (the user's) or "auto"
    floor_factor: float = FLOOR_FACTOR  # the factor applied to the cross-validated RMS (`floor_factor`)

    def as_dict(self) -> dict[str, Any]:
        return {"passed": self.passed, "threshold": self.threshold, "reason": self.reason,
                "rule": self.rule, "floor_factor": self.floor_factor, "class_margin": CLASS_MARGIN}


def judge(validation_rms: float, cross_validation: Any, robot: str,
          acceptance: float | None = None, validation_poses: int | None = None,
          predicted: float | None = None) -> Verdict:
    """The verdict of a campaign whose validation RMS is `validation_rms` (m) over `validation_poses`
    poses (None: unknown, `FLOOR_FACTOR` applies).

    `cross_validation`: the fit's `CrossValidation`; `acceptance`: the user's threshold (None: the
    automatic rule of the module docstring); `predicted`: the validation RMS (m) the stopping rule
    stopped the acquisition on (None: it did not stop it).
    """
    factor = floor_factor(validation_poses, getattr(cross_validation, "poses", None))
    rms = f"validation RMS {validation_rms * 1e3:.4f} mm"
    if acceptance is not None:
        limit, rule = float(acceptance), "threshold"
        said = f"acceptance {limit * 1e3:.4f} mm"
    else:
        cv_rms = float(cross_validation.calibrated.rms)
        stopped_on = predicted is not None and np.isfinite(predicted) and predicted > cv_rms
        reference = float(predicted) if stopped_on else cv_rms
        floor = factor * reference
        bound = class_bound(robot)
        limit, rule = min(floor, bound), "auto"
        what = (f"the stopping rule's predicted {reference * 1e3:.4f} mm (cross-validated "
                f"{cv_rms * 1e3:.4f} mm)" if stopped_on else f"the cross-validated {cv_rms * 1e3:.4f} mm")
        said = f"{factor:.3g} x {what}" if floor <= bound else f"the {robot} class bound {bound * 1e3:.4f} mm"
    if not cross_validation.better_than_nominal:
        return Verdict(False, limit, cross_validation.verdict(), rule, factor)
    passed = validation_rms <= limit
    return Verdict(passed, limit, f"{rms} {'<=' if passed else '>'} {said}", rule, factor)
