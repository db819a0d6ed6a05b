"""The ``[warmup]`` and ``[drift]`` sections of a station configuration: defaults, ranges naming the key,
unknown keys refused, and the example's values."""

from __future__ import annotations

import tomllib

import pytest

from hil.errors import InputError
from hil.station.config import EXAMPLE, default_config, parse_config


def test_the_defaults_warm_up_and_watch_the_drift():
    config = default_config()
    assert config.warmup == {"enabled": True, "interval": 120.0, "limit": 10e-6, "max_time": 3600.0}
    assert config.drift == {"every": 10, "limit": 30e-6, "settle": 2.0, "samples": 20}
    example = tomllib.loads(EXAMPLE.read_text())
    assert parse_config(example).warmup == config.warmup and parse_config(example).drift == config.drift


@pytest.mark.parametrize(("section", "values", "message"), [
    ("warmup", {"enabled": "yes"}, "warmup.enabled: must be true or false"),
    ("warmup", {"interval": 0.5}, "warmup.interval: must be in [10, 3600] s, got 0.5"),
    ("warmup", {"limit": 0.01}, "warmup.limit: must be in (0, 0.001] m, got 0.01"),
    ("warmup", {"limit": 0}, "warmup.limit: must be in (0, 0.001] m"),
    ("warmup", {"max_time": 1e6}, "warmup.max_time: must be in [10, 14400] s"),
    ("warmup", {"max_time": 60.0}, "warmup.max_time: 60 s is shorter than one warmup.interval (120 s)"),
    ("warmup", {"limt": 1e-5},
     "unknown key warmup.limt (known in [warmup]: enabled, interval, limit, max_time)"),
    ("drift", {"every": -1}, "drift.every: must be in [0, 1000], got -1"),
    ("drift", {"every": 2.5}, "drift.every: must be an integer"),
    ("drift", {"limit": 30}, "drift.limit: must be in (0, 0.001] m, got 30"),
    ("drift", {"settle": -1.0}, "drift.settle: must be in [0, 60] s, got -1"),
    ("drift", {"samples": 0}, "drift.samples: must be in [1, 100], got 0"),
    ("drift", {"watch": True}, "unknown key drift.watch (known in [drift]: every, limit, settle, samples)"),
])
def test_a_wrong_value_is_refused_naming_the_key(section, values, message):
    with pytest.raises(InputError) as exc:
        parse_config({section: values}, "station.toml")
    assert str(exc.value).startswith(f"station.toml: {message}")


def test_off_is_a_valid_setting():
    config = parse_config({"warmup": {"enabled": False}, "drift": {"every": 0}})
    assert not config.warmup["enabled"] and config.drift["every"] == 0
