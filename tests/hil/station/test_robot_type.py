"""The robot type every source names must agree, the controller's word included (issue 19).

* `agreed_robot` names each source in one line, whichever side it is on.
* The controller's spelling (the driver's `RobotIdentity.model`: ``UR5e`` e-Series, ``UR5`` CB3, ``UR20``)
  maps onto the catalog, so a UR5e configured against a CB3 UR5 is a mismatch, not a match.
* `simulated_station` refuses a robot its truth contradicts instead of silently simulating the truth's.
* A simulated CB3 controller reports what it simulates, read through the real driver.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from hil.calibration.model_file import truth_document, write_json
from hil.calibration.synthetic import Noise, random_truth
from hil.errors import InputError
from hil.station.config import StationConfig, default_config
from hil.station.robot_type import Claim, agreed_robot, check_controller


def _config(robot: str, address: str = "127.0.0.2", source: str = "station.toml") -> StationConfig:
    config = default_config().with_overrides(robot__type=robot, robot__address=address)
    return dataclasses.replace(config, source=source)  # as `load_config` names it


def _info(model: str) -> SimpleNamespace:
    return SimpleNamespace(model=model, serial="20235500001", software_version="5.15.0")


def test_disagreeing_sources_are_named_each_in_one_line() -> None:
    with pytest.raises(InputError) as exc:
        agreed_robot([Claim("ur10e", "--robot is ur10e"), Claim("ur5e", "the model m.json is for ur5e"),
                      Claim("UR5e", "the controller at 127.0.0.2 reports UR5e")])
    assert str(exc.value) == ("--robot is ur10e but the model m.json is for ur5e and the controller at "
                              "127.0.0.2 reports UR5e")
    # those that agree with the first come first, whatever their order
    with pytest.raises(InputError) as exc:
        agreed_robot([Claim("ur5e", "A"), Claim("ur10e", "B"), Claim("UR5e", "C")])
    assert str(exc.value) == "A and C but B"


def test_agreeing_sources_give_the_catalog_name_and_none_gives_the_default() -> None:
    assert agreed_robot([Claim("UR10e", "x"), Claim("ur10e", "y")]) == "ur10e"
    assert agreed_robot([], default="UR5e") == "ur5e"


@pytest.mark.parametrize(("configured", "reported"), [
    ("ur5e", "UR5e"), ("ur5", "UR5"), ("ur20", "UR20"), ("ur3e", "UR3e"), ("ur16e", "UR16e"),
    ("ur10", "UR10")])
def test_the_controllers_spelling_matches_its_catalog_entry(configured: str, reported: str) -> None:
    check_controller(_config(configured), _info(reported))  # no error


@pytest.mark.parametrize(("configured", "reported"), [
    ("ur10e", "UR5e"), ("ur3e", "UR5e"), ("ur5e", "UR5"), ("ur5", "UR5e"), ("ur5e", "UR15"), ("ur5e", "")])
def test_a_controller_of_another_model_is_refused_naming_both(configured: str, reported: str) -> None:
    with pytest.raises(InputError) as exc:
        check_controller(_config(configured, "127.0.0.9"), _info(reported))
    said = reported or "no model"
    assert str(exc.value) == (f"robot.type is {configured} in station.toml but the controller at 127.0.0.9 "
                              f"reports {said}")


def test_a_stand_in_robot_that_reports_no_model_is_not_checked() -> None:
    check_controller(_config("ur10e"), SimpleNamespace(rate_hz=125.0))  # test fakes have no model
    check_controller(_config("ur10e"), None)


def test_the_simulated_station_refuses_a_robot_its_truth_contradicts(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from hil.station.simulated import simulated_station

    def started(**_kw: object) -> None:
        raise AssertionError("the simulator was started")

    monkeypatch.setattr("mocks.station.start_station", started)
    truth = tmp_path / "t.json"
    write_json(truth, truth_document(random_truth("ur5e", np.random.default_rng(1), ideal=True), Noise()))
    with pytest.raises(InputError) as exc, simulated_station("ur10e", str(truth)):
        pass
    assert str(exc.value) == f"--robot is ur10e but the truth {truth} is for ur5e"


def test_a_simulated_cb3_controller_reports_its_own_model(tmp_path: Path) -> None:
    """Read through the real driver: a CB3 UR5 says "UR5" (no "e"), which is ur5 and not ur5e."""
    from hil.station.devices import open_devices
    from mocks.station import start_station

    sim = start_station(robot="ur5", speed=20.0, seed=3)
    try:
        config = _config("ur5", sim.address).with_overrides(
            tracker__url=sim.info["services"][0]["tracker_url"])
        devices = open_devices(config)
        try:
            info = devices.robot.info
        finally:
            devices.close()
    finally:
        sim.stop()
    assert info is not None and info.model == "UR5" and info.series == "cb3"
    check_controller(config, info)
    with pytest.raises(InputError) as exc:
        check_controller(config.with_overrides(robot__type="ur5e"), info)
    assert str(exc.value) == (f"robot.type is ur5e in station.toml but the controller at {sim.address} "
                              "reports UR5")
