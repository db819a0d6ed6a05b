"""Option parsing of the ``hil sim`` robot part (no process started)."""

from __future__ import annotations

import argparse

import pytest

from mocks.ur.cli_entry import add_arguments, config_from_args


def parse(*argv: str) -> argparse.Namespace:
    p = argparse.ArgumentParser()
    add_arguments(p)
    return p.parse_args(list(argv))


def test_options_build_the_config() -> None:
    cfg = config_from_args(parse("--address", "127.3.4.5", "--speed", "20", "--polyscope", "5.11.2.1",
                                 "--local-control", "--fault", "protective_stop"))
    assert cfg.address == "127.3.4.5" and cfg.speed == 20.0 and cfg.version == (5, 11, 2, 1)
    assert cfg.remote_control is False and cfg.faults == [{"name": "protective_stop"}]


@pytest.mark.parametrize(("argv", "field"), [
    (("--address", "10.0.0.2"), "--address"),
    (("--polyscope", "5.x"), "--polyscope"),
    (("--speed-slider", "1.5"), "--speed-slider"),
    (("--speed", "0"), "--speed"),
])
def test_bad_options_name_the_field(argv: tuple[str, ...], field: str) -> None:
    with pytest.raises(ValueError, match=field):
        config_from_args(parse(*argv))
