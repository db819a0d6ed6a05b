"""The controller's own kinematic model in a campaign: what it reported, and how far it is from the truth.

A UR controller moves, reports ``actual_TCP_pose`` and solves IK with its nominal DH table plus the
factory deltas it publishes as KinematicsInfo (robot-state message 16, sub-package 5;
docs/design.md, "Contracts: the
controller's own calibration"). A campaign keeps that model (`controller_record`: the same JSON in
the result's ``robot_info``, the store's ``campaigns.controller`` / ``robots.controller`` and, as its
deltas, checksums and status, the model file's ``controller`` block) and measures how far it is from
what the tracker saw (`controller_validation`), beside hil's model before and after calibration.

How the controller's model is judged: exactly as "before calibration" judges the nominal arm — its
joints and flange kept, the tracker pose and SMR offset fitted to the calibration points (`register`
with ``arm=``), the errors taken on the held-out validation poses. Taking hil's *fitted* tracker pose
and SMR offset instead would charge the controller with a choice of frames that is not its error: the
tracker's measurements cannot fix where the base frame is (hil holds joint 1's origin nominal and
lets the tracker pose absorb it, the controller carries its own δd1 and δθ1), nor the flange frame's
turn about its axis (hil's SMR offset is in the nominal flange frame, the controller's flange turns
by δθ6: about 50 mm × 1 mrad = 50 µm for an SMR 5 cm off the axis, as large as a good calibration's
whole error). Each model with its own registration is the like-for-like comparison.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from hil.arm.controller_model import DELTA_KEYS, ControllerCalibration
from hil.calibration.identification import ErrorStats, register, validate
from hil.calibration.measurements import Measurements

#: KinematicsInfo's fields in package order (docs/design.md, Facts: UR primary interface): full DH per joint.
DH_KEYS: tuple[str, ...] = ("dh_theta", "dh_a", "dh_d", "dh_alpha")


def _field(kinematics: Any, key: str) -> Any:
    return kinematics.get(key) if isinstance(kinematics, Mapping) else getattr(kinematics, key, None)


def _six(value: Any) -> list[float] | None:
    try:
        out = [float(v) for v in value]
    except (TypeError, ValueError):
        return None
    return out if len(out) == 6 and all(math.isfinite(v) for v in out) else None


def controller_record(robot: str, kinematics: Any) -> dict[str, Any] | None:
    """The controller's model as kept with a campaign, or None when it did not report a usable one.

    `kinematics` is the driver's KinematicsInfo (``ControllerInfo.kinematics``: ``checksum``, ``dh_theta``
    … ``dh_alpha``, ``calibration_status``) or its ``as_dict()``. The record is one flat JSON object:
    those fields as the controller sent them, plus the deltas to `robot`'s nominal DH (the
    ``controller`` block of docs/design.md, Contracts: the controller's own calibration), so any
    reader finds the block it knows in it. The deltas are
    not bounded here: they are the controller's own word, and a real one carries cancelling d values
    on the parallel joints far beyond a file's plausibility limits.
    """
    if kinematics is None:
        return None
    dh = [_six(_field(kinematics, key)) for key in DH_KEYS]
    if any(values is None for values in dh):
        return None
    theta, a, d, alpha = (np.array(v) for v in dh)
    deltas = ControllerCalibration.from_dh(robot, theta, a, d, alpha)
    return {
        "checksum": _integers(_field(kinematics, "checksum")),
        **{key: list(values) for key, values in zip(DH_KEYS, dh, strict=True)},
        "calibration_status": _integer(_field(kinematics, "calibration_status")),
        **deltas.to_dict(),
    }


def _integer(value: Any) -> int | None:
    return int(value) if isinstance(value, int | np.integer) and not isinstance(value, bool) else None


def _integers(value: Any) -> list[int] | None:
    try:
        out = [_integer(v) for v in value]
    except TypeError:
        return None
    ints = [v for v in out if v is not None]
    return ints if len(ints) == len(out) else None


def controller_calibration(record: Mapping[str, Any]) -> ControllerCalibration:
    """The deltas of a record as a `ControllerCalibration` (unbounded: see `controller_record`)."""
    return ControllerCalibration(**{key: np.asarray(record[key], float) for key in DELTA_KEYS})


def controller_validation(calibration: ControllerCalibration, robot: str, fitted: Measurements,
                          held_out: Measurements, smr_guess: np.ndarray | None = None) -> ErrorStats:
    """Errors of the controller's own model on the held-out poses (see the module docstring).

    The tracker pose and SMR offset are fitted for the controller's arm on `fitted` (the campaign's
    calibration and bootstrap points, as "before calibration" is), then its predictions are compared
    with `held_out`.
    """
    located = register(fitted, robot, smr_guess, arm=calibration.geometry(robot))
    return validate(located, held_out)
