"""What the screens show, as plain data: the station's status and the live run's progress.

The run state is folded from the campaign's events (`RunState.apply`) on the UI thread, so the
screens never read the engine or the devices directly, and a test (or a snapshot) can build the same
state from canned events.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

from hil.campaign.events import (
    AcquisitionStopped,
    DriftFlagged,
    Event,
    Message,
    PhaseChanged,
    PlanReady,
    PointMeasured,
    PoseReached,
    PoseSkipped,
    PoseStarted,
    ReferenceMeasured,
    Resumed,
    RunFinished,
    RunStarted,
    StateChanged,
    Suspended,
    SuspendExtended,
    SweepFitted,
    SweepPlanned,
    SweepSegmentDone,
    ValidationDone,
    WarmupFinished,
    WarmupProgress,
)
from hil.campaign.reference_lines import describe as describe_reference
from hil.campaign.sweep_lines import describe as describe_sweep

# Suspended.kind -> (station field, reading while suspended, reading once resumed); the run's own
# events keep the Station screen current while the run has the devices (it does not poll them then).
_SUSPENSION_READINGS: dict[str, tuple[str, str, str]] = {
    "beam_lost": ("lock", "BEAM LOST (the run waits)", "locked in"),
    "tracker_unplugged": ("lock", "link lost (the run waits)", "-"),
    "tracker_not_ready": ("lock", "not ready (the run waits)", "-"),
    "protective_stop": ("safety", "PROTECTIVE STOP", "normal"),
    "connection_lost": ("safety", "link lost (the run waits)", "normal"),
}


@dataclass
class StationState:
    """Connection and status of the robot and the tracker, as last read."""

    phase: str = "starting"  # starting, disconnected, connecting, connected, in run, failed
    name: str = ""
    simulated: bool = False
    detail: str = ""  # e.g. "speed 20x, seed 1"
    robot_address: str = ""
    tracker_url: str = ""
    robot: dict[str, str] = field(default_factory=dict)  # model, serial, software
    tracker: dict[str, str] = field(default_factory=dict)  # name, serial, firmware
    safety: str = "-"
    lock: str = "-"
    last_point: str = ""
    error: str = ""
    fault: str = ""  # a fault the operator must clear by hand, e.g. "EMERGENCY STOP"
    steps: tuple[str, ...] = ()  # what to do about `fault`, in order
    # resumable campaign: id, poses measured, poses planned, bootstrap points measured
    unfinished: tuple[str, int, int, int] | None = None

    @property
    def connected(self) -> bool:
        return self.phase in ("connected", "in run")

    def apply(self, event: Event) -> bool:
        """Fold one of the run's events into the readings; True if something shown changed."""
        before = (self.safety, self.lock)
        if isinstance(event, Suspended | Resumed) and event.kind in _SUSPENSION_READINGS:
            name, suspended, resumed = _SUSPENSION_READINGS[event.kind]
            setattr(self, name, suspended if isinstance(event, Suspended) else resumed)
        elif isinstance(event, PointMeasured):  # the arm reached the pose and the tracker measured it
            self.safety, self.lock = "normal", "locked in"
        return before != (self.safety, self.lock)


@dataclass
class PoseRow:
    """One pose of the live table."""

    index: int
    role: str
    target: list[float]
    status: str = "moving"  # moving, reached, measured, skipped
    q: list[float] | None = None
    p: list[float] | None = None
    deviation: float | None = None
    reason: str = ""


@dataclass
class RunState:
    """The live run, folded from events (see `apply`)."""

    campaign: str = ""
    active: bool = False
    planned: int = 0
    resumed_with: int = 0
    state: str = "idle"
    phase: str = ""
    detail: str = ""
    rows: dict[tuple[str, int], PoseRow] = field(default_factory=dict)
    deviations: list[float] = field(default_factory=list)  # in measuring order (m)
    suspended: Suspended | None = None
    suspend_deadline: float | None = None  # when the suspension's time-out acts (Unix time)
    last_resumed: Resumed | None = None
    started_t: float | None = None
    measured_times: list[float] = field(default_factory=list)  # event times of this run's points
    finished: RunFinished | None = None
    validation: ValidationDone | None = None
    plan: PlanReady | None = None
    messages: list[str] = field(default_factory=list)
    ended: bool = False  # the session's final word on the run arrived (see `end`)
    # warm-up and drift watch: the latest line about the reference pose (`hil.campaign.reference_lines`)
    reference_line: str = ""
    drift_flagged: bool = False  # the reference drifted beyond its limit (the verdict stays validation's)
    # a sweep campaign: the latest line on its segments and streams (`hil.campaign.sweep_lines`)
    sweep_line: str = ""

    @property
    def measured(self) -> int:
        return self.resumed_with + len(self.measured_times)

    @property
    def skipped(self) -> int:
        return sum(1 for r in self.rows.values() if r.status == "skipped")

    def eta(self) -> float | None:
        """Seconds to the last pose, from this run's pace so far (None until two points)."""
        t = self.measured_times
        if len(t) < 2 or self.planned <= 0:
            return None
        pace = (t[-1] - t[0]) / (len(t) - 1)
        left = max(0, self.planned - self.measured - self.skipped)
        return pace * left

    def apply(self, event: Event) -> None:
        """Fold one event into the state."""
        if isinstance(event, RunStarted):
            self.__init__()  # type: ignore[misc]  # a fresh run
            self.campaign, self.active, self.planned = event.campaign, True, event.poses
            self.resumed_with, self.started_t = event.measured, event.t
        elif isinstance(event, StateChanged):
            self.state = event.state
            if event.state != "suspended":  # resumed, or the pose given up, or the run ended
                self.suspended, self.suspend_deadline = None, None
        elif isinstance(event, PhaseChanged):
            self.phase, self.detail = event.phase, event.detail
        elif isinstance(event, PlanReady):
            self.plan = event
        elif isinstance(event, PoseStarted):
            self.rows[(event.role, event.index)] = PoseRow(event.index, event.role, list(event.target))
        elif isinstance(event, PoseReached):
            row = self.rows.get((event.role, event.index))
            if row is not None:
                row.status, row.q = "reached", list(event.q)
        elif isinstance(event, PointMeasured):
            row = self.rows.setdefault((event.role, event.index),
                                       PoseRow(event.index, event.role, list(event.target or event.q)))
            row.status, row.q, row.p = "measured", list(event.q), list(event.p)
            row.deviation = event.deviation
            if event.role != "bootstrap":
                self.measured_times.append(event.t)
            if event.deviation is not None:
                self.deviations.append(event.deviation)
        elif isinstance(event, PoseSkipped):
            row = self.rows.setdefault((event.role, event.index), PoseRow(event.index, event.role, []))
            row.status, row.reason = "skipped", event.reason
        elif isinstance(event, Suspended):
            self.suspended = event
            self.suspend_deadline = event.t + event.timeout if event.timeout is not None else None
        elif isinstance(event, SuspendExtended):
            if self.suspended is not None:
                self.suspend_deadline = event.t + event.timeout
        elif isinstance(event, Resumed):
            self.suspended, self.last_resumed, self.suspend_deadline = None, event, None
        elif isinstance(event, ValidationDone):
            self.validation = event
        elif isinstance(event, Message):
            self.messages.append(f"{event.level}: {event.text}")
        elif isinstance(event, AcquisitionStopped):  # the stopping rule: the count and ETA shrink
            self.planned = max(self.measured, self.planned - event.poses_left)
            self.messages.append(f"info: stopping early, {event.poses_left} calibration poses not needed "
                                 f"(predicted validation RMS {event.predicted_rms * 1e3:.4f} mm)")
        elif isinstance(event, WarmupProgress | WarmupFinished | ReferenceMeasured | DriftFlagged):
            if self.drift_flagged and not isinstance(event, DriftFlagged):
                return  # the flag stays in view once raised
            self.reference_line = describe_reference(event) or self.reference_line
            self.drift_flagged = self.drift_flagged or isinstance(event, DriftFlagged)
        elif isinstance(event, SweepPlanned | SweepSegmentDone | SweepFitted):
            self.sweep_line = describe_sweep(event) or self.sweep_line
        elif isinstance(event, RunFinished):
            self.finished, self.active, self.suspended = event, False, None
            self.suspend_deadline = None

    def restore(self, campaign: str, points: Sequence[PointMeasured]) -> None:
        """The points a resumed campaign measured before it was interrupted, into the table and the
        plot as measured: the operator sees what the campaign already has, and the bootstrap's
        count beside the poses, as after an uninterrupted run. Not counted again (`RunStarted`'s
        ``measured``, `resumed_with`, holds the poses among them, the count ``hil calibrate``
        resumes from) nor in this run's pace (the ETA)."""
        if campaign != self.campaign:  # a late message of another run
            return
        earlier: dict[tuple[str, int], PoseRow] = {}
        deviations: list[float] = []
        for e in points:
            key = (e.role, e.index)
            if key in self.rows:  # measured again by this run already
                continue
            earlier[key] = PoseRow(e.index, e.role, list(e.target or e.q), status="measured", q=list(e.q),
                                   p=list(e.p), deviation=e.deviation)
            if e.deviation is not None:
                deviations.append(e.deviation)
        # in measuring order: the earlier run's points before this run's
        self.rows = {**earlier, **self.rows}
        self.deviations = deviations + self.deviations

    def end(self, status: str, detail: str) -> None:
        """The session's final status and plain-words detail of the run (RunEnded): it may differ
        from the engine's RunFinished (an e-stop or a quit leaves the campaign resumable)."""
        self.active, self.suspended, self.suspend_deadline, self.ended = False, None, None, True
        if self.finished is not None:
            self.finished = replace(self.finished, status=status, detail=detail)
        elif self.campaign:
            self.finished = RunFinished(campaign=self.campaign, status=status, detail=detail)
