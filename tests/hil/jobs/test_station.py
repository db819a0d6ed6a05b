"""Taking a station (`hil.jobs.station.take_station`), the one sequence every job that drives an arm
goes through: the store opened first, the arm's address lock, the controller's word on the robot type
(asked before the devices are opened), the devices, a new store created only after that, one robot
identity — and all of it released on every way out. On in-process fakes:
`hil.station.devices.ask_controller` and `open_devices` are monkeypatched, nothing connects.

And where a job's station comes from (`StationSource.of`): the options checked before anything starts.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

import hil.jobs.station as job_station
from drivers.robot.errors import RobotUnreachable
from drivers.robot.model import ControllerInfo, RobotIdentity
from hil.errors import InputError
from hil.jobs.station import SimulatedSpec, StationSource, station_setup, take_station
from hil.station.config import StationConfig, default_config
from hil.station.robot_type import Claim, ControllerMismatch
from hil.store import LeaseRefused, Store, StoreError, address_lock

SERIAL = "20235500001"


def _info(model: str = "UR5e", serial: str = SERIAL, software: str = "5.15.0") -> ControllerInfo:
    return ControllerInfo(model, serial, software, (5, 15, 0, 0), "e", 500.0)


class FakeDevices:
    """Devices whose robot reports `model`; counts its closes and notes whether the arm's address lock
    was still held when it was closed (the station is released in reverse order)."""

    def __init__(self, address: str, model: str = "UR5e", **info: str) -> None:
        self.address = address
        self.robot = SimpleNamespace(info=_info(model, **info))
        self.tracker = SimpleNamespace(identity=None)
        self.closes = 0
        self.lock_held_at_close: bool | None = None

    def close(self) -> None:
        self.closes += 1
        try:
            with address_lock(self.address, what="probe"):
                self.lock_held_at_close = False
        except LeaseRefused:
            self.lock_held_at_close = True


class Opener:
    """Stands in for `hil.station.devices.open_devices` (`__call__`) and `ask_controller` (`ask`): records
    each call; raises `error` (opening) or `ask_error` (asking) if set, else opens new `FakeDevices` of
    `model` / answers that controller. `ask_lock_held` notes, per question, whether the arm's address
    lock was held when the controller was asked (it must be: the lock comes before connecting)."""

    def __init__(self, address: str) -> None:
        self.address = address
        self.model = "UR5e"
        self.info: dict[str, str] = {}
        self.error: BaseException | None = None
        self.ask_error: BaseException | None = None
        self.calls: list[StationConfig] = []
        self.asked: list[StationConfig] = []
        self.ask_lock_held: list[bool] = []
        self.opened: list[FakeDevices] = []

    def ask(self, config: StationConfig) -> ControllerInfo:
        self.asked.append(config)
        try:
            assert_lock_free(self.address)
            self.ask_lock_held.append(False)
        except LeaseRefused:
            self.ask_lock_held.append(True)
        if self.ask_error is not None:
            raise self.ask_error
        return _info(self.model, **self.info)

    def __call__(self, config: StationConfig) -> FakeDevices:
        self.calls.append(config)
        if self.error is not None:
            raise self.error
        devices = FakeDevices(self.address, self.model, **self.info)
        self.opened.append(devices)
        return devices


@pytest.fixture
def opener(monkeypatch: pytest.MonkeyPatch, address: str) -> Opener:
    op = Opener(address)
    monkeypatch.setattr("hil.station.devices.open_devices", op)
    monkeypatch.setattr("hil.station.devices.ask_controller", op.ask)
    return op


def _config(address: str, robot: str = "ur5e", **overrides: Any) -> StationConfig:
    return default_config().with_overrides(robot__type=robot, robot__address=address, **overrides)


def assert_lock_free(address: str) -> None:
    """The arm's address lock can be taken again right now (LeaseRefused otherwise)."""
    with address_lock(address, what="after"):
        pass


def assert_closed(store: Store) -> None:
    with pytest.raises(StoreError, match="closed"):
        store.campaigns()


# --- released on every way out ------------------------------------------------------------------------

def _ends(way_out: type[BaseException] | None) -> Any:
    """What the body's way out looks like from outside: nothing, or the exception it raised."""
    return contextlib.nullcontext() if way_out is None else pytest.raises(way_out, match="in the body")


@pytest.mark.parametrize("way_out", [None, RuntimeError, KeyboardInterrupt])
def test_every_way_out_of_the_body_releases_the_devices_then_the_lock(
        opener: Opener, address: str, way_out: type[BaseException] | None) -> None:
    config = _config(address)
    with _ends(way_out), take_station(config, what="test") as taken:
        assert taken.devices is opener.opened[0]
        with pytest.raises(LeaseRefused):  # held while the job runs
            assert_lock_free(address)
        if way_out is not None:
            raise way_out("in the body")
    (devices,) = opener.opened
    assert devices.closes == 1
    assert devices.lock_held_at_close is True  # reverse order: the devices before the lock
    assert_lock_free(address)
    with take_station(config, what="again"):  # and the station can be taken again at once
        pass
    assert len(opener.calls) == 2 and opener.opened[1].closes == 1


def test_a_controller_of_another_robot_is_refused_before_any_device_is_opened(
        opener: Opener, address: str) -> None:
    """Asked under the lock, refused on its answer: the devices (the driver's client process, its control
    script, the tracker: seconds to open and close) are never opened (issue 31: refused within 2 s)."""
    opener.model = "UR10e"
    config = _config(address)
    with pytest.raises(ControllerMismatch) as exc, take_station(config, what="test"):
        raise AssertionError("the body ran on a controller of another robot")
    assert str(exc.value) == f"robot.type is ur5e but the controller at {address} reports UR10e"
    assert opener.asked == [config] and opener.ask_lock_held == [True]
    assert opener.calls == []  # nothing opened, so nothing to close
    assert_lock_free(address)


def test_a_claim_the_controller_contradicts_is_refused_naming_every_source(
        opener: Opener, address: str) -> None:
    with pytest.raises(ControllerMismatch) as exc, take_station(
            _config(address), what="test", claims=[Claim("ur10e", "--robot is ur10e")]):
        raise AssertionError("the body ran")
    assert str(exc.value) == (f"robot.type is ur5e and the controller at {address} reports UR5e "
                              "but --robot is ur10e")
    assert opener.calls == []
    assert_lock_free(address)


def test_the_opened_controller_is_checked_again_and_closed_when_it_disagrees(
        opener: Opener, address: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """The controller the devices connected to is what the run records: its word is checked too (a
    controller that answered the question as a UR5e and connected as a UR10e is refused, devices
    closed)."""
    monkeypatch.setattr("hil.station.devices.ask_controller", lambda config: _info("UR5e"))
    opener.model = "UR10e"
    with pytest.raises(ControllerMismatch), take_station(_config(address), what="test"):
        raise AssertionError("the body ran")
    assert opener.opened[0].closes == 1 and opener.opened[0].lock_held_at_close is True
    assert_lock_free(address)


def test_a_controller_that_does_not_answer_the_question_raises_the_drivers_error(
        opener: Opener, address: str, tmp_path: Path) -> None:
    location = tmp_path / "new.db"
    opener.ask_error = error = RobotUnreachable(f"no RTDE answer from {address}:30004")
    with pytest.raises(RobotUnreachable) as exc, take_station(_config(address), what="test", store=location):
        raise AssertionError("the body ran without a controller")
    assert exc.value is error  # typed, as the driver raised it: the caller's station fault
    assert opener.calls == [] and not location.exists()
    assert_lock_free(address)


def test_a_device_that_cannot_be_reached_raises_the_drivers_error_and_nothing_stays_taken(
        opener: Opener, address: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    location = tmp_path / "hil.db"
    Store.open(location).close()  # an existing store: opened before the devices
    opened: list[Store | None] = []
    original = job_station.open_existing_store

    def spy(where: Any, config: StationConfig) -> Store | None:
        opened.append(original(where, config))
        return opened[-1]

    monkeypatch.setattr(job_station, "open_existing_store", spy)
    opener.error = error = RobotUnreachable(f"nothing answers at {address}:30004")
    with pytest.raises(RobotUnreachable) as exc, take_station(_config(address), what="test", store=location):
        raise AssertionError("the body ran without devices")
    assert exc.value is error  # as the driver raised it, typed
    (store,) = opened
    assert store is not None
    assert_closed(store)
    assert_lock_free(address)


# --- the lock before the devices, the store before the lock ----------------------------------------------

def test_a_held_lock_is_refused_before_any_device_is_opened_or_store_created(
        opener: Opener, address: str, tmp_path: Path) -> None:
    location = tmp_path / "new.db"
    with address_lock(address, what="hil calibrate"), pytest.raises(LeaseRefused) as exc, \
            take_station(_config(address), what="test", store=location):
        raise AssertionError("the body ran on a held arm")
    assert f"the robot at {address} is in use by hil calibrate (pid " in str(exc.value)
    assert opener.asked == [] and opener.calls == []  # not even asked: the lock comes before connecting
    assert not location.exists()


def test_a_damaged_store_is_refused_before_the_lock_and_the_devices(
        opener: Opener, address: str, tmp_path: Path) -> None:
    location = tmp_path / "bad.db"
    location.write_bytes(b"not a database " * 100)
    with address_lock(address, what="other"), pytest.raises(InputError) as exc, \
            take_station(_config(address), what="test", store=location):
        raise AssertionError("the body ran")
    assert not isinstance(exc.value, LeaseRefused)  # the store was looked at first
    assert str(location) in str(exc.value) and "not a hil database" in str(exc.value)
    assert opener.asked == [] and opener.calls == []


def test_a_new_store_is_created_only_once_the_controller_agreed_and_closed_on_exit(
        opener: Opener, address: str, tmp_path: Path) -> None:
    location = tmp_path / "new.db"
    opener.model = "UR10e"
    with pytest.raises(ControllerMismatch), take_station(_config(address), what="test", store=location):
        raise AssertionError("the body ran")
    assert list(tmp_path.iterdir()) == []  # a refused station leaves no file behind
    assert opener.calls == []

    opener.model = "UR5e"
    with take_station(_config(address), what="test", store=location) as taken:
        store = taken.store
        assert isinstance(store, Store) and store.path == location
        assert location.exists()
        assert store.campaigns() == []  # open
    assert_closed(store)


def test_an_open_store_is_handed_through_and_left_open(opener: Opener, address: str, tmp_path: Path) -> None:
    store = Store.open(tmp_path / "own.db")
    try:
        with take_station(_config(address), what="test", store=store) as taken:
            assert taken.store is store
        assert store.campaigns() == []  # still open: its owner closes it
    finally:
        store.close()


def test_the_robot_identity_is_the_configured_type_as_the_controller_reports_itself(
        opener: Opener, address: str) -> None:
    opener.model, opener.info = "UR10e", {"serial": "20205500042", "software": "5.12.3.1234"}
    config = _config(address, "ur10e")
    with take_station(config, what="test") as taken:
        assert taken.robot == RobotIdentity("ur10e", "20205500042", "UR10e", "5.12.3.1234")
        assert taken.config is config and opener.asked == [config] and opener.calls == [config]
        assert taken.devices is opener.opened[0]
        assert taken.store is None  # none asked for


# --- StationSource.of ---------------------------------------------------------------------------------------

def _station_toml(address: str = "127.0.0.2", robot: str = "ur5e") -> StationConfig:
    config = _config(address, robot, tracker__url="socket://127.0.0.2:2000")
    return dataclasses.replace(config, source="station.toml")  # as `load_config` names it


def _refused(**kwargs: Any) -> str:
    with pytest.raises(InputError) as exc:
        StationSource.of(**kwargs)
    text = str(exc.value)
    assert "\n" not in text  # one line
    return text


@pytest.mark.parametrize(("option", "named"), [
    ({"truth": "truth.json"}, "--truth"), ({"speed": 2.0}, "--speed"),
    ({"tracker_protocol": "emscon"}, "--tracker-protocol"), ({"seed": 3}, "--seed"),
    ({"seed": 1}, "--seed"),  # the default value, given: still the simulator's option, not the config's
    ({"seed": 3, "speed": 2.0}, "--speed, --seed"),
])
def test_the_simulators_options_with_a_configuration_are_refused_naming_them(option: dict[str, Any],
                                                                             named: str) -> None:
    text = _refused(config=_station_toml(), sim=False, **option)
    assert text.startswith(f"{named}: go{'' if ',' in named else 'es'} with --sim, not --config"), text


@pytest.mark.parametrize(("speed", "says"), [(0.0, "must be in (0, 1000], got 0"),
                                             (-2.0, "must be in (0, 1000], got -2"),
                                             (math.nan, "expected a finite number in (0, 1000], got nan"),
                                             (1e-320, "a denormal number")])
def test_a_speed_that_is_not_positive_is_refused(speed: float, says: str) -> None:
    text = _refused(config=None, sim=True, speed=speed)
    assert text.startswith("--speed: ") and says in text, text


@pytest.mark.parametrize("config", [None, "station"])
def test_an_unknown_robot_is_refused_naming_the_option(config: str | None) -> None:
    text = _refused(config=_station_toml() if config else None, sim=config is None, robot="ur99")
    assert text.startswith("--robot: ") and "ur99" in text


def test_a_robot_the_configuration_contradicts_is_refused_naming_both() -> None:
    assert (_refused(config=_station_toml(robot="ur5e"), sim=False, robot="ur10e")
            == "robot.type is ur5e in station.toml but --robot is ur10e")


def test_a_configuration_no_station_can_run_on_and_no_station_at_all_are_refused() -> None:
    assert "tracker.url" in _refused(config=dataclasses.replace(_config("127.0.0.2"), source="s.toml"),
                                     sim=False)
    assert _refused(config=None, sim=False) == "--config or --sim: which station?"


def test_the_sources_the_options_name() -> None:
    toml = _station_toml()
    source = StationSource.of(config=toml, sim=False, robot="UR5e",
                              overrides={"campaign__calibration_poses": 40})
    assert source.config is toml and source.sim is None and source.speed == 1.0
    with station_setup(source) as setup:  # the overrides applied, the identity the configuration's
        assert setup.config.campaign["calibration_poses"] == 40 and toml.campaign["calibration_poses"] != 40
        assert setup.identity == setup.config.as_dict() and setup.truth is None
    sim = StationSource.of(config=None, sim=True, speed=4.0, seed=7, robot="ur10e")
    assert sim.sim == SimulatedSpec("ur10e", None, 4.0, 7, "geocom") and sim.speed == 4.0


def test_a_simulated_stations_campaigns_go_to_their_own_store_and_it_is_said(tmp_path, monkeypatch) -> None:
    """--sim without --db: the simulated stations' store, whatever $HIL_DB says (the plant's), said
    once; --db is obeyed for both; a real station's store is $HIL_DB's, silently."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    monkeypatch.setenv("HIL_DB", str(tmp_path / "plant.db"))
    said: list[tuple[str, str]] = []

    def say(text: str, severity: str = "information") -> None:
        said.append((text, severity))

    sim = StationSource.of(config=None, sim=True)
    config = default_config().with_overrides(tracker__url="socket://127.0.0.3:1")
    real = StationSource.of(config=config, sim=False)
    sim_db = tmp_path / "data" / "hil" / "sim.db"
    assert job_station.store_location(None, sim, None, say) == sim_db
    assert len(said) == 1 and str(sim_db) in said[0][0] and "$HIL_DB" in said[0][0]
    assert job_station.store_location(str(tmp_path / "mine.db"), sim, None, say) == tmp_path / "mine.db"
    assert job_station.store_location(None, real, config, say) == tmp_path / "plant.db"
    assert len(said) == 1


def test_ideal_is_a_choice_of_the_random_simulated_arm_only(tmp_path) -> None:
    """--ideal/--no-ideal choose the random arm: with a truth file (whose blocks rule) or a
    configuration they are bad input, named."""
    from hil.jobs.station import StationSource

    assert StationSource.of(config=None, sim=True, ideal=False).sim.ideal is False
    assert StationSource.of(config=None, sim=True).sim.ideal is None  # the simulator's default
    with pytest.raises(InputError, match="--no-ideal chooses a random arm.*truth"):
        StationSource.of(config=None, sim=True, truth=str(tmp_path / "t.json"), ideal=False)
    with pytest.raises(InputError, match="--ideal goes with --sim, not --config"):
        StationSource.of(config=str(tmp_path / "station.toml"), sim=False, ideal=True)
