"""`Router.route` checks a folded transit for self-collision only after its legs passed the keep-in box
(the cheaper check first): the route it picks must be the one of the plain rule — straight if safe,
else the least-travel route among `candidates` (collision-free by construction) whose every leg is
safe — on legs of a UR10e in the example box, where many need detours."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry
from hil.arm.routes import Router, UnsafePathError, travel
from hil.arm.safety import check_target
from hil.errors import HilError
from hil.station.config import EXAMPLE, load_config

SPEC = get_robot("ur10e")
CONFIG = load_config(EXAMPLE)
BOX = (np.array(CONFIG.keep_in["min"], float), np.array(CONFIG.keep_in["max"], float))
HOME = np.array([0.0, -np.pi / 2, 0.0, -np.pi / 2, 0.0, 0.0])


def _router() -> Router:
    return Router(SPEC, BOX, Geometry.nominal(SPEC, smr=(0.0, 0.0, 0.045)), HOME)


def _reference(router: Router, here: np.ndarray, q: np.ndarray) -> list[np.ndarray] | None:
    """The plain rule over `candidates` (which leaves out folded postures that collide)."""
    safe = []
    for route in router.candidates(here, q):
        try:
            start = here
            for target in route:
                check_target(target, SPEC, BOX, router.model, start)
                start = target
        except HilError:
            continue
        if len(route) == 1:
            return route
        safe.append(route)
    return min(safe, key=lambda r: travel(here, r)) if safe else None


@pytest.fixture(scope="module")
def poses() -> list[np.ndarray]:
    router, rng, out = _router(), np.random.default_rng(5), []
    while len(out) < 31:
        q = rng.uniform(SPEC.lower / 2, SPEC.upper / 2)
        try:
            router.route(None, q)
        except HilError:
            continue
        out.append(q)
    return out


def test_route_is_the_plain_rules_choice(poses: list[np.ndarray]) -> None:
    router = _router()
    kinds = {"straight": 0, "detour": 0, "none": 0}
    for here, q in itertools.pairwise(poses):
        expected = _reference(router, here, q)
        if expected is None:
            with pytest.raises(UnsafePathError):
                router.route(here, q)
            kinds["none"] += 1
            continue
        got = router.route(here, q)
        assert len(got) == len(expected)
        for a, b in zip(got, expected, strict=True):
            np.testing.assert_array_equal(a, b)
        kinds["straight" if len(got) == 1 else "detour"] += 1
    assert kinds["straight"] and kinds["detour"] >= 5  # both paths of the rule are exercised


def test_a_colliding_folded_transit_is_never_taken(poses: list[np.ndarray]) -> None:
    """With every folded posture colliding, only the straight path, home and the upright transit
    remain: each route taken passes through one of them."""
    router = _router()
    router.collides = lambda q: True  # type: ignore[method-assign]
    for here, q in itertools.pairwise(poses):
        try:
            route = router.route(here, q)
        except UnsafePathError:
            continue
        if len(route) == 2:
            np.testing.assert_array_equal(route[0], HOME)
        elif len(route) == 3:
            assert route[0][1] == -np.pi / 2 and route[0][2] == 0.0  # the upright posture
