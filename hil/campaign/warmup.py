"""Warm-up and drift watch: the arm is warmed up before it is measured, and a reference pose is watched
while it is.

Why. A UR's joints warm by a few kelvin over the first tens of minutes of motion and its aluminium links
grow with them (2.3e-5 /K, `hil.arm.thermal`): a metre of arm grows by about 0.1 mm, the whole
acceptance of a calibration. Points measured on a cold arm and on a warm one do not fit one geometry,
and a model fitted cold is wrong on the warm arm it will drive. Calibration practice — ISO 9283:1998
§6.2 (the robot is warmed up before it is tested) and §7.6 (drift of pose characteristics), and every
laser-tracker calibration guide — warms the arm up first and re-measures a reference while measuring.

How (the plan steps of `ReferenceWatch`; the plan, `hil.campaign.calibration_plan`, says when):

* **The reference pose** (`reference_pose`) is the validation pose whose SMR is nearest the middle of
  all the planned SMR positions: one the selector checked the tracker sees, well inside the
  workspace. It is stored with the plan (`PlanReady.reference`), so a resumed run measures the same one.
  Every visit approaches it the same way, from a pose a little below it in every joint (ISO 9283
  §7.2.1 approaches each pose from the same direction), so the arm's own repositioning spread (UR5e
  repeatability ±0.03 mm, UR's e-Series data sheet) adds as little as it can to what is watched.
* **Warm-up** (`warm_up`, ``[warmup]``): measure the reference, cycle through the planned calibration
  poses in order for ``interval`` seconds of station time (real motion, so the joints warm as they will
  while measuring), measure it again, and so on. Each check reports how far the reference moved since
  the previous one, but that is not what decides: with a 2-minute interval and a 15-minute time
  constant one interval shows only an eighth of the growth still to come, so "two consecutive
  measurements within 10 µm" would call an arm warm with some 80 µm of growth ahead (and the tracker's
  noise decides the last micrometres). The arm is warm when the first-order fit of the whole series
  (`hil.calibration.warmup_fit.fit_warmup`, from its 4th measurement) says the drift still to come is below
  ``limit`` and the series spans three fitted time constants (the fit has then seen the curve
  flatten, not guessed it from its start), both taken at the fit's upper 99 % confidence limits
  (the most drift still to come, the longest time constant the series allows), never the point
  estimates, which jump between visits on a noisy series. An arm already warm when the warm-up began
  (its reported joint temperatures never moved 0.3 K over the series) gives no curve to fit; it is
  warm when every joint's temperature stayed within the sensor's resolution (0.1 K) over the last
  three measurements (two intervals of cycling) and the reference moved by less than ``limit`` among
  them — on a warming arm that is no proof, and the fit decides. The rule and its evidence are
  `hil.calibration.warmup_decision`; every check's `WarmupProgress` carries the evidence (the fit's
  τ and drift still to come, their upper limits, the span, the flat-temperature figures) and the
  verdict in words, so a user sees why the warm-up went on or stopped. After ``max_time`` the run
  goes on with a warning (`WarmupFinished`, ``converged`` false), recorded in the result. The last
  warm-up measurement is the **baseline**.
* **Drift watch** (`start`, `after_pose`, `finish`, ``[drift]``): the reference is measured again after
  every ``every`` measured poses and once when the measuring ends; its drift is its displacement from
  the baseline. Beyond ``limit`` the campaign is flagged (`DriftFlagged`, the result's ``drift``
  block, the report) — and keeps the accept/reject verdict its validation gives: drift says the
  measurements may be less consistent than the validation shows, not that the model failed. With the
  warm-up off, the first drift measurement is the baseline.
* **Reading the reference**: each visit stands still ``drift.settle`` seconds after its approach and
  averages ``drift.samples`` tracker readings (more than a pose's). The arm rings after every move; a
  pose's settle-on-evidence window (five readings within ``campaign.stability``) cannot tell a ring
  aliased by 0.1 s readings from the tracker's noise, so on the realistic simulated UR5e the watch
  read 9–24 µm of ring along the approach's tip direction while the truth drifted 0.4–5 µm. Still
  and averaged, it reads the drift (docs/design.md, Facts: what a drift watch sees).
* **Displacement** is what the tracker saw minus what the arm's joint readings explain (the change of
  the nominal model's prediction between the two joint readings), when the tracker's frame was located
  from measured points (the bootstrap): the arm not returning to exactly the same joints is not drift.
  With a configured tracker position the frame's orientation is only a guess, so the tracker's
  displacement is taken as it is.
* **Resume.** A resumed run warms up again (the arm may have cooled while it stood) and keeps the
  campaign's baseline and every earlier reference measurement (the store's log of `ReferenceMeasured`
  events, which are committed before the next move as points are). Reference measurements are never
  campaign points: no fit, no validation, no pose count ever sees them (`hil.campaign.steps.REFERENCE`).

Times are station seconds since the run started (`ReadConditions`: a fast-time simulation's
seconds, the wall clock's on a station); each run of a campaign starts at zero, so a series is kept
with its run number.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Generator, Mapping, Sequence
from typing import Any

import numpy as np

from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.arm.safety import check_target
from hil.calibration.warmup_decision import WarmupDecision, decide_warm
from hil.calibration.warmup_fit import DriftFit
from hil.campaign.events import (
    DriftFlagged,
    Message,
    ReferenceMeasured,
    WarmupFinished,
    WarmupProgress,
)
from hil.campaign.reference_lines import DRIFT, WARMUP, um
from hil.campaign.steps import (
    REFERENCE,
    Conditions,
    Emit,
    Move,
    Phase,
    PoseRecord,
    ReadConditions,
    Skipped,
    Step,
    acquire,
)
from hil.errors import InputError
from hil.station.config import StationConfig

#: The approach offset (rad, every joint): each reference visit first goes this far below the
#: reference in every joint, so it is always reached the same way (ISO 9283 §7.2.1).
APPROACH = 0.05


def approach_pose(config: StationConfig, reference: np.ndarray) -> np.ndarray | None:
    """Where every reference visit starts from (`APPROACH` below the reference in every joint), or None
    when that pose or the way from it to the reference is not safe (joint limits, keep-in box: the
    engine's own checks): the reference is then approached from wherever the arm is."""
    q = np.asarray(reference, float) - APPROACH
    spec = get_robot(config.robot["type"])
    box = (np.array(config.keep_in["min"]), np.array(config.keep_in["max"]))
    model = Geometry.nominal(spec, config.smr["offset"])
    try:
        check_target(q, spec, box, model)
        check_target(np.asarray(reference, float), spec, box, model, start=q)
    except InputError:
        return None
    return q


def reference_pose(model: Geometry, validation: np.ndarray, planned: np.ndarray) -> np.ndarray:
    """The validation pose whose SMR (by `model`) is nearest the median of the `planned` poses' SMR
    positions: seen by the tracker (the selector checked it) and well inside the workspace."""
    kin = Kinematics(model)
    centre = np.median(kin.points(np.asarray(planned, float), frame="base"), axis=0)
    candidates = np.asarray(validation, float).reshape(-1, 6)
    where = kin.points(candidates, frame="base")
    return candidates[int(np.argmin(np.linalg.norm(where - centre, axis=1)))].copy()


class ReferenceWatch:
    """The reference pose of one campaign run: its warm-up, drift checks and the result's ``drift`` block.

    `earlier`: the campaign's reference measurements from earlier runs (the store's log), in order.
    `located`: whether `model`'s tracker frame was located from measured points (the bootstrap), so
    joint-reading differences can be taken out of the displacement (see the module docstring).
    """

    def __init__(self, config: StationConfig, campaign: str, reference: np.ndarray, model: Geometry,
                 visit: Mapping[str, Any], earlier: Sequence[ReferenceMeasured] = (),
                 located: bool = False) -> None:
        self.config, self.campaign = config, campaign
        self.reference = np.asarray(reference, float).reshape(6)
        self.approach = approach_pose(config, self.reference)
        # every reference visit stands still `drift.settle` s and averages `drift.samples` readings: the
        # arm's ring after its approach, not the drift, was most of what the watch read (module docstring)
        self.visit = {**visit, "samples": int(config.drift["samples"]),
                      "dwell": float(config.drift["settle"])}
        self.kin = Kinematics(model) if located else None
        self.points: list[ReferenceMeasured] = list(earlier)
        self.run = 1 + max((p.run for p in self.points), default=0)
        self.baseline: ReferenceMeasured | None = next((p for p in self.points if p.baseline), None)
        self.previous: ReferenceMeasured | None = None  # this run's last measurement
        self.since = 0  # poses measured since the last drift check
        self.flagged = False  # this run emitted DriftFlagged
        self.warmup: dict[str, Any] | None = None  # this run's warm-up (None: none ran)
        self._k = 0  # where the warm-up cycle goes on

    # --- measuring the reference ----------------------------------------------------------------
    def displacement(self, a: ReferenceMeasured, b: ReferenceMeasured) -> float:
        """How far the reference moved from `a` to `b` (m), see the module docstring."""
        return float(np.linalg.norm(self.positions([a, b])[1]))

    def positions(self, points: Sequence[ReferenceMeasured]) -> np.ndarray:
        """The reference's positions (N, 3; tracker frame, m) relative to the first of `points`, with
        what the arm's joint readings explain taken out (when the tracker frame was located)."""
        xyz = np.array([p.xyz for p in points], dtype=float).reshape(-1, 3)
        d = xyz - xyz[0]
        if self.kin is not None and len(points):
            pred = self.kin.points(np.array([p.q for p in points], dtype=float))
            d = d - (pred - pred[0])
        return d

    def settled(self, series: Sequence[ReferenceMeasured]) -> tuple[bool, DriftFit | None]:
        """Whether a warm-up `series` (this run's, in order) shows the arm warm, and the fit (None before
        `hil.calibration.warmup_fit.MIN_POINTS` measurements); `decide` gives the evidence too."""
        decision = self.decide(series)
        return decision.warm, decision.fit

    def decide(self, series: Sequence[ReferenceMeasured]) -> WarmupDecision:
        """The warm-up's rule (`hil.calibration.warmup_decision.decide_warm`: the fitted drift still to
        come below ``warmup.limit`` over three time constants, at their upper confidence limits, or an
        arm warm from the start) on a `series` (this run's, in order), with its evidence."""
        times = np.array([p.elapsed for p in series], dtype=float)
        # the joint temperatures the controller reports, when every measurement has them, fix τ
        # without the tracker's noise (hil.calibration.warmup_fit)
        temps = ([p.temperatures for p in series]
                 if series and all(p.temperatures for p in series) else None)
        return decide_warm(times, self.positions(series), float(self.config.warmup["limit"]),
                           temperatures=None if temps is None else np.array(temps, dtype=float))

    def _visit(self) -> Generator[Step, Any, tuple[PoseRecord, Conditions] | None]:
        """Approach and measure the reference; None (said in a warning) when the visit was given up."""
        if self.approach is not None:
            yield Move(tuple(float(v) for v in self.approach), self.visit.get("speed"),
                       self.visit.get("acceleration"), optional=True)
        seq = 1 + max((p.seq for p in self.points), default=0)
        record = yield acquire(seq, REFERENCE, self.reference, **self.visit)
        if not isinstance(record, PoseRecord):
            reason = record.reason if isinstance(record, Skipped) else "no reading"
            yield Emit(Message(campaign=self.campaign, level="warning",
                               text=f"the reference pose could not be measured ({reason}); the run goes on"))
            return None
        conditions = yield ReadConditions()
        return record, conditions

    def _record(self, record: PoseRecord, conditions: Conditions, phase: str, *,
                baseline: bool, limit: float) -> Generator[Step, Any, ReferenceMeasured]:
        """Emit the `ReferenceMeasured` of a visit (the store commits it before the next step)."""
        event = ReferenceMeasured(
            campaign=self.campaign, seq=1 + max((p.seq for p in self.points), default=0), run=self.run,
            phase=phase, elapsed=float(conditions.t), q=[float(v) for v in record.q],
            xyz=[float(v) for v in record.p], p_spread=[float(v) for v in record.p_spread],
            baseline=baseline, limit=limit,
            temperatures=None if conditions.temperatures is None else list(conditions.temperatures))
        moved = None if self.previous is None else self.displacement(self.previous, event)
        drift = 0.0 if baseline else (None if self.baseline is None else
                                      self.displacement(self.baseline, event))
        event = dataclasses.replace(event, moved=moved, drift=drift)
        yield Emit(event)
        self.points.append(event)
        self.previous = event
        if baseline:
            self.baseline = event
        return event

    # --- warm-up --------------------------------------------------------------------------------
    def warm_up(self, cycle: Sequence[np.ndarray]) -> Generator[Step, Any, None]:
        """Cycle through `cycle` (the planned calibration poses) until the reference settles; see the
        module docstring. Does nothing when ``warmup.enabled`` is false or there is nothing to cycle."""
        w = self.config.warmup
        if not w["enabled"] or not len(cycle):
            return
        interval, limit, max_time = float(w["interval"]), float(w["limit"]), float(w["max_time"])
        yield Phase(WARMUP, f"cycling {len(cycle)} calibration poses; the reference pose is measured every "
                            f"{interval:g} s until less than {um(limit)} of drift is still to come (at "
                            f"most {max_time:g} s)")
        start = (yield ReadConditions(temperatures=False)).t
        series: list[ReferenceMeasured] = []
        moved: float | None = None
        decision: WarmupDecision | None = None
        converged, reason = False, ""
        while True:
            got = yield from self._visit()
            if got is not None:
                record, conditions = got
                elapsed = conditions.t - start
                candidate = [*series, _as_point(record, conditions)]
                decision = self.decide(candidate)
                converged = decision.warm
                end = converged or elapsed >= max_time
                event = yield from self._record(record, conditions, WARMUP, limit=limit,
                                                baseline=end and self.baseline is None)
                if series:
                    moved = event.moved
                    # every check says why it went on or stopped (the fit, τ and its upper limit, the
                    # flat-temperature evidence): the JSON events, the store's log, the result
                    yield Emit(WarmupProgress(
                        campaign=self.campaign, elapsed=elapsed, moved=float(moved or 0.0),
                        interval=conditions.t - series[-1].elapsed, limit=limit, max_time=max_time,
                        **decision.evidence()))
                series.append(event)
                if end:
                    break
                now = conditions.t
            else:
                now = (yield ReadConditions(temperatures=False)).t
                if now - start >= max_time:
                    reason = "the reference pose could not be measured"
                    break
            if not (yield from self._cycle(cycle, min(now + interval, start + max_time))):
                reason = "no calibration pose could be reached safely to cycle through"
                break
        seconds = (yield ReadConditions(temperatures=False)).t - start
        # what the rule compared with three time constants: the span of the series it judged
        span = series[-1].elapsed - series[0].elapsed if series else None
        if not converged and not reason and decision is not None and decision.fit is not None:
            reason = decision.reason.removeprefix("not yet: ")  # the last check's own words
        evidence = {} if decision is None else decision.evidence()
        judged = {k: evidence.get(k) for k in ("remaining", "remaining_upper", "time_constant",
                                               "time_constant_upper", "decision")}
        rule = str(evidence.get("rule") or "")
        self.warmup = {"seconds": seconds, "converged": converged, "references": len(series),
                       "reason": reason, "moved": moved, "span": span, "rule": rule, **judged,
                       "evidence": evidence or None}
        yield Emit(WarmupFinished(campaign=self.campaign, seconds=seconds, converged=converged,
                                  references=len(series), moved=moved, limit=limit, reason=reason,
                                  span=span, rule=rule, **judged))

    def _cycle(self, cycle: Sequence[np.ndarray], until: float) -> Generator[Step, Any, bool]:
        """Move through `cycle` (going on where the last cycle stopped) until station time `until`;
        False when a whole round of targets had no safe path (nothing would warm the arm)."""
        skipped = 0
        while (yield ReadConditions(temperatures=False)).t < until:
            q = cycle[self._k % len(cycle)]
            self._k += 1
            reply = yield Move(tuple(float(v) for v in q), self.visit.get("speed"),
                               self.visit.get("acceleration"), optional=True)
            skipped = skipped + 1 if isinstance(reply, Skipped) else 0
            if skipped >= len(cycle):
                return False
        return True

    # --- drift watch ----------------------------------------------------------------------------
    def start(self) -> Generator[Step, Any, None]:
        """Before the measuring: a baseline, when the drift watch is on and there is none yet."""
        if self.config.drift["every"] and self.baseline is None:
            yield from self._check()

    def after_pose(self) -> Generator[Step, Any, None]:
        """After each measured pose: a drift check every ``drift.every`` poses."""
        every = self.config.drift["every"]
        if not every:
            return
        self.since += 1
        if self.since >= every:
            yield from self._check()

    def finish(self) -> Generator[Step, Any, None]:
        """When the measuring ends: a last drift check covering the poses since the previous one."""
        if self.config.drift["every"] and self.since > 0:
            yield from self._check()

    def _check(self) -> Generator[Step, Any, None]:
        self.since = 0
        got = yield from self._visit()
        if got is None:
            return
        limit = float(self.config.drift["limit"])
        event = yield from self._record(*got, DRIFT, baseline=self.baseline is None, limit=limit)
        if event.drift is not None and event.drift > limit and not self.flagged:
            self.flagged = True
            yield Emit(DriftFlagged(campaign=self.campaign, drift=event.drift, limit=limit,
                                    elapsed=event.elapsed, seq=event.seq))

    # --- the result -----------------------------------------------------------------------------
    def summary(self) -> dict[str, Any]:
        """The result's ``drift`` block (`hil.report`): every reference measurement of the campaign with
        its drift from the baseline (warm-up ones too, so the plot shows the warm-up), the largest
        drift watched while measuring, the limit, whether the campaign is flagged, and the warm-ups."""
        w, d = self.config.warmup, self.config.drift
        series = []
        for p in self.points:
            drift = None if self.baseline is None else (0.0 if p.seq == self.baseline.seq
                                                        else self.displacement(self.baseline, p))
            series.append({"seq": p.seq, "run": p.run, "phase": p.phase, "elapsed": p.elapsed, "time": p.t,
                           "q": list(p.q), "xyz": list(p.xyz), "moved": p.moved, "drift": drift,
                           "baseline": p.baseline, "temperatures": p.temperatures})
        watched = [s["drift"] for s in series if s["phase"] == DRIFT and s["drift"] is not None]
        worst = max(watched) if watched else None
        runs = []
        for run in sorted({p.run for p in self.points} | ({self.run} if self.warmup else set())):
            if run == self.run and self.warmup is not None:
                runs.append({"run": run, **{k: self.warmup[k] for k in (
                    "seconds", "converged", "references", "remaining", "time_constant", "span",
                    "remaining_upper", "time_constant_upper", "rule", "decision")}})
                continue
            ws = [p for p in self.points if p.run == run and p.phase == WARMUP]
            if ws:  # an earlier run: judged again from its stored series
                decision = self.decide(ws)
                ev = decision.evidence()
                runs.append({"run": run, "seconds": ws[-1].elapsed - ws[0].elapsed, "references": len(ws),
                             "converged": decision.warm, "span": ws[-1].elapsed - ws[0].elapsed,
                             **{k: ev[k] for k in ("remaining", "time_constant", "remaining_upper",
                                                   "time_constant_upper", "rule", "decision")}})
        mine = self.warmup or {}
        return {
            "reference": [float(v) for v in self.reference],
            "every": int(d["every"]),
            "limit": float(d["limit"]),
            "max": worst,
            "flagged": worst is not None and worst > float(d["limit"]),
            "baseline": None if self.baseline is None else self.baseline.seq,
            "series": series,
            "warmup": {"enabled": bool(w["enabled"]), "interval": float(w["interval"]),
                       "limit": float(w["limit"]), "max_time": float(w["max_time"]),
                       "ran": self.warmup is not None, "seconds": mine.get("seconds"),
                       "converged": mine.get("converged"), "reason": mine.get("reason", ""),
                       "remaining": mine.get("remaining"), "time_constant": mine.get("time_constant"),
                       "span": mine.get("span"), "remaining_upper": mine.get("remaining_upper"),
                       "time_constant_upper": mine.get("time_constant_upper"), "rule": mine.get("rule"),
                       "decision": mine.get("decision"), "evidence": mine.get("evidence"), "runs": runs},
        }


def _as_point(record: PoseRecord, conditions: Conditions) -> ReferenceMeasured:
    """A visit as a (not yet emitted) reference measurement, for `ReferenceWatch.settled`: its time and
    joint temperatures with it, as the emitted one will have them."""
    temps = None if conditions.temperatures is None else list(conditions.temperatures)
    return ReferenceMeasured(campaign="", seq=0, run=0, phase="", elapsed=float(conditions.t),
                             q=list(record.q), xyz=list(record.p), temperatures=temps)
