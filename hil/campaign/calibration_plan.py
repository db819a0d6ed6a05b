"""The calibration campaign as a plan: bootstrap, select, measure, identify, validate.

`calibration_plan` is a generator of plain steps (see `hil.campaign.steps`); the engine executes it against
a robot and a tracker, and the same plan runs headless (CLI) and under the TUI. The plan does no I/O:
pose selection and identification are computations on what the engine sends back.

* **Bootstrap** (only when the tracker's position is not configured; its targets are stored, by
  `BootstrapPlanned`, before the first is visited, so a resumed run visits the same ones and measures
  only those still missing): the operator has locked the
  beam on the SMR at the arm's current pose; the plan measures a few small moves around it that keep
  the SMR facing the same way, plus turns of the last joint (which turn the SMR about its own opening
  axis, so it keeps facing the tracker while its offset from that axis shows), and fits the tracker
  pose *and* the SMR offset to them (`register`), so the selector's line-of-sight checks use where the
  tracker and the SMR really are. Fitting the tracker alone against the SMR guess put it 4-22 cm off
  (the guess lies on the flange axis, the real SMR 2-6 cm beside it), and a few selected poses then
  turned out hidden behind the arm; with the SMR fitted too the tracker is found to about a centimetre
  (`bench/`-free check: tests/hil/campaign/test_plan_visibility.py).
* **Select**: calibration poses by the injected chooser (the tabu selector in production), then
  validation poses the fit never sees. `PlanReady` carries them to the store, so a resumed run visits
  exactly the same poses.
* **Warm up** (``[warmup]``, `hil.campaign.warmup`): cycle through the planned calibration poses,
  re-measuring a reference pose (stored with the plan) until it settles, so every point is measured on
  a warm arm; a resumed run with poses left warms up again.
* **Measure**: before each visit the pose is checked again against the tracker and SMR fitted to the
  points measured so far (`_SightCheck`); one the tracker would not see is skipped at once, with the
  reason, rather than driven to and waited on. Each pose is one `Acquire` (move, settle, read joints,
  measure); the engine's
  `PointMeasured` event reaches the store before the next move. Poses already measured (a resumed
  run) are skipped. After `campaign.max_consecutive_lost` poses in a row lost the beam the run stops
  (`TrackerLooksWrong`): the tracker is not where the plan has it, and waiting out the re-lock time
  at every remaining pose would only cost time. With ``campaign.stop_early`` the stopping rule
  (`hil.campaign.stopping`) fits the points after each calibration pose and, once the fit predicts the
  acceptance with margin, the remaining calibration poses are not visited (`AcquisitionStopped`, kept
  by the store, so a resumed run keeps the decision); validation poses, wherever they are in the
  visiting order, are all still measured. The reference is measured again every
  ``drift.every`` poses (drift watch); a drift beyond ``drift.limit`` flags the campaign. Reference
  measurements are never campaign points: no fit or validation sees them.
* **Identify** on the calibration (and bootstrap) points; **validate** on the others: before (the
  nominal arm with only the tracker pose and SMR fitted) and after, plus ISO 9283 pose accuracy (AP)
  and repeatability (RP) when validation poses are visited more than once, plus — when the controller
  reported its own kinematic model — that model judged like "before" (`hil.campaign.controller`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry, look_at_tracker, pose_to_dict
from hil.arm.kinematics import Kinematics
from hil.calibration.cross_validation import CrossValidation, cross_validate
from hil.calibration.identification import (
    ErrorStats,
    FitResult,
    IdentificationError,
    register,
    validate,
)
from hil.calibration.joint_error_request import parse_request
from hil.calibration.joint_error_selection import identify_with_joint_errors
from hil.calibration.measurements import Measurements
from hil.calibration.model_file import model_document
from hil.calibration.validation_precision import campaign_validation_precision
from hil.campaign.acceptance import Verdict, judge
from hil.campaign.acceptance import threshold as acceptance_threshold
from hil.campaign.controller import controller_calibration, controller_validation
from hil.campaign.events import (
    BootstrapPlanned,
    Message,
    ModelIdentified,
    PlanReady,
    PoseSkipped,
    ReferenceMeasured,
    SweepFitted,
    SweepPlanned,
    ValidationDone,
    is_bootstrap_segment,
)
from hil.campaign.steps import (
    Emit,
    Phase,
    Plan,
    PoseRecord,
    ReadJoints,
    SegmentRecord,
    Skipped,
    Sweep,
    SweepRecorded,
    SweepSegment,
    acquire,
    visit_settings,
)
from hil.campaign.stopping import EarlyStop, StoppingRule
from hil.campaign.sweep_bootstrap import bootstrap_segments
from hil.campaign.sweep_plan import (
    CONTROLLER_RATE_HZ,
    SWEEP,
    TRACKER_RATE_HZ,
    VALIDATION_GUARD_RAD,
    first_clock,
    hop_limits,
    stored_tour,
    streams_of,
    sweep_terms,
    sweep_tour,
    sweep_verdict,
    tour_visits,
)
from hil.campaign.sweep_rests import hold_point
from hil.campaign.warmup import ReferenceWatch, reference_pose
from hil.errors import HilError, InputError
from hil.station.config import StationConfig

BOOTSTRAP, CALIBRATION, VALIDATION = "bootstrap", "calibration", "validation"

#: `campaign.selection` of the time-aware selection: calibration and validation poses in one tour.
TIME_AWARE = "time-aware"

# Small moves of joints 1-3 around the start pose; joint 4 compensates joints 2+3 so the wrist, and
# with it the SMR, keeps facing the tracker (joint 1 turns it by at most 0.15 rad ≈ 9°).
_BOOTSTRAP_DELTAS = np.array([
    (0.0, 0.0, 0.0), (0.15, 0.0, 0.0), (-0.15, 0.0, 0.0), (0.0, -0.12, 0.0),
    (0.0, 0.0, 0.2), (0.1, 0.1, -0.2), (-0.1, -0.1, 0.15), (0.05, 0.15, -0.1),
])
# Turns of joint 6 (rad): the flange z axis, along which the SMR opens, does not move, so the SMR keeps
# facing the tracker while its centre circles the axis and its offset becomes measurable.
# In this order the wrist travels 4.2 rad in all (0.7, 1.4, -0.7, -1.4), not the 7 rad of alternating
# signs: 5 s less of the bootstrap at a 0.5 rad/s movej.
_WRIST_TURNS = np.array([0.7, 1.4, -0.7, -1.4])


@dataclass(frozen=True)
class SelectionRequest:
    """What the pose chooser is asked for."""

    role: str
    count: int
    model: Geometry  # nominal arm, SMR guess, tracker estimate (base frame)
    keep_in: tuple[np.ndarray, np.ndarray]
    acceptance_angle: float  # degrees
    index: str
    candidates: int
    seed: int
    exclude: np.ndarray  # poses already chosen (validation must differ from calibration)
    start: np.ndarray | None = None  # where the arm is (for the visiting order)
    # poses the same tour visits anyway (time-aware selection: the validation poses); the Choice's
    # info then has a "tour" saying where they come
    fixed: np.ndarray | None = None


@dataclass(frozen=True)
class Choice:
    """The chooser's answer: poses in visiting order and figures about them."""

    poses: np.ndarray  # (count, 6)
    info: dict[str, Any] = field(default_factory=dict)


#: Chooses poses; may carry ``hidden(robot, smr, tracker_position, q, acceptance_angle) -> str | None``,
#: the same visibility tests for checking a planned pose again during the run.
ChoosePoses = Callable[[SelectionRequest], Choice]


@dataclass
class ResumeState:
    """What the store already holds of an interrupted campaign."""

    poses: list[tuple[int, str, np.ndarray]] | None = None
    tracker: pin.SE3 | None = None
    # the stored bootstrap plan, (index, target) in visiting order; None: none was stored
    bootstrap: list[tuple[int, np.ndarray]] | None = None
    records: dict[tuple[str, int], PoseRecord] = field(default_factory=dict)
    selection: dict[str, Any] = field(default_factory=dict)
    # the warm-up/drift reference pose stored with the plan (None: choose one) and the campaign's
    # reference measurements so far, in order (the store's ReferenceMeasured events)
    reference: np.ndarray | None = None
    references: list[ReferenceMeasured] = field(default_factory=list)
    # the stopping rule's decision (the figures of the store's AcquisitionStopped event), kept as it was
    stopping: dict[str, Any] | None = None
    # a sweep campaign's segments recorded whole (their SweepSegmentDone's take), by segment index
    sweep: dict[int, SegmentRecord] = field(default_factory=dict)
    # the tour the campaign planned first (its stored SweepPlanned's segments); None: none yet
    sweep_tour: list[dict[str, Any]] | None = None


@dataclass
class CampaignResult:
    """Everything the report and the result file need."""

    fit: FitResult
    before: ErrorStats
    after: ErrorStats
    passed: bool
    records: list[PoseRecord]
    tracker_estimate: pin.SE3
    selection: dict[str, Any]
    iso9283: dict[str, Any] | None
    model: dict[str, Any]
    # the controller's own model on the validation poses (`controller_validation`); None: not reported
    controller: ErrorStats | None = None
    # warm-up and drift watch (`ReferenceWatch.summary`); None when both are off
    drift: dict[str, Any] | None = None
    # the stopping rule (`EarlyStop.summary`: stopped or not, why, the prediction); None when it is off
    stopping: dict[str, Any] | None = None
    # the validation RMS's standard error under the validation design (`validation_precision`)
    validation_precision: dict[str, Any] | None = None
    # poses planned and measured per role (`pose_counts`): the one source of every output's counts
    counts: dict[str, dict[str, int]] = field(default_factory=dict)
    # the fit's cross-validation beside the nominal and the controller's models (`cross_validate`)
    cross_validation: CrossValidation | None = None
    # the verdict and its reason (`hil.campaign.acceptance.judge`); `passed` is its `passed`
    verdict: Verdict | None = None
    # a sweep's join and fit (`SweepFitted`'s figures); None for stop-and-go
    sweep: dict[str, Any] | None = None


def pose_counts(bootstrap: list[tuple[int, np.ndarray]] | None, planned: list[tuple[int, str, np.ndarray]],
                records: Mapping[tuple[str, int], PoseRecord]) -> dict[str, dict[str, int]]:
    """Poses planned and measured per role: the bootstrap's from its stored plan (its arm moves,
    ``campaign.bootstrap_poses``, plus the wrist turns: `bootstrap_targets`; none when the tracker
    position was configured, or as many as were measured by an older hil that stored no bootstrap
    plan), calibration and validation poses from the campaign's plan (validation cycles included).
    The fit uses the bootstrap and calibration points measured; every count a report, a result, the
    console or the TUI shows is one of these."""
    measured = {role: sum(1 for r, _ in records if r == role)
                for role in (BOOTSTRAP, CALIBRATION, VALIDATION)}
    boot = len(bootstrap) if bootstrap is not None else measured[BOOTSTRAP]
    return {BOOTSTRAP: {"planned": boot, "measured": measured[BOOTSTRAP]},
            **{role: {"planned": sum(1 for _, r, _ in planned if r == role), "measured": measured[role]}
               for role in (CALIBRATION, VALIDATION)}}


def bootstrap_words(count: int) -> str:
    """How many bootstrap poses, and what they are: ``campaign.bootstrap_poses`` moves of the arm
    plus the wrist turns (`bootstrap_targets`), so a config saying 6 measures 10."""
    turns = len(_WRIST_TURNS)
    return f"{count} bootstrap poses ({count - turns} small moves of the arm, {turns} turns of the wrist)"


def _tour_plan(first: int, cal: Choice, val: Choice) -> list[tuple[int, str, np.ndarray]]:
    """The planned poses in the time-aware chooser's tour (``cal.info["tour"]``: selected poses and the
    fixed validation poses interleaved), numbered in visiting order from `first`."""
    tour = cal.info.get("tour")
    if tour is None:  # a chooser without a tour: calibration, then validation
        tour = ([{"role": "selected", "index": i} for i in range(len(cal.poses))]
                + [{"role": "fixed", "index": i} for i in range(len(val.poses))])
    planned = []
    for k, stop in enumerate(tour):
        calibration = stop["role"] == "selected"
        q = (cal.poses if calibration else val.poses)[int(stop["index"])]
        planned.append((first + k, CALIBRATION if calibration else VALIDATION, np.asarray(q, dtype=float)))
    return planned


def bootstrap_targets(start: np.ndarray, count: int) -> np.ndarray:
    """Bootstrap poses around `start`: `count` arm moves (`_BOOTSTRAP_DELTAS`), then the wrist turns
    (`_WRIST_TURNS` of joint 6) that make the SMR's offset observable."""
    deltas = _BOOTSTRAP_DELTAS[: max(4, min(count, len(_BOOTSTRAP_DELTAS)))]
    out = np.repeat(np.asarray(start, float)[None, :], len(deltas) + len(_WRIST_TURNS), axis=0)
    out[: len(deltas), :3] += deltas
    out[: len(deltas), 3] -= deltas[:, 1] + deltas[:, 2]
    out[len(deltas):, 5] += _WRIST_TURNS
    return out


class _SightCheck:
    """Whether the tracker will see the SMR at a planned pose, by the station as the points show it.

    The poses were chosen with the tracker located by the bootstrap (to about a centimetre); every
    point measured since narrows that down, so before each visit the tracker position and the SMR
    offset are fitted again to all the points so far (the nominal arm, `register`: every
    `REFIT_EVERY` new points) and the pose is checked with the selector's line-of-sight and
    acceptance tests — the chooser's own (its ``hidden`` attribute, `hidden_reason` in production; a
    chooser without one is trusted as it is).
    """

    REFIT_EVERY = 3
    MIN_POINTS = 8

    def __init__(self, robot: str, smr: np.ndarray, tracker: np.ndarray, acceptance_angle: float,
                 check: Callable[..., str | None] | None) -> None:
        self.robot, self.smr, self.tracker = robot, np.asarray(smr, float), np.asarray(tracker, float)
        self.acceptance_angle = acceptance_angle
        self.check = check
        self._fitted_on = 0

    def refine(self, records: list[PoseRecord]) -> None:
        if self.check is None or len(records) < self.MIN_POINTS or \
                len(records) - self._fitted_on < self.REFIT_EVERY:
            return
        located = register(measurements_of(records, "measured so far"), self.robot, self.smr)
        self.smr, self.tracker = located.smr, located.tracker.translation
        self._fitted_on = len(records)

    def hidden(self, q: np.ndarray) -> str | None:
        if self.check is None:
            return None
        return self.check(self.robot, self.smr, self.tracker, q, self.acceptance_angle)


class TrackerLooksWrong(HilError):
    """Several poses in a row lost the beam: the tracker is not where the plan has it.

    Not bad input (the configuration parsed) but a station fault: the run fails (resumable, exit 3)
    after `campaign.max_consecutive_lost` such poses instead of waiting out the re-lock time at every
    remaining pose, and says where the measured points put the tracker."""


#: Largest RMS (m) of the nominal arm registered on the points measured so far for the tracker
#: position it implies to be quoted; the nominal arm alone is off by millimetres.
_QUOTE_RMS = 5e-3


def _tracker_looks_wrong(config: StationConfig, lost: list[Any], tracker: pin.SE3,
                         measured: list[PoseRecord], smr_guess: np.ndarray) -> str:
    """The operator's message: which poses lost the beam, where the plan has the tracker (the
    configuration's ``tracker.position`` or the bootstrap's estimate) and, when at least 4 points were
    measured and the nominal arm fits them, where those points put it."""
    poses = ", ".join(str(s.index) for s in lost)
    wait = config.timeouts["relock"]
    head = (f"{len(lost)} poses in a row lost the beam (poses {poses}, each after up to {wait:g} s "
            "waiting to re-lock)")
    here = [round(float(v), 3) for v in tracker.translation]
    if config.tracker["position"] is not None:
        given = [round(float(v), 3) for v in config.tracker["position"]]
        where_set = "" if config.source.startswith("<") else f"{config.source}: "
        text = f"{head}: {where_set}tracker.position {given} looks wrong"
        fix = "correct tracker.position (or remove it to have the run locate the tracker)"
    else:
        text = (f"{head}: the tracker position the bootstrap found ({here} m) looks wrong, or "
                "something blocks the line of sight")
        fix = "check the line of sight, or set tracker.position"
    where = None
    if len(measured) >= 4:
        try:
            located = register(measurements_of(measured, "measured so far"), config.robot["type"],
                               smr_guess)
            q, p = np.array([r.q for r in measured]), np.array([r.p for r in measured])
            rms = float(np.sqrt(np.mean(np.sum((Kinematics(located).points(q) - p) ** 2, axis=1))))
            if rms < _QUOTE_RMS:
                where = [round(float(v), 2) for v in located.tracker.translation]
        except (HilError, ValueError, np.linalg.LinAlgError):  # too few or degenerate points
            where = None
    if where is not None:
        text += (f"; the {len(measured)} points measured put the tracker at about {where} m "
                 "(robot base frame)")
    return f"{text}: {fix}, then run again"


def _locate(boot: list[PoseRecord], robot: str, smr_guess: np.ndarray) -> tuple[pin.SE3, np.ndarray]:
    """(tracker pose, SMR offset) fitted to the bootstrap points with the nominal arm."""
    located = register(measurements_of(boot, "bootstrap"), robot, smr_guess)
    return located.tracker, located.smr


def measurements_of(records: list[PoseRecord], source: str) -> Measurements:
    """Records as identification input; a pose is named by its campaign index. Hashed as the
    measurements CSV of these poses, in this order (`measurements_sha256`)."""
    return Measurements.from_arrays(np.array([r.q for r in records]), np.array([r.p for r in records]),
                                    source, lines=np.array([r.index for r in records], dtype=int))


def iso9283(records: list[PoseRecord], geometry: Geometry) -> dict[str, Any] | None:
    """ISO 9283 position accuracy AP and repeatability RP per repeated validation pose.

    The commanded position of a pose is what `geometry` predicts for its target joints; AP is the
    distance from the barycentre of the attained positions to it, RP = l̄ + 3·S_l over the distances
    l_j of the attained positions to their barycentre. Needs poses visited at least twice.
    """
    groups: dict[tuple[float, ...], list[PoseRecord]] = {}
    for r in records:
        groups.setdefault(tuple(np.round(r.target, 9)), []).append(r)
    rows = []
    kin = Kinematics(geometry)
    for target, visits in groups.items():
        if len(visits) < 2:
            continue
        pts = np.array([v.p for v in visits])
        bary = pts.mean(axis=0)
        commanded = kin.points(np.array(target))[0]
        dist = np.linalg.norm(pts - bary, axis=1)
        rows.append({"target": list(target), "cycles": len(visits),
                     "AP": float(np.linalg.norm(bary - commanded)),
                     "RP": float(dist.mean() + 3 * dist.std(ddof=1))})
    if not rows:
        return None
    return {"poses": rows, "AP_max": max(r["AP"] for r in rows), "RP_max": max(r["RP"] for r in rows)}


def approached_from_below(meas: Measurements) -> Measurements:
    """`meas` with every joint's approach direction +1: still poses a campaign approached from below."""
    import dataclasses

    return dataclasses.replace(meas, directions=np.ones((len(meas), 6)))


def _sweep_finish(config: StationConfig, campaign: str, start: Geometry, static: Measurements,
                  segments: list[SegmentRecord], records: dict[tuple[str, int], PoseRecord],
                  tracker: pin.SE3, selection: dict[str, Any], watch: ReferenceWatch, stop: EarlyStop,
                  boot_plan: list[tuple[int, np.ndarray]] | None, planned: list[tuple[int, str, np.ndarray]],
                  controller: Mapping[str, Any] | None) -> Plan:
    """A sweep campaign's fit, validation and verdict (`hil.campaign.sweep_plan`): the kinematics and
    the clock map fitted together from the recorded streams and the bootstrap's still poses
    (`hil.calibration.sweep_fit.fit_sweep`), then validated on the held-out still poses as
    stop-and-go's are. The fit starts from the nominal arm located on the bootstrap's points (tracker
    pose and SMR; a resumed run has only the stored tracker and the SMR's guess otherwise, centimetres
    off). Returns the `CampaignResult`."""
    from hil.calibration.sweep_fit import fit_sweep

    robot, camp = config.robot["type"], config.campaign
    boot = [r for (role, _), r in sorted(records.items()) if role == BOOTSTRAP]
    if len(boot) >= 3:  # the first model from the still poses: also on a resume, which skips locating
        located_tracker, located_smr = _locate(boot, robot, np.asarray(start.smr, dtype=float))
        start = Geometry.nominal(robot, located_smr, located_tracker)
    joints, stream, other, joined = streams_of(segments)
    offset, drift = first_clock(joined)
    # every still pose was approached from below in every joint (``campaign.approach``): it lags by
    # the lost motion in +1 directions (the stream's samples to the side each joint last moved), and
    # the validation's predictions lag as its poses do
    from_below = float(camp["approach"]) > 0
    static = approached_from_below(static) if from_below else static
    try:
        validation_q = np.array([q for _, r, q in planned if r == VALIDATION], dtype=float).reshape(-1, 6)
        terms = sweep_terms(parse_request(camp["joint_errors"], "campaign.joint_errors"))
        swept = fit_sweep(start, joints, stream, static=static if len(static) else None,
                          compliance=camp["compliance"], initial_offset_s=offset, initial_drift=drift,
                          guard=(validation_q, VALIDATION_GUARD_RAD), joint_errors=terms)
    except InputError as exc:  # too little trusted data: the run failed, the input was fine
        raise IdentificationError(f"cannot identify from the sweep: {exc}") from None
    fit = swept.fit
    assert fit is not None
    fit.baseline = start  # the nominal arm, located by the bootstrap: "before"
    clock = swept.clock
    left = {k: int(v) for k, v in {**swept.left_out, **other}.items() if v}
    figures = {"offset_s": clock.offset_s, "drift": clock.drift, "sigma_offset_s": clock.sigma_offset_s,
               "t_ref": clock.t_ref, "sigma_at_ref_s": clock.sigma_at_ref_s,
               "sigma_drift": clock.sigma_drift, "used": int(swept.used), "left_out": left,
               "rms": float(swept.rms_m), "segments": len(segments),
               "joint_samples": len(joints.t), "tracker_samples": len(stream.t)}
    yield Emit(SweepFitted(campaign=campaign, offset_s=clock.offset_s, drift=clock.drift,
                           sigma_offset_s=clock.sigma_offset_s, sigma_drift=clock.sigma_drift,
                           used=int(swept.used), left_out=left, rms=float(swept.rms_m),
                           t_ref=float(clock.t_ref), sigma_at_ref_s=float(clock.sigma_at_ref_s)))
    yield Emit(ModelIdentified(campaign=campaign, rms=fit.rms, max=fit.max_error, iterations=fit.iterations,
                               rejected=[], model=model_document(fit, controller=controller)))
    yield Phase("validate")
    val_records = [r for (role, _), r in sorted(records.items()) if role == VALIDATION]
    held_out = measurements_of(val_records, f"campaign {campaign} validation")
    held_out = approached_from_below(held_out) if from_below else held_out
    before = validate(start, held_out)
    after = validate(fit.geometry, held_out)
    try:
        precision = campaign_validation_precision(after.errors, [r.index for r in val_records],
                                                  selection.get("validation"))
    except (ValueError, TypeError, KeyError) as exc:
        precision = None
        yield Emit(Message(campaign=campaign, level="warning",
                           text=f"the validation RMS's standard error could not be estimated: {exc}"))
    verdict = sweep_verdict(after.rms, before.rms, robot, camp["acceptance"])
    yield Emit(ValidationDone(campaign=campaign, before=before.as_dict(), after=after.as_dict(),
                              passed=verdict.passed, controller=None))
    doc = model_document(fit, after.as_dict(), controller=controller)
    drift = watch.summary() if config.warmup["enabled"] or config.drift["every"] or watch.points else None
    return CampaignResult(fit, before, after, verdict.passed, list(records.values()), tracker, selection,
                          iso9283(val_records, fit.geometry), doc, None, drift, stop.summary(), precision,
                          pose_counts(boot_plan, planned, records), None, verdict, figures)


def calibration_plan(config: StationConfig, choose: ChoosePoses, campaign: str,
                     resume: ResumeState | None = None, validation_cycles: int = 1,
                     controller: Mapping[str, Any] | None = None, keep_in_check: Geometry | None = None,
                     session: str = "") -> Plan:
    """The whole campaign as a generator of steps; returns a `CampaignResult`.

    `controller`: the controller's own model (`controller_record`), when it reported one: kept in
    the model document and validated on the same held-out poses as hil's. A sweep campaign
    (``campaign.mode = "sweep"``, `hil.campaign.sweep_plan`) checks its tour with `keep_in_check`
    (the arm the engine checks moves with; default: the located nominal arm) and records its
    segments under `session` (this run's).
    """
    resume = resume or ResumeState()
    robot = config.robot["type"]
    camp = config.campaign
    smr_guess = np.array(config.smr["offset"])
    keep_in = (np.array(config.keep_in["min"]), np.array(config.keep_in["max"]))
    visit = visit_settings(config)
    records = dict(resume.records)
    sweeping = camp["mode"] == SWEEP
    sweep_records = dict(resume.sweep)

    def sweep_bootstrap(plan: list[tuple[int, np.ndarray]]) -> Plan:
        """The bootstrap's segments (`bootstrap_segments`), those not recorded yet swept in one step;
        returns the segment that holds at each bootstrap pose (None: none does)."""
        located = Geometry.nominal(robot, smr_guess)  # keep-in and limits need no tracker
        spec = get_robot(robot)
        targets = np.array([q for _, q in plan], dtype=float).reshape(-1, 6)
        segments = bootstrap_segments(targets, config, spec, keep_in_check or located, located)
        todo = [g for g in segments if g is not None and g.index not in sweep_records]
        if todo:
            hop = hop_limits(config, spec, targets, located)
            got = yield Sweep(tuple(todo), len(segments), TRACKER_RATE_HZ, session, *hop)
            if isinstance(got, SweepRecorded):
                sweep_records.update({r.index: r for r in got.segments})
        return {i: g for (i, _), g in zip(plan, segments, strict=True)}

    # --- where is the tracker? -----------------------------------------------------------------
    tracker = resume.tracker
    if tracker is None and config.tracker["position"] is not None:
        tracker = look_at_tracker(config.tracker["position"])
    boot = [r for (role, _), r in sorted(records.items()) if role == BOOTSTRAP]
    boot_plan = resume.bootstrap
    if tracker is None and boot_plan is None and \
            len(boot) >= len(bootstrap_targets(np.zeros(6), camp["bootstrap_poses"])):
        # a run of an older hil (no stored bootstrap plan) interrupted after its bootstrap: locate
        # from those points, not again
        tracker, smr_guess = _locate(boot, robot, smr_guess)
    if tracker is None:
        if boot_plan is None:
            count = len(bootstrap_targets(np.zeros(6), camp["bootstrap_poses"]))
            yield Phase("bootstrap", f"locating the tracker from {bootstrap_words(count)} around the "
                                     "start pose")
            start = np.asarray((yield ReadJoints(config.robot["joint_samples"])).q, float)
            # after any index an older run used, so no stored pose is given another target
            first = 1 + max((i for _, i in records), default=-1)
            boot_plan = [(first + k, q) for k, q in enumerate(
                bootstrap_targets(start, camp["bootstrap_poses"]))]
            # stored before the first move: a resumed run visits these targets, not new ones
            # centred on wherever the arm stopped
            yield Emit(BootstrapPlanned(
                campaign=campaign, start=[float(v) for v in start],
                poses=[{"index": i, "role": BOOTSTRAP, "q": [float(v) for v in q]} for i, q in boot_plan]))
        else:
            left = sum(1 for i, _ in boot_plan if (BOOTSTRAP, i) not in records)
            yield Phase("bootstrap", f"locating the tracker: {left} of {len(boot_plan)} bootstrap poses "
                                     "left to measure")
        # a sweep campaign streams its bootstrap: each pose read off a hold of one swept path
        # (`hil.campaign.sweep_bootstrap`); a pose it cannot read so is visited still, as here
        held: dict[int, SweepSegment | None] = {}
        if sweeping:
            held = yield from sweep_bootstrap(boot_plan)
        for i, q in boot_plan:
            if (BOOTSTRAP, i) in records:  # measured before the run was interrupted
                continue
            segment = held.get(i)
            record = yield from hold_point(campaign, i, BOOTSTRAP, q, segment,
                                           None if segment is None else sweep_records.get(segment.index),
                                           float(camp["stability"]))
            if record is None:
                record = yield acquire(i, BOOTSTRAP, q, **visit)
            if isinstance(record, PoseRecord):  # else skipped (the engine said why)
                records[(BOOTSTRAP, i)] = record
        boot = [r for (role, _), r in sorted(records.items()) if role == BOOTSTRAP]
        if len(boot) < 3:  # three points fix a frame; fewer is a station problem, not a fit failure
            raise IdentificationError(
                f"cannot locate the tracker: {len(boot)} of {len(boot_plan)} bootstrap points "
                "measured (is the SMR facing the tracker with a clear line of sight at the start pose? "
                "or set tracker.position in the configuration)")
        tracker, smr_guess = _locate(boot, robot, smr_guess)
    model = Geometry.nominal(robot, smr_guess, tracker)

    # --- which poses? --------------------------------------------------------------------------
    selection = dict(resume.selection)
    if resume.poses is None:
        yield Phase("select", f"{camp['calibration_poses']} calibration + "
                              f"{camp['validation_poses']} validation poses")
        base = dict(model=model, keep_in=keep_in, acceptance_angle=config.smr["acceptance_angle"],
                    index=camp["index"], candidates=camp["candidates"])
        # one numbering across roles, after the bootstrap's (skipped ones included)
        first = 1 + max([i for _, i in records] + [i for i, _ in boot_plan or ()], default=-1)
        if camp["selection"] == TIME_AWARE and validation_cycles == 1:
            # validation poses first (a sample of the workspace, as always), then the calibration poses
            # and one tour through both, from where the arm stands now
            here = np.asarray((yield ReadJoints(config.robot["joint_samples"])).q, dtype=float)
            val = choose(SelectionRequest(VALIDATION, camp["validation_poses"], seed=camp["seed"] + 1,
                                          exclude=np.zeros((0, 6)), **base))
            cal = choose(SelectionRequest(CALIBRATION, camp["calibration_poses"], seed=camp["seed"],
                                          exclude=val.poses, start=here, fixed=val.poses, **base))
            planned = _tour_plan(first, cal, val)
            # validation pose k of each planned validation entry: the tour's fixed stops carry it
            tour = cal.info.get("tour")  # none: validation poses after the calibration, in order
            fixed = (range(len(val.poses)) if tour is None
                     else [int(s["index"]) for s in tour if s["role"] != "selected"])
            pose_of = dict(zip([i for i, r, _ in planned if r == VALIDATION], fixed, strict=True))
        else:
            cal = choose(SelectionRequest(CALIBRATION, camp["calibration_poses"], seed=camp["seed"],
                                          exclude=np.zeros((0, 6)), **base))
            val = choose(SelectionRequest(VALIDATION, camp["validation_poses"], seed=camp["seed"] + 1,
                                          exclude=cal.poses, start=cal.poses[-1], **base))
            planned = [(first + i, CALIBRATION, q) for i, q in enumerate(cal.poses)]
            n = first + len(planned)
            pose_of = {}
            for cycle in range(validation_cycles):
                planned += [(n + cycle * len(val.poses) + i, VALIDATION, q)
                            for i, q in enumerate(val.poses)]
                pose_of.update({n + cycle * len(val.poses) + i: i for i in range(len(val.poses))})
        # stored with the plan: a resumed run maps its validation records to their poses alike
        # (`campaign_validation_precision`)
        selection = {"calibration": cal.info, "validation": {
            **val.info, "pose_of_index": {str(i): int(k) for i, k in pose_of.items()}}}
    else:
        planned = resume.poses
    reference = resume.reference
    if reference is None:  # a new plan (or one stored by an older hil): the same one from now on
        reference = reference_pose(model, np.array([q for _, r, q in planned if r == VALIDATION] or
                                                   [q for _, _, q in planned]),
                                   np.array([q for _, _, q in planned]))
    yield Emit(PlanReady(campaign=campaign, poses=[{"index": i, "role": r, "q": list(map(float, q))}
                                                   for i, r, q in planned],
                         tracker=pose_to_dict(tracker), selection=selection,
                         reference=[float(v) for v in reference]))

    # --- measure -------------------------------------------------------------------------------
    segments: list[SweepSegment] = []
    # a sweep rests at the first cycle's validation poses along its tour: measured still there (read
    # off the hold of the segment arriving, else visited as stop-and-go visits them), without a tour
    # of their own (`hil.campaign.sweep_plan`, `hil.campaign.sweep_rests`)
    rests: dict[int, np.ndarray] = {}
    for i, r, q in planned if sweeping else ():
        if r == VALIDATION and not any(np.array_equal(q, other) for other in rests.values()):
            rests[i] = np.asarray(q, dtype=float)
    if sweeping:  # the tour through the calibration poses, checked whole before the sweep moves
        waypoints = np.array([q for _, r, q in planned if r == CALIBRATION] + list(rests.values()))
        if resume.sweep_tour:  # the tour the campaign began: its segments' numbers name what is recorded
            segments = stored_tour(resume.sweep_tour, config, get_robot(robot), keep_in_check or model,
                                   limit_model=model, waypoints=waypoints)
        else:
            # the tour starts at the calibration waypoint nearest the arm (the largest joint
            # difference): the move there is not swept, and a rest it started at would be visited
            here = np.asarray((yield ReadJoints(config.robot["joint_samples"])).q, dtype=float)
            calibration = waypoints[: len(waypoints) - len(rests)]
            first = int(np.argmin(np.max(np.abs(calibration - here), axis=1))) if len(calibration) else 0
            waypoints = waypoints[[first, *(k for k in range(len(waypoints)) if k != first)]]
            segments = sweep_tour(waypoints, config, get_robot(robot), keep_in_check or model,
                                  sight_model=model, limit_model=model,
                                  rests=np.array(list(rests.values())).reshape(-1, 6))
    visits = tour_visits(segments, rests)
    in_tour = {i for kind, i in visits if kind == "rest"}
    todo = [(i, r, q) for i, r, q in planned if (r, i) not in records
            and not (sweeping and r == CALIBRATION) and i not in in_tour]
    # the stopping rule (campaign.stop_early): a stop the store holds is kept as it was decided
    stop = EarlyStop(StoppingRule(robot, smr_guess, np.array([q for _, r, q in planned if r == VALIDATION]),
                                  acceptance_threshold(camp["acceptance"], robot), camp["stop_margin"],
                                  compliance=camp["compliance"],
                                  payload=config.payload, gravity=config.gravity)
                     if camp["stop_early"] and not sweeping else None, resume.stopping)

    def fitted() -> list[PoseRecord]:
        return [r for (role, _), r in sorted(records.items()) if role in (BOOTSTRAP, CALIBRATION)]

    def calibration_left(after: int) -> list[int]:
        return [j for j, r, _ in todo[after:] if r == CALIBRATION and (r, j) not in records]

    def measured_calibration() -> int:
        return sum(1 for role, _ in records if role == CALIBRATION)

    if measured_calibration():  # resumed: the check the interrupted run may not have made on these
        stopped = stop.consider(campaign, fitted(), measured_calibration(), calibration_left(0))
        if stopped is not None:
            yield Emit(stopped)
    # the tracker frame was located from measured points (the bootstrap) unless it was configured
    watch = ReferenceWatch(config, campaign, reference, model, visit, resume.references,
                           located=config.tracker["position"] is None)
    sweep_left = [g for g in segments if g.index not in sweep_records]
    rests_left = [i for i in in_tour if (VALIDATION, i) not in records]
    if todo or sweep_left or rests_left:  # warm (again, on a resume: the arm may have cooled) first
        yield from watch.warm_up([q for _, r, q in planned if r == CALIBRATION])
    sight = _SightCheck(robot, smr_guess, tracker.translation, config.smr["acceptance_angle"],
                        getattr(choose, "hidden", None))
    lost: list[Skipped] = []  # beam lost at each of these poses, one after another

    def measure_still(i: int, role: str, q: np.ndarray) -> Plan:
        """One still pose measured (`acquire`), unless predicted out of sight; True if recorded."""
        sight.refine(list(records.values()))
        reason = sight.hidden(q)
        if reason is not None:  # don't drive there and wait for a beam that cannot come
            yield Emit(PoseSkipped(campaign=campaign, index=i, role=role,
                                   reason=f"predicted out of the tracker's sight: {reason}"))
            return False
        record = yield acquire(i, role, q, **visit)
        if isinstance(record, PoseRecord):
            records[(role, i)] = record
            lost.clear()
            yield from watch.after_pose()
            return True
        if isinstance(record, Skipped) and record.lost:
            lost.append(record)
            if len(lost) >= camp["max_consecutive_lost"]:
                raise TrackerLooksWrong(_tracker_looks_wrong(
                    config, lost, tracker, list(records.values()), smr_guess))
        return False

    def rest_from_stream(i: int, q: np.ndarray, arrived: SweepSegment | None) -> Plan:
        """Validation pose `i` read off the hold of the segment that `arrived` there
        (`hil.campaign.sweep_rests`); False when it cannot be, and the pose is visited."""
        record = yield from hold_point(campaign, i, VALIDATION, q, arrived,
                                       None if arrived is None else sweep_records.get(arrived.index),
                                       float(camp["stability"]))
        if record is None:
            return False
        records[(VALIDATION, i)] = record
        lost.clear()
        yield from watch.after_pose()
        return True

    if segments:
        yield Phase("sweep", f"{len(sweep_left)} of {len(segments)} sweep segments to record"
                    + (f", resting at {len(rests_left)} still validation poses" if rests_left else ""))
        yield Emit(SweepPlanned(
            campaign=campaign, segments=[{"index": g.index, "from": list(g.start),
                                          "to": [float(v) for v in g.q[-1]],
                                          "seconds": (len(g.q) - 1) / CONTROLLER_RATE_HZ,
                                          "samples": len(g.q),
                                          "knots": [] if g.knots is None else np.asarray(g.knots).tolist(),
                                          "dwell": int(g.dwell)}
                                         for g in segments],
            waypoints=[list(map(float, w)) for w in waypoints], rate_hz=CONTROLLER_RATE_HZ,
            tracker_rate_hz=TRACKER_RATE_HZ,
            done=sorted(i for i in sweep_records if not is_bootstrap_segment(i)),
            rests=sorted(in_tour)))
        if rests_left:
            yield from watch.start()
        # the unswept moves between segments at the sweep's own limits when it has them
        hop = hop_limits(config, get_robot(robot), waypoints, model)
        by_index = {g.index: g for g in segments}
        pending: list[SweepSegment] = []
        last: SweepSegment | None = None  # the segment the tour arrived by
        for kind, ref in [*visits, ("end", -1)]:
            if kind == "segment":
                last = by_index[ref]
                if ref not in sweep_records:
                    pending.append(by_index[ref])
                continue
            if pending:  # the segments up to this rest, swept in one step
                got = yield Sweep(tuple(pending), len(segments), TRACKER_RATE_HZ, session, *hop)
                if isinstance(got, SweepRecorded):
                    sweep_records.update({r.index: r for r in got.segments})
                pending = []
            if kind == "rest" and (VALIDATION, ref) not in records:
                arrived = last if last is not None and np.allclose(
                    last.q[-1], rests[ref], rtol=0.0, atol=1e-9) else None
                read = yield from rest_from_stream(ref, rests[ref], arrived)
                if not read:
                    yield from measure_still(ref, VALIDATION, rests[ref])
    left = [(i, r) for i, r, _ in todo if not (r == CALIBRATION and stop.stopped)]
    if sweeping:  # the calibration poses were swept: the still ones left are the validation's
        still = sum(1 for _, r, _ in planned if r != CALIBRATION) - len(in_tour)
        yield Phase("measure", f"{len(left)} of {still} still validation poses to measure")
    else:
        yield Phase("measure", f"{len(left)} of {len(planned)} poses to measure")
    if todo:
        yield from watch.start()
    for k, (i, role, q) in enumerate(todo):
        if role == CALIBRATION and stop.stopped:  # the fit so far already predicts the acceptance
            continue
        measured = yield from measure_still(i, role, q)
        if measured and role == CALIBRATION:
            stopped = stop.consider(campaign, fitted(), measured_calibration(), calibration_left(k + 1))
            if stopped is not None:
                yield Emit(stopped)

    yield from watch.finish()

    # --- identify and validate (reference measurements are not records: no fit ever sees them) ---
    yield Phase("identify")
    fit_records = [r for (role, _), r in sorted(records.items()) if role in (BOOTSTRAP, CALIBRATION)]
    fitted = measurements_of(fit_records, f"campaign {campaign}")
    if sweeping:
        return (yield from _sweep_finish(config, campaign, model, fitted, list(sweep_records.values()),
                                         records, tracker, selection, watch, stop, boot_plan, planned,
                                         controller))
    try:
        fit = identify_with_joint_errors(
            fitted, robot, smr_guess, compliance=camp["compliance"], payload=config.payload,
            gravity=config.gravity,
            request=parse_request(camp["joint_errors"], "campaign.joint_errors"))
    except InputError as exc:  # too many poses skipped: the run failed, the input was fine
        raise IdentificationError(f"cannot identify from the measured poses: {exc}") from None
    their_arm = None
    if controller is not None:
        try:
            their_arm = controller_calibration(controller).geometry(robot)
        except (HilError, ValueError, KeyError) as exc:
            yield Emit(Message(campaign=campaign, level="warning",
                               text=f"the controller's own model could not be compared: {exc}"))
    cv = cross_validate(fitted, fit, controller=their_arm, smr_guess=smr_guess)
    yield Emit(ModelIdentified(campaign=campaign, rms=fit.rms, max=fit.max_error,
                               iterations=fit.iterations, rejected=[r.line for r in fit.rejected],
                               model=model_document(fit, controller=controller,
                                                    cross_validation=cv.as_dict())))
    yield Phase("validate")
    val_records = [r for (role, _), r in sorted(records.items()) if role == VALIDATION]
    held_out = measurements_of(val_records, f"campaign {campaign} validation")
    before = validate(fit.baseline, held_out)
    after = validate(fit.geometry, held_out)
    try:  # how precise that RMS is, under the design that chose the poses (the plan's selection info)
        precision = campaign_validation_precision(after.errors, [r.index for r in val_records],
                                                  selection.get("validation"))
    except (ValueError, TypeError, KeyError) as exc:  # a malformed stored plan: said, never a failure
        precision = None
        yield Emit(Message(campaign=campaign, level="warning",
                           text=f"the validation RMS's standard error could not be estimated: {exc}"))
    stopping = stop.summary()
    predicted = stopping.get("predicted_rms") if stopping and stopping.get("stopped") else None
    verdict = judge(after.rms, cv, robot, camp["acceptance"], validation_poses=after.count,
                    predicted=None if predicted is None else float(predicted))
    iso = iso9283(val_records, fit.geometry)
    theirs = None
    if controller is not None:  # a comparison that cannot be made is said, never fails the campaign
        try:
            theirs = controller_validation(controller_calibration(controller), robot, fitted, held_out,
                                           smr_guess)
        except (HilError, ValueError, KeyError, np.linalg.LinAlgError) as exc:
            yield Emit(Message(campaign=campaign, level="warning",
                               text=f"the controller's own model could not be compared: {exc}"))
    yield Emit(ValidationDone(campaign=campaign, before=before.as_dict(), after=after.as_dict(),
                              passed=verdict.passed,
                              controller=None if theirs is None else theirs.as_dict()))
    doc = model_document(fit, after.as_dict(), controller=controller, cross_validation=cv.as_dict())
    drift = watch.summary() if config.warmup["enabled"] or config.drift["every"] or watch.points else None
    return CampaignResult(fit, before, after, verdict.passed, list(records.values()), tracker, selection,
                          iso, doc, theirs, drift, stopping, precision,
                          pose_counts(boot_plan, planned, records), cv, verdict)
