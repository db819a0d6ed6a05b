"""Cross-validation of a 6-D or several-reflector fit, judged as the position fit is.

The folds, the one-step fold fits warm-started from the full fit, the MAP prior and the nominal (and
controller's) model registered in each fold, and the scoring of the poses the fit rejected as outliers
(every pose is scored held out: `score_folds`), are `hil.calibration.cross_validation`'s; here the rows of
a pose are every reflector's position and the measured frame's orientation, each divided by its stated
noise (`hil.calibration.pose_identification`). The nominal model fits what places the tool and the
instrument: tracker pose, SMR offset, tool rotation, further reflectors.

**Better or not.** The same one-sided test at `SIGNIFICANCE` (the folds' log ratios), on each pose's
held-out error in units of σ: the sum of its squared position errors over σ_p² and orientation errors
over σ_o² — the quantity the fit minimises, so a model counts as better only when it predicts the
whole measurement better, not one kind at the other's cost. The figures are reported in their own
units: the position errors of every reflector in metres (``calibrated``, ``nominal``, ``controller``
as for a position fit) and the orientation errors in radians (the ``orientation`` block).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hil.arm import tool_frame as tf
from hil.arm.geometry import Geometry
from hil.calibration.cross_validation import (
    SIGNIFICANCE,
    CrossValidation,
    held_out_residuals,
    ratio_p_value,
    score_folds,
)
from hil.calibration.identification import ErrorStats, FitResult
from hil.calibration.measurements import Measurements
from hil.calibration.pose_identification import PoseFit, identify_pose, whitened

#: What the verdict of a 6-D fit is judged on, as results state it.
JUDGED_ON = ("per-pose sum of squared held-out position and orientation errors, each over its stated "
             "noise squared")


@dataclass(frozen=True)
class PoseCrossValidation(CrossValidation):
    """`CrossValidation` of a 6-D / several-reflector fit: positions in metres (every reflector),
    orientations in radians, and the verdict on each pose's whitened squared error."""

    orientation: dict[str, ErrorStats | None] = field(default_factory=dict)  # rad, by model
    scores: dict[str, np.ndarray] = field(default_factory=dict)  # (poses,) whitened squared errors

    def p_value(self, other: ErrorStats) -> float:
        """As `CrossValidation.p_value`, on the whitened per-pose errors (module docstring)."""
        name = "nominal" if other is self.nominal else "controller" if other is self.controller else None
        if name is None or name not in self.scores:
            return super().p_value(other)
        return ratio_p_value(self.scores[name], self.scores["calibrated"], self.folds)

    def verdict(self) -> str:
        """`CrossValidation.verdict`, with the orientation figures when there are any."""
        line = super().verdict()
        if not self.orientation:
            return line
        shown = ", ".join(f"{k} {v.rms * 1e3:.3f} mrad" for k, v in self.orientation.items() if v is not None)
        return f"{line}; orientation RMS: {shown}"

    def as_dict(self) -> dict[str, Any]:
        """`CrossValidation.as_dict` plus the ``orientation`` block (rad) and what was judged."""
        out = super().as_dict()
        out["orientation"] = ({k: None if v is None else v.as_dict() for k, v in self.orientation.items()}
                              if self.orientation else None)
        out["judged_on"] = JUDGED_ON
        return out


def _held_out(meas: Measurements, geometry: Geometry, info: PoseFit, cols: np.ndarray, fold: np.ndarray,
              train: np.ndarray, weights: np.ndarray | None = None,
              offset: np.ndarray | None = None) -> tuple[ErrorStats, ErrorStats | None, np.ndarray]:
    """Held-out position errors (every reflector), orientation errors and per-pose scores of the model
    `geometry` whose columns `cols` are refitted in each fold on the `train` poses (the others
    predicted by the fit on all of them)."""
    r, J = whitened(meas, geometry, info)
    err = held_out_residuals(r, J[:, :, cols], fold, weights, offset, train)
    score = np.sum(err * err, axis=1)
    physical = err * info.whiten()
    positions = ErrorStats.of(physical[:, : 3 * info.reflectors])
    orientation = ErrorStats.of(physical[:, -3:]) if info.orientation else None
    return positions, orientation, score


def cross_validate_pose(meas: Measurements, fit: FitResult, *, controller: Geometry | None = None,
                        folds: int | None = None, smr_guess: np.ndarray | None = None) -> PoseCrossValidation:
    """Cross-validate the 6-D / several-reflector `fit` (made from `meas` by `identify_pose`) beside the
    nominal model and, when given, the controller's own arm, on the same folds; every pose of `meas` is
    scored, those the fit rejected included (`score_folds`)."""
    t0 = time.perf_counter()
    info: PoseFit = fit.pose_fit
    used, fold = score_folds(fit.used, folds)
    sub = meas.subset(used)
    offset = None
    if fit.prior is not None and fit.prior_weights is not None:
        offset = fit.values - fit.prior.mean
    cal, cal_o, cal_s = _held_out(meas, fit.geometry, info, info.local, fold, used, fit.prior_weights,
                                  offset)
    reg = tf.registration_columns(info.reflectors, info.orientation)
    assert fit.baseline is not None  # identify_pose always registers the nominal first
    nom, nom_o, nom_s = _held_out(meas, fit.baseline, info, reg, fold, used)
    orientation: dict[str, ErrorStats | None] = {}
    if info.orientation:
        orientation = {"calibrated": cal_o, "nominal": nom_o}
    scores = {"calibrated": cal_s, "nominal": nom_s}
    theirs = None
    if controller is not None:
        located = identify_pose(sub, fit.robot, fit.geometry.smr if smr_guess is None else smr_guess,
                                position_noise=info.position_noise,
                                orientation_noise=info.orientation_noise, arm=controller,
                                registration_only=True, reject_outliers=False, prior=False).baseline
        assert located is not None
        theirs, their_o, scores["controller"] = _held_out(meas, located, info, reg, fold, used)
        if info.orientation:
            orientation["controller"] = their_o
    return PoseCrossValidation(int(fold.max()) + 1, len(meas), cal, nom, theirs, time.perf_counter() - t0,
                               int((~used).sum()), orientation, scores)


__all__ = ["JUDGED_ON", "SIGNIFICANCE", "PoseCrossValidation", "cross_validate_pose"]
