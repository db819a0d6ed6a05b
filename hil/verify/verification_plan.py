"""The pose test as a plan of steps, run by the campaign engine like a calibration.

Every visit is one `Acquire` (move, settle, read joints, measure) of a stored target, so the engine's
suspenders, pause/abort, keep-in routing and the store's commit-before-the-next-move apply unchanged.
Visits are numbered 1..N in the order of `Design.visits` (per cycle: each mode's P1, P5, P4, P3, P2);
a resumed test skips those already measured.

The unidirectional approach of ISO 9283 (§7.2.1: every pose reached from the same side each time)
needs the arm to come from the previous pose of the sequence. So before the first visit measured in
this run — the test's start, or where an interrupted test resumes — the arm first moves (without
measuring) to the previous visit's target: the first visit is approached from P2 as every later P1
is. After a visit given up the arm is already there (a lost beam) or that target has no safe path (a
skipped move), so the next visit is approached from where the arm stands.

Several visits in a row without the beam mean the tracker is not looking where the test thinks (as
`TrackerLooksWrong` in a calibration): the run stops as a fault, resumable, rather than wait out the
re-lock time at every remaining visit.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

from hil.campaign.events import PlanReady
from hil.campaign.steps import Emit, Move, Phase, Plan, PoseRecord, Skipped, acquire
from hil.errors import HilError
from hil.verify.design import Design

#: The store's role of a verification visit (its pose table knows bootstrap, calibration, validation):
#: a verification measures held-out poses, as validation does. The campaign's plan says it is a
#: verification (``"kind": "verification"``).
ROLE = "validation"
KIND = "verification"


class BeamKeepsFailing(HilError):
    """Several visits in a row lost the beam: the run stops as a station fault (resumable)."""


def verification_plan(design: Design, campaign: str, done: Mapping[int, PoseRecord], *,
                      evaluate: Callable[[dict[int, PoseRecord], dict[int, str]], Any],
                      settle: float, joint_samples: int, samples: int, speed: float | None = None,
                      acceleration: float | None = None, max_lost: int = 3) -> Plan:
    """The whole test; returns `evaluate(records, skipped)` of every measured visit (by index)."""
    visits = design.visits()
    records = {i: r for i, r in done.items() if 1 <= i <= len(visits)}
    # each visit also says its pose, mode and cycle (1-based, as "cycle k of n"): the progress lines
    yield Emit(PlanReady(campaign=campaign, poses=[{"index": v.index, "role": ROLE,
                                                    "q": [float(x) for x in v.q], "pose": v.pose,
                                                    "mode": v.mode, "cycle": v.cycle + 1} for v in visits],
                         selection={"kind": KIND, "cycles": design.cycles, "modes": list(design.modes)}))
    todo = [v for v in visits if v.index not in records]
    yield Phase("measure", f"{len(todo)} of {len(visits)} visits to measure: {design.cycles} cycles of "
                           f"P1, P5, P4, P3, P2, {' and '.join(design.modes)}")
    visit = dict(settle=settle, joint_samples=joint_samples, samples=samples, speed=speed,
                 acceleration=acceleration)
    skipped: dict[int, str] = {}
    if todo:  # come from the previous visit's target, as in an unbroken sequence
        yield Move(tuple(float(x) for x in design.lead_in(todo[0])), speed, acceleration)
    lost = 0
    for v in todo:
        record = yield acquire(v.index, ROLE, v.q, **visit)
        if isinstance(record, PoseRecord):
            records[v.index] = record
            lost = 0
        elif isinstance(record, Skipped):
            skipped[v.index] = record.reason
            lost = lost + 1 if record.lost else 0
            if lost >= max_lost:
                raise BeamKeepsFailing(
                    f"{lost} visits in a row lost the beam (the last: visit {v.index}, {v.pose} "
                    f"{v.mode}): is the tracker where the test cube faces ({design.tracker_source})? "
                    "Check the line of sight, then run the same command again to continue")
    yield Phase("evaluate", "ISO 9283 AP and RP per pose")
    return evaluate(records, skipped)
