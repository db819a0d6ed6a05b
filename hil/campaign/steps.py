"""Plans say what to do: plain steps, no I/O.

A plan is a generator of steps. The engine executes each step and sends its result back into the
generator (``reading = yield ReadJoints(10)``), as in bluesky, so a plan can depend on what it
measured — a bootstrap that locates the tracker before the selector runs — and still do no I/O of its
own. Because steps are plain data, a plan can be dry-run against canned replies (`dry_run`) and its
every motion laid out before the arm moves, along the same routes the engine will take
(`plan_motion`: straight, a detour through safe postures, or skipped for want of a safe path) and
checked against the joint limits and the keep-in zone (`check_motion`).

`Acquire` groups the steps of one pose (move, settle, read joints, measure; or move and
`SettleMeasure`, which settles on the tracker's evidence and reads the joints in the same window). It
is the unit of
recovery: if a suspender trips inside it (protective stop mid-move, lost beam), the engine resumes
by re-running the whole group, so a joint reading is never paired with a point from another visit.
An `Acquire` of role `REFERENCE` measures the warm-up and drift reference pose (`hil.campaign.warmup`):
the engine hands its record back to the plan only, never as a campaign point (`PointMeasured`), so a
reference measurement cannot reach the identification or the validation.
"""

from __future__ import annotations

from collections.abc import Callable, Generator, Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hil.arm.catalog import RobotSpec
from hil.arm.geometry import Geometry
from hil.arm.routes import Router, UnsafePathError

#: The role of a reference-pose visit (warm-up and drift watch): not one of the campaign's poses.
REFERENCE = "reference"


@dataclass(frozen=True)
class Move:
    """Move the arm to joint vector `q` (radians) and wait until it is steady.

    `optional`: a target with no safe path from where the arm is (`UnsafePathError`) is answered with
    `Skipped` instead of ending the run — the warm-up's cycling motion, where one target more or less
    only changes how the arm warms. `approach` (rad, 0: none): arrive with every joint moving up, from
    `approach` below the target (`hil.arm.routes.Router.route`), so each joint's lost motion lags the
    same way at every pose a campaign measures.
    """

    q: tuple[float, ...]
    speed: float | None = None
    acceleration: float | None = None
    optional: bool = False
    approach: float = 0.0


@dataclass(frozen=True)
class Settle:
    """Wait `seconds` (on the engine's clock) for vibrations to decay."""

    seconds: float


@dataclass(frozen=True)
class ReadJoints:
    """Average the joint readings over `samples` controller cycles."""

    samples: int


@dataclass(frozen=True)
class Measure:
    """Measure the SMR with the tracker, `samples` samples averaged."""

    samples: int


@dataclass(frozen=True)
class SettleMeasure:
    """Settle on evidence: take single tracker readings until the last `samples` agree, then measure.

    Replaces `Settle` + `ReadJoints` + `Measure` (``robot.settle = "stable"``). After the move the
    tracker reads the SMR one reading at a time, and after each reading the joints are read (enough
    controller cycles that the window holds at least `joint_samples` of them). As soon as the last
    ``max(samples, 2)`` readings are still (`hil.campaign.stillness`: per axis they agree within
    `stability` (m), largest minus smallest, and their older and newer halves do not drift apart),
    the point is their mean and the joints are the mean of the same window's frames: the arm's ring
    (the links flex after a stop; the encoders do not see it) has died out, and nothing waits longer
    than it must. Two readings at least, because one reading has no spread to judge stillness by.
    Nothing still among the windows begun within `max_wait` seconds of station time, nor in one begun
    after it (a ring that does not die out, a vibrating floor): the tracker's `UnstablePoint`, as a
    fixed wait's measurement would raise. No minimum wait: ``robot.settle_time`` is the fixed mode's
    wait only. Answered with `Settled`.
    """

    samples: int
    joint_samples: int
    stability: float
    max_wait: float


@dataclass(frozen=True)
class Settled:
    """What `SettleMeasure` measured: the window's point and joints, how long it waited (station s)."""

    p: np.ndarray
    p_spread: np.ndarray
    samples: int
    q: np.ndarray
    q_spread: np.ndarray
    waited: float  # from the end of the move to the first reading of the accepted window
    readings: int  # tracker readings taken in all (the window's and those before it)


@dataclass(frozen=True)
class Acquire:
    """One pose visit: the steps above as a unit that is retried whole after a suspension."""

    index: int  # the pose's campaign index; a reference visit's: its number among the references
    role: str  # bootstrap, calibration, validation, reference
    steps: tuple[Move | Settle | ReadJoints | Measure | SettleMeasure, ...]

    @property
    def target(self) -> tuple[float, ...]:
        return next(s.q for s in self.steps if isinstance(s, Move))


@dataclass(frozen=True)
class ReadConditions:
    """The station's running time and, if asked and the arm reports them, its joint temperatures.

    Answered with `Conditions`. The time is the engine's clock since the run started, in the station's
    seconds (a fast-time simulation's, not the wall clock's), so a plan can cycle for a given time."""

    temperatures: bool = True


@dataclass(frozen=True)
class Conditions:
    """What `ReadConditions` reads: seconds since the run started, joint temperatures (°C) or None."""

    t: float
    temperatures: tuple[float, ...] | None = None


@dataclass(frozen=True)
class Phase:
    """Marks the start of a campaign phase (for progress, timing and the event log)."""

    name: str
    detail: str = ""


@dataclass(frozen=True)
class Emit:
    """Hand an event (built by the plan from results) to the engine's subscribers."""

    event: Any


@dataclass(frozen=True)
class Checkpoint:
    """Everything before this point is recorded; a resumed run need not redo it."""

    label: str


@dataclass(frozen=True)
class SweepSegment:
    """One segment of a sweep's tour: the servo samples `q` (n, 6) rad at the controller period, from
    one waypoint (at rest) to the next (at rest), already checked (`hil.campaign.sweep_plan`)."""

    index: int
    q: np.ndarray
    rate_hz: float = 500.0  # samples per second of station time
    # the leg's knots in order (m, 6): its start, any vias, its end (`hil.campaign.sweep_plan`); a
    # resumed campaign plans the same segment again from them
    knots: np.ndarray | None = None
    # samples of `q` at its end that hold the last pose: a rest read off the streams
    # (`hil.campaign.sweep_rests`); 0: the segment ends as it arrives
    dwell: int = 0

    @property
    def start(self) -> tuple[float, ...]:
        return tuple(float(v) for v in self.q[0])


@dataclass(frozen=True)
class Sweep:
    """Sweep the arm through `segments` while both instruments stream, committing what they record.

    The engine moves the arm to each segment's start (a routed `Move`, as a pose visit's), streams its
    samples with the robot's `follow` while the tracker streams at `tracker_rate_hz`, and emits the
    segment's chunks and its `SweepSegmentDone`: a segment is the unit of recovery (after a suspension,
    or in a resumed campaign, it is swept again whole under a new take). `total`: the tour's segments
    (for "segment i of m"), `session`: the run recording them. Answered with `SweepRecorded`."""

    segments: tuple[SweepSegment, ...]
    total: int
    tracker_rate_hz: float
    session: str = ""
    # the joint speed (rad/s) and acceleration (rad/s²) of the moves to a segment's start that are not
    # swept (None: the station's movej): a sweep at its own limits (``campaign.sweep_speed``) hops at them
    speed: float | None = None
    acceleration: float | None = None


@dataclass(frozen=True)
class SegmentRecord:
    """What one segment recorded: the controller's stream (stamps (K,) s, joints (K, 6) rad) and the
    tracker's (its own stamps (M,) s, points (M, 3) m, NaN rows where the beam was lost)."""

    index: int
    session: str
    joint_t: np.ndarray
    joint_q: np.ndarray
    tracker_t: np.ndarray
    tracker_p: np.ndarray
    # (tracker stamp, controller stamp) of one instant, both read against the host's clock: a first
    # guess of the map between the two clocks (None: the instruments did not say enough)
    anchor: tuple[float, float] | None = None


@dataclass(frozen=True)
class SweepRecorded:
    """The answer to `Sweep`: the record of every segment it swept, in order."""

    segments: tuple[SegmentRecord, ...]


Step = (Move | Settle | ReadJoints | Measure | SettleMeasure | Acquire | Phase | Emit | Checkpoint
        | ReadConditions | Sweep)
Plan = Generator[Step, Any, Any]


@dataclass(frozen=True)
class PoseRecord:
    """What one `Acquire` produced: reached joints and the measured point."""

    index: int
    role: str
    target: np.ndarray
    q: np.ndarray
    q_spread: np.ndarray
    p: np.ndarray
    p_spread: np.ndarray
    samples: int
    seconds: float = 0.0
    extra: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Skipped:
    """What the engine sends back for an `Acquire` it gave up (the `PoseSkipped` event says why).

    `lost` is True when the tracker never saw the SMR there (the beam did not come back within the
    re-lock wait, or the operator skipped the wait): a run of those in a row means the tracker is
    not where the plan thinks, which the plan stops on rather than wait out pose after pose. False
    for a pose with no safe path to it, which says nothing about the tracker.
    """

    index: int
    role: str
    reason: str
    lost: bool


def acquire(index: int, role: str, q: Iterable[float], *, settle: float, joint_samples: int,
            samples: int, speed: float | None = None, acceleration: float | None = None,
            mode: str = "fixed", stability: float = 50e-6, settle_max: float = 5.0,
            approach: float = 0.0, dwell: float = 0.0) -> Acquire:
    """The standard pose visit: move (arriving from `approach` below in every joint, `Move`), then
    (``mode="fixed"``) wait `settle` s, read averaged joints, measure; or (``mode="stable"``) settle
    and measure on the tracker's evidence (`SettleMeasure`). `dwell` s of standing still come first in
    either mode: a visit that must see micrometres (the drift watch's reference) lets the arm's ring
    die out before any reading, which a window's spread cannot tell from the tracker's noise."""
    move = Move(tuple(float(v) for v in q), speed, acceleration, approach=approach)
    if mode == "stable":
        wait = (Settle(dwell),) if dwell > 0 else ()
        measure = SettleMeasure(samples, joint_samples, stability, settle_max)
        return Acquire(index, role, (move, *wait, measure))
    if mode != "fixed":
        raise ValueError(f"settle mode must be 'stable' or 'fixed', got {mode!r}")
    return Acquire(index, role, (move, Settle(settle + dwell), ReadJoints(joint_samples), Measure(samples)))


#: How far below each pose (rad, every joint) a campaign's visit starts its last leg (`Move.approach`;
#: the default of ``campaign.approach``):
#: every joint then arrives moving up, so its lost motion lags the same way at every pose measured and
#: becomes a constant offset the geometry absorbs. Several times a strain-wave gear's whole lost-motion
#: band (twice the Harmonic Drive catalog's 1 arc-min hysteresis loss, 5.8e-4 rad) and a hundred times
#: the simulator's direction threshold (`mocks.ur.directions`), yet a short leg: 0.14 s at 1 rad/s²
#: (`approach_seconds`), the SMR moving a few millimetres.
APPROACH = 0.005


def approach_seconds(approach: float, speed: float, acceleration: float) -> float:
    """Robot time (s) of the approach leg: a moveJ of `approach` rad under the driver's trapezoid."""
    if approach <= 0:
        return 0.0
    if approach <= speed * speed / acceleration:  # never reaches its speed: a triangle
        return 2.0 * float(np.sqrt(approach / acceleration))
    return approach / speed + speed / acceleration


def visit_settings(config: Any) -> dict[str, Any]:
    """`acquire`'s keyword arguments from a station configuration (`hil.station.config.StationConfig`):
    every pose visit of a campaign (and its warm-up's reference visits) is made the same way, each
    pose approached from ``campaign.approach`` below in every joint."""
    robot = config.robot
    return dict(settle=robot["settle_time"], joint_samples=robot["joint_samples"],
                samples=config.campaign["samples"], speed=robot["speed"],
                acceleration=robot["acceleration"], mode=robot["settle"],
                stability=config.campaign["stability"], settle_max=robot["settle_max"],
                approach=config.campaign.get("approach", APPROACH))


def dry_run(plan: Plan, respond: Callable[[Step], Any], limit: int = 100_000) -> tuple[list[Step], Any]:
    """Run `plan` against canned replies; returns every step it yields and its return value."""
    steps: list[Step] = []
    reply: Any = None
    try:
        step = next(plan)
        while True:
            steps.append(step)
            if len(steps) > limit:
                raise RuntimeError(f"plan yielded more than {limit} steps")
            reply = respond(step)
            step = plan.send(reply)
    except StopIteration as stop:
        return steps, stop.value


def moves_of(steps: Iterable[Step]) -> list[np.ndarray]:
    """Every motion target in a list of steps, in order (inside `Acquire` groups too)."""
    out: list[np.ndarray] = []
    for s in steps:
        if isinstance(s, Move):
            out.append(np.array(s.q))
        elif isinstance(s, Acquire):
            out.extend(np.array(x.q) for x in s.steps if isinstance(x, Move))
    return out


@dataclass(frozen=True)
class Leg:
    """One motion of a (dry-run) plan as the engine will make it (`plan_motion`).

    `via`: the postures of the detour the arm takes before `target` (the home pose, or two transit
    postures), empty when it goes straight. `skipped`: why the run will not go there at all (no safe
    path: the pose visit, or an optional move, is skipped and the arm stays where it was), "" when it
    moves.
    """

    target: tuple[float, ...]
    via: tuple[tuple[float, ...], ...] = ()
    skipped: str = ""

    @property
    def detour(self) -> bool:
        return bool(self.via)


def plan_motion(steps: Iterable[Step], router: Router, start: np.ndarray | None = None) -> list[Leg]:
    """Every motion of a (dry-run) plan as the engine will make it, in order: each leg planned from
    where the arm will be with the engine's own routes (`Router.route`), from `start` (default: the
    router's home pose, where the engine starts; None: the first target alone is checked).

    A target outside the joint limits or the keep-in box raises InputError (the run would stop there,
    before moving); a plain `Move` with no safe path raises `UnsafePathError`, as the run would; inside
    an `Acquire` or for an ``optional`` move that leg is `Leg.skipped`, as the run skips it.
    """
    here = start if start is not None else router.home
    legs: list[Leg] = []
    for step in steps:
        if isinstance(step, Move):
            moves, skippable = [step], step.optional
        elif isinstance(step, Acquire):
            moves, skippable = [x for x in step.steps if isinstance(x, Move)], True
        else:
            continue
        for move in moves:
            try:
                route = router.route(here, np.asarray(move.q, dtype=float), move.approach)
            except UnsafePathError as exc:
                if not skippable:
                    raise
                legs.append(Leg(tuple(move.q), skipped=str(exc)))
                break  # the engine gives up the whole visit: the arm stays where it is
            legs.append(Leg(tuple(move.q), tuple(tuple(float(v) for v in p) for p in route[:-1])))
            here = route[-1]
    return legs


def check_motion(steps: Iterable[Step], spec: RobotSpec,
                 keep_in: tuple[np.ndarray, np.ndarray] | None = None,
                 model: Geometry | None = None, start: np.ndarray | None = None,
                 home: np.ndarray | None = None) -> int:
    """Check every motion of a (dry-run) plan along the routes the run will take (`plan_motion`);
    returns how many targets were checked."""
    return len(plan_motion(steps, Router(spec, keep_in, model, home), start))
