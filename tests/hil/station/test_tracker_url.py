"""tracker.url is checked with the rest of the configuration, before anything connects (issue 31,
class 4): a scheme the protocol does not speak, a missing host or port, a port out of range."""

from __future__ import annotations

import pytest

from hil.errors import InputError
from hil.station.config import parse_config, tracker_url_problem


@pytest.mark.parametrize(("url", "protocol"), [
    ("/dev/ttyUSB0", "geocom"), ("socket://127.0.0.1:5000", "geocom"), ("rfc2217://moxa:4001", "geocom"),
    ("spy:///dev/ttyUSB0?file=log.txt", "geocom"), ("spy://socket://tracker:5000", "geocom"),
    ("socket://[::1]:4000", "geocom"), ("tcp://at960:700", "emscon"), ("tcp://at960", "emscon"),
    ("socket://10.0.0.5", "emscon"), ("", "geocom"),
])
def test_urls_the_drivers_take_pass(url, protocol) -> None:
    assert tracker_url_problem(url, protocol) is None


@pytest.mark.parametrize(("url", "protocol", "says"), [
    ("http://tracker:80", "geocom", "http:// is not a URL a geocom tracker speaks"),
    ("spy://", "geocom", "spy:// wraps a port"),
    ("socket://tracker:99999", "geocom", "port '99999' .* is not a TCP port \\(1 to 65535\\)"),
    ("socket://tracker:0", "geocom", "is not a TCP port"),
    ("socket://tracker:x", "geocom", "is not a TCP port"),
    ("socket://tracker", "geocom", "names no port"),
    ("rfc2217://", "geocom", "names no host"),
    ("rfc2217://:4001", "geocom", "names no host"),
    ("spy://socket://tracker:70000", "geocom", "is not a TCP port"),
    ("socket://not a host:5000", "geocom", "must be an IP address or a host name"),
    ("/dev/ttyUSB0", "emscon", "an emScon tracker is reached by tcp://host"),
    ("rfc2217://tracker:4001", "emscon", "rfc2217:// is not a URL a emscon tracker speaks"),
])
def test_urls_no_driver_takes_are_refused(url, protocol, says) -> None:
    assert tracker_url_problem(url, protocol) is not None
    with pytest.raises(InputError, match=f"^station.toml: tracker.url: .*{says}"):
        parse_config({"tracker": {"protocol": protocol, "url": url}}, "station.toml")


@pytest.mark.parametrize("url", ["postgresql:/db", "dbhost:5432/hil", "postgres:hil"])
def test_a_store_url_that_is_not_a_url_is_said_so(url) -> None:
    """Taken for a file path it was "no such database"; it is a URL with a typo (issue 31)."""
    with pytest.raises(InputError, match=f"^s.toml: store.url: '{url}' is not a URL"):
        parse_config({"store": {"url": url}}, "s.toml")
    for path in ("hil.db", "C:/stores/hil.db", "data/a:b.db"):  # paths still pass
        assert parse_config({"store": {"url": path}}, "s.toml").store["url"] == path
