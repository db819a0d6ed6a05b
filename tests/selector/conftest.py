"""Shared fixtures: small synthetic candidate blocks (fast) and a real UR5e candidate set (cached)."""

from __future__ import annotations

import numpy as np
import pytest

from hil.calibration.selection import SelectionModel
from selector.candidates import Constraints, generate_candidates
from selector.indices import scale_columns


@pytest.fixture(scope="session")
def blocks() -> np.ndarray:
    """400 random candidate blocks for 9 parameters: structure-free but quick."""
    return np.random.default_rng(3).normal(size=(400, 3, 9))


@pytest.fixture(scope="session")
def ur5e_model() -> SelectionModel:
    return SelectionModel("ur5e", smr=(0.03, -0.02, 0.045), tracker=(2.5, 0.5, 0.5))


@pytest.fixture(scope="session")
def ur5e_blocks(ur5e_model: SelectionModel) -> np.ndarray:
    """1500 feasible UR5e candidates' scaled Jacobians (27 parameters)."""
    cands = generate_candidates(ur5e_model, 1500, Constraints(tracker=(2.5, 0.5, 0.5)), seed=1)
    return scale_columns(cands.jacobian, "unit")
