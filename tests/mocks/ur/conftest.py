"""Fixtures: one simulated controller shared by a module (`sim`, a fresh one, is in tests/conftest.py)."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from mocks.ur.process import SimProcess
from mocks.ur.testing import start_sim


@pytest.fixture(scope="module")
def shared_sim() -> Iterator[SimProcess]:
    """One simulator for tests that leave it healthy."""
    s = start_sim(speed=5.0)
    try:
        yield s
    finally:
        s.stop()
