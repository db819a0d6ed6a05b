"""Issue 19: a changed tracker URL (or robot address, timeout, store) resumes the campaign, so the poses
already measured are reused; what changes the measurement still starts a new one. Old stores too."""

from __future__ import annotations

import json
import sqlite3

import pytest

from hil.station.config import default_config
from hil.store import RobotIdentity, Store, measurement_hash
from tests.hil.store.legacy_schema import make_legacy

ROBOT = RobotIdentity(type="ur5e", serial="20235500123", model="UR5e", software="5.15.0")


def cfg(**overrides) -> dict:
    data = default_config().as_dict()
    data["station"]["name"] = "cell-1"
    data["tracker"]["url"] = "/dev/ttyUSB0"
    data["robot"]["address"] = "192.168.0.10"
    for dotted, value in overrides.items():
        section, key = dotted.split("__")
        data[section][key] = value
    return data


@pytest.mark.parametrize("change", [
    {"tracker__url": "/dev/ttyUSB1"},  # the same tracker on another port
    {"tracker__url": "socket://192.168.0.20:4000"},  # ... or reached over the network
    {"tracker__baudrate": 9600, "tracker__parity": "E"},
    {"tracker__timeout": 9.0, "tracker__warmup": 120.0},
    {"timeouts__relock": 300.0, "timeouts__connect": 30.0},
    {"robot__address": "192.168.0.11"},  # the serial says it is the same arm
    {"store__path": "/elsewhere.db"},
])
def test_what_does_not_change_the_measurement_resumes_the_campaign(tmp_path, change):
    with Store.open(tmp_path / "hil.db") as store:
        cid = store.create_campaign(cfg(), ROBOT)
        store.record_measurement(cid, 0, "calibration", [0.1] * 6, [1, 2, 3], t=1.0)
        assert store.find_resumable(cfg(**change), ROBOT.serial) == cid
        assert sorted(store.measured_poses(cid)) == [0]  # what the resume reuses


@pytest.mark.parametrize("change", [
    {"tracker__protocol": "emscon"},  # measures differently (stationary time, reflector)
    {"tracker__temperature": 30.0},  # atmospheric correction: every distance changes
    {"tracker__position": (1.0, 0.0, 0.5)},
    {"smr__offset": (0.0, 0.0, 0.05)},
    {"robot__type": "ur10e"},
    {"robot__joint_samples": 3},
    {"campaign__samples": 9},
    {"campaign__seed": 2},
    {"station__name": "cell-2"},
])
def test_what_changes_the_measurement_starts_anew(tmp_path, change):
    with Store.open(tmp_path / "hil.db") as store:
        store.create_campaign(cfg(), ROBOT)
        assert store.find_resumable(cfg(**change), ROBOT.serial) is None


def test_without_a_serial_the_robot_address_tells_the_arm(tmp_path):
    with Store.open(tmp_path / "hil.db") as store:
        cid = store.create_campaign(cfg(), RobotIdentity(type="ur5e"))
        assert store.find_resumable(cfg(tracker__url="/dev/ttyUSB1")) == cid
        assert store.find_resumable(cfg(robot__address="192.168.0.11")) is None  # maybe another arm


def test_a_simulated_station_keeps_what_it_simulates():
    """The simulated station's identity says seed and truth in a ``sim:`` URL: never dropped."""
    a = cfg(tracker__url="sim:seed=1;truth=aaa", robot__address="sim")
    b = cfg(tracker__url="sim:seed=1;truth=bbb", robot__address="sim")
    assert measurement_hash(a) != measurement_hash(b)
    assert measurement_hash(a) == measurement_hash(cfg(tracker__url="sim:seed=1;truth=aaa"))


def test_a_version_2_store_resumes_after_a_changed_tracker_url(tmp_path):
    db = tmp_path / "hil.db"
    make_legacy(db, 2)
    conn = sqlite3.connect(db, isolation_level=None)
    conn.execute("INSERT INTO stations (id, name, created) VALUES (1, 'cell-1', 0)")
    conn.execute("INSERT INTO campaigns (id, station, robot_type, config, config_hash, status, created, "
                 "updated) VALUES ('20240101-000000-abcd', 1, 'ur5e', ?, 'x', 'running', 1, 1)",
                 (json.dumps(cfg()),))
    conn.close()
    with Store.open(db) as store:
        assert store.find_resumable(cfg(tracker__url="/dev/ttyUSB3")) == "20240101-000000-abcd"
        assert store.leases() == []
