"""Helpers for tests and benchmarks: start a simulator process on a free loopback address.

Every simulator owns a distinct 127.x.y.z (all loopback on Linux), so parallel simulators — and parallel
test runs — never fight over the fixed ports 30004/29999/30003. A clash (the address is taken) is
retried on another random address.
"""

from __future__ import annotations

import os
import random
import time
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

from mocks.ur.controller import SimConfig
from mocks.ur.process import SimProcess, SimStartError

_rng = random.Random(os.getpid() ^ time.time_ns())


def random_loopback() -> str:
    """A random 127.x.y.z away from 127.0.0.1 (which ur_rtde treats specially)."""
    return f"127.{_rng.randint(16, 254)}.{_rng.randint(0, 254)}.{_rng.randint(2, 254)}"


def start_sim(config: SimConfig | None = None, *, attempts: int = 5, services: Sequence[str] = (),
              **overrides: Any) -> SimProcess:
    """Start a simulator process on a free random loopback address; the caller must `stop()` it."""
    base = config or SimConfig()
    last: Exception | None = None
    for _ in range(attempts):
        cfg = replace(base, address=random_loopback(), **overrides)
        try:
            return SimProcess(cfg, services).start()
        except SimStartError as exc:
            last = exc
            if "Address already in use" not in str(exc) and "Errno 98" not in str(exc):
                raise
    raise SimStartError(f"no free loopback address after {attempts} attempts: {last}")
