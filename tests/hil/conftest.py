"""Fixtures shared by hil's test packages: a realistic fleet's store (`tests.hil.fleet_data`), built
once per session on each engine (an SQLite file, a PostgreSQL database) and copied for each test."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.hil.fleet_data import Fleet, build_fleet


@pytest.fixture(scope="session")
def _sqlite_fleet(tmp_path_factory: pytest.TempPathFactory) -> Fleet:
    return build_fleet(tmp_path_factory.mktemp("fleet") / "fleet.db")


@pytest.fixture(scope="session")
def _postgresql_fleet(postgres) -> Fleet:
    return build_fleet(postgres.create_database("fleet"), server=postgres)


@pytest.fixture(params=["sqlite", "postgresql"])
def built_fleet(request: pytest.FixtureRequest) -> Fleet:
    """Three robots calibrated three times each at two stations (about half a second to build), on
    each engine: shared, never written to; tests take `fleet_store_location`, their own copy."""
    return request.getfixturevalue(f"_{request.param}_fleet")


@pytest.fixture
def fleet_store_location(built_fleet: Fleet, tmp_path: Path) -> Path | str:
    """This test's own copy of the fleet's store, free to write to: an SQLite file, or a PostgreSQL
    database made from the built one (``CREATE DATABASE … TEMPLATE``)."""
    return built_fleet.copy_to(tmp_path)
