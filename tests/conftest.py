"""Shared fixtures: seeded generators, a simulated UR controller, PostgreSQL servers of the tests' own."""

from __future__ import annotations

import itertools
import os
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from hil.arm.blas_threads import limit_blas_threads
from mocks.ur.process import SimProcess
from mocks.ur.testing import start_sim
from tests.pg_server import PostgresServer, find_binaries

# as in the hil command and the simulators: one BLAS thread per process (hil.arm.blas_threads)
limit_blas_threads()


@pytest.fixture(autouse=True)
def _own_lock_dir(tmp_path_factory, monkeypatch) -> None:
    """Each test its own folder of robot address locks (hil.store.leases): tests run side by side,
    and by several people on one machine, use the same loopback addresses for different fake arms."""
    monkeypatch.setenv("HIL_LOCK_DIR", str(tmp_path_factory.mktemp("locks")))


@pytest.fixture(autouse=True)
def _own_data_dir(tmp_path_factory, monkeypatch) -> None:
    """Each test its own per-user data folder, and no plant store from the environment: a test that
    leaves the store to its default (``hil calibrate --sim`` writes ``sim.db`` there) must neither read
    nor write the person's own, which another hil version may have written (a newer schema is refused)."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path_factory.mktemp("data")))
    monkeypatch.delenv("HIL_DB", raising=False)


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


def _postgres_binaries() -> Path:
    """Where initdb, pg_ctl and postgres are; without them a test that needs PostgreSQL is skipped on a
    developer's machine, but fails in CI (CI set): there a silent skip would hide the whole store."""
    binaries = find_binaries()
    if binaries is None:
        reason = ("PostgreSQL server binaries (initdb, pg_ctl, postgres) not found on PATH nor under "
                  "/usr/lib/postgresql/*/bin; install PostgreSQL (Debian: apt-get install postgresql)")
        if os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no"):
            pytest.fail(f"CI is set and {reason}", pytrace=False)
        pytest.skip(reason)
    return binaries


@pytest.fixture(scope="session")
def postgres() -> Iterator[PostgresServer]:
    """One PostgreSQL server for the whole test session (started on first use, about 1 s, and removed
    with its data at the end). Tests get databases of their own on it through `pg_url`; a test that
    stops, restarts or kills the server takes `own_postgres` instead."""
    server = PostgresServer(_postgres_binaries())
    try:
        server.start()
        yield server
    finally:
        server.close()


_databases = itertools.count(1)


@pytest.fixture
def pg_url(postgres: PostgresServer) -> str:
    """A new, empty database for this test on the session's server: `postgresql://hil@127.0.0.1:PORT/hil_N`."""
    return postgres.create_database(f"hil_{next(_databases)}")


@pytest.fixture
def own_postgres() -> Iterator[PostgresServer]:
    """A PostgreSQL server of this test's own, started, for tests that stop, restart or kill it
    (`stop()`, `start()`, `kill()`; URLs stay valid across restarts); removed at the end."""
    server = PostgresServer(_postgres_binaries())
    try:
        server.start()
        yield server
    finally:
        server.close()
