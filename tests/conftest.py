"""Shared fixtures: seeded generators and a simulated UR controller."""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np
import pytest

from mocks.ur.process import SimProcess
from mocks.ur.testing import start_sim


@pytest.fixture(autouse=True)
def _own_lock_dir(tmp_path_factory, monkeypatch) -> None:
    """Each test its own folder of robot address locks (hil.store.leases): tests run side by side,
    and by several people on one machine, use the same loopback addresses for different fake arms."""
    monkeypatch.setenv("HIL_LOCK_DIR", str(tmp_path_factory.mktemp("locks")))


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture
def sim() -> Iterator[SimProcess]:
    """A fresh UR simulator in its own process at 10x speed (protective-stop unlock: 0.5 s real)."""
    s = start_sim(speed=10.0)
    try:
        yield s
    finally:
        s.stop()
