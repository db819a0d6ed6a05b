"""Held-out errors of a model with a tool frame or several reflectors, on a 6-D or several-reflector
file: what `hil validate` reports beyond the first reflector's distances.

A model fitted by the 6-D fit (`hil.calibration.pose_identification`) carries the measured frame's
orientation in the flange frame and every reflector's offset (`hil.arm.tool_frame`). Checking such a
model on its first reflector's positions alone would leave the part of it the orientations fixed
unchecked, so the validation uses everything the file and the model share: every reflector the model
knows (distances, per reflector and together) and, when both have them, the orientations (the angle
of log(R_measured · R_modelᵀ)). What the file holds and the model cannot predict is said, one sentence
each, never dropped silently.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hil.arm.geometry import Geometry
from hil.arm.tool_frame import predict, reflector_offsets, rotation_residuals
from hil.calibration.identification import ErrorStats
from hil.calibration.measurements import Measurements


@dataclass(frozen=True)
class AngleStats:
    """Angles (rad) between predicted and measured frames."""

    count: int
    mean: float
    rms: float
    max: float

    @classmethod
    def of(cls, angles: np.ndarray) -> AngleStats:
        a = np.asarray(angles, dtype=float)
        return cls(len(a), float(a.mean()), float(np.sqrt(np.mean(a**2))), float(a.max()))

    def as_dict(self) -> dict[str, float | int]:
        return {"count": self.count, "mean_rad": self.mean, "rms_rad": self.rms, "max_rad": self.max}


@dataclass(frozen=True)
class ToolValidation:
    """The errors a tool-frame or several-reflector check adds to the first reflector's."""

    reflectors: int  # reflectors compared (1: the first alone)
    per_reflector: tuple[ErrorStats, ...]  # each compared reflector's distances
    all_reflectors: ErrorStats | None  # every compared reflector's distances together (None with one)
    orientation: AngleStats | None  # None when the file or the model has no orientation
    notes: list[str] = field(default_factory=list)

    def as_dict(self) -> dict[str, object]:
        out: dict[str, object] = {"reflectors": self.reflectors}
        if self.reflectors > 1:
            out["per_reflector"] = [s.as_dict() for s in self.per_reflector]
            out["all_reflectors"] = None if self.all_reflectors is None else self.all_reflectors.as_dict()
        out["orientation"] = None if self.orientation is None else self.orientation.as_dict()
        return out


def validate_tool(geometry: Geometry, meas: Measurements) -> ToolValidation | None:
    """The orientation and further-reflector errors of `geometry` on `meas`; None when the file holds
    neither orientations nor further reflectors (the first reflector's check is then all there is)."""
    file_reflectors = 1 if meas.reflectors is None else meas.reflectors.shape[1]
    if meas.rotation is None and file_reflectors == 1:
        return None
    notes: list[str] = []
    model_reflectors = len(reflector_offsets(geometry))
    compared = min(file_reflectors, model_reflectors)
    if file_reflectors > model_reflectors:
        notes.append(f"{meas.source}: {file_reflectors} reflectors per pose read; the model knows "
                     f"{model_reflectors}, so reflectors {model_reflectors + 1}..{file_reflectors} are "
                     "not checked")
    points, frames = predict(geometry, meas.q)
    measured = meas.p[:, None, :] if meas.reflectors is None else meas.reflectors
    per = tuple(ErrorStats.of(measured[:, k] - points[:, k]) for k in range(compared))
    together = ErrorStats.of((measured[:, :compared] - points[:, :compared]).reshape(-1, 3)) \
        if compared > 1 else None
    orientation: AngleStats | None = None
    if meas.rotation is not None:
        if geometry.tool_rotation is None:
            notes.append(f"{meas.source}: {len(meas)} orientations read but not checked: the model has "
                         "no tool frame (it was fitted to positions)")
        else:
            residual = rotation_residuals(meas.rotation, frames)
            orientation = AngleStats.of(np.linalg.norm(residual, axis=1))
    return ToolValidation(compared, per, together, orientation, notes)
