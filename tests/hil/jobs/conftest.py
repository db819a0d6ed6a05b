"""Fixtures of the jobs' tests: an arm address of each test's own."""

from __future__ import annotations

import zlib

import pytest


@pytest.fixture
def address(request: pytest.FixtureRequest) -> str:
    """A loopback address derived from the test's name: the address lock is per address and host-wide,
    and tests run side by side (pytest-xdist)."""
    h = zlib.crc32(request.node.nodeid.encode())
    return f"127.{(h >> 16) & 0xFF}.{(h >> 8) & 0xFF}.{h % 254 + 1}"
