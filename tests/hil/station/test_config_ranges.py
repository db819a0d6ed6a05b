"""Every number of a station configuration has a physical range, checked when the file is read.

Issue 19: temperature -300 °C, humidity 500 %, joint_samples 1e9, settle_time 1e12, calibration_poses
1e8, seed -1, an SMR offset of 10 m, robot.speed 1e9 (exit 70) and robot.address "not an address"
(exit 3, at connect) were accepted, and an empty file created the database before the missing
tracker.url was reported. Each must be one line naming the file, the key and the allowed range, exit 2,
with no database created and nothing connected.
"""

from __future__ import annotations

import tomllib
from pathlib import Path
from typing import Any

import pytest

from hil.cli import main
from hil.errors import InputError
from hil.station.config import EXAMPLE, SCHEMA, load_config, parse_config

#: A complete, valid configuration (loopback addresses only: nothing here may reach a network).
BASE: dict[str, dict[str, Any]] = {
    **tomllib.loads(EXAMPLE.read_text()),
    "robot": {**tomllib.loads(EXAMPLE.read_text())["robot"], "address": "127.0.0.77"},
}

#: (key, absurd value, what the message must say): the issue's values first, then every other number.
BAD: list[tuple[str, Any, str]] = [
    ("tracker.temperature", -300.0, "[-20, 50] °C"),
    ("tracker.humidity", 500.0, "[0, 100] %"),
    ("robot.joint_samples", 1_000_000_000, "[1, 1000]"),
    ("robot.settle_time", 1e12, "[0, 60] s"),
    ("campaign.calibration_poses", 100_000_000, "[1, 1000]"),
    ("campaign.seed", -1, "[0, 4294967295]"),
    ("smr.offset", [10.0, 0.0, 0.0], "its length (smr offset) must be in [0, 0.5] m"),
    ("robot.speed", 1e9, "(0, 3.14] rad/s"),
    ("robot.address", "not an address", "an IP address or a host name"),
    ("robot.address", "127.0.0.256", "an IP address or a host name"),
    ("robot.address", "", "an IP address or a host name"),
    ("robot.address", "-cell-.local", "an IP address or a host name"),
    ("station.name", "", "1 to 64 printable characters"),
    ("robot.speed", 0, "(0, 3.14] rad/s"),
    ("robot.acceleration", 1e9, "(0, 40] rad/s²"),
    ("robot.settle_time", -1, "[0, 60] s"),
    ("robot.joint_samples", 0, "[1, 1000]"),
    ("tracker.baudrate", 10**12, "[300, 921600] baud"),
    ("tracker.baudrate", 0, "[300, 921600] baud"),
    ("tracker.timeout", 1e12, "(0, 300] s"),
    ("tracker.position", [1e6, 0.0, 0.3],
     "its length (tracker distance from the base) must be in [0, 21.75] m"),
    ("tracker.temperature", 1000.0, "[-20, 50] °C"),
    ("tracker.pressure", 1e6, "[500, 1100] hPa"),
    ("tracker.pressure", 0, "[500, 1100] hPa"),
    ("tracker.humidity", -1.0, "[0, 100] %"),
    ("tracker.measure_time", 1e12, "(0, 60] s"),
    ("tracker.warmup", 1e12, "[0, 7200] s"),
    ("keep_in.max", [1e308, 1e308, 1e308], "[-5, 5] m"),
    ("keep_in.min", [-1e4, -1.0, 0.0], "[-5, 5] m"),
    ("campaign.validation_poses", 100_000_000, "[1, 1000]"),
    ("campaign.bootstrap_poses", 100_000_000, "[4, 8]"),
    ("campaign.samples", 1_000_000_000, "[1, 100]"),
    ("campaign.stability", 10.0, "(0, 0.001] m"),
    ("campaign.acceptance", 0.1, "(0, 0.01] m"),
    ("campaign.candidates", 1_000_000_000, "[1, 200000]"),
    ("timeouts.connect", 1e12, "(0, 600] s"),
    ("timeouts.move", 1e12, "(0, 3600] s"),
    ("timeouts.measure", 1e12, "(0, 600] s"),
    ("timeouts.suspend", 1e12, "(0, 28800] s"),
    ("timeouts.relock", 1e12, "(0, 3600] s"),
]


def _toml(value: Any) -> str:
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value)


def config_text(**changes: Any) -> str:
    """BASE as TOML with `changes` (``{"robot.speed": 1e9}``) applied."""
    doc = {section: dict(keys) for section, keys in BASE.items()}
    for dotted, value in changes.items():
        section, key = dotted.split(".")
        doc[section][key] = value
    return "".join(f"[{section}]\n" + "".join(f"{k} = {_toml(v)}\n" for k, v in keys.items())
                   for section, keys in doc.items())


@pytest.fixture
def no_hardware(monkeypatch: pytest.MonkeyPatch) -> None:
    """Opening the station's devices fails the test: bad input must be refused before connecting."""
    import hil.station.devices

    def tripwire(config: object) -> None:
        raise AssertionError("connected to the station before refusing the configuration")

    monkeypatch.setattr(hil.station.devices, "open_devices", tripwire)
    monkeypatch.setattr(hil.station.devices, "ask_controller", tripwire)  # asking it connects too


@pytest.mark.parametrize(("key", "value", "span"), BAD, ids=[f"{k}={v}" for k, v, _ in BAD])
def test_absurd_value_is_one_line_exit_2_naming_file_key_and_range(
        key: str, value: Any, span: str, tmp_path: Path, capsys: pytest.CaptureFixture[str],
        no_hardware: None) -> None:
    config, db = tmp_path / "station.toml", tmp_path / "k.db"
    config.write_text(config_text(**{key: value}))
    assert main(["calibrate", "--config", str(config), "--db", str(db)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert f"{config}: {key}: " in err and span in err, err
    assert not db.exists(), "the database was created before the configuration was refused"


def test_empty_config_names_tracker_url_and_creates_no_database(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], no_hardware: None) -> None:
    config, db = tmp_path / "empty.toml", tmp_path / "k.db"
    config.write_text("")
    assert main(["calibrate", "--config", str(config), "--db", str(db)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and f"{config}: tracker.url" in err, err
    assert not db.exists()


def test_tui_refuses_a_config_without_tracker_url_before_the_app(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    import hil.tui.app

    monkeypatch.setattr(hil.tui.app, "create_app", lambda *a: pytest.fail("the app started"))
    config, db = tmp_path / "empty.toml", tmp_path / "tui.db"
    config.write_text("[robot]\naddress = \"127.0.0.77\"\n")
    assert main(["tui", "--config", str(config), "--db", str(db)]) == 2
    assert "tracker.url" in capsys.readouterr().err and not db.exists()


#: Values at the edges of their ranges, and plausible ones near them: accepted (the ranges are
#: physical limits, not a whitelist of the example's values).
GOOD: list[tuple[str, Any]] = [
    ("robot.speed", 3.14), ("robot.acceleration", 40.0), ("robot.settle_time", 0.0),
    ("robot.joint_samples", 1), ("robot.joint_samples", 1000),
    ("robot.address", "192.168.1.10"), ("robot.address", "ur-cell-3.plant.example"),
    ("robot.address", "fe80::1"), ("robot.address", "localhost"),
    ("tracker.baudrate", 9600), ("tracker.temperature", -15.0), ("tracker.temperature", 45.0),
    ("tracker.pressure", 540.0), ("tracker.humidity", 0.0), ("tracker.humidity", 100.0),
    ("tracker.position", [-3.0, 0.0, 0.3]), ("tracker.position", [15.0, 10.0, 2.0]),
    ("smr.offset", [0.0, 0.1, 0.3]), ("keep_in.min", [-5.0, -5.0, -1.0]),
    ("campaign.seed", 0), ("campaign.seed", 2**32 - 1), ("campaign.calibration_poses", 1000),
    ("campaign.bootstrap_poses", 4), ("campaign.bootstrap_poses", 8), ("campaign.acceptance", 0.01),
    ("campaign.candidates", 200_000), ("timeouts.suspend", 8 * 3600.0), ("tracker.warmup", 3600.0),
]


@pytest.mark.parametrize(("key", "value"), GOOD, ids=[f"{k}={v}" for k, v in GOOD])
def test_plausible_values_at_the_edges_are_accepted(key: str, value: Any, tmp_path: Path) -> None:
    path = tmp_path / "station.toml"
    path.write_text(config_text(**{key: value}))
    got = load_config(path).get(key)
    assert got == (tuple(value) if isinstance(value, list) else value)


def test_every_number_of_the_example_has_a_range() -> None:
    """Each numeric key (and the address, the name) of station.example.toml is checked; the example's
    own values pass."""
    example = tomllib.loads(EXAMPLE.read_text())
    for section, keys in SCHEMA.items():
        for name, key in keys.items():
            if key.kind.rstrip("?") in ("int", "float", "vec3") or name in ("address", "name"):
                assert key.check is not None, f"{section}.{name} has no range check"
    for section, keys in example.items():
        for name in keys:
            assert name in SCHEMA[section], f"{section}.{name} of the example is not declared"
    parse_config(example, "example")


def test_overrides_are_range_checked_too() -> None:
    """What the command line overrides (--poses, --candidates ...) meets the same ranges."""
    with pytest.raises(InputError, match=r"campaign.candidates: must be in \[1, 200000\]"):
        parse_config(BASE, "cfg").with_overrides(campaign__candidates=10**9)


def test_a_payload_mass_without_its_centre_of_mass_is_refused_naming_the_key() -> None:
    """As ``--payload 6`` alone is: the mass would be put at the flange, a moment arm of zero."""
    data = {**BASE, "robot": {**BASE["robot"], "payload": {"mass": 6.0}}}
    with pytest.raises(InputError, match=r"st\.toml: robot\.payload: .*com = \[x, y, z\]"):
        parse_config(data, "st.toml")
    data["robot"]["payload"] = {"mass": 6.0, "com": [0.0, 0.0, 0.05]}
    assert parse_config(data, "st.toml").payload.mass == 6.0
    data["robot"]["payload"] = {"mass": 0.0}
    assert parse_config(data, "st.toml").payload.mass == 0.0
