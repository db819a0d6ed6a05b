"""The report of an identification rather than a campaign: ``hil report --model``.

A campaign's report is rebuilt from its ``hil-result/1``; an arm that no campaign can drive (any serial
arm read from its URDF: the campaign stays UR) has only ``hil identify``'s ``hil-model/1``. That model
already holds what the report's fit sections show (parameters, covariance, fit figures, rejected poses,
cross-validation, and for a URDF arm the URDF itself, so its kinematics need nothing else). This module
turns it into a ``hil-result/1``-shaped document, so the one reader (`report_data_from_result`) and the
one renderer serve both, with no second report layout to keep in step:

* **validation** — with the held-out measurements (`validation`), per pose: the model against the
  nominal arm registered (tracker pose and SMR offset fitted, `identification.register`) on the
  calibration measurements, as a campaign's "before" is; on the validation poses themselves when no
  calibration file is given (said in a note). Without them, the model's own cross-validation figures
  (calibrated and nominal, held out fold by fold), said in a note.
* **calibration** — with the measurements the model was fitted to (`calibration`; their sha256 must be
  the model's ``input.sha256``), the per-pose residuals before and after and which poses the fit kept.
* **verdict** — with `accept_rms`, validation RMS ≤ it; without, the campaign's automatic rule
  (`hil.campaign.acceptance`: better than nominal under cross-validation, and the validation RMS at most
  `FLOOR_FACTOR` × the cross-validated one and the class bound for the arm's reach). Either way a model
  cross-validation does not show better than the nominal is a FAIL.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.calibration.identification import register
from hil.calibration.measurements import Measurements
from hil.calibration.model_file import MODEL_FORMAT, RESULT_FORMAT, check_geometry_block
from hil.calibration.synthetic import chain_reach
from hil.campaign.acceptance import (
    CLASS_MARGIN,
    FLOOR_FACTOR,
    REAL_UR5_CALIBRATED,
    REAL_UR5_REACH,
    class_bound,
)
from hil.errors import InputError


def result_from_model(doc: Mapping[str, Any], source: str, *, calibration: Measurements | None = None,
                      validation: Measurements | None = None,
                      accept_rms: float | None = None) -> dict[str, Any]:
    """A ``hil-result/1`` document for the ``hil-model/1`` `doc` read from `source` (module docstring)."""
    if doc.get("format") != MODEL_FORMAT:
        raise InputError(f"{source}: field 'format' is {doc.get('format')!r}, expected {MODEL_FORMAT}")
    check_geometry_block(dict(doc), source)
    geometry = Geometry.from_dict(dict(doc), source=source)
    robot = geometry.chain if geometry.chain is not None else geometry.robot  # a UR: its catalog name
    notes = [f"Built from the identification {source} (hil identify), not from a campaign: there is no "
             "station, warm-up, drift watch or event log to show."]
    per_pose: dict[str, Any] = {}
    baseline = None
    if calibration is not None:
        _check_fitted_data(doc, calibration, source)
        baseline = register(calibration, robot, smr_guess=geometry.smr)
        per_pose["calibration"] = {
            "before": _errors(baseline, calibration).tolist(),
            "after": _errors(geometry, calibration).tolist(),
            "used": _used(doc, len(calibration), source).tolist(),
            "lines": [int(v) for v in calibration.lines],
            "line_kind": "input line"}
    if validation is not None:
        if baseline is None:
            baseline = register(validation, robot, smr_guess=geometry.smr)
            notes.append(f"Before calibration: the nominal arm with the tracker and SMR registered on the "
                         f"validation poses of {validation.source} (no calibration measurements given).")
        before, after = _errors(baseline, validation), _errors(geometry, validation)
        per_pose["validation"] = {"before": before.tolist(), "after": after.tolist(),
                                  "lines": [int(v) for v in validation.lines]}
        figures = {"before": _summary(before), "after": _summary(after)}
    else:
        cv = doc.get("cross_validation")
        if not isinstance(cv, Mapping) or not all(isinstance(cv.get(k), Mapping)
                                                  for k in ("calibrated", "nominal")):
            raise InputError(f"{source}: the model has no cross_validation block; give the held-out "
                             "measurements with --validation")
        figures = {"before": dict(cv["nominal"]), "after": dict(cv["calibrated"])}
        notes.append(f"Validation figures are the model's {cv.get('folds', '?')}-fold cross-validation "
                     "on its calibration poses (no --validation file): each pose predicted by a model "
                     "fitted without it.")
    verdict = _verdict(doc, figures["after"], robot, accept_rms, source)
    return {"format": RESULT_FORMAT, "campaign": "", "station": "", "robot": str(doc.get("robot") or ""),
            "accept_rms": verdict["threshold"], "passed": verdict["passed"], "verdict": verdict,
            "model": dict(doc), "validation": figures, "per_pose": per_pose,
            "hashes": _hashes(doc, validation), "notes": notes,
            "started": None, "finished": None}


def _errors(geometry: Geometry, meas: Measurements) -> np.ndarray:
    """(m, 3) measured − predicted positions (m, tracker frame)."""
    return meas.p - Kinematics(geometry).points(meas.q, directions=meas.directions)


def _summary(errors: np.ndarray) -> dict[str, float]:
    norms = np.linalg.norm(errors, axis=1)
    return {"count": len(norms), "mean": float(norms.mean()), "rms": float(np.sqrt(np.mean(norms**2))),
            "max": float(norms.max())}


def _check_fitted_data(doc: Mapping[str, Any], meas: Measurements, source: str) -> None:
    """The calibration file must be the one the model was fitted to: its rows and lines are what the
    model's rejected poses name."""
    recorded = (doc.get("input") or {}).get("sha256") if isinstance(doc.get("input"), Mapping) else None
    if recorded and meas.sha256 and recorded != meas.sha256:
        raise InputError(f"{meas.source}: not the measurements {source} was fitted to (sha256 "
                         f"{meas.sha256[:12]}…, the model's input.sha256 is {str(recorded)[:12]}…)")


def _used(doc: Mapping[str, Any], count: int, source: str) -> np.ndarray:
    """(count,) bool: the poses the fit kept (its ``fit.rejected`` poses are not)."""
    used = np.ones(count, dtype=bool)
    for r in (doc.get("fit") or {}).get("rejected") or []:
        pose = r.get("pose") if isinstance(r, Mapping) else None
        if isinstance(pose, bool) or not isinstance(pose, int) or not 0 <= pose < count:
            raise InputError(f"{source}: field 'fit.rejected[].pose' must be a pose of the calibration "
                             f"file (0..{count - 1}), got {pose!r}")
        used[pose] = False
    return used


def _verdict(doc: Mapping[str, Any], after: Mapping[str, Any], robot: Any, accept_rms: float | None,
             source: str) -> dict[str, Any]:
    """The ``verdict`` block (module docstring): `accept_rms`, or the campaign's automatic rule."""
    rms = after.get("rms")
    if isinstance(rms, bool) or not isinstance(rms, int | float):
        raise InputError(f"{source}: the validation RMS is not a number")
    better = doc.get("better_than_nominal")
    said_rms = f"validation RMS {rms * 1e3:.4f} mm"
    if accept_rms is not None:
        limit, rule, said = float(accept_rms), "threshold", f"acceptance {accept_rms * 1e3:.4f} mm"
    else:
        cv = (doc.get("cross_validation") or {}).get("calibrated") or {}
        floor = FLOOR_FACTOR * float(cv.get("rms", np.inf))
        reach = chain_reach(robot) if not isinstance(robot, str) else None
        bound = class_bound_for_reach(reach) if reach is not None else class_bound(robot)
        limit, rule = min(floor, bound), "auto"
        said = (f"{FLOOR_FACTOR:g} x the cross-validated {cv.get('rms', float('nan')) * 1e3:.4f} mm"
                if floor <= bound else f"the class bound {bound * 1e3:.4f} mm")
    if better is False:
        return {"passed": False, "threshold": limit, "rule": rule,
                "reason": "cross-validation does not show the model better than the nominal"}
    passed = bool(rms <= limit)
    return {"passed": passed, "threshold": limit, "rule": rule,
            "reason": f"{said_rms} {'<=' if passed else '>'} {said}"}


def class_bound_for_reach(reach: float) -> float:
    """`hil.campaign.acceptance.class_bound` for an arm of `reach` metres (a URDF arm's, from its chain:
    `chain_reach`, an upper bound of its reach), the real UR5's figure scaled the same way."""
    return CLASS_MARGIN * REAL_UR5_CALIBRATED * max(reach / REAL_UR5_REACH, 1.0)


def _hashes(doc: Mapping[str, Any], validation: Measurements | None) -> dict[str, str]:
    out: dict[str, str] = {}
    block = doc.get("input")
    if isinstance(block, Mapping) and block.get("sha256"):
        out["calibration measurements"] = str(block["sha256"])
    if validation is not None and validation.sha256:
        out["validation measurements"] = validation.sha256
    urdf = doc.get("urdf")
    if isinstance(urdf, Mapping) and urdf.get("sha256"):
        out["URDF"] = str(urdf["sha256"])
    return out
