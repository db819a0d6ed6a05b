"""Plans say what to do: plain steps, no I/O.

A plan is a generator of steps. The engine executes each step and sends its result back into the
generator (``reading = yield ReadJoints(10)``), as in bluesky, so a plan can depend on what it
measured — a bootstrap that locates the tracker before the selector runs — and still do no I/O of its
own. Because steps are plain data, a plan can be dry-run against canned replies (`dry_run`) and its
every motion checked against the joint limits and the keep-in zone before the arm moves
(`check_motion`).

`Acquire` groups the steps of one pose (move, settle, read joints, measure). It is the unit of
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
from hil.arm.safety import check_target

#: The role of a reference-pose visit (warm-up and drift watch): not one of the campaign's poses.
REFERENCE = "reference"


@dataclass(frozen=True)
class Move:
    """Move the arm to joint vector `q` (radians) and wait until it is steady.

    `optional`: a target with no safe path from where the arm is (`UnsafePathError`) is answered with
    `Skipped` instead of ending the run — the warm-up's cycling motion, where one target more or less
    only changes how the arm warms.
    """

    q: tuple[float, ...]
    speed: float | None = None
    acceleration: float | None = None
    optional: bool = False


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
class Acquire:
    """One pose visit: the steps above as a unit that is retried whole after a suspension."""

    index: int  # the pose's campaign index; a reference visit's: its number among the references
    role: str  # bootstrap, calibration, validation, reference
    steps: tuple[Move | Settle | ReadJoints | Measure, ...]

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


Step = Move | Settle | ReadJoints | Measure | Acquire | Phase | Emit | Checkpoint | ReadConditions
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
            samples: int, speed: float | None = None, acceleration: float | None = None) -> Acquire:
    """The standard pose visit: move, settle, read averaged joints, measure."""
    return Acquire(index, role, (
        Move(tuple(float(v) for v in q), speed, acceleration),
        Settle(settle),
        ReadJoints(joint_samples),
        Measure(samples),
    ))


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


def check_motion(steps: Iterable[Step], spec: RobotSpec,
                 keep_in: tuple[np.ndarray, np.ndarray] | None = None,
                 model: Geometry | None = None, start: np.ndarray | None = None) -> int:
    """Check every motion of a (dry-run) plan; returns how many targets were checked."""
    previous = start
    count = 0
    for q in moves_of(steps):
        check_target(q, spec, keep_in, model, previous)
        previous = q
        count += 1
    return count
