"""The dry run shows what the run will do: a leg whose straight path leaves the keep-in box is laid
out as the detour the engine takes (the same postures, in the same order), and a leg with no safe way
as skipped, as the engine skips it (a UR10e in the example's 1.2 m box)."""

from __future__ import annotations

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.arm.routes import Router, UnsafePathError
from hil.arm.safety import check_target
from hil.campaign.engine import Engine
from hil.campaign.events import EventBus, PoseSkipped
from hil.campaign.steps import Move, acquire, check_motion, plan_motion
from hil.errors import HilError
from hil.station.config import EXAMPLE, load_config
from tests.hil.campaign.fakes import FakeArm, FakeTracker

SPEC = get_robot("ur10e")
CONFIG = load_config(EXAMPLE)
BOX = (np.array(CONFIG.keep_in["min"]), np.array(CONFIG.keep_in["max"]))
MODEL = Geometry.nominal(SPEC, CONFIG.smr["offset"])


def _straight_is_safe(a: np.ndarray, b: np.ndarray) -> bool:
    try:
        check_target(b, SPEC, BOX, MODEL, a)
        return True
    except HilError:
        return False


@pytest.fixture(scope="module")
def detour_leg() -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """Two poses inside the box whose straight path leaves it and that the router joins by a detour."""
    rng = np.random.default_rng(5)
    q = rng.uniform(-np.pi, np.pi, (600, 6))
    q[:, 2] = rng.uniform(-2.5, 2.5, len(q))
    p = Kinematics(MODEL).points(q, frame="base")
    inside = q[np.all((p >= BOX[0]) & (p <= BOX[1]), axis=1)]
    router = Router(SPEC, BOX, MODEL)
    for _ in range(200):
        a, b = inside[rng.choice(len(inside), 2, replace=False)]
        if _straight_is_safe(a, b):
            continue
        try:
            route = router.route(a, b)
        except UnsafePathError:
            continue
        return a, b, route
    pytest.fail("no leg with a detour found")


def _plan(a: np.ndarray, b: np.ndarray) -> list:
    return [acquire(i, "calibration", q, settle=0.0, joint_samples=1, samples=1)
            for i, q in enumerate((a, b))]


def _engine(a: np.ndarray, events: list) -> tuple[Engine, FakeArm]:
    arm = FakeArm(np.asarray(a, float))
    bus = EventBus()
    bus.subscribe(events.append, critical=True)
    return Engine(arm, FakeTracker(arm, MODEL), "c1", SPEC, bus=bus, keep_in=BOX, check_model=MODEL), arm


def _run(engine: Engine, steps: list) -> None:
    def plan():
        for step in steps:  # each reply (a record, or Skipped) is not needed here
            _ = yield step

    engine.run(plan())


def test_a_leg_the_run_detours_is_shown_as_that_detour(detour_leg) -> None:
    a, b, route = detour_leg
    steps = _plan(a, b)
    legs = plan_motion(steps, Router(SPEC, BOX, MODEL))
    assert [leg.detour for leg in legs] == [False, True] and not any(leg.skipped for leg in legs)
    assert np.allclose(np.array(legs[1].via), np.array(route[:-1])) and np.allclose(legs[1].target, b)
    assert check_motion(steps, SPEC, BOX, MODEL) == 2  # not refused: the run gets there safely

    events: list = []
    engine, arm = _engine(a, events)
    _run(engine, steps)
    shown = [np.asarray(q) for leg in legs for q in (*leg.via, leg.target)]
    assert len(arm.targets) == len(shown)
    assert all(np.allclose(moved, planned) for moved, planned in zip(arm.targets, shown, strict=True))


def test_a_leg_with_no_safe_way_is_shown_skipped_as_the_run_skips_it(detour_leg, monkeypatch) -> None:
    import hil.arm.routes as routes_module

    monkeypatch.setattr(routes_module, "TRANSIT_POSTURES", ())  # no detour left: nothing reaches b
    a, b, _ = detour_leg
    steps = _plan(a, b)
    legs = plan_motion(steps, Router(SPEC, BOX, MODEL))
    assert not legs[0].skipped and "no safe path" in legs[1].skipped and not legs[1].detour

    events: list = []
    engine, arm = _engine(a, events)
    _run(engine, steps)
    assert len(arm.targets) == 1 and np.allclose(arm.targets[0], a)
    assert [e.index for e in events if isinstance(e, PoseSkipped)] == [1]

    with pytest.raises(UnsafePathError):  # a plain move the run cannot make ends the run: so here
        plan_motion([Move(tuple(a)), Move(tuple(b))], Router(SPEC, BOX, MODEL))
