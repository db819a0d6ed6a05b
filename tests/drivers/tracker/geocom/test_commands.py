"""Each typed command sends the exact GeoCOM request and maps return codes to typed errors."""

from __future__ import annotations

import pytest

from drivers.tracker.errors import GarbledReply, GeoComError, TargetLost
from drivers.tracker.geocom.commands import (
    AtmosphericCorrection,
    DistanceMode,
    LockStatus,
    MeasureProgram,
    TrackerCommands,
)
from drivers.tracker.geocom.protocol import GeoComClient
from tests.drivers.tracker.geocom.scripted import ScriptedTransport


def commands(*exchange: tuple[str, str]) -> tuple[TrackerCommands, ScriptedTransport]:
    """Commands whose transport expects requests with trids 1, 2, ... (first one LF-prefixed)."""
    script = []
    for i, (req, rep) in enumerate(exchange):
        prefix = "\n" if i == 0 else ""
        script.append(((prefix + req + "\r\n").encode(), [rep.encode()]))
    t = ScriptedTransport(script)
    return TrackerCommands(GeoComClient(t, timeout=0.1)), t


def test_identity_exchange() -> None:
    cmd, t = commands(
        ("%R1Q,5004,1:", '%R1P,0,1:0,"AT960-SIM"'),
        ("%R1Q,5003,2:", "%R1P,0,2:0,960001"),
        ("%R1Q,5034,3:", "%R1P,0,3:0,1,4,2"),
        ("%R1Q,110,4:", "%R1P,0,4:0,1,50,0"),
        ("%R1Q,0,5:", "%R1P,0,5:0"),
    )
    assert cmd.get_instrument_name() == "AT960-SIM"
    assert cmd.get_instrument_number() == 960001
    assert cmd.get_firmware_version() == (1, 4, 2)
    assert cmd.get_geocom_version() == (1, 50, 0)
    cmd.null_proc()
    assert t.done()


def test_measurement_exchange() -> None:
    cmd, t = commands(
        ("%R1Q,2008,1:8,1", "%R1P,0,1:0"),
        ("%R1Q,2108,2:100,1", "%R1P,0,2:0,0.5,1.5,2.25"),
        ("%R1Q,2082,3:100,1", "%R1P,0,3:0,1.0,2.0,0.5,123,1.0,2.0,0.5,123"),
        ("%R1Q,17017,4:2", "%R1P,0,4:1284,0.5,1.5,2.25,2"),
    )
    cmd.do_measure(MeasureProgram.RTRK_DIST)
    r = cmd.get_simple_measurement(100)
    assert (r.hz, r.v, r.distance, r.warning) == (0.5, 1.5, 2.25, False)
    c = cmd.get_coordinate(100)
    assert (c.east, c.north, c.height) == (1.0, 2.0, 0.5)
    flagged = cmd.measure_distance_angle(DistanceMode.DEF_DIST)
    assert flagged.warning and flagged.distance == 2.25
    assert t.done()


def test_atmosphere_and_automation_exchange() -> None:
    cmd, t = commands(
        ("%R1Q,2028,1:0.000000658,950.0,35.0,30.5", "%R1P,0,1:0"),
        ("%R1Q,2029,2:", "%R1P,0,2:0,0.000000658,950.0,35.0,30.5"),
        ("%R1Q,9013,3:", "%R1P,0,3:0"),
        ("%R1Q,9029,4:0.05,0.05,0", "%R1P,0,4:0"),
        ("%R1Q,9037,5:0.01,0.02", "%R1P,0,5:0"),
        ("%R1Q,6021,6:", "%R1P,0,6:0,1"),
    )
    atm = AtmosphericCorrection(6.58e-7, 950.0, 35.0, 30.5)
    cmd.set_atmospheric_correction(atm)
    assert cmd.get_atmospheric_correction() == atm
    cmd.lock_in()
    cmd.search(0.05, 0.05)
    cmd.fine_adjust(0.01, 0.02)
    assert cmd.read_lock_status() is LockStatus.LOCKED_IN
    assert t.done()


@pytest.mark.parametrize("rc", [1285, 1292, 1294, 8710, 8725])
def test_lost_target_codes_raise_target_lost(rc: int) -> None:
    cmd, _ = commands(("%R1Q,2108,1:100,1", f"%R1P,0,1:{rc},0.5,1.5,0.0"))
    with pytest.raises(TargetLost) as info:
        cmd.get_simple_measurement(100)
    assert info.value.rc == rc


def test_other_codes_raise_geocom_error_not_values() -> None:
    cmd, _ = commands(("%R1Q,2108,1:100,1", "%R1P,0,1:1293,0.5,1.5,2.0"), ("%R1Q,9013,2:", "%R1P,0,2:3081"))
    with pytest.raises(GeoComError) as info:
        cmd.get_simple_measurement(100)
    assert info.value.rc == 1293 and not isinstance(info.value, TargetLost)
    with pytest.raises(GeoComError) as info:
        cmd.lock_in()  # an instrument without ATR answers "procedure unavailable"
    assert info.value.rc == 3081


def test_short_or_malformed_values_are_garbled() -> None:
    cmd, _ = commands(("%R1Q,2108,1:100,1", "%R1P,0,1:0,0.5,1.5"))
    with pytest.raises(GarbledReply):
        cmd.get_simple_measurement(100)
    cmd, _ = commands(("%R1Q,6021,1:", "%R1P,0,1:0,7"))
    with pytest.raises(GarbledReply):
        cmd.read_lock_status()
