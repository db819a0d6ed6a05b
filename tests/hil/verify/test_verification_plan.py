"""The pose test as a plan: cycles × poses × modes in ISO 9283's order, the unidirectional approach,
the stored targets, a resumed test measuring only what is missing, and a beam that keeps failing."""

from __future__ import annotations

import numpy as np
import pytest

from hil.campaign.events import PlanReady
from hil.campaign.steps import Acquire, Emit, Move, Phase, PoseRecord, Skipped, dry_run
from hil.verify.cube import CYCLE_ORDER, POSE_NAMES
from hil.verify.design import COMPENSATED, MODES, UNCOMPENSATED, Design
from hil.verify.verification_plan import ROLE, BeamKeepsFailing, verification_plan
from tests.hil.verify.station import cell

VISIT = dict(settle=0.0, joint_samples=2, samples=3)


@pytest.fixture(scope="module")
def design() -> Design:
    return cell().design(cycles=3)


def record(index: int, q: np.ndarray) -> PoseRecord:
    return PoseRecord(index, ROLE, np.asarray(q), np.asarray(q), np.zeros(6), np.zeros(3), np.zeros(3), 3)


def answer(step):
    if isinstance(step, Acquire):
        return record(step.index, np.array(step.target))
    return None


def run(design: Design, done=None, respond=answer, **kw):
    seen = {}

    def evaluate(records, skipped):
        seen.update(records=dict(records), skipped=dict(skipped))
        return "figures"

    steps, value = dry_run(verification_plan(design, "c1", done or {}, evaluate=evaluate, **VISIT, **kw),
                           respond)
    return steps, value, seen


def test_cycles_times_poses_times_modes_in_the_iso_order_with_the_compensators_joints(design: Design) -> None:
    steps, value, seen = run(design)
    assert value == "figures"
    plan = next(s.event for s in steps if isinstance(s, Emit) and isinstance(s.event, PlanReady))
    assert len(plan.poses) == 3 * 5 * 2 and {p["role"] for p in plan.poses} == {ROLE}
    assert plan.selection["kind"] == "verification"
    visits = [s for s in steps if isinstance(s, Acquire)]
    assert [a.index for a in visits] == list(range(1, 31))
    expected = []
    for _cycle in range(3):
        for mode in (UNCOMPENSATED, COMPENSATED):
            expected += [design.joints[mode][POSE_NAMES.index(p)] for p in CYCLE_ORDER]
    assert np.allclose([a.target for a in visits], expected)
    # the compensated targets are the compensator's joints for the same tool poses
    c = cell()
    for name in POSE_NAMES:
        i = POSE_NAMES.index(name)
        solved = c.compensator.solve(design.target(name), design.joints[UNCOMPENSATED][i])
        assert np.allclose(solved.q, design.joints[COMPENSATED][i], atol=1e-9)
    # each visit: move, settle, read the joints, measure — what the engine retries whole
    assert [type(s).__name__ for s in visits[0].steps] == ["Move", "Settle", "ReadJoints", "Measure"]
    assert len(seen["records"]) == 30 and seen["skipped"] == {}


def test_the_first_visit_is_approached_from_p2_as_every_later_p1(design: Design) -> None:
    steps, _, _ = run(design)
    first = next(i for i, s in enumerate(steps) if isinstance(s, Acquire))
    lead = steps[first - 1]
    assert isinstance(lead, Move) and not any(isinstance(s, Move) for s in steps[first:])
    p2 = design.joints[COMPENSATED][POSE_NAMES.index("P2")]
    assert np.allclose(lead.q, p2)  # the last pose of a cycle, as before each cycle's P1
    acquired = [s for s in steps if isinstance(s, Acquire)]
    assert np.allclose(acquired[10].target, design.joints[UNCOMPENSATED][0])  # cycle 2's P1, after P2
    assert np.allclose(acquired[9].target, p2)


def test_a_resumed_test_measures_only_what_is_missing_approaching_as_before(design: Design) -> None:
    visits = design.visits()
    done = {v.index: record(v.index, v.q) for v in visits[:7]}
    steps, _, seen = run(design, done)
    acquired = [s.index for s in steps if isinstance(s, Acquire)]
    assert acquired == list(range(8, 31))
    lead = next(s for s in steps if isinstance(s, Move))
    assert np.allclose(lead.q, visits[6].q)  # from visit 7's target, as the interrupted run would have
    plan = next(s.event for s in steps if isinstance(s, Emit))
    assert len(plan.poses) == 30  # the whole plan again, the same targets (the store keeps them)
    assert set(seen["records"]) == set(range(1, 31))


def test_skipped_visits_are_named_and_a_beam_that_keeps_failing_stops_the_run(design: Design) -> None:
    def skip_some(step):
        if isinstance(step, Acquire) and step.index in (4, 9):
            return Skipped(step.index, ROLE, "no safe path", lost=False)
        return answer(step)

    _, _, seen = run(design, respond=skip_some)
    assert seen["skipped"] == {4: "no safe path", 9: "no safe path"} and len(seen["records"]) == 28

    def lose_beam(step):
        if isinstance(step, Acquire) and step.index >= 5:
            return Skipped(step.index, ROLE, "beam lost", lost=True)
        return answer(step)

    with pytest.raises(BeamKeepsFailing, match="3 visits in a row lost the beam .*visit 7"):
        run(design, respond=lose_beam)


def test_phases_say_what_is_measured(design: Design) -> None:
    steps, _, _ = run(design)
    phases = [s for s in steps if isinstance(s, Phase)]
    assert [p.name for p in phases] == ["measure", "evaluate"]
    assert "30 of 30 visits" in phases[0].detail and " and ".join(MODES) in phases[0].detail
