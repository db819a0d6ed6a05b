"""Events: what a campaign tells the outside world, as frozen dataclasses.

The engine never prints; it emits these to subscribers. The store is a *critical* subscriber (a
failure to record stops the run); the CLI's JSON-lines printer, progress bar, TUI and live plots are
non-critical (a failure is logged and the run goes on). Every event serialises to one JSON object
with an ``"event"`` key naming its type, which is also what ``--json`` prints one per line.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from typing import Any, ClassVar

import numpy as np

log = logging.getLogger(__name__)


def jsonable(value: Any) -> Any:
    """JSON-ready copy of a value: arrays and tuples become lists, non-finite floats become None."""
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, np.generic):
        return jsonable(value.item())
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


@dataclass(frozen=True, kw_only=True)
class Event:
    """Base of every event: which campaign, and when (Unix time, seconds)."""

    campaign: str
    t: float = field(default_factory=time.time)
    registry: ClassVar[dict[str, type[Event]]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        Event.registry[cls.__name__] = cls

    @property
    def name(self) -> str:
        return type(self).__name__

    def to_dict(self) -> dict[str, Any]:
        return {"event": self.name, **{f.name: jsonable(getattr(self, f.name)) for f in fields(self)}}

    @staticmethod
    def from_dict(data: dict[str, Any]) -> Event:
        """Rebuild an event from `to_dict` output (the store reads its log back this way)."""
        kind = Event.registry[data["event"]]
        names = {f.name for f in fields(kind)}
        return kind(**{k: v for k, v in data.items() if k in names})


@dataclass(frozen=True, kw_only=True)
class RunStarted(Event):
    robot: str
    station: str
    poses: int  # poses planned (calibration + validation)
    resumed: bool = False
    measured: int = 0  # poses already measured (a resumed run)


@dataclass(frozen=True, kw_only=True)
class ControllerModel(Event):
    """The controller's own kinematic model, as it reported it at connect (its KinematicsInfo: full
    DH table, per-joint checksums, calibration status, and the deltas to the nominal DH derived from
    it; `hil.campaign.controller.controller_record`). Emitted right after `RunStarted` when the
    controller said; the store keeps it with the campaign (the model the arm moved with) and as the
    robot's latest."""

    model: dict[str, Any]


@dataclass(frozen=True, kw_only=True)
class StateChanged(Event):
    state: str  # idle, running, paused, suspended, stopping, aborted, done
    previous: str


@dataclass(frozen=True, kw_only=True)
class PhaseChanged(Event):
    phase: str  # connect, bootstrap, select, measure, identify, validate, export, report
    detail: str = ""


@dataclass(frozen=True, kw_only=True)
class PlanReady(Event):
    """The poses the campaign will visit (saved so that a resumed run visits the same ones)."""

    poses: list[dict[str, Any]]  # {"index": i, "role": r, "q": [6 floats]}
    tracker: dict[str, Any] | None = None  # tracker pose estimate used to plan ({"xyz","rpy"})
    selection: dict[str, Any] = field(default_factory=dict)  # index value, % of bound, method...
    # the warm-up and drift reference pose (6 joint angles), kept so a resumed run measures the same one
    reference: list[float] | None = None


@dataclass(frozen=True, kw_only=True)
class BootstrapPlanned(Event):
    """The bootstrap poses (around the arm's pose at the start), saved before the first is visited so
    that a run interrupted during the bootstrap resumes it at the same targets, not around wherever
    the arm stopped. Not the campaign's plan (`PlanReady`): these only locate the tracker."""

    poses: list[dict[str, Any]]  # {"index": i, "role": "bootstrap", "q": [6 floats]}
    start: list[float] = field(default_factory=list)  # the joints the targets are centred on


@dataclass(frozen=True, kw_only=True)
class PoseStarted(Event):
    index: int
    role: str  # bootstrap, calibration, validation
    target: list[float]


@dataclass(frozen=True, kw_only=True)
class PoseReached(Event):
    index: int
    role: str
    q: list[float]  # joint angles averaged over the samples
    q_spread: list[float]
    seconds: float  # motion + settle time


@dataclass(frozen=True, kw_only=True)
class PointMeasured(Event):
    index: int
    role: str
    q: list[float]
    p: list[float]  # SMR in the tracker frame (m)
    p_spread: list[float]
    samples: int
    deviation: float | None = None  # distance from the nominal model's prediction (m), if known
    q_spread: list[float] = field(default_factory=list)
    target: list[float] = field(default_factory=list)


@dataclass(frozen=True, kw_only=True)
class PoseSkipped(Event):
    index: int
    role: str
    reason: str


@dataclass(frozen=True, kw_only=True)
class Suspended(Event):
    kind: str  # beam_lost, protective_stop, connection_lost, tracker_unplugged, ...
    message: str  # what the operator should do, in plain words
    detail: str = ""  # the device's error, for the log ("TargetLost: ...")
    timeout: float | None = None  # seconds from `t` until `on_timeout` happens
    on_timeout: str = ""  # "skip": the pose is skipped; "fail": the run stops


@dataclass(frozen=True, kw_only=True)
class SuspendExtended(Event):
    """The operator chose to wait longer: the suspension's limit is now `timeout` s from `t`."""

    kind: str
    timeout: float


@dataclass(frozen=True, kw_only=True)
class Resumed(Event):
    kind: str
    waited: float  # seconds


@dataclass(frozen=True, kw_only=True)
class ReferenceMeasured(Event):
    """The reference pose measured (warm-up or drift watch, `hil.campaign.warmup`); never a campaign
    point: the store keeps it in the campaign's log, and no fit ever sees it.

    Displacements are the reference's movement as the tracker saw it minus what the arm's own joint
    readings explain (the arm does not return to exactly the same joints), in metres."""

    seq: int  # the campaign's reference measurements, numbered from 1 across runs
    run: int  # which run of the campaign measured it (1; a resumed run adds one)
    phase: str  # "warmup" or "drift"
    elapsed: float  # station seconds since this run started (simulated seconds in a fast-time simulation)
    q: list[float]  # joints read at the reference (rad)
    xyz: list[float]  # the SMR in the tracker frame (m)
    p_spread: list[float] = field(default_factory=list)
    moved: float | None = None  # since this run's previous reference measurement (m)
    drift: float | None = None  # from the baseline (m); None while there is none yet
    baseline: bool = False  # this measurement is the baseline later ones are compared with
    limit: float | None = None  # the phase's limit (m): warm-up's on `moved`, the drift watch's on `drift`
    temperatures: list[float] | None = None  # joint temperatures (°C) when the arm reports them


@dataclass(frozen=True, kw_only=True)
class WarmupProgress(Event):
    """One warm-up check: the reference moved `moved` m in `interval` s; the first-order fit of the
    series says `remaining` m of drift is still to come (warm below `limit`; `hil.campaign.warmup`)."""

    elapsed: float  # station seconds since the warm-up started
    moved: float
    interval: float
    limit: float
    max_time: float
    remaining: float | None = None  # None before the fit has enough measurements
    time_constant: float | None = None  # the fitted warm-up time constant (s)
    # the check's evidence (`hil.calibration.warmup_decision`; None in events stored before it was kept)
    remaining_upper: float | None = None  # the most drift still to come the series allows (m)
    time_constant_upper: float | None = None  # the longest τ the series allows (s)
    time_constant_source: str | None = None  # τ fitted to "temperatures" (the joints') or "positions"
    span: float | None = None  # s the series spans (warm once ≥ 3 × time_constant_upper)
    temperature_span: float | None = None  # K the joints' mean temperature moved over the series
    temperatures_flat: bool | None = None  # the last three within the sensor's resolution
    flat_moved: float | None = None  # m the reference moved among those three
    warm: bool | None = None  # this check's verdict
    rule: str | None = None  # which rule called it warm: "fit", "flat", "" (not warm)
    decision: str | None = None  # the verdict and why, in one line


@dataclass(frozen=True, kw_only=True)
class WarmupFinished(Event):
    """The warm-up ended: `converged` (the reference settled within the limit) or not (max_time
    reached, or no reference or motion possible: `reason`)."""

    seconds: float  # station seconds it took
    converged: bool
    references: int  # reference measurements it made
    moved: float | None = None  # the last check's movement (m)
    limit: float = 0.0
    reason: str = ""
    remaining: float | None = None  # the fitted drift still to come (m) at the end
    time_constant: float | None = None  # the fitted time constant (s)
    remaining_upper: float | None = None  # its upper confidence limit (m)
    time_constant_upper: float | None = None  # its upper confidence limit (s)
    span: float | None = None  # s the judged series spans
    rule: str | None = None  # which rule called the arm warm ("fit", "flat"; "" when it did not settle)
    decision: str | None = None  # the last check's verdict and why, in one line


@dataclass(frozen=True, kw_only=True)
class DriftFlagged(Event):
    """The reference moved more than the drift limit from its baseline: the campaign is flagged (its
    accept/reject verdict still comes from validation)."""

    drift: float  # m
    limit: float  # m
    elapsed: float  # station seconds since this run started
    seq: int  # the reference measurement that showed it


@dataclass(frozen=True, kw_only=True)
class AcquisitionStopped(Event):
    """The stopping rule (``campaign.stop_early``, `hil.campaign.stopping`) ended the calibration
    poses early: the fit so far predicts the acceptance with margin. The remaining calibration poses
    are not visited; validation poses still are. The store keeps it, so a resumed campaign keeps the
    decision."""

    reason: str  # the verdict in words
    predicted_rms: float  # predicted validation RMS (m), σ at its upper confidence bound
    target: float  # margin × acceptance (m): the prediction reached it
    poses_used: int  # calibration poses measured when it stopped
    poses_left: int  # calibration poses planned but not to be visited
    skipped: list[int] = field(default_factory=list)  # their indices
    figures: dict[str, Any] = field(default_factory=dict)  # the rule's record (`StoppingRule.record`)


@dataclass(frozen=True, kw_only=True)
class ModelIdentified(Event):
    rms: float
    max: float
    iterations: int
    rejected: list[int]
    model: dict[str, Any]


@dataclass(frozen=True, kw_only=True)
class ValidationDone(Event):
    before: dict[str, Any]
    after: dict[str, Any]
    passed: bool
    # the controller's own model on the same poses ({count, mean, rms, max}), when it was reported
    controller: dict[str, Any] | None = None


@dataclass(frozen=True, kw_only=True)
class SweepPlanned(Event):
    """The sweep's tour, checked before it moves: `segments` between the `waypoints` (the calibration
    poses and the validation poses it rests at), each ``{"index", "from", "to", "seconds", "samples",
    "knots"}``; `done`: the segments a resumed campaign already has (not swept again); `rests`: the
    validation poses (their plan indices) measured still where a segment starts or ends."""

    segments: list[dict[str, Any]]
    waypoints: list[list[float]]
    rate_hz: float  # the servo stream's rate (the controller period's)
    tracker_rate_hz: float
    done: list[int] = field(default_factory=list)
    rests: list[int] = field(default_factory=list)


@dataclass(frozen=True, kw_only=True)
class SweepChunk(Event):
    """A chunk of one stream of one sweep segment's attempt (`take`), for the store's
    ``stream_chunks`` table. `stamps` (s, the stream's own clock) and `values` (joints: 6 rad; tracker:
    x, y, z m, or None when the beam was lost) stay out of its dict (the event log and ``--json`` carry
    the counts; the samples are the table's), so `from_dict` rebuilds it without them."""

    segment: int
    take: str
    stream: str  # "joints" or "tracker"
    chunk: int
    session: str = ""
    count: int = 0
    stamps: tuple[float, ...] = ()
    values: tuple[Any, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        data = super().to_dict()
        del data["stamps"], data["values"]
        return data


#: The first number of a swept bootstrap's segments (`hil.campaign.sweep_bootstrap`): above any tour's
#: (0, 1, …), so one campaign's sweep records hold both apart.
BOOTSTRAP_SEGMENTS = 10_000


def is_bootstrap_segment(index: int) -> bool:
    """Whether a recorded segment's number is a swept bootstrap's."""
    return index >= BOOTSTRAP_SEGMENTS


@dataclass(frozen=True, kw_only=True)
class SweepSegmentDone(Event):
    """Segment `segment` (of `segments`) is recorded whole under `take`: its chunks count; a resumed
    campaign does not sweep it again. The stream's health: samples per stream, beam breaks (runs of
    lost tracker samples), lost samples, and the robot time the segment took (s)."""

    segment: int
    segments: int
    take: str
    session: str
    joints: int
    tracker: int
    lost: int
    breaks: int
    seconds: float
    # (tracker stamp, controller stamp) of one instant by the host's clock (`sweep_recording.anchor`)
    anchor: list[float] | None = None
    # the segment's planned duration (s): its servo samples at the controller's rate (0: not said)
    planned: float = 0.0


@dataclass(frozen=True, kw_only=True)
class SweepFitted(Event):
    """The sweep's join and fit: the clock map t_ctrl = offset + (1 + drift)·t_trk with its σ, the
    tracker samples used and those left out by reason, the residual RMS (m)."""

    offset_s: float
    drift: float
    sigma_offset_s: float
    sigma_drift: float
    used: int
    left_out: dict[str, int]
    rms: float
    t_ref: float = 0.0  # the tracker time the fit is centred on, where the map is known best
    sigma_at_ref_s: float = 0.0  # the map's σ there (s)


@dataclass(frozen=True, kw_only=True)
class Message(Event):
    level: str  # info, warning, error
    text: str


@dataclass(frozen=True, kw_only=True)
class RunFinished(Event):
    status: str  # accepted, rejected, aborted, failed
    detail: str = ""
    result: dict[str, Any] = field(default_factory=dict)


Subscriber = Callable[[Event], None]


class EventBus:
    """Delivers events to subscribers: critical ones first (their failure propagates), then others."""

    def __init__(self) -> None:
        self._critical: list[Subscriber] = []
        self._others: list[Subscriber] = []

    def subscribe(self, fn: Subscriber, critical: bool = False) -> None:
        (self._critical if critical else self._others).append(fn)

    def unsubscribe(self, fn: Subscriber) -> None:
        for group in (self._critical, self._others):
            if fn in group:
                group.remove(fn)

    def emit(self, event: Event) -> None:
        for fn in self._critical:
            fn(event)
        for fn in list(self._others):
            try:
                fn(event)
            except Exception:  # a display must never stop a measurement
                log.exception("event subscriber %r failed on %s", fn, event.name)
