"""Requests geometry proves empty are refused before any draw; feasible ones are never refused by it;
and sampling with no survivor stops at its own bound, whatever the candidate count asked."""

from __future__ import annotations

import numpy as np
import pytest

from hil.calibration.selection import SelectionModel
from selector.candidates import Constraints, generate_candidates, sampling_box
from selector.errors import NoCandidatesError
from selector.feasibility import _PROBES, impossible


class Counting:
    """A model that counts the configurations its frames were asked for (the draws' cost)."""

    def __init__(self, model: SelectionModel) -> None:
        self.model = model
        self.rows = 0

    def __getattr__(self, name: str) -> object:
        return getattr(self.model, name)

    def frames(self, q: np.ndarray) -> np.ndarray:
        self.rows += len(q)
        return self.model.frames(q)


@pytest.fixture(scope="module")
def model() -> SelectionModel:
    return SelectionModel("ur5e", smr=(0.0, 0.0, 0.045))


def _proof(model: SelectionModel, **settings: object) -> tuple[str, str] | None:
    c = Constraints(**settings)  # type: ignore[arg-type]
    return impossible(model, c, *sampling_box(model, c))


@pytest.mark.parametrize(("settings", "constraint"), [
    ({"tracker": (0.0, 0.0, 0.0)}, "line-of-sight"),  # inside the base
    ({"tracker": (0.03, -0.02, 0.12)}, "line-of-sight"),
    ({"tracker": (20.0, 0.0, 0.0), "tracker_range": (0.8, 2.0)}, "range"),  # too far for the range
    ({"tracker": (0.0, 0.0, 0.2), "tracker_range": (3.0, 20.0)}, "range"),  # too near for the range
    ({"keep_in_lower": (3.0, 3.0, 3.0), "keep_in_upper": (4.0, 4.0, 4.0)}, "keep-in"),
    ({"floor": 1.5}, "floor"),
])
def test_an_empty_request_is_refused_before_any_draw(model: SelectionModel, settings: dict,
                                                     constraint: str) -> None:
    proof = _proof(model, **settings)
    assert proof is not None and proof[0] == constraint
    counting = Counting(model)
    with pytest.raises(NoCandidatesError) as err:
        generate_candidates(counting, 20_000, Constraints(**settings), seed=0)  # type: ignore[arg-type]
    assert err.value.constraint == constraint
    assert counting.rows <= _PROBES  # the probe only: no candidate was drawn


@pytest.mark.parametrize("settings", [
    {"tracker": (2.5, 0.5, 0.5)},
    {"tracker": (0.0, 0.0, 0.6)},  # above the shoulder, inside the reach: possible, so not refused
    {"tracker": (0.3, 0.0, 0.0), "tracker_range": (0.5, 1.2)},
    {"keep_in_lower": (0.5, -0.2, 0.0), "keep_in_upper": (0.9, 0.2, 0.3)},
    {"floor": 0.05},
    {},
])
def test_a_request_sampling_satisfies_is_never_refused(model: SelectionModel, settings: dict) -> None:
    cands = generate_candidates(model, 20, Constraints(**settings), seed=0)  # type: ignore[arg-type]
    assert len(cands) > 0  # sampling found some: the request is possible
    assert _proof(model, **settings) is None


def test_the_disabled_constraint_proves_nothing(model: SelectionModel) -> None:
    assert _proof(model, tracker=(0.0, 0.0, 0.0), disabled=frozenset({"line-of-sight"})) is None
    assert _proof(model, floor=1.5, disabled=frozenset({"floor"})) is None


def test_no_survivor_stops_at_the_give_up_bound_for_any_count(model: SelectionModel) -> None:
    """A request geometry cannot refuse (both singularity margins near 90°) drew 2,000,000 joint
    vectors for 20,000 candidates (a guess of the acceptance rate made from zero survivors): 15–35 s."""
    counting = Counting(model)
    settings = Constraints(wrist_margin_deg=89.9, elbow_margin_deg=89.9)
    assert impossible(model, settings, *sampling_box(model, settings)) is None
    batch = 8192
    with pytest.raises(NoCandidatesError) as err:
        generate_candidates(counting, 20_000, settings, seed=0, batch=batch)  # type: ignore[arg-type]
    hopeless = max(10 * batch, 50_000)
    assert err.value.constraint in ("wrist", "elbow")
    assert counting.rows <= _PROBES + hopeless + batch  # the draws, the ranking batch
