"""The JSON result a plant's MES (manufacturing execution system) reads after each campaign.

An MES maps fields by name into its own database, so the keys below are a contract: new keys may be
added, none is renamed or removed within ``hil-result/1``. Non-finite numbers are written as
``null`` (JSON has no NaN).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hil.report.data import RESULT_FORMAT, ErrorSet, ReportData


def _plain(value: Any) -> Any:
    """JSON-ready copy: arrays and tuples become lists, numpy scalars floats, NaN/inf null."""
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, np.generic):
        return _plain(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


#: The ``units`` block of every result: what its numbers are in (it is in SI; the report and the
#: terminal show millimetres and milliradians).
UNITS = {
    "length": "m",  # accept_rms, validation, fit, per_pose, tracker_pose.xyz, model (geometry, parameters)
    "angle": "rad",  # tracker_pose.rpy (URDF roll/pitch/yaw), model rpy and rotation parameters
    "time": "s",  # times (except times.retries, a count), fit seconds, suspensions waited
    "timestamps": "ISO 8601 (started, finished); Unix seconds (suspensions t)",
}


def _per_pose(errors: ErrorSet | None) -> list[Any] | None:
    if errors is None or not errors.per_pose:
        return None
    return (errors.vectors if errors.vectors is not None else errors.norms).tolist()


def mes_result(data: ReportData) -> dict[str, Any]:
    """The ``hil-result/1`` document of a campaign (lengths in metres, times in seconds).

    Keys (stable within ``hil-result/1``; readers must ignore keys they do not know):

    * ``format``: ``"hil-result/1"``
    * ``campaign``: campaign id; ``station``: station name
    * ``robot``: catalog type (``"ur5e"``); ``robot_serial``, ``robot_software``: as the controller
      reports them (``""`` when unknown)
    * ``passed``: bool, the campaign's verdict (``verdict``): validation RMS ≤ ``accept_rms`` (metres)
      and, for a cross-validated model, ``better_than_nominal``
    * ``accept_rms``: the threshold applied (m): the user's ``campaign.acceptance``, or without one
      min(2 × the cross-validated RMS, the robot class's bound) (`hil.campaign.acceptance`)
    * ``verdict`` (a campaign's): ``{"passed", "threshold": m, "reason": one line, "rule": "threshold" |
      "auto", "floor_factor", "class_margin"}``
    * ``cross_validation`` and ``better_than_nominal`` (when the model was cross-validated): the model's
      block (`hil.calibration.cross_validation`: ``folds``, ``rule``, ``poses``, ``calibrated``,
      ``nominal``, ``controller`` (S or null, S as under ``validation``), ``better_than_nominal``,
      ``better_than_controller``, ``p_value_nominal``, ``p_value_controller``, ``significance``,
      ``seconds``), repeated at the top level for readers of the result alone
    * ``started``, ``finished``: ISO 8601 or null
    * ``validation``: ``{"before": S, "after": S, "iso9283": {"AP": m, "RP": m, ...} | null}``
      where S is ``{"count", "mean", "rms", "max"}``; *before* is the nominal arm (only the tracker
      pose and SMR fitted), *after* the calibrated model, both on held-out poses; plus
      ``"controller": S`` when the controller reported its own kinematic model (that model, the
      tracker pose and SMR fitted for it, on the same poses; its deltas are ``model.controller``);
      plus, for a campaign, ``"precision": {"design": "simple random" | "clustered", "poses": n,
      "clusters": k | null, "rms_standard_error": m | null, "design_effect": float | null}``: the
      standard error of *after*'s RMS under the design that chose the validation poses
      (`hil.calibration.validation_precision`)
    * ``fit``: ``{"rms", "max", "sigma", "initial_rms", "iterations", "condition", "poses", "used",
      "rejected_lines"}`` (a summary; the full block is in ``model.fit``)
    * ``observability``: ``{"index", "value", "bound", "percent", "method"[, "tour"]}`` or null; ``tour``
      (time-aware selection only): ``{"poses", "robot_time": s, "relative_error", "seed_poses",
      "seed_robot_time": s, "reused": bool | null}``, the tour's prediction beside method 000's
    * ``times``: ``{"motion", "settle", "measure", "compute", ...}`` seconds per phase, plus
      ``total`` (the run's wall time, not a phase), ``events_in_motion`` (the part of ``motion`` spent
      committing points while the arm travelled: inside ``motion``, not a phase of its own) and
      ``retries`` (a count of retried pose visits), or null
    * ``suspensions``: list of ``{"kind", "message", "waited", "t"}``; ``notes``: list of strings
    * ``hashes``: ``{what: sha256}`` of the input data; ``software``: ``{package: version}``
    * ``config``: the station configuration as validated
    * ``model``: the full ``hil-model/1`` document (geometry, parameters, covariance, fit, ...);
      its ``tracker.tx … tracker.rz`` parameters are se(3) log coordinates, not a position
    * ``tracker_pose``: the tracker frame in the robot base frame in plain terms, ``{"xyz": m,
      "rpy": rad (URDF roll, pitch, yaw), "xyz_std", "rpy_std"}``
    * ``per_pose``: ``{"validation": {"before", "after", "lines"[, "controller"]}, "calibration":
      {"before", "after", "used", "lines", "line_kind"}}`` — per-pose errors as ``[x, y, z]`` lists
      (or distances; the controller's are distances), so the HTML report can be rebuilt from this
      file (``hil report``); entries may be null. ``lines``
      name the poses: campaign pose numbers (``line_kind`` ``"pose"``) or input file lines
      (``"input line"``)
    * ``units``: what the numbers above are in (`UNITS`: metres, radians, seconds)
    * ``verification`` (``hil calibrate --verify`` only): the ISO 9283 pose test of the calibrated
      model, its ``hil-verification/1`` document (``results`` per mode: AP and RP per pose), or
      ``{"status": "not run", "reason"}``
    * ``drift`` (when the warm-up or the drift watch was on): ``{"reference": q (rad), "every": N,
      "limit": m, "max": m | null, "flagged": bool, "baseline": seq | null, "series": [{"seq", "run",
      "phase": "warmup" | "drift", "elapsed": station s since the run started, "time": Unix s, "q",
      "xyz": m (tracker frame), "moved": m | null, "drift": m from the baseline | null, "baseline",
      "temperatures": °C | null}], "warmup": {"enabled", "interval", "limit", "max_time", "ran",
      "seconds", "converged", "reason", "remaining": m | null, "time_constant": s | null, "span": s |
      null, "remaining_upper": m | null, "time_constant_upper": s | null, "rule": "fit" | "flat" | "",
      "decision": str | null, "evidence": {...} | null, "runs": [{"run", "seconds", "converged",
      "references", "remaining", "time_constant", "span", "remaining_upper", "time_constant_upper",
      "rule", "decision"}]}}``: the warm-up's rule (`hil.calibration.warmup_decision`) judged
      ``remaining_upper`` (the most drift still to come the first-order fit allows; ``remaining`` its
      estimate) against ``limit`` and ``span`` (station seconds from the run's first warm-up measurement
      to its last) against three ``time_constant_upper``, or (``rule`` "flat") an arm warm from the
      start by its flat joint temperatures; ``decision`` says it in one line, ``evidence`` holds the last
      check's every figure (as its ``WarmupProgress`` event).
      ``flagged``: the reference drifted beyond ``limit`` while measuring; ``passed`` is still the
      validation's verdict alone
    * ``poses`` (a campaign's): ``{"bootstrap": C, "calibration": C, "validation": C}``, C =
      ``{"planned", "measured"}``: the bootstrap's poses are ``campaign.bootstrap_poses`` moves of the
      arm plus 4 wrist turns (none with ``tracker.position`` configured); validation counts every
      cycle; the fit uses the bootstrap and calibration poses measured (``fit.poses``)
    * ``stopping`` (when the stopping rule was on, ``campaign.stop_early``): ``{"stopped": bool,
      "reason", "predicted_rms": m, "target": m (margin × acceptance), "acceptance": m, "margin",
      "confidence", "poses_used", "poses_left": calibration poses measured and not visited,
      "fitted_points", "sigma": m, "sigma_bound": m, "model_rms": m, "effective_dof"}`` (the figures of
      the check that stopped the run, or of the last check when it did not stop)
    """
    obs = data.observability
    doc = _plain({
        "format": RESULT_FORMAT,
        "campaign": data.campaign,
        "station": data.station,
        "robot": data.robot.type,
        "robot_serial": data.robot.serial,
        "robot_software": data.robot.software,
        "passed": bool(data.passed),
        "accept_rms": data.accept_rms,
        "started": data.started,
        "finished": data.finished,
        "validation": {
            "before": data.validation_before.as_dict(),
            "after": data.validation_after.as_dict(),
            "iso9283": dict(data.iso9283) if data.iso9283 else None,
        },
        "fit": {
            "rms": data.fit.rms, "max": data.fit.max, "sigma": data.fit.sigma,
            "initial_rms": data.fit.initial_rms, "iterations": data.fit.iterations,
            "condition": data.fit.condition, "poses": data.fit.poses, "used": data.fit.used,
            "rejected_lines": [r.line for r in data.rejected],
        },
        "observability": None if obs is None else {
            "index": obs.index, "value": obs.value, "bound": obs.bound, "percent": obs.percent,
            "method": obs.method, **({"tour": dict(obs.tour)} if obs.tour else {}),
        },
        "times": dict(data.times) if data.times else None,
        "suspensions": [{"kind": s.kind, "message": s.message, "waited": s.waited, "t": s.t}
                        for s in data.suspensions],
        "notes": list(data.notes),
        "hashes": dict(data.hashes),
        "software": dict(data.software),
        "config": dict(data.config),
        "model": dict(data.model) if data.model is not None else None,
        "tracker_pose": dict(data.tracker_pose) if data.tracker_pose is not None else None,
        "units": UNITS,
        "per_pose": {
            "validation": {
                "before": _per_pose(data.validation_before),
                "after": _per_pose(data.validation_after),
                "lines": None if data.validation_lines is None else data.validation_lines.tolist(),
            },
            "calibration": {
                "before": _per_pose(data.calibration_before),
                "after": _per_pose(data.calibration_after),
                "used": None if data.calibration_used is None else data.calibration_used.tolist(),
                "lines": None if data.calibration_lines is None else data.calibration_lines.tolist(),
                "line_kind": data.line_kind,
            },
        },
    })
    theirs = data.validation_controller
    if theirs is not None:  # added only when known: readers of older results see the same keys
        doc["validation"]["controller"] = _plain(theirs.as_dict())
        doc["per_pose"]["validation"]["controller"] = _per_pose(theirs)
    if data.validation_precision is not None:  # likewise only when known (a campaign's)
        doc["validation"]["precision"] = _plain(dict(data.validation_precision))
    if data.verification is not None:  # likewise only with --verify
        doc["verification"] = _plain(dict(data.verification))
    if data.drift is not None:  # likewise only with a warm-up or a drift watch
        doc["drift"] = _plain(dict(data.drift))
    if data.stopping is not None:  # likewise only with the stopping rule on
        doc["stopping"] = _plain(dict(data.stopping))
    if data.poses is not None:  # likewise only for a campaign
        doc["poses"] = _plain({k: dict(v) for k, v in data.poses.items()})
    if data.cross_validation is not None:  # likewise only when the model was cross-validated
        doc["cross_validation"] = _plain(dict(data.cross_validation))
        doc["better_than_nominal"] = bool(data.cross_validation.get("better_than_nominal"))
    if data.verdict is not None:
        doc["verdict"] = _plain(dict(data.verdict))
    return doc
