"""Fixtures: a simulated controller process on a unique loopback address, and a driver config for it."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from mocks.ur.process import SimProcess
from mocks.ur.testing import start_sim


@pytest.fixture
def sim() -> Iterator[SimProcess]:
    """A fresh simulator at 10x speed, stopped after the test."""
    s = start_sim(speed=10.0)
    try:
        yield s
    finally:
        s.stop()
