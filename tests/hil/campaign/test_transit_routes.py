"""`Router.route` (the routes the engine moves along) on a UR10e in the example's keep-in box: where the
straight path and the upright detour both leave the box (the UR10e stands ~1.5 m tall upright, above
the 1.2 m box), a folded transit posture gets there; every leg it sends stays in the box and no posture
it uses folds the arm onto itself."""

from __future__ import annotations

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry
from hil.arm.routes import TRANSIT_POSTURES, Router, UnsafePathError, transit
from hil.arm.safety import check_target
from hil.calibration.selection import SelectionModel
from hil.errors import HilError
from hil.station.config import EXAMPLE, load_config
from selector.candidates import CONSTRAINT_NAMES, Constraints, evaluate, generate_candidates

SPEC = get_robot("ur10e")
CONFIG = load_config(EXAMPLE)
BOX = (np.array(CONFIG.keep_in["min"]), np.array(CONFIG.keep_in["max"]))
MODEL = Geometry.nominal(SPEC)


def _safe(a: np.ndarray, b: np.ndarray) -> bool:
    try:
        check_target(b, SPEC, BOX, MODEL, a)
        return True
    except HilError:
        return False


@pytest.fixture(scope="module")
def hard_legs() -> list[tuple[np.ndarray, np.ndarray]]:
    """Pairs of poses inside the box whose straight path and upright detour both leave it."""
    model = SelectionModel("ur10e", tracker=(2.5, 0.0, 0.3))
    box = Constraints(tracker=(2.5, 0.0, 0.3), keep_in_lower=tuple(BOX[0]), keep_in_upper=tuple(BOX[1]),
                      floor=float(BOX[0][2]))
    cands = generate_candidates(model, 300, box, seed=4)
    rng = np.random.default_rng(1)
    legs = []
    for _ in range(400):
        a, b = cands.q[rng.choice(len(cands.q), 2, replace=False)]
        up_a, up_b = transit(a), transit(b)
        if not _safe(a, b) and not (_safe(a, up_a) and _safe(up_a, up_b) and _safe(up_b, b)):
            legs.append((a, b))
        if len(legs) == 12:
            break
    assert len(legs) >= 5  # the situation the folded postures are for is common on a UR10e
    return legs


def _routed(router: Router, legs: list) -> list[tuple[np.ndarray, np.ndarray, list[np.ndarray]]]:
    """(start, target, route) of every leg the router finds a route for."""
    out = []
    for a, b in legs:
        try:
            out.append((a, b, router.route(a, b)))
        except UnsafePathError:
            continue
    return out


def _router() -> Router:
    return Router(SPEC, keep_in=BOX, model=MODEL)


def test_a_folded_posture_reaches_what_the_upright_one_cannot(hard_legs) -> None:
    router = _router()
    shape = SelectionModel("ur10e")
    others = frozenset(CONSTRAINT_NAMES) - {"self-collision"}
    routed = _routed(router, hard_legs)
    for a, b, route in routed:
        assert len(route) == 3 and np.array_equal(route[-1], b)
        start = a
        for target in route:  # every leg inside the box, checked independently of the engine
            assert _safe(start, target)
            start = target
        passes, _ = evaluate(shape, np.linspace(route[0], route[1], 5), Constraints(disabled=others))
        assert passes["self-collision"].all()
        assert (route[0][1], route[0][2]) in TRANSIT_POSTURES[1:]
    assert len(routed) >= 0.7 * len(hard_legs)


def test_a_posture_that_folds_the_arm_onto_itself_is_never_used(hard_legs, monkeypatch) -> None:
    import hil.arm.routes as routes_module

    # a posture with the elbow folded flat back (collides) tried first: the route must skip it
    monkeypatch.setattr(routes_module, "TRANSIT_POSTURES", (TRANSIT_POSTURES[0], (-np.pi / 2, 3.1),
                                                            *TRANSIT_POSTURES[1:]))
    router = _router()
    for _, _, route in _routed(router, hard_legs):
        assert not np.isclose(route[0][2], 3.1)


def test_of_the_safe_detours_the_quickest_is_taken(hard_legs) -> None:
    router = _router()

    def travel(start: np.ndarray, route: list[np.ndarray]) -> float:
        return sum(float(np.max(np.abs(b - a))) for a, b in zip([start, *route[:-1]], route, strict=True))

    for a, b, route in _routed(router, hard_legs):
        others = [[transit(a, s, e), transit(b, s, e), b] for s, e in TRANSIT_POSTURES]
        safe = [r for r in others if _safe(a, r[0]) and _safe(r[0], r[1]) and _safe(r[1], r[2])
                and not router.collides(np.linspace(r[0], r[1], 5))]
        assert travel(a, route) <= min(travel(a, r) for r in safe) + 1e-12
