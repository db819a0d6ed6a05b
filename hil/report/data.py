"""What a calibration report shows, as one typed value (`ReportData`), and the ways to build it.

The report and the MES result are both rendered from a `ReportData`, never from live objects, so
that a report can be rebuilt later from a saved result file (`report_data_from_result`) and look the
same as the one written at the end of the campaign. The engine builds it with `report_data_from`
from what it has at hand: the `FitResult`, the validation statistics, the station config and
whatever optional extras it collected (ISO 9283 figures, observability, time breakdown, events).

Units: metres and radians everywhere in this module; formatting to mm / mrad happens in the renderer.
"""

from __future__ import annotations

import datetime as _dt
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from drivers.robot.model import RobotIdentity
from hil.arm.kinematics import Kinematics
from hil.calibration.identification import Correlation, ErrorStats, FitResult, RejectedPose
from hil.calibration.measurements import Measurements
from hil.calibration.model_file import RESULT_FORMAT, check_geometry_block
from hil.campaign.events import (
    DriftFlagged,
    Event,
    Message,
    PoseSkipped,
    Resumed,
    Suspended,
    WarmupFinished,
)
from hil.campaign.reference_lines import describe as describe_reference
from hil.errors import InputError
from hil.files.inputs import json_number
from hil.station.config import StationConfig


@dataclass(frozen=True)
class ErrorSet:
    """Per-pose position errors (measured − predicted, metres) of one model on one pose set.

    ``vectors`` (m, 3) when the per-axis errors are known, otherwise only ``norms`` (m,) — an
    `ErrorStats` carries only distances, and an old result file may carry nothing per pose
    (``norms`` empty, the summary figures then come from ``summary``).
    """

    norms: np.ndarray
    vectors: np.ndarray | None = None
    summary: Mapping[str, float] | None = None  # count/mean/rms/max when norms are not available

    @classmethod
    def of_vectors(cls, vectors: np.ndarray) -> ErrorSet:
        v = np.asarray(vectors, dtype=float).reshape(-1, 3)
        return cls(np.linalg.norm(v, axis=1), v)

    @classmethod
    def of_stats(cls, stats: ErrorStats, vectors: np.ndarray | None = None) -> ErrorSet:
        if vectors is not None:
            return cls.of_vectors(vectors)
        return cls(np.asarray(stats.errors, dtype=float))

    def _stat(self, key: str) -> float:
        if len(self.norms):
            e = self.norms
            return float({"mean": e.mean(), "rms": np.sqrt(np.mean(e**2)), "max": e.max()}[key])
        if self.summary is not None and key in self.summary:
            return float(self.summary[key])
        return math.nan

    @property
    def count(self) -> int:
        if len(self.norms) or self.summary is None:
            return len(self.norms)
        return int(self.summary.get("count", 0))

    @property
    def mean(self) -> float:
        return self._stat("mean")

    @property
    def rms(self) -> float:
        return self._stat("rms")

    @property
    def max(self) -> float:
        return self._stat("max")

    @property
    def per_pose(self) -> bool:
        """Whether per-pose errors are known (else only the summary figures)."""
        return len(self.norms) > 0

    def as_dict(self) -> dict[str, float | int]:
        return {"count": self.count, "mean": self.mean, "rms": self.rms, "max": self.max}


@dataclass(frozen=True)
class FitSummary:
    """The identification's own figures (calibration poses, metres)."""

    rms: float
    max: float
    sigma: float
    initial_rms: float
    iterations: int
    condition: float
    poses: int
    used: int
    seconds: float = 0.0


@dataclass(frozen=True)
class Parameter:
    """One identified parameter: deviation from nominal (m or rad; the SMR offset is absolute)."""

    name: str
    value: float
    std: float


@dataclass(frozen=True)
class Observability:
    """How informative the chosen calibration poses are (the selector's index and its bound)."""

    index: str  # O1..O5
    value: float
    bound: float | None = None  # relaxation upper bound for this pose count, if known
    method: str = ""  # tabu, exchange, random, time-aware, ...
    # the time-aware selection's prediction beside method 000's (`tour_summary`); None for other methods
    tour: dict[str, Any] | None = None

    @property
    def percent(self) -> float | None:
        if self.bound is None or not self.bound or not math.isfinite(self.bound):
            return None
        return 100.0 * self.value / self.bound


def tour_summary(selection: Mapping[str, Any]) -> dict[str, Any] | None:
    """What the time-aware selection predicted for its tour and for method 000's poses (reported beside
    it), and whether the plan came from the plan cache: the report's line on what the tour bought."""
    pred, seed = selection.get("predicted"), selection.get("seed_method")
    if not isinstance(pred, Mapping) or not isinstance(seed, Mapping):
        return None
    cache = selection.get("plan_cache")
    return {"poses": pred.get("poses"), "robot_time": pred.get("robot_time"),
            "relative_error": pred.get("relative_error"), "seed_poses": seed.get("poses"),
            "seed_robot_time": seed.get("robot_time"),
            "reused": cache.get("reused") if isinstance(cache, Mapping) else None}


@dataclass(frozen=True)
class Suspension:
    """A time the campaign stopped by itself (lost beam, protective stop, ...) and how long for."""

    kind: str
    message: str
    waited: float | None = None  # seconds; None if it never resumed
    t: float | None = None  # Unix time it started


@dataclass(frozen=True)
class ReportData:
    """Everything one campaign report shows. Built by `report_data_from` or from a result file."""

    campaign: str
    station: str
    robot: RobotIdentity
    accept_rms: float  # acceptance threshold on the validation RMS (m)
    passed: bool
    validation_before: ErrorSet  # nominal arm (tracker + SMR fitted) on the validation poses
    validation_after: ErrorSet  # calibrated model on the validation poses
    fit: FitSummary
    parameters: tuple[Parameter, ...]
    calibration_before: ErrorSet | None = None  # baseline residuals on the calibration poses
    calibration_after: ErrorSet | None = None  # calibrated residuals on the calibration poses
    calibration_used: np.ndarray | None = None  # (m,) bool: not rejected as outliers
    calibration_lines: np.ndarray | None = None  # (m,) input file lines, or campaign pose numbers
    line_kind: str = "input line"  # what the *_lines are: "input line" (a CSV) or "pose" (a campaign)
    validation_lines: np.ndarray | None = None  # (n,) as calibration_lines, for the validation poses
    correlated: tuple[Correlation, ...] = ()
    rejected: tuple[RejectedPose, ...] = ()
    iso9283: Mapping[str, float] | None = None  # e.g. {"AP": m, "RP": m} on repeated poses
    observability: Observability | None = None
    config: Mapping[str, Any] = field(default_factory=dict)  # StationConfig.as_dict()
    hashes: Mapping[str, str] = field(default_factory=dict)  # what -> sha256 of the input data
    software: Mapping[str, str] = field(default_factory=dict)
    times: Mapping[str, float] | None = None  # seconds: motion, settle, measure, compute, ...
    suspensions: tuple[Suspension, ...] = ()
    notes: tuple[str, ...] = ()  # warnings, skipped poses
    started: str | None = None  # ISO 8601
    finished: str | None = None
    model: Mapping[str, Any] | None = None  # the hil-model/1 document, for the MES result
    tracker_pose: Mapping[str, Any] | None = None  # plain tracker pose (model_file.tracker_pose)
    # the controller's own model on the validation poses (tracker pose and SMR fitted for it, as for
    # "before"); None when the controller did not report its model. Its DH deltas: model["controller"]
    validation_controller: ErrorSet | None = None
    # ``hil calibrate --verify``: the ISO 9283 pose test of the calibrated model (``hil-verification/1``,
    # or why it has no figures: ``{"status": "not run", "reason"}``, an interrupted test's status)
    verification: Mapping[str, Any] | None = None
    # warm-up and drift watch (`hil.campaign.warmup.ReferenceWatch.summary`: the reference's series,
    # the largest drift, its limit, flagged, the warm-ups); None when both were off
    drift: Mapping[str, Any] | None = None
    # the stopping rule (`hil.campaign.calibration_plan.CampaignResult.stopping`: stopped, reason,
    # predicted_rms, target, poses_used, poses_left, ...); None when it was off
    stopping: Mapping[str, Any] | None = None
    # the validation RMS's standard error under the validation design
    # (`hil.calibration.validation_precision`: design, poses, clusters, rms_standard_error,
    # design_effect); None when not known (an offline identification, an older result)
    validation_precision: Mapping[str, Any] | None = None
    # poses planned and measured per role, {"bootstrap"|"calibration"|"validation": {"planned",
    # "measured"}} (`hil.campaign.calibration_plan.pose_counts`); None when not known (an offline
    # identification, an older result)
    poses: Mapping[str, Mapping[str, int]] | None = None
    # the campaign's verdict (`hil.campaign.acceptance.Verdict.as_dict`: passed, threshold, reason,
    # rule); None when not known (an older result)
    verdict: Mapping[str, Any] | None = None

    @property
    def cross_validation(self) -> Mapping[str, Any] | None:
        """The model's ``cross_validation`` block (held-out RMS of calibrated, nominal, controller)."""
        block = self.model.get("cross_validation") if self.model is not None else None
        return block if isinstance(block, Mapping) else None

    @property
    def drift_flagged(self) -> bool:
        """The reference drifted beyond its limit while measuring (the verdict stays the validation's)."""
        return bool((self.drift or {}).get("flagged"))

    @property
    def controller(self) -> Mapping[str, Any] | None:
        """The model's ``controller`` block (the controller's deltas, checksums, status), if any."""
        block = self.model.get("controller") if self.model is not None else None
        return block if isinstance(block, Mapping) else None


def _iso(t: float | str | _dt.datetime | None) -> str | None:
    """ISO 8601 (UTC, seconds) from Unix time, a datetime or a string (kept as given)."""
    if t is None or isinstance(t, str):
        return t
    if isinstance(t, _dt.datetime):
        return t.isoformat(timespec="seconds")
    return _dt.datetime.fromtimestamp(float(t), _dt.UTC).isoformat(timespec="seconds")


def summarise_events(events: Iterable[Event]) -> tuple[tuple[Suspension, ...], tuple[str, ...]]:
    """Suspensions (each paired with the Resumed that ended it) and notes worth a reader's eye."""
    suspensions: list[Suspension] = []
    open_: dict[str, int] = {}
    notes: list[str] = []
    for ev in events:
        if isinstance(ev, Suspended):
            open_[ev.kind] = len(suspensions)
            suspensions.append(Suspension(ev.kind, ev.message, None, ev.t))
        elif isinstance(ev, Resumed) and ev.kind in open_:
            i = open_.pop(ev.kind)
            s = suspensions[i]
            suspensions[i] = Suspension(s.kind, s.message, float(ev.waited), s.t)
        elif isinstance(ev, PoseSkipped):
            notes.append(f"{ev.role} pose {ev.index} skipped: {ev.reason}")
        elif isinstance(ev, Message) and ev.level in ("warning", "error"):
            notes.append(f"{ev.level}: {ev.text}")
        elif (isinstance(ev, WarmupFinished) and not ev.converged) or isinstance(ev, DriftFlagged):
            notes.append(str(describe_reference(ev)))
    return tuple(suspensions), tuple(notes)


def report_data_from(
    fit: FitResult,
    validation_before: ErrorStats,
    validation_after: ErrorStats,
    config: StationConfig | Mapping[str, Any],
    *,
    campaign: str,
    robot: RobotIdentity | None = None,
    started: float | str | _dt.datetime | None = None,
    finished: float | str | _dt.datetime | None = None,
    accept_rms: float | None = None,
    calibration: Measurements | None = None,
    validation: Measurements | None = None,
    iso9283: Mapping[str, float] | None = None,
    observability: Observability | None = None,
    times: Mapping[str, float] | None = None,
    events: Iterable[Event] = (),
    hashes: Mapping[str, str] | None = None,
    model: Mapping[str, Any] | None = None,
    line_kind: str = "input line",
    validation_controller: ErrorStats | None = None,
    verification: Mapping[str, Any] | None = None,
    drift: Mapping[str, Any] | None = None,
    stopping: Mapping[str, Any] | None = None,
    validation_precision: Mapping[str, Any] | None = None,
    poses: Mapping[str, Mapping[str, int]] | None = None,
    passed: bool | None = None,
    verdict: Mapping[str, Any] | None = None,
) -> ReportData:
    """Assemble a `ReportData` from what the campaign engine has at the end of a run.

    Only the fit, the two validation statistics, the config and a campaign id are required; the
    rest makes the report richer when the engine has it:

    * ``calibration`` (the measurements the fit used) adds the per-pose residuals *before*
      calibration (the fit's baseline geometry) and the file lines of every pose;
    * ``validation`` (the held-out measurements) adds per-axis validation errors — without it the
      per-axis plot falls back to the calibration residuals;
    * ``accept_rms`` defaults to the config's ``campaign.acceptance``;
    * ``hashes`` is merged over the fit's own input digest (and the validation data's);
    * ``model`` defaults to ``model_document(fit, validation_after.as_dict())``;
    * ``line_kind`` says what the calibration measurements' ``lines`` are: ``"input line"`` (rows of a
      CSV file) or ``"pose"`` (a campaign's pose numbers);
    * ``validation_controller``: the controller's own model on the validation poses
      (`hil.campaign.controller.controller_validation`), shown beside before and after;
    * ``verification``: the pose test run after the calibration (``hil calibrate --verify``), its
      document as the result embeds it under ``verification``;
    * ``drift``: the warm-up and drift watch (`hil.campaign.calibration_plan.CampaignResult.drift`);
    * ``stopping``: the stopping rule's record (`hil.campaign.calibration_plan.CampaignResult.stopping`);
    * ``validation_precision``: the validation RMS's standard error under the validation design
      (`hil.campaign.calibration_plan.CampaignResult.validation_precision`);
    * ``poses``: poses planned and measured per role (`hil.campaign.calibration_plan.pose_counts`);
    * ``passed`` and ``verdict``: the campaign's verdict (`hil.campaign.acceptance.judge`); without
      them the verdict is validation RMS ≤ ``accept_rms``.
    """
    from hil.calibration.model_file import model_document, software_versions, tracker_pose

    if isinstance(config, StationConfig):
        cfg: dict[str, Any] = config.as_dict()
    else:
        cfg = {k: dict(v) if isinstance(v, Mapping) else v for k, v in config.items()}
    if accept_rms is None and verdict is not None:
        accept_rms = float(verdict["threshold"])
    if accept_rms is None:
        from hil.campaign.acceptance import threshold

        try:  # the user's threshold, else the robot class's bound (`hil.campaign.acceptance`)
            accept_rms = threshold(cfg["campaign"]["acceptance"], fit.robot)
        except (KeyError, TypeError, ValueError):
            raise InputError("report: no acceptance threshold (config campaign.acceptance)") from None
    station = str(cfg.get("station", {}).get("name", "")) if isinstance(cfg.get("station"), Mapping) else ""
    if robot is None:
        robot = RobotIdentity(fit.robot)

    cal_before = cal_after = None
    lines = None
    if calibration is not None and len(calibration) == len(fit.residuals):
        if fit.baseline is not None:
            cal_before = ErrorSet.of_vectors(calibration.p - Kinematics(fit.baseline).points(calibration.q))
        lines = np.asarray(calibration.lines, dtype=int)
    cal_after = ErrorSet.of_vectors(fit.residuals)

    v_before = v_after = v_lines = None
    if validation is not None and len(validation) == validation_after.count:
        if fit.baseline is not None:
            v_before = validation.p - Kinematics(fit.baseline).points(validation.q)
        v_after = validation.p - Kinematics(fit.geometry).points(validation.q)
        v_lines = np.asarray(validation.lines, dtype=int)

    digests = {}
    if fit.sha256:
        digests["calibration measurements"] = fit.sha256
    if validation is not None and validation.sha256:
        digests["validation measurements"] = validation.sha256
    digests.update(hashes or {})

    suspensions, notes = summarise_events(events)
    after = ErrorSet.of_stats(validation_after, v_after)
    if model is None:
        model = model_document(fit, validation_after.as_dict())
    return ReportData(
        campaign=campaign,
        station=station,
        robot=robot,
        accept_rms=float(accept_rms),
        passed=bool(after.rms <= accept_rms) if passed is None else bool(passed),
        validation_before=ErrorSet.of_stats(validation_before, v_before),
        validation_after=after,
        fit=FitSummary(rms=fit.rms, max=fit.max_error, sigma=fit.sigma, initial_rms=fit.initial_rms,
                       iterations=fit.iterations, condition=fit.condition, poses=len(fit.used),
                       used=int(np.sum(fit.used)), seconds=fit.seconds),
        parameters=tuple(Parameter(n, float(v), float(s))
                         for n, v, s in zip(fit.names, fit.values, fit.std, strict=True)),
        calibration_before=cal_before,
        calibration_after=cal_after,
        calibration_used=np.asarray(fit.used, dtype=bool).copy(),
        calibration_lines=lines,
        line_kind=line_kind,
        validation_lines=v_lines,
        correlated=tuple(fit.correlated),
        rejected=tuple(fit.rejected),
        iso9283=dict(iso9283) if iso9283 else None,
        observability=observability,
        config=cfg,
        hashes=digests,
        software=software_versions(),
        times=dict(times) if times else None,
        suspensions=suspensions,
        notes=notes,
        started=_iso(started),
        finished=_iso(finished),
        model=model,
        tracker_pose=tracker_pose(fit.geometry.tracker, fit.names, fit.covariance),
        validation_controller=(None if validation_controller is None
                               else ErrorSet.of_stats(validation_controller)),
        verification=dict(verification) if verification is not None else None,
        drift=dict(drift) if drift is not None else None,
        stopping=dict(stopping) if stopping is not None else None,
        validation_precision=dict(validation_precision) if validation_precision is not None else None,
        poses={k: dict(v) for k, v in poses.items()} if poses is not None else None,
        verdict=dict(verdict) if verdict is not None else None,
    )


# --- reading a saved result back -------------------------------------------------------------------

def _num(value: Any, where: str) -> float:
    if value is None:
        return math.nan
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise InputError(f"{where}: must be a number, got {value!r}")
    return float(value)


def _error_set(block: Any, per_pose: Any, where: str) -> ErrorSet:
    """An ErrorSet from a summary dict and an optional per-pose list (vectors or distances)."""
    if per_pose:
        arr = np.asarray(per_pose, dtype=float)
        if arr.ndim == 2 and arr.shape[1] == 3:
            return ErrorSet.of_vectors(arr)
        if arr.ndim == 1:
            return ErrorSet(arr)
        raise InputError(f"{where}: per-pose errors must be a list of numbers or of [x, y, z]")
    if not isinstance(block, Mapping):
        raise InputError(f"{where}: missing validation figures")
    return ErrorSet(np.zeros(0), summary={k: _num(block.get(k), f"{where}.{k}")
                                          for k in ("count", "mean", "rms", "max")})


def report_data_from_result(doc: Mapping[str, Any], source: str = "result") -> ReportData:
    """Rebuild the `ReportData` of a saved ``hil-result/1`` document (see `mes_result`).

    Older or offline results without the ``per_pose`` block give a report without the per-pose
    plots; everything else is read from the embedded model. Missing required keys are InputErrors
    naming the key; any other malformed content is an InputError naming the file, never a crash.
    """
    try:
        return _from_result(doc, source)
    except InputError:
        raise
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise InputError(f"{source}: malformed result ({type(exc).__name__}: {exc})") from None


def _from_result(doc: Mapping[str, Any], source: str) -> ReportData:
    if doc.get("format") != RESULT_FORMAT:
        raise InputError(f"{source}: field 'format' is {doc.get('format')!r}, expected {RESULT_FORMAT}")

    def need(d: Mapping[str, Any], key: str, where: str) -> Any:
        if not isinstance(d, Mapping) or key not in d:
            raise InputError(f"{source}: missing field '{where}{key}'")
        return d[key]

    if not isinstance(doc.get("model"), Mapping):
        status = doc.get("status")
        if status is not None:  # aborted, failed: the campaign stopped before it had a model
            error = f" ({doc['error']})" if doc.get("error") else ""
            raise InputError(f"{source}: campaign {doc.get('campaign') or '?'} did not finish (status "
                             f"{status!r}{error}): it has no calibrated model, so there is no report to "
                             "build; resume the campaign (run the same hil calibrate command again)")
    model = need(doc, "model", "")
    fit_block = need(model, "fit", "model.")
    validation = need(doc, "validation", "")
    per_pose = doc.get("per_pose") or {}
    pv = per_pose.get("validation") or {}
    pc = per_pose.get("calibration") or {}
    robot_model = str(doc.get("robot") or model.get("robot") or "")
    accept = json_number(need(doc, "accept_rms", ""), f"{source}: accept_rms", "rms threshold")
    passed = need(doc, "passed", "")
    if not isinstance(passed, bool):  # "yes" would read as a pass: a verdict is true or false, nothing else
        raise InputError(f"{source}: passed: expected true or false, got {passed!r}")
    check_geometry_block(model, source, "model.")
    params = tuple(Parameter(str(need(p, "name", "model.parameters[].")),
                             _num(p.get("value"), f"{source}: model.parameters.value"),
                             _num(p.get("std"), f"{source}: model.parameters.std"))
                   for p in need(model, "parameters", "model."))
    fit = FitSummary(**{k: _num(fit_block.get(src), f"{source}: model.fit.{src}") for k, src in (
        ("rms", "rms"), ("max", "max"), ("sigma", "sigma"), ("initial_rms", "initial_rms"),
        ("condition", "condition"), ("seconds", "seconds"))},
        iterations=int(_num(fit_block.get("iterations", 0), f"{source}: model.fit.iterations")),
        poses=int(_num(fit_block.get("poses", 0), f"{source}: model.fit.poses")),
        used=int(_num(fit_block.get("used", 0), f"{source}: model.fit.used")))
    obs = doc.get("observability")
    observability = None
    if isinstance(obs, Mapping) and "index" in obs:
        observability = Observability(str(obs["index"]), _num(obs.get("value"), "observability.value"),
                                      None if obs.get("bound") is None
                                      else _num(obs["bound"], "observability.bound"),
                                      str(obs.get("method", "")),
                                      dict(obs["tour"]) if isinstance(obs.get("tour"), Mapping) else None)
    hashes = dict(doc.get("hashes") or {})
    if not hashes and isinstance(model.get("input"), Mapping) and model["input"].get("sha256"):
        hashes = {"calibration measurements": str(model["input"]["sha256"])}
    cal_before, cal_after = (_error_set(None, pc[k], f"{source}: per_pose.calibration.{k}")
                             if pc.get(k) else None for k in ("before", "after"))
    used = np.asarray(pc["used"], dtype=bool) if pc.get("used") else None
    lines = np.asarray(pc["lines"], dtype=int) if pc.get("lines") else None
    config = doc.get("config") or {}
    station = doc.get("station")
    station = str(station) if station is not None else str((config.get("station") or {}).get("name", ""))
    return ReportData(
        campaign=str(doc.get("campaign") or ""),
        station=station,
        robot=RobotIdentity(robot_model, str(doc.get("robot_serial") or ""),
                            software=str(doc.get("robot_software") or "")),
        accept_rms=accept,
        passed=passed,
        validation_before=_error_set(need(validation, "before", "validation."), pv.get("before"),
                                     f"{source}: validation.before"),
        validation_after=_error_set(need(validation, "after", "validation."), pv.get("after"),
                                    f"{source}: validation.after"),
        fit=fit,
        parameters=params,
        calibration_before=cal_before,
        calibration_after=cal_after,
        calibration_used=used,
        calibration_lines=lines,
        line_kind=str(pc.get("line_kind") or "pose"),  # a hil-result/1 is a campaign's: pose numbers
        validation_lines=np.asarray(pv["lines"], dtype=int) if pv.get("lines") else None,
        correlated=tuple(Correlation(str(c["a"]), str(c["b"]), _num(c.get("rho"), "rho"))
                         for c in fit_block.get("correlated", [])),
        rejected=tuple(RejectedPose(int(r["pose"]), int(r["line"]), _num(r.get("residual"), "residual"),
                                    _num(r.get("p_value"), "p_value"))
                       for r in fit_block.get("rejected", [])),
        iso9283=validation.get("iso9283") or None,
        observability=observability,
        config=config,
        hashes=hashes,
        software=dict(doc.get("software") or model.get("software") or {}),
        times=doc.get("times") or None,
        suspensions=tuple(Suspension(str(s.get("kind", "")), str(s.get("message", "")), s.get("waited"),
                                     s.get("t")) for s in doc.get("suspensions") or []),
        notes=tuple(str(n) for n in doc.get("notes") or []),
        started=doc.get("started"),
        finished=doc.get("finished"),
        model=model,
        tracker_pose=_tracker_pose(model, source),
        validation_controller=(None if validation.get("controller") is None else _error_set(
            validation["controller"], pv.get("controller"), f"{source}: validation.controller")),
        verification=_verification(doc.get("verification"), source),
        drift=_drift(doc.get("drift"), source),
        stopping=_stopping(doc.get("stopping"), source),
        validation_precision=_precision(validation.get("precision"), source),
        poses=_pose_counts(doc.get("poses"), source),
        verdict=doc["verdict"] if isinstance(doc.get("verdict"), Mapping) else None,
    )


def _pose_counts(block: Any, source: str) -> Mapping[str, Mapping[str, int]] | None:
    """The result's ``poses`` block: per role, whole numbers ``planned`` and ``measured``."""
    if block is None:
        return None
    if not isinstance(block, Mapping):
        raise InputError(f"{source}: field 'poses' must be an object")
    out = {}
    for role, counts in block.items():
        if not isinstance(counts, Mapping):
            raise InputError(f"{source}: field 'poses.{role}' must be an object")
        for key in ("planned", "measured"):
            value = counts.get(key)
            if isinstance(value, bool) or not isinstance(value, int) or value < 0:
                raise InputError(f"{source}: field 'poses.{role}.{key}' must be a whole number of poses")
        out[str(role)] = {"planned": counts["planned"], "measured": counts["measured"]}
    return out


def _precision(block: Any, source: str) -> Mapping[str, Any] | None:
    """The result's ``validation.precision`` block, checked as far as the report reads it: a design
    name, the standard error (m) and the design effect numbers or null, the counts whole numbers."""
    if block is None:
        return None
    if not isinstance(block, Mapping) or not isinstance(block.get("design"), str):
        raise InputError(f"{source}: field 'validation.precision' must be an object with a 'design'")
    for key in ("rms_standard_error", "design_effect"):
        if block.get(key) is not None and not _is_number(block.get(key)):
            raise InputError(f"{source}: field 'validation.precision.{key}' must be a number or null")
    for key in ("poses", "clusters"):
        value = block.get(key)
        if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 0):
            raise InputError(f"{source}: field 'validation.precision.{key}' must be a whole number")
    return dict(block)


def _stopping(block: Any, source: str) -> Mapping[str, Any] | None:
    """The result's ``stopping`` block, checked as far as the report reads it: ``stopped`` a boolean,
    the RMS figures numbers (m) or null, the pose counts whole numbers."""
    if block is None:
        return None
    if not isinstance(block, Mapping) or not isinstance(block.get("stopped"), bool):
        raise InputError(f"{source}: field 'stopping' must be an object with a boolean 'stopped'")
    for key in ("predicted_rms", "target"):
        if block.get(key) is not None and not _is_number(block.get(key)):
            raise InputError(f"{source}: field 'stopping.{key}' must be a number (m) or null")
    for key in ("poses_used", "poses_left"):
        value = block.get(key)
        if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 0):
            raise InputError(f"{source}: field 'stopping.{key}' must be a whole number of poses")
    return dict(block)


def _drift(block: Any, source: str) -> Mapping[str, Any] | None:
    """The result's ``drift`` block, checked as far as the report reads it: its series' points carry
    a run, a station time and a drift (m, or null), its limit is a number."""
    if block is None:
        return None
    if not isinstance(block, Mapping):
        raise InputError(f"{source}: field 'drift' must be an object")
    series = block.get("series")
    if not isinstance(series, list):
        raise InputError(f"{source}: field 'drift.series' must be a list of reference measurements")
    for i, point in enumerate(series):
        ok = (isinstance(point, Mapping) and _is_number(point.get("elapsed")) and _is_number(point.get("run"))
              and (point.get("drift") is None or _is_number(point.get("drift"))))
        if not ok:
            raise InputError(f"{source}: field 'drift.series[{i}]' needs numbers 'run', 'elapsed' and "
                             "'drift' (m, or null)")
    for key in ("limit", "max"):
        if block.get(key) is not None and not _is_number(block.get(key)):
            raise InputError(f"{source}: field 'drift.{key}' must be a number (m)")
    return dict(block)


def _verification(block: Any, source: str) -> Mapping[str, Any] | None:
    """The result's ``verification`` block (``hil calibrate --verify``), checked as far as the report
    reads it: a finished test's figures, else its status (not run, interrupted), shown as such."""
    if block is None:
        return None
    if not isinstance(block, Mapping):
        raise InputError(f"{source}: field 'verification' must be an object")
    if "results" in block:
        check_verification(block, source, "verification.")
    return dict(block)


def _is_number(value: Any) -> bool:
    """A JSON number (true and false are not)."""
    return isinstance(value, int | float) and not isinstance(value, bool)


def check_verification(doc: Any, source: str, prefix: str = "") -> None:
    """Refuse, with an InputError naming the file and field, a verification the report cannot show.

    A saved result may be old, edited or cut short: what the report reads is checked first (the
    figures of every mode as `hil.verify.result.evaluate` writes them), so ``hil report`` says what is
    wrong in one line instead of failing half-way through the page. A test that did not finish (no
    ``results``) is refused naming its status: it has no figures to show.
    """
    if not isinstance(doc, Mapping):
        raise InputError(f"{source}: field '{prefix.rstrip('.') or 'verification'}' must be an object")
    if "results" not in doc:
        status, error = doc.get("status"), doc.get("error") or doc.get("reason")
        raise InputError(f"{source}: verification {doc.get('campaign') or '?'} did not finish (status "
                         f"{status!r}{f': {error}' if error else ''}): it has no figures, so there is no "
                         "report to build; run the same hil verify command again to continue it")
    results = doc["results"]
    if not isinstance(results, Mapping) or not results:
        raise InputError(f"{source}: field '{prefix}results' must map each mode to its figures")
    blocks = {f"{prefix}results.{mode}": block for mode, block in results.items()}
    if doc.get("own_frame") is not None:
        blocks[f"{prefix}own_frame"] = doc["own_frame"]
    for where, block in blocks.items():
        if not isinstance(block, Mapping):
            raise InputError(f"{source}: field '{where}' must be an object")
        for key in ("AP_max", "RP_max"):
            if not _is_number(block.get(key)):
                raise InputError(f"{source}: field '{where}.{key}' must be a number (m)")
        if not isinstance(block.get("poses"), list):
            raise InputError(f"{source}: field '{where}.poses' must be a list of poses")
        for i, row in enumerate(block["poses"]):
            here = f"{where}.poses[{i}]"
            if not isinstance(row, Mapping) or not isinstance(row.get("pose"), str):
                raise InputError(f"{source}: field '{here}.pose' must name the pose (P1..P5)")
            if "AP_P" not in row:
                continue
            for key in ("n", "AP_x", "AP_y", "AP_z", "AP_P", "S_l", "RP_l"):
                if not _is_number(row.get(key)):
                    raise InputError(f"{source}: field '{here}.{key}' must be a number")
            offsets = row.get("offsets")
            if not (isinstance(offsets, list) and offsets and all(
                    isinstance(o, list) and len(o) == 3 and all(_is_number(v) for v in o) for o in offsets)):
                raise InputError(f"{source}: field '{here}.offsets' must be a list of [x, y, z] (m)")
    if isinstance(doc.get("own_frame"), Mapping) and not isinstance(doc["own_frame"].get("frame"), Mapping):
        raise InputError(f"{source}: field '{prefix}own_frame.frame' must be an object")


def _tracker_pose(model: Mapping[str, Any], source: str) -> Mapping[str, Any] | None:
    """The model's plain tracker pose: its ``tracker_pose`` block, or (older models) computed from
    the geometry's ``tracker`` and the covariance."""
    from hil.arm.geometry import pose
    from hil.calibration.model_file import tracker_pose

    if isinstance(model.get("tracker_pose"), Mapping):
        return dict(model["tracker_pose"])
    block = model.get("tracker")
    if not isinstance(block, Mapping):
        return None
    try:
        M = pose(block["xyz"], block["rpy"])
    except (KeyError, TypeError, ValueError):
        raise InputError(f"{source}: field 'model.tracker' needs xyz and rpy triples") from None
    cov = model.get("covariance") if isinstance(model.get("covariance"), Mapping) else {}
    names = [str(n) for n in cov.get("parameters") or []]
    matrix = cov.get("matrix")
    ok = names and isinstance(matrix, list) and np.shape(matrix) == (len(names), len(names))
    return tracker_pose(M, names, matrix if ok else None)
