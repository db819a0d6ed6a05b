"""Station configuration (TOML): what the campaign needs to know about one cell.

Every key is declared once below with its type, default and check, so the error for a wrong value
names the key (``station.toml: robot.speed: must be > 0, got -1``) and an unknown key is refused
rather than silently ignored (a typo in ``acceptance`` must not pass a bad robot). A commented
example lives in ``hil/station/station.example.toml``.
"""

from __future__ import annotations

import math
import os
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from hil.arm.catalog import get_robot
from hil.errors import InputError
from hil.files.inputs import read_input_text

EXAMPLE = Path(__file__).with_name("station.example.toml")
PROTOCOLS = ("geocom", "emscon")


@dataclass(frozen=True)
class Key:
    """One declared configuration key."""

    kind: str  # "str", "float", "int", "bool", "vec3", "str?", "vec3?"
    default: Any
    check: Callable[[Any], str | None] | None = None  # returns an error text or None
    help: str = ""


def _positive(v: Any) -> str | None:
    return None if v > 0 else f"must be > 0, got {v}"


def _non_negative(v: Any) -> str | None:
    return None if v >= 0 else f"must be >= 0, got {v}"


def _angle(v: Any) -> str | None:
    return None if 0 < v < 90 else f"must be between 0 and 90 degrees, got {v}"


def _robot(v: Any) -> str | None:
    try:
        get_robot(v)
    except InputError as exc:
        return str(exc)
    return None


def _index(v: Any) -> str | None:
    return None if v in ("O1", "O2", "O3", "O4", "O5") else f"must be one of O1..O5, got {v!r}"


def _protocol(v: Any) -> str | None:
    return None if v in PROTOCOLS else f"must be one of {', '.join(PROTOCOLS)}, got {v!r}"


def _parity(v: Any) -> str | None:
    return None if v in ("N", "E", "O", "M", "S") else f"must be one of N, E, O, M, S, got {v!r}"


SCHEMA: dict[str, dict[str, Key]] = {
    "station": {
        "name": Key("str", "station", help="a name for reports and the history"),
    },
    "robot": {
        "type": Key("str", "ur5e", _robot),
        "address": Key("str", "127.0.0.1"),
        "speed": Key("float", 0.5, _positive, "joint speed of moves (rad/s)"),
        "acceleration": Key("float", 1.0, _positive, "joint acceleration of moves (rad/s²)"),
        "settle_time": Key("float", 0.3, _non_negative, "wait after the arm is steady (s)"),
        "joint_samples": Key("int", 10, _positive, "joint readings averaged per pose"),
    },
    "tracker": {
        "protocol": Key("str", "geocom", _protocol,
                        "geocom (GeoCOM on a serial line) or emscon (Leica emScon TPI over TCP)"),
        "url": Key("str", "", help="geocom: serial device or socket://, rfc2217://, spy:// URL; "
                                   "emscon: tcp://host:700"),
        "baudrate": Key("int", 115200, _positive),
        "parity": Key("str", "N", _parity),
        "timeout": Key("float", 3.0, _positive, "reply timeout (s)"),
        "position": Key("vec3?", None, help="approximate position in the robot base frame (m)"),
        "temperature": Key("float", 20.0, help="air temperature (°C) for the atmospheric correction"),
        "pressure": Key("float", 1013.25, _positive, "air pressure (hPa)"),
        "humidity": Key("float", 50.0, _non_negative, "relative humidity (%)"),
        "reflector": Key("str", "", help="emscon: reflector name as the tracker lists it (empty: keep the "
                                         "tracker's current one)"),
        "measure_time": Key("float", 0.5, _positive, "emscon: stationary measuring time per sample (s)"),
        "bird_bath": Key("bool", False, help="emscon: after a failed search for the SMR, send the beam to "
                                             "the bird bath for an operator to catch"),
        "warmup": Key("float", 0.0, _non_negative,
                      "emscon: longest wait at connect for the laser to warm up (s); then the run waits"),
    },
    "smr": {
        "offset": Key("vec3", (0.0, 0.0, 0.045), help="SMR centre guess in the flange frame (m)"),
        "acceptance_angle": Key("float", 30.0, _angle, "SMR acceptance half-angle (degrees)"),
    },
    "keep_in": {
        "min": Key("vec3", (-2.0, -2.0, 0.0), help="keep-in box corner (robot base frame, m)"),
        "max": Key("vec3", (2.0, 2.0, 2.0)),
    },
    "campaign": {
        "calibration_poses": Key("int", 30, _positive),
        "validation_poses": Key("int", 20, _positive),
        "bootstrap_poses": Key("int", 6, _positive, "poses measured to locate the tracker"),
        "samples": Key("int", 5, _positive, "tracker samples per point"),
        "stability": Key("float", 50e-6, _positive, "largest per-axis spread of a point (m)"),
        "acceptance": Key("float", 0.1e-3, _positive, "validation RMS threshold (m)"),
        "index": Key("str", "O1", _index, "observability index for pose selection"),
        "candidates": Key("int", 20000, _positive, "candidate poses for the selector"),
        "seed": Key("int", 1),
    },
    "timeouts": {
        "connect": Key("float", 10.0, _positive),
        "move": Key("float", 60.0, _positive),
        "measure": Key("float", 10.0, _positive),
        "suspend": Key("float", 600.0, _positive, "longest wait for a suspender to clear (s)"),
        "relock": Key("float", 30.0, _positive, "longest wait for a lost beam before the pose is skipped"),
    },
    "store": {
        "path": Key("str", "", help="SQLite database (default: the user's data directory)"),
    },
}


@dataclass(frozen=True)
class StationConfig:
    """A validated station configuration: ``config.section["key"]`` or ``config.get("robot.speed")``."""

    values: dict[str, dict[str, Any]]
    source: str = "<defaults>"
    raw: dict[str, Any] = field(default_factory=dict, repr=False)

    def get(self, dotted: str) -> Any:
        section, key = dotted.split(".", 1)
        return self.values[section][key]

    def __getattr__(self, section: str) -> dict[str, Any]:
        try:
            return self.values[section]
        except KeyError:
            raise AttributeError(section) from None

    def with_overrides(self, **dotted: Any) -> StationConfig:
        """A copy with some keys replaced (``robot__address="127.0.0.5"``), re-validated."""
        merged = {s: dict(v) for s, v in self.values.items()}
        for name, value in dotted.items():
            section, key = name.split("__", 1)
            merged[section][key] = value
        return parse_config(merged, self.source)

    def as_dict(self) -> dict[str, dict[str, Any]]:
        return {s: {k: (list(v) if isinstance(v, tuple) else v) for k, v in d.items()}
                for s, d in self.values.items()}


def _coerce(value: Any, key: Key, where: str) -> Any:
    kind = key.kind.rstrip("?")
    if value is None and key.kind.endswith("?"):
        return None
    if kind == "str":
        if not isinstance(value, str):
            raise InputError(f"{where}: must be a string, got {value!r}")
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            raise InputError(f"{where}: must be true or false, got {value!r}")
        return value
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            raise InputError(f"{where}: must be an integer, got {value!r}")
        return value
    if kind == "float":
        if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
            raise InputError(f"{where}: must be a number, got {value!r}")
        return float(value)
    if kind == "vec3":
        ok = (isinstance(value, list | tuple) and len(value) == 3
              and all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                      for v in value))
        if not ok:
            raise InputError(f"{where}: must be a list of three numbers [x, y, z], got {value!r}")
        return tuple(float(v) for v in value)
    raise AssertionError(kind)


def parse_config(data: dict[str, Any], source: str = "<config>") -> StationConfig:
    """Validate a parsed TOML document against `SCHEMA`; InputError naming the key on any problem."""
    values: dict[str, dict[str, Any]] = {}
    for section in data:
        if section not in SCHEMA:
            raise InputError(f"{source}: unknown section [{section}] "
                             f"(known: {', '.join(SCHEMA)})")
        if not isinstance(data[section], dict):
            raise InputError(f"{source}: {section}: must be a table [{section}]")
    for section, keys in SCHEMA.items():
        given = data.get(section, {})
        for name in given:
            if name not in keys:
                raise InputError(f"{source}: unknown key {section}.{name} "
                                 f"(known in [{section}]: {', '.join(keys)})")
        out = {}
        for name, key in keys.items():
            where = f"{source}: {section}.{name}"
            value = _coerce(given[name], key, where) if name in given else key.default
            if value is not None and key.check is not None and name in given:
                problem = key.check(value)
                if problem:
                    raise InputError(f"{where}: {problem}")
            out[name] = value
        values[section] = out
    lo, hi = values["keep_in"]["min"], values["keep_in"]["max"]
    if any(a >= b for a, b in zip(lo, hi, strict=True)):
        raise InputError(f"{source}: keep_in.min must be below keep_in.max on every axis")
    return StationConfig(values, source, data)


def load_config(path: str | os.PathLike[str]) -> StationConfig:
    """Read and validate a station TOML file."""
    name = str(path)
    try:
        data = tomllib.loads(read_input_text(path, "a TOML file"))
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{name}: not valid TOML: {exc}") from None
    return parse_config(data, name)


def default_config() -> StationConfig:
    """Every key at its default (what ``--sim`` starts from)."""
    return parse_config({}, "<defaults>")
