"""Every constraint filters what it should: constructed configurations on a real UR5e model."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.optimize

from hil.calibration.selection import SelectionModel
from selector import arm
from selector.candidates import CONSTRAINT_NAMES, Constraints, evaluate, generate_candidates
from selector.errors import NoCandidatesError, SelectorError

READY = np.array([0.0, -1.2, 1.5, -1.9, -1.57, 0.0])  # SMR in front of the robot, flange facing down


def _smr_and_axis(model: SelectionModel, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    F = model.frames(q[None])[0]
    return F[6, :3, :3] @ model.smr + F[6, :3, 3], F[6, :3, 2]


def _masks(model: SelectionModel, q: np.ndarray, **settings: object) -> dict[str, bool]:
    passes, _ = evaluate(model, np.atleast_2d(q), Constraints(**settings))  # type: ignore[arg-type]
    return {k: bool(v[0]) for k, v in passes.items()}


@pytest.fixture(scope="module")
def model() -> SelectionModel:
    return SelectionModel("ur5e", smr=(0.03, -0.02, 0.045))


@pytest.fixture(scope="module")
def facing(model: SelectionModel) -> tuple[float, float, float]:
    """A tracker 2 m along READY's SMR opening axis: READY passes every constraint."""
    p, z = _smr_and_axis(model, READY)
    return tuple(p + 2.0 * z)


def test_reference_configuration_passes_everything(model: SelectionModel, facing: tuple) -> None:
    masks = _masks(model, READY, tracker=facing)
    assert set(masks) == set(CONSTRAINT_NAMES)
    assert all(masks.values())


def test_each_constraint_rejects_its_case(model: SelectionModel, facing: tuple) -> None:
    p, z = _smr_and_axis(model, READY)
    behind_base = p + 3.0 * (np.array([0.0, 0.0, 0.1]) - p) / np.linalg.norm(np.array([0, 0, 0.1]) - p)
    cases = {
        "keep-in": (READY, {"tracker": facing, "keep_in_upper": (10.0, 10.0, 0.2)}),
        "floor": (READY, {"tracker": facing, "floor": 0.25}),
        "range": (READY, {"tracker": tuple(p + 0.5 * z)}),
        "acceptance": (READY, {"tracker": tuple(p - 2.0 * z)}),
        "line-of-sight": (READY, {"tracker": tuple(behind_base)}),
        "wrist": (np.r_[READY[:4], 0.05, READY[5]], {"tracker": None}),
        "elbow": (np.r_[READY[:2], 0.05, READY[3:]], {"tracker": None}),
        "self-collision": (np.r_[READY[:2], 2.9, READY[3:]], {"tracker": None}),
    }
    for name, (q, settings) in cases.items():
        masks = _masks(model, q, **settings)
        assert masks[name] is False, name
        assert _masks(model, q, **settings, disabled=frozenset({name})).get(name) is None


def test_shoulder_singularity_is_rejected(model: SelectionModel) -> None:
    def signed(q3: float) -> float:
        F = model.frames(np.r_[READY[:2], q3, READY[3:]][None])
        n = np.cross(F[0, 0, :3, 2], F[0, 1, :3, 2])
        return float((F[0, 4, :3, 3] - F[0, 0, :3, 3]) @ n / np.linalg.norm(n))

    grid = np.linspace(-2.0, -0.3, 60)  # the forearm folds back over the base
    values = np.array([signed(v) for v in grid])
    k = int(np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:]))[0])
    q3 = scipy.optimize.brentq(signed, grid[k], grid[k + 1])
    q = np.r_[READY[:2], q3, READY[3:]]
    assert arm.shoulder_measure(model.frames(q[None]))[0] < 1e-9
    masks = _masks(model, q, disabled=frozenset({"self-collision", "floor"}))
    assert masks["shoulder"] is False and masks["elbow"] is True and masks["wrist"] is True


def test_no_candidates_names_the_worst_constraint(model: SelectionModel, facing: tuple) -> None:
    c = Constraints(tracker=facing, half_angle_deg=0.001)
    with pytest.raises(NoCandidatesError, match="'acceptance' removed the most"):
        generate_candidates(model, 100, c, max_samples=20_000)


def test_generation_is_deterministic_and_feasible(model: SelectionModel, facing: tuple) -> None:
    c = Constraints(tracker=facing)
    a = generate_candidates(model, 300, c, seed=4)
    b = generate_candidates(model, 300, c, seed=4)
    assert np.array_equal(a.q, b.q) and len(a) == 300
    assert a.jacobian.shape == (300, 3, len(model.parameters))
    passes, smr = evaluate(model, a.q, c)
    assert all(v.all() for v in passes.values())
    assert np.allclose(smr, a.smr)
    assert np.all(model.spec.within_limits(a.q))
    assert sum(a.rejected.values()) == a.sampled - 300 or a.sampled - sum(a.rejected.values()) >= 300


def test_disabling_tracker_constraints_without_tracker(model: SelectionModel) -> None:
    c = Constraints()
    assert not set(c.enabled()) & {"range", "acceptance", "line-of-sight"}
    assert c.as_dict()["tracker"] is None


def test_bad_settings() -> None:
    with pytest.raises(SelectorError, match="unknown constraint"):
        Constraints(disabled=frozenset({"gravity"}))
    with pytest.raises(SelectorError, match="keep-in"):
        Constraints(keep_in_lower=(0, 0, 1), keep_in_upper=(1, 1, 0))
    with pytest.raises(SelectorError, match="range"):
        Constraints(tracker_range=(5.0, 1.0))
    with pytest.raises(SelectorError, match="half-angle"):
        dataclasses.replace(Constraints(), half_angle_deg=0.0)


def test_segment_distance_matches_sampling() -> None:
    rng = np.random.default_rng(0)
    p1, q1, p2, q2 = (rng.normal(size=(200, 3)) for _ in range(4))
    q2[:10] = p2[:10]  # degenerate segments (points)
    q2[10:20] = p2[10:20] + 0.3 * (q1[10:20] - p1[10:20])  # parallel segments
    t = np.linspace(0, 1, 401)
    a = p1[:, None] + (q1 - p1)[:, None] * t[None, :, None]
    b = p2[:, None] + (q2 - p2)[:, None] * t[None, :, None]
    brute = np.min(np.linalg.norm(a[:, :, None] - b[:, None, :], axis=-1), axis=(1, 2))
    d = arm.segment_distance(p1, q1, p2, q2)
    assert np.all(d <= brute + 1e-12)
    assert np.allclose(d, brute, atol=5e-3)
