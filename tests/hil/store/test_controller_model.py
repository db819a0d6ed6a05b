"""Issue 14: the store keeps the controller's own kinematic model with every campaign (schema v5).

On both engines: a `ControllerModel` event puts the controller's KinematicsInfo record on the campaign
(`campaigns.controller`, revision 0005) and on its robot (`robots.controller`, the latest); a
`ValidationDone` carrying the controller's figures keeps them in the validation's details; and a store
written by hil at v4 (Alembic 0004) upgrades in place, its campaigns without a controller model.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from alembic import command
from sqlalchemy import create_engine

from hil.campaign.events import ControllerModel, RunStarted, ValidationDone
from hil.store import SCHEMA_VERSION, RobotIdentity, Store
from hil.store import migrate as migrate_mod
from hil.store.fleet import robot_history
from tests.hil.store.raw import raw
from tests.hil.store.test_engines import cfg, count

ROBOT = RobotIdentity(type="ur5e", serial="20235500777", model="UR5e", software="5.15.0")
# what `controller_record` makes of a KinematicsInfo: the package's fields and the derived deltas
RECORD = {"checksum": [1, 2, 3, 4, 5, 4294967295],
          "dh_theta": [1e-4, 0.0, 0.0, 0.0, 0.0, -2e-4], "dh_a": [0.0, -0.4251, -0.3922, 0.0, 0.0, 0.0],
          "dh_d": [0.1625, 0.3, -0.3, 0.1333, 0.0997, 0.0996],
          "dh_alpha": [1.5708, 0.0, 0.0, 1.5708, -1.5708, 0.0], "calibration_status": 2,
          "delta_theta": [1e-4, 0.0, 0.0, 0.0, 0.0, -2e-4], "delta_a": [0.0, -1e-4, 0.0, 0.0, 0.0, 0.0],
          "delta_d": [0.0, 0.3, -0.3, 0.0, 0.0, 0.0], "delta_alpha": [0.0] * 6}


@pytest.fixture(params=["sqlite", "postgresql"])
def location(request, tmp_path) -> str:
    """An SQLite file (not there yet), or a fresh, empty PostgreSQL database (as in test_engines)."""
    if request.param == "sqlite":
        return str(tmp_path / "data" / "hil.db")
    return str(request.getfixturevalue("pg_url"))


def test_a_campaign_keeps_the_controller_model_it_ran_with_and_the_robot_the_latest(location):
    newer = {**RECORD, "calibration_status": 3, "checksum": [9, 9, 9, 9, 9, 9]}
    with Store.open(location) as s:
        first = s.create_campaign(cfg(), ROBOT)
        s.record_event(RunStarted(campaign=first, robot="ur5e", station="cell-1", poses=3))
        assert s.campaign(first).controller is None  # not reported (yet)
        s.record_event(ControllerModel(campaign=first, model=RECORD))
        second = s.create_campaign(cfg("cell-2"), ROBOT)  # the same arm, recalibrated since
        s.record_event(ControllerModel(campaign=second, model=newer))
        unknown = s.create_campaign(cfg("cell-3"))  # no serial: no robot row to update
        s.record_event(ControllerModel(campaign=unknown, model=RECORD))
    with Store.open(location, readonly=True) as s:
        assert s.campaign(first).controller == RECORD
        assert s.campaign(second).controller == newer and s.campaign(unknown).controller == RECORD
        assert s.campaign(first).as_dict()["controller"] == RECORD  # `hil show --json`
        assert robot_history(s, ROBOT.serial).robot.controller == newer
        assert [e.name for e in s.events(first)] == ["RunStarted", "ControllerModel"]
        assert s.events(first)[1] == ControllerModel(campaign=first, t=s.events(first)[1].t, model=RECORD)


def test_the_controller_figures_of_a_validation_are_kept_in_its_details(location):
    figures = {"count": 12, "mean": 1e-4, "rms": 1.2e-4, "max": 3e-4}
    with Store.open(location) as s:
        cid = s.create_campaign(cfg(), ROBOT)
        s.record_event(ValidationDone(campaign=cid, before={"rms": 1e-3}, after={"rms": 2e-5}, passed=True,
                                      controller=figures))
        other = s.create_campaign(cfg("cell-2"), ROBOT)
        s.record_event(ValidationDone(campaign=other, before={"rms": 1e-3}, after={"rms": 2e-5},
                                      passed=True))
        assert s.campaign(cid).validation.details == {"controller": figures}
        assert s.campaign(other).validation.details is None  # as before v5


def _v4_store(location: str) -> None:
    """A store exactly as hil at schema v4 left it (Alembic revision 0004), with a robot whose
    controller calibration was recorded and one finished campaign."""
    if location.startswith("postgresql"):
        url = location.replace("postgresql://", "postgresql+psycopg://", 1)
    else:
        Path(location).parent.mkdir(parents=True, exist_ok=True)
        url = f"sqlite:///{location}"
    engine = create_engine(url)
    try:
        with engine.begin() as conn:
            command.upgrade(migrate_mod.alembic_config(conn), "0004")
            if conn.dialect.name == "sqlite":
                conn.exec_driver_sql("PRAGMA user_version = 4")
            conn.exec_driver_sql("INSERT INTO stations (id, name, created) VALUES (1, 'old-cell', 1.0)")
            conn.exec_driver_sql(
                "INSERT INTO robots (id, serial, type, model, software, first_seen, last_seen, controller) "
                f"VALUES (1, '{ROBOT.serial}', 'ur5e', 'UR5e', '5.15.0', 1.0, 2.0, '{json.dumps(RECORD)}')")
            conn.exec_driver_sql(
                "INSERT INTO campaigns (id, station, robot, robot_type, config, status, created, updated) "
                f"VALUES ('20240101-000000-abcd', 1, 1, 'ur5e', '{json.dumps(cfg('old-cell'))}', "
                "'accepted', 1.0, 2.0)")
    finally:
        engine.dispose()


def test_a_v4_store_upgrades_to_the_head_in_place(location, monkeypatch):
    _v4_store(location)
    upgrades: list[str] = []
    real = command.upgrade
    monkeypatch.setattr(command, "upgrade",
                        lambda config, revision, *a, **k: (upgrades.append(revision), real(config, revision)))
    with Store.open(location) as s:
        assert upgrades == ["0006"] and SCHEMA_VERSION == 6
        assert raw(s).execute("SELECT version_num FROM alembic_version").fetchall() == [("0006",)]
        if not location.startswith("postgresql"):
            assert count(s, "PRAGMA user_version") == 6
        old = s.campaign("20240101-000000-abcd")
        assert old.controller is None and old.summary.status == "accepted"  # ran before v5
        assert robot_history(s, ROBOT.serial).robot.controller == RECORD  # kept through the upgrade
        cid = s.create_campaign(cfg("old-cell"), ROBOT)
        s.record_event(ControllerModel(campaign=cid, model=RECORD))
        assert s.campaign(cid).controller == RECORD
    with Store.open(location) as s:  # opened again: nothing more to upgrade
        assert upgrades == ["0006"] and s.campaign(cid).controller == RECORD


def test_a_controller_model_is_stored_as_json_text(location):
    """Not JSONB: the text is what hil wrote, on both engines (the store's rule for JSON columns)."""
    with Store.open(location) as s:
        cid = s.create_campaign(cfg(), ROBOT)
        s.record_event(ControllerModel(campaign=cid, model=RECORD))
        text = raw(s).execute("SELECT controller FROM campaigns WHERE id = ?", (cid,)).fetchone()[0]
        assert isinstance(text, str) and json.loads(text) == RECORD
