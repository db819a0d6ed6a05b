"""The selector on an arm that is not a UR: any number of joints, capsules between the joint origins
(`ChainShape`), the model's own self-collision check, and sampling inside limits of less than a turn."""

from __future__ import annotations

import math

import numpy as np
import pytest

from selector.arm import ChainShape
from selector.candidates import Constraints, evaluate, generate_candidates, sampling_box
from selector.errors import SelectorError


class PlanarArm:
    """Three revolute joints about parallel vertical axes, links of 0.4 m along x, the flange at the
    last joint's origin: a toy `PoseModel` of an arm with three joints."""

    def __init__(self, lower: float = -math.pi, upper: float = math.pi) -> None:
        self.lower, self.upper = np.full(3, lower), np.full(3, upper)
        self.max_joint_speed = np.ones(3)
        self.smr = np.array([0.0, 0.0, 0.05])
        self.parameter_names = ("a", "b")
        self.parameter_scale = np.ones(2)
        self.arm = ChainShape(radii=(0.05, 0.04, 0.04, 0.04, 0.02), pairs=((0, 2), (0, 3)), floor_from=1)
        self.aim_joint = None
        self.calls = 0

    def collides(self, q: np.ndarray) -> np.ndarray:
        """A stand-in for a URDF's meshes: the arm folded back (|q2| > 2.5 rad) collides."""
        self.calls += len(q)
        return np.abs(q[:, 1]) > 2.5

    def frames(self, q: np.ndarray) -> np.ndarray:
        q = np.atleast_2d(q)
        out = np.zeros((len(q), 4, 4, 4))
        angle = np.zeros(len(q))
        position = np.zeros((len(q), 3))
        position[:, 2] = 0.3
        for j in range(3):
            angle = angle + q[:, j]
            c, s = np.cos(angle), np.sin(angle)
            out[:, j, 0, 0], out[:, j, 0, 1], out[:, j, 1, 0], out[:, j, 1, 1] = c, -s, s, c
            out[:, j, 2, 2] = out[:, j, 3, 3] = 1.0
            out[:, j, :3, 3] = position
            position = position + 0.4 * np.stack([c, s, np.zeros_like(c)], axis=1)
        out[:, 3] = out[:, 2]
        return out

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        q = np.atleast_2d(q)
        return np.stack([np.stack([np.cos(q[:, 0]), np.sin(q[:, 1]), q[:, 2]], 1)] * 2, axis=2)


def test_segments_run_between_the_frame_origins_to_the_smr() -> None:
    model = PlanarArm()
    q = np.array([[0.3, -0.4, 1.0]])
    F = model.frames(q)
    smr = F[:, -1, :3, :3] @ model.smr + F[:, -1, :3, 3]
    segs = model.arm.segments(F, smr)
    assert segs.shape == (1, 5, 2, 3)
    assert np.allclose(segs[0, 0, 0], 0.0) and np.allclose(segs[0, 0, 1], F[0, 0, :3, 3])
    assert np.allclose(segs[0, 1:4, 1], F[0, 1:, :3, 3]) and np.allclose(segs[0, 4, 1], smr[0])


def test_candidates_of_three_joints_use_the_models_own_self_collision() -> None:
    model = PlanarArm()
    constraints = Constraints(disabled=frozenset({"wrist", "elbow", "shoulder"}))
    cands = generate_candidates(model, 200, constraints, seed=2)
    assert cands.q.shape == (200, 3)
    assert not np.any(model.collides(cands.q))
    assert cands.rejected["self-collision"] > 0 and model.calls > 0
    assert set(evaluate(model, cands.q, constraints)[0]) >= {"self-collision", "floor"}


def test_the_ur_singularity_measures_are_refused_on_a_chain_shape() -> None:
    with pytest.raises(SelectorError, match="singularity measures are a UR's"):
        evaluate(PlanarArm(), np.zeros((1, 3)), Constraints())


@pytest.mark.parametrize(("lower", "upper", "lo", "hi"), [
    (-2 * math.pi, 2 * math.pi, -math.pi, math.pi),  # a UR joint: one turn about zero
    (0.8, 5.5, 0.8, 5.5),  # less than a turn: the limits as they are
    (1.0, 9.0, 1.0, 1.0 + 2 * math.pi),  # a turn or more, zero outside: the turn nearest zero
])
def test_sampling_box(lower: float, upper: float, lo: float, hi: float) -> None:
    box = sampling_box(PlanarArm(lower, upper), Constraints())
    assert np.allclose(box[0], lo) and np.allclose(box[1], hi)
