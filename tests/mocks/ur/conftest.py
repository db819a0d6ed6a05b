"""Fixtures: a simulated controller in its own process on a unique loopback address."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from mocks.ur.process import SimProcess
from mocks.ur.testing import start_sim


@pytest.fixture
def sim() -> Iterator[SimProcess]:
    """A fresh simulator at 10x speed (protective-stop unlock delay: 0.5 s real)."""
    s = start_sim(speed=10.0)
    try:
        yield s
    finally:
        s.stop()


@pytest.fixture(scope="module")
def shared_sim() -> Iterator[SimProcess]:
    """One simulator for tests that leave it healthy."""
    s = start_sim(speed=5.0)
    try:
        yield s
    finally:
        s.stop()
