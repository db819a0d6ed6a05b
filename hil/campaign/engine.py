"""One engine says how: it executes plans against devices and owns the run's state.

It only executes. Each step a plan yields goes to its handler by the step's type (`_plan_handlers`;
the steps of a pose visit, `_device_handlers`); the devices are the drivers' typed ones
(`drivers.robot.model.Robot`, `drivers.tracker.device.Tracker`), and what only some arms can do is a
declared protocol (`SplitMoves`, `ReadsJointTemperatures`). How the arm gets to a target — straight, or
a detour through safe postures inside the keep-in box — is the arm package's (`hil.arm.routes.Router`),
the same routes a dry run lays out (`hil.campaign.steps.plan_motion`).

Every pose a campaign measures — bootstrap, calibration, validation, the warm-up's reference — is
approached from the same side in every joint: a visit's `Move` asks for an approach
(``campaign.approach``, `hil.campaign.steps.APPROACH`), and its route ends with a short leg up from
that far below the pose (`Router.route`; the verification's ISO 9283 cycles keep their own sequence).
A joint's lost motion (its link lagging the encoder in the direction of its last motion) is then the
same at every pose, a constant offset the fitted geometry absorbs, instead of a scatter of ± the lag
that no model can predict; after a suspension the re-run visit approaches again.

States: idle → running ⇄ paused / suspended → stopping → aborted | interrupted | done (| failed).
Requests to pause, resume and abort come from other threads (the TUI) and take effect at step
boundaries; an abort stops the arm. A `KeyboardInterrupt` (Ctrl-C, or `RunInterrupted`, which the
headless CLI raises for SIGINT, SIGTERM and SIGHUP) ends the run wherever it lands: the arm is
stopped, the state becomes ``interrupted`` and the exception propagates — an interruption is not an
abort: the campaign stays resumable. *Suspenders* are small conditions — beam lost, protective stop,
connection lost, tracker unplugged — matched against the exception a device raised: the engine
stops the arm, tells the operator what to do (a `Suspended` event), polls the condition until it
clears (bounded by `suspend_timeout`) and re-runs the interrupted pose visit from its start.
Anything no suspender claims ends the run: the arm is stopped, `RunFinished(status="failed")` is
emitted and the exception propagates.

The engine never prints. It emits events; the store subscribes as a critical subscriber (delivered
first: a failure ends the run). A measured point's events (`PoseReached`, `PointMeasured`) are held
back until the next step: when that step is a move and the arm can be started and waited for apart
(`SplitMoves`: `start_move` / `wait_move`, as `drivers.robot.ur.URRobot`), the engine sends the move,
delivers the held events — the store commits the point — while the arm travels, then waits for the
arm; any other step, any other event, a pause or the end of the run delivers them first. So the order
of events is unchanged for every subscriber, the commit costs no robot time, and it is always finished
before the next measurement. A failed commit stops the arm and fails the run (no suspender retries it).
What the operator is promised stays true: a point reported measured (a `PointMeasured` that reached
the displays, which come after the store) is in the store; an interrupted run (Ctrl-C, a stop
request, an abort) stops the arm and then commits the point it holds; only a ``kill -9`` (or a power
cut) during the next move can lose the point whose commit had not finished, and the resumed
campaign measures that one pose again — at most that one. ``overlap=False`` commits each point
before the next move starts, as an engine without it did.

For the warm-up and the drift watch (`hil.campaign.warmup`) it also answers `ReadConditions` (the
station time since the run started, its clock scaled by the clock's ``speed``, and the arm's joint
temperatures when the driver reports them), skips an ``optional`` move without a safe path instead of
failing, and hands a visit of role `REFERENCE` back to the plan alone: no pose events, no
`PointMeasured`, never among `records`.
"""

from __future__ import annotations

import logging
import secrets
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from drivers.robot.model import JointReading, ReadsJointTemperatures, Robot, SplitMoves
from drivers.tracker.device import Tracker, TrackerPoint
from drivers.tracker.errors import TargetLost, UnstablePoint
from hil.arm.catalog import RobotSpec
from hil.arm.geometry import Geometry
from hil.arm.routes import Router, UnsafePathError
from hil.campaign.events import (
    Event,
    EventBus,
    Message,
    PhaseChanged,
    PointMeasured,
    PoseReached,
    PoseSkipped,
    PoseStarted,
    Resumed,
    StateChanged,
    Suspended,
    SuspendExtended,
)
from hil.campaign.interruption import RunInterrupted  # defined apart: imported by signal handlers
from hil.campaign.steps import (
    REFERENCE,
    Acquire,
    Checkpoint,
    Conditions,
    Emit,
    Measure,
    Move,
    Phase,
    Plan,
    PoseRecord,
    ReadConditions,
    ReadJoints,
    Settle,
    Settled,
    SettleMeasure,
    Skipped,
    Step,
    Sweep,
    SweepRecorded,
    SweepSegment,
)
from hil.campaign.stillness import judge
from hil.errors import HilError

log = logging.getLogger(__name__)

IDLE, RUNNING, PAUSED, SUSPENDED, STOPPING, ABORTED, INTERRUPTED, DONE, FAILED = (
    "idle", "running", "paused", "suspended", "stopping", "aborted", "interrupted", "done", "failed")


class RunAborted(HilError):
    """The operator (or the caller) aborted the run."""


class StopRequested(RunInterrupted):
    """`Engine.request_interrupt`: the operator stopped the run to continue it later (a UI's quit).

    An interruption like Ctrl-C (the campaign stays resumable), with the operator's words as its text.
    """

    def __init__(self, reason: str = "stopped on request") -> None:
        super().__init__(2)
        self.reason = reason

    def __str__(self) -> str:
        return self.reason


class SuspendTimeout(HilError):
    """A suspender did not clear within its time limit."""

    def __init__(self, text: str, kind: str = "", limit: float = 0.0, instruction: str = "") -> None:
        super().__init__(text)
        self.kind, self.limit, self.instruction = kind, limit, instruction


class PoseSkippedError(HilError):
    """A pose visit was given up (its suspender clears by skipping, e.g. a beam that never returns)."""


class Clock(Protocol):
    """The engine's clock: `monotonic` (its statistics' seconds) and `sleep` (station seconds).

    A clock may also have ``station()`` (seconds on the station's clock; else ``monotonic() · speed``)
    and ``busy()``, a context the engine holds while a step waits on the station: a fast-time
    simulated station's clock (`hil.station.paced_clock.PacedClock`) runs the simulator fast only
    then, and at the wall's rate while the plan computes between steps.
    """

    def monotonic(self) -> float: ...

    def sleep(self, seconds: float) -> None: ...


class RealClock:
    """Wall-clock time; `speed` > 1 shortens the engine's own waits (fast-time simulation)."""

    def __init__(self, speed: float = 1.0) -> None:
        self.speed = speed

    def monotonic(self) -> float:
        return time.monotonic()

    def station(self) -> float:
        """Station seconds: the wall's, times the fast-time factor."""
        return time.monotonic() * self.speed

    def sleep(self, seconds: float) -> None:
        if seconds > 0:
            time.sleep(seconds / self.speed)


#: Steps that only tell the plan's progress: the station is not waited on while they run.
_BOOKKEEPING = (Phase, Emit, Checkpoint)


@dataclass
class Suspender:
    """A condition that pauses the run until it clears.

    `matches` picks the exceptions it handles; `clear` is polled every `poll` seconds and returns
    True once the run can go on (it may act: re-lock the tracker, reconnect); `message` is the
    operator's instruction, shown verbatim by the UIs.
    """

    kind: str
    matches: Callable[[BaseException], bool]
    clear: Callable[[], bool]
    message: str
    poll: float = 0.5
    backoff: float = 1.0  # the poll interval grows by this factor (reconnects back off)
    timeout: float | None = None  # None: the engine's suspend_timeout
    max_poll: float = 10.0
    on_timeout: str = "fail"  # "fail": the run fails; "skip": the pose visit is skipped


@dataclass
class RunStats:
    """Where the time went (seconds), for the report and the overhead benchmark."""

    motion: float = 0.0
    settle: float = 0.0
    joints: float = 0.0
    measure: float = 0.0
    suspended: float = 0.0
    compute: float = 0.0  # plan code between steps (selection, identification)
    events: float = 0.0  # delivering events (the store's commits first) with the arm standing still
    events_in_motion: float = 0.0  # delivering a point's events while the arm travels (in `motion`)
    total: float = 0.0
    retries: int = 0

    def as_dict(self) -> dict[str, float]:
        return {k: float(v) for k, v in self.__dict__.items()}


def _handler(table: dict[type, Callable[[Any], Any]], step: Step) -> Callable[[Any], Any]:
    """The handler of `step`'s type (or of the nearest base it derives from) in `table`."""
    for kind in type(step).__mro__:
        handler = table.get(kind)
        if handler is not None:
            return handler
    raise TypeError(f"the engine cannot execute {step!r}")


@dataclass
class Engine:
    """Executes a plan; see the module docstring."""

    robot: Robot  # `SplitMoves` too lets a point's commit overlap the next move
    tracker: Tracker
    campaign: str
    spec: RobotSpec
    bus: EventBus = field(default_factory=EventBus)
    suspenders: Sequence[Suspender] = ()
    clock: Clock = field(default_factory=RealClock)
    keep_in: tuple[np.ndarray, np.ndarray] | None = None
    check_model: Geometry | None = None  # nominal model (+ SMR guess) for keep-in checks
    suspend_timeout: float = 600.0
    max_retries: int = 5  # suspensions of the same pose visit before giving up
    deviation: Callable[[PoseRecord], float | None] | None = None  # for PointMeasured events
    home: np.ndarray | None = None  # a safe pose to route through when a direct path is unsafe
    overlap: bool = True  # commit a point while the arm moves to the next pose (module docstring)

    def __post_init__(self) -> None:
        self.state = IDLE
        self.router = Router(self.spec, self.keep_in, self.check_model, self.home)
        # step type → handler: what the plan yields, and what a pose visit (`Acquire`) is made of
        self._device_handlers: dict[type, Callable[[Any], Any]] = {
            Move: self._go, Settle: self._settle, ReadJoints: self._read_joints, Measure: self._measure,
            SettleMeasure: self._settle_measure}
        self._plan_handlers: dict[type, Callable[[Any], Any]] = {
            Acquire: self._acquire, Phase: self._phase, Emit: self._emit, Checkpoint: self._checkpoint,
            ReadConditions: self._read_conditions, Move: self._plan_move, Sweep: self._sweep,
            Settle: self._plan_device_step,
            ReadJoints: self._plan_device_step, Measure: self._plan_device_step,
            SettleMeasure: self._plan_device_step}
        self.stats = RunStats()
        self._lock = threading.Lock()
        self._pause = threading.Event()
        self._abort = threading.Event()
        self._resume = threading.Event()
        self._interrupt: str | None = None  # request_interrupt's reason
        self._skip = threading.Event()  # request_skip: give up the suspended pose visit now
        self._extend = 0  # request_extend: pending "wait longer" requests for the current suspension
        self._poke = threading.Event()  # wakes a suspension's wait for any request
        self._last_q: np.ndarray | None = None
        self._s0: float | None = None  # the station's clock then (`ReadConditions`)
        self.current: Acquire | None = None
        self.records: list[PoseRecord] = []
        # events held back for delivery during the next move, each with the record it commits
        self._pending: list[tuple[Event, PoseRecord | None]] = []
        self._commit_error: BaseException | None = None  # a failed delivery: never a suspension

    # --- requests from other threads -------------------------------------------------------------
    def request_pause(self) -> None:
        self._pause.set()

    def request_resume(self) -> None:
        self._pause.clear()
        self._resume.set()

    def request_abort(self) -> None:
        self._abort.set()
        self._resume.set()
        self._poke.set()

    def request_interrupt(self, reason: str = "stopped on request") -> None:
        """Stop the arm now and end the run as interrupted (resumable), wherever it is.

        Called from another thread (a UI's quit): the arm's stop is sent at once — a move in progress
        ends there — and the engine raises `StopRequested` instead of going on.
        """
        self._interrupt = reason
        self.request_abort()
        self._stop_arm()

    def request_skip(self) -> None:
        """Give up the pose visit of the current suspension now, as its time-out would (only for a
        suspender that skips on time-out, e.g. a lost beam); ignored when nothing is suspended."""
        self._skip.set()
        self._poke.set()

    def request_extend(self) -> None:
        """Wait longer for the current suspension: its time limit moves by its own length again."""
        with self._lock:
            self._extend += 1
        self._poke.set()

    def _stop_error(self, what: str) -> BaseException:
        """The exception an abort (final) or an interruption (resumable) request ends the run with."""
        if self._interrupt is not None:
            return StopRequested(self._interrupt)
        return RunAborted(what)

    @property
    def abort_requested(self) -> bool:
        return self._abort.is_set()

    # --- state ------------------------------------------------------------------------------------
    def emit(self, event: Event) -> None:
        """Deliver `event` now, after any held back (subscribers see events in the order they arose)."""
        self._flush()
        self._deliver(event)

    def _deliver(self, event: Event, moving: bool = False) -> None:
        t = self.clock.monotonic()
        try:
            self.bus.emit(event)
        finally:
            if moving:
                self.stats.events_in_motion += self.clock.monotonic() - t
            else:
                self.stats.events += self.clock.monotonic() - t

    def _flush(self, moving: bool = False) -> None:
        """Deliver the held-back events in order; a point's record joins `records` once delivered.

        Each is taken off the queue before it is delivered, so one whose delivery failed (or was
        interrupted) is never delivered twice."""
        while self._pending:
            event, record = self._pending.pop(0)
            self._deliver(event, moving)
            if record is not None:
                self.records.append(record)

    @property
    def _overlaps(self) -> bool:
        """Whether a point's commit can run during the next move (the arm has start/wait)."""
        return self.overlap and isinstance(self.robot, SplitMoves)

    def _hold(self, event: Event, record: PoseRecord | None = None) -> None:
        """Deliver `event` with the next move (`_move`), or now when moves cannot overlap."""
        if self._overlaps:
            self._pending.append((event, record))
            return
        self.emit(event)
        if record is not None:
            self.records.append(record)

    def _set_state(self, new: str) -> None:
        with self._lock:
            old, self.state = self.state, new
        if old != new:
            self.emit(StateChanged(campaign=self.campaign, state=new, previous=old))

    def _stop_arm(self) -> None:
        try:
            self.robot.stop()
        except Exception:  # stopping is best effort; the original error matters more
            log.exception("stopping the arm failed")

    def _end_states(self, *states: str) -> None:
        """Enter the final states of a run that is ending on an exception, which stays the error:
        a subscriber failing to record them (the store, on a full disk) is logged, not raised."""
        for state in states:
            try:
                self._set_state(state)
            except Exception as exc:  # debug: no handler prints it (the run's own error will be)
                log.debug("recording the run's state %r failed: %s", state, exc)

    def _between_steps(self) -> None:
        """Honour pause and abort requests (only ever between steps)."""
        if self._abort.is_set():
            raise self._stop_error("aborted by request")
        if self._pause.is_set():
            self._set_state(PAUSED)
            while self._pause.is_set() and not self._abort.is_set():
                self._resume.wait(0.1)
                self._resume.clear()
            if self._abort.is_set():
                raise self._stop_error("aborted by request while paused")
            self._set_state(RUNNING)

    # --- execution --------------------------------------------------------------------------------
    def run(self, plan: Plan) -> Any:
        """Execute `plan` to its end; returns the plan's return value."""
        t0 = self.clock.monotonic()
        self._s0 = self._station_now()
        self._set_state(RUNNING)
        if self.home is not None:
            self._last_q = np.asarray(self.home, dtype=float)
        reply: Any = None
        try:
            mark = self.clock.monotonic()
            step = next(plan)
            while True:
                self.stats.compute += self.clock.monotonic() - mark
                self._between_steps()
                reply = self._execute(step)
                mark = self.clock.monotonic()
                step = plan.send(reply)
        except StopIteration as stop:
            self._set_state(DONE)
            return stop.value
        except RunAborted:
            self._stop_arm()
            self._end_states(STOPPING, ABORTED)
            plan.close()
            raise
        except KeyboardInterrupt:
            self._stop_arm()  # first: nothing (not even an event) before the arm is stopped
            self._end_states(STOPPING, INTERRUPTED)
            plan.close()
            raise
        except BaseException:
            # the arm first: the failure may be the store's (a full disk), and then recording the
            # state changes below fails too
            self._stop_arm()
            self._end_states(STOPPING, FAILED)
            plan.close()
            raise
        finally:
            self.stats.total = self.clock.monotonic() - t0

    def _execute(self, step: Step) -> Any:
        """Run one step of the plan by its handler (`_plan_handlers`); returns the plan's reply."""
        if not isinstance(step, Acquire | Move):  # only a move overlaps a held point's commit
            self._flush()
        handler = _handler(self._plan_handlers, step)
        busy = getattr(self.clock, "busy", None)
        if busy is None or isinstance(step, _BOOKKEEPING):
            return handler(step)
        with busy():  # the station works (and a fast-time one runs fast) while the step waits on it
            return handler(step)

    def _phase(self, step: Phase) -> None:
        self.emit(PhaseChanged(campaign=self.campaign, phase=step.name, detail=step.detail))

    def _emit(self, step: Emit) -> None:
        self.emit(step.event)

    def _checkpoint(self, step: Checkpoint) -> None:
        """Nothing to do: everything before it was recorded as it happened (the store's events)."""

    def _read_conditions(self, step: ReadConditions) -> Conditions:
        return self._conditions(step.temperatures)

    def _plan_move(self, step: Move) -> JointReading | Skipped:
        """A `Move` outside a pose visit; an ``optional`` one without a safe path is `Skipped`."""
        try:
            return self._with_suspenders(lambda: self._device_step(step))
        except UnsafePathError as exc:
            if not step.optional:
                raise
            return Skipped(-1, "", str(exc), lost=False)

    def _sweep(self, step: Sweep) -> SweepRecorded:
        """`Sweep`: each segment moved to, streamed and recorded (`hil.campaign.sweep_recording`), its
        chunks and `SweepSegmentDone` delivered (the store commits them) before the next segment; a
        suspension sweeps the interrupted segment again whole, under a new take. A segment whose
        suspension ends in a skip (the beam not found again within the re-lock wait, or the operator's
        skip, as a pose visit's), or that still loses the beam after its retries, is left out, said in
        a message, and the sweep goes on, as a pose visit that cannot be measured is skipped: the plan
        visits still what that segment would have read (`hil.campaign.sweep_rests`)."""
        records = []
        for segment in step.segments:
            self._between_steps()
            try:
                records.append(self._with_suspenders(lambda s=segment: self._sweep_segment(s, step)))
            except (PoseSkippedError, UnsafePathError, TargetLost) as exc:
                self._stop_arm()
                self._last_q = None  # stopped wherever it was: check the next path from its target only
                self.emit(Message(campaign=self.campaign, level="warning",
                                  text=f"sweep segment {segment.index} left out: {exc}"))
        return SweepRecorded(tuple(records))

    def _sweep_segment(self, segment: SweepSegment, step: Sweep) -> Any:
        from hil.campaign.sweep_recording import record_segment, segment_events

        # at rest at its start: by a safe route, as any move
        self._device_step(Move(segment.start, speed=step.speed, acceleration=step.acceleration))
        t = self.clock.monotonic()
        record = record_segment(self.robot, self.tracker, segment, step.tracker_rate_hz, step.session)
        self._last_q = np.asarray(segment.q[-1], dtype=float)
        seconds = self.clock.monotonic() - t
        self.stats.motion += seconds
        take = secrets.token_hex(6)  # this attempt's: a segment cut short is never read back
        for event in segment_events(self.campaign, record, take, step.total,
                                    seconds * float(getattr(self.clock, "speed", 1.0)),
                                    (len(segment.q) - 1) / float(segment.rate_hz)):
            self.emit(event)
        return record

    def _plan_device_step(self, step: Settle | ReadJoints | Measure | SettleMeasure) -> Any:
        """A device step outside a pose visit: retried after a suspension like a visit."""
        return self._with_suspenders(lambda: self._device_step(step))

    def station_time(self) -> float:
        """Seconds since the run started, on the station's clock: the engine's clock scaled by its
        ``speed`` (`RealClock` of a fast-time simulation: the simulators' seconds; 1 on a station)."""
        if self._s0 is None:
            return 0.0
        return self._station_now() - self._s0

    def _station_now(self) -> float:
        station = getattr(self.clock, "station", None)
        if station is not None:
            return float(station())
        return self.clock.monotonic() * float(getattr(self.clock, "speed", 1.0))

    def _conditions(self, temperatures: bool) -> Conditions:
        """`ReadConditions`: the station time and, when asked and the arm has ``joint_temperatures()``
        (RTDE ``joint_temperatures``, `drivers.robot.ur.URRobot`), its joint temperatures. A reading
        that fails is left out (None): it describes the measurement, it is not one."""
        temps = None
        if temperatures and isinstance(self.robot, ReadsJointTemperatures):
            try:
                temps = tuple(float(v) for v in
                              np.asarray(self.robot.joint_temperatures(), dtype=float).reshape(-1))
            except Exception as exc:  # a missing RTDE field, a dropped link: the next move will tell
                log.debug("reading the joint temperatures failed: %s", exc)
        return Conditions(self.station_time(), temps)

    def _device_step(self, step: Step) -> Any:
        """Run one device step (`_device_handlers`), its time counted in `stats`."""
        if not isinstance(step, Move):  # a held point is committed before anything is measured
            self._flush()
        return _handler(self._device_handlers, step)(step)

    def _go(self, step: Move) -> JointReading | None:
        """`Move`: every leg of the route to its target (`_route`)."""
        t = self.clock.monotonic()
        result = None
        for target in self._route(np.asarray(step.q, dtype=float), step.approach):
            result = self._move(target, step)
            self._last_q = target
        self.stats.motion += self.clock.monotonic() - t
        return result

    def _settle(self, step: Settle) -> None:
        t = self.clock.monotonic()
        self.clock.sleep(step.seconds)
        self.stats.settle += self.clock.monotonic() - t

    def _read_joints(self, step: ReadJoints) -> JointReading:
        t = self.clock.monotonic()
        result = self.robot.read_joints(step.samples)
        self.stats.joints += self.clock.monotonic() - t
        return result

    def _measure(self, step: Measure) -> TrackerPoint:
        t = self.clock.monotonic()
        result = self.tracker.measure_point(step.samples)
        self.stats.measure += self.clock.monotonic() - t
        return result

    def _settle_measure(self, step: SettleMeasure) -> Settled:
        """`SettleMeasure`: single readings, each followed by the joints, until the window is still.

        The time until the accepted window's first reading counts as settling, the window itself as
        measuring (its joint readings included). Waits are in the station's seconds (`station_time`).
        """
        clock = self.clock
        speed = float(getattr(clock, "speed", 1.0))
        window = max(2, int(step.samples))
        frames = max(1, -(-int(step.joint_samples) // window))  # joint frames after each reading
        t0 = clock.monotonic()
        points: list[np.ndarray] = []
        joints: list[np.ndarray] = []
        stamps: list[float] = []
        while True:
            stamps.append(clock.monotonic())
            points.append(np.asarray(self.tracker.sample().xyz, float))
            joints.append(np.asarray(self.robot.read_joints(frames).q, float))
            if len(points) >= window:
                P = np.array(points[-window:])
                verdict = judge(P, step.stability)  # agree within stability, and no drift
                spread = verdict.spread
                if verdict.still:
                    break
                # given up only on a window begun after max_wait: when readings come seconds apart (a
                # loaded fast-time station: wall milliseconds times the speed) the first window may end
                # past max_wait holding the one reading taken while the arm still rang, and the next
                # reading would have made a still window
                if (stamps[-window] - t0) * speed > step.max_wait:
                    raise UnstablePoint(f"not steady within {step.max_wait:g} s: the last {window} readings' "
                                        f"{verdict.describe(step.stability)}",
                                        tuple(float(v) for v in verdict.spread))
        end = clock.monotonic()
        start = stamps[-window]
        self.stats.settle += start - t0
        self.stats.measure += end - start
        Q = np.array(joints[-window:])
        return Settled(p=P.mean(axis=0), p_spread=spread, samples=window, q=Q.mean(axis=0),
                       q_spread=Q.std(axis=0, ddof=1), waited=(start - t0) * speed,
                       readings=len(points))

    def _move(self, target: np.ndarray, step: Move) -> JointReading:
        """One leg of a `Move`. With events held back (the last point's), the move is sent first,
        they are delivered while the arm travels, and then the arm is waited for; a delivery that
        fails stops the arm and ends the run. Without (or when moves cannot overlap): deliver, move."""
        robot = self.robot
        if not (self._pending and self.overlap and isinstance(robot, SplitMoves)):  # `_overlaps`
            self._flush()
            return robot.move_to(target, speed=step.speed, acceleration=step.acceleration)
        robot.start_move(target, speed=step.speed, acceleration=step.acceleration)
        try:
            self._flush(moving=True)
        except BaseException as exc:
            self._commit_error = exc  # the point may not be kept: no suspender may retry this visit
            self._stop_arm()
            raise
        return robot.wait_move()

    def _route(self, q: np.ndarray, approach: float = 0.0) -> list[np.ndarray]:
        """Targets to move through from where the arm is to reach `q` safely, the last leg coming up
        from `approach` below it when asked (`Router.route`)."""
        return self.router.route(self._last_q, q, approach)

    def _acquire(self, group: Acquire) -> PoseRecord | Skipped:
        """Run one pose visit; after a suspension, run it again from its first step.

        A visit given up is answered with `Skipped` (saying whether the beam was lost), so the plan
        can tell a tracker that sees nothing from a pose with no safe path."""
        self.current = group
        # a reference visit is not a campaign pose: its events are the plan's (ReferenceMeasured)
        pose = group.role != REFERENCE
        if pose:  # after the last point's held-back events, which its move delivers
            started = PoseStarted(campaign=self.campaign, index=group.index, role=group.role,
                                  target=list(group.target))
            if self._pending:
                self._hold(started)
            else:
                self.emit(started)
        t0 = self.clock.monotonic()
        try:
            results = self._with_suspenders(lambda: [self._device_step(s) for s in group.steps])
        except (PoseSkippedError, UnsafePathError) as exc:
            if pose:
                self.emit(PoseSkipped(campaign=self.campaign, index=group.index, role=group.role,
                                      reason=str(exc)))
            self.current = None
            return Skipped(group.index, group.role, str(exc), lost=isinstance(exc, PoseSkippedError))
        settled = next((r for r in results if isinstance(r, Settled)), None)
        if settled is not None:  # settled on evidence: joints and point from the same window
            record = PoseRecord(
                index=group.index, role=group.role, target=np.array(group.target),
                q=settled.q, q_spread=settled.q_spread, p=settled.p, p_spread=settled.p_spread,
                samples=settled.samples, seconds=self.clock.monotonic() - t0,
                extra={"settle_s": settled.waited, "readings": settled.readings})
        else:
            reading = next(r for s, r in zip(group.steps, results, strict=True) if isinstance(s, ReadJoints))
            point = next(r for s, r in zip(group.steps, results, strict=True) if isinstance(s, Measure))
            xyz = np.asarray(point.xyz, dtype=float)
            record = PoseRecord(
                index=group.index, role=group.role, target=np.array(group.target),
                q=np.asarray(reading.q, float), q_spread=np.asarray(reading.spread, float),
                p=xyz, p_spread=np.asarray(point.spread, float), samples=int(point.samples),
                seconds=self.clock.monotonic() - t0)
        if not pose:  # handed back to the plan only: never a campaign point, never in a fit
            self.current = None
            return record
        self._hold(PoseReached(campaign=self.campaign, index=group.index, role=group.role,
                               q=record.q.tolist(), q_spread=record.q_spread.tolist(),
                               seconds=record.seconds))
        dev = self.deviation(record) if self.deviation is not None else None
        # Committed by the store (critical) during the next move, or before any other step or event
        # (module docstring); the record joins `records` once it is.
        self._hold(PointMeasured(campaign=self.campaign, index=record.index, role=record.role,
                                 q=record.q.tolist(), p=record.p.tolist(),
                                 p_spread=record.p_spread.tolist(), samples=record.samples,
                                 deviation=dev, q_spread=record.q_spread.tolist(),
                                 target=record.target.tolist()), record)
        self.current = None
        return record

    def _with_suspenders(self, action: Callable[[], Any]) -> Any:
        """Run `action`; when a suspender claims its exception, wait for it to clear and run it again."""
        attempts = 0
        while True:
            try:
                return action()
            except BaseException as exc:
                if self._abort.is_set() and not isinstance(exc, RunAborted | KeyboardInterrupt):
                    # the device call ended because of the request (a stopped move): not a fault
                    raise self._stop_error("aborted by request") from exc
                suspender = self._suspender_for(exc)
                attempts += 1
                if suspender is None or attempts > self.max_retries:
                    raise
                self.stats.retries += 1
                self._suspend(suspender, exc)
                self._between_steps()

    def _suspender_for(self, exc: BaseException) -> Suspender | None:
        if isinstance(exc, RunAborted | KeyboardInterrupt) or exc is self._commit_error:
            return None
        return next((s for s in self.suspenders if s.matches(exc)), None)

    def _suspend(self, suspender: Suspender, exc: BaseException) -> None:
        """Stop, tell the operator, wait for the condition to clear (bounded), then go on."""
        self._stop_arm()
        self._last_q = None  # the arm may be anywhere now: check the next path from the target only
        self._set_state(SUSPENDED)
        limit = suspender.timeout if suspender.timeout is not None else self.suspend_timeout
        what = suspender.kind.replace("_", " ")
        with self._lock:  # requests made before this suspension are not for it
            self._skip.clear()
            self._extend = 0
            self._poke.clear()
        self.emit(Suspended(campaign=self.campaign, kind=suspender.kind, message=suspender.message,
                            detail=f"{type(exc).__name__}: {exc}", timeout=limit,
                            on_timeout=suspender.on_timeout))
        start = time.monotonic()
        poll = suspender.poll
        while True:
            if self._abort.is_set():
                raise self._stop_error(f"aborted while suspended ({what})")
            if self._skip.is_set() and suspender.on_timeout == "skip":
                self._set_state(RUNNING)
                raise PoseSkippedError(f"skipped by the operator after {time.monotonic() - start:.0f} s "
                                       f"waiting ({what})")
            with self._lock:
                extend, self._extend = self._extend, 0
            if extend:
                original = suspender.timeout if suspender.timeout is not None else self.suspend_timeout
                limit += extend * original
                self.emit(SuspendExtended(campaign=self.campaign, kind=suspender.kind,
                                          timeout=max(0.0, limit - (time.monotonic() - start))))
            try:
                if suspender.clear():
                    break
            except Exception as err:  # a failing check is just "not clear yet"
                log.debug("suspender %s check failed: %s", suspender.kind, err)
            if time.monotonic() - start > limit:
                self._set_state(RUNNING)
                if suspender.on_timeout == "skip":
                    raise PoseSkippedError(f"gave up after {limit:.0f} s waiting ({what})")
                raise SuspendTimeout(f"{suspender.kind} did not clear within {limit:.0f} s: "
                                     f"{suspender.message}", suspender.kind, limit,
                                     suspender.message) from exc
            self._poke.wait(poll)
            self._poke.clear()
            poll = min(poll * suspender.backoff, suspender.max_poll)
        waited = time.monotonic() - start
        self.stats.suspended += waited
        self._set_state(RUNNING)
        self.emit(Resumed(campaign=self.campaign, kind=suspender.kind, waited=waited))
