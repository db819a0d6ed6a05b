"""The simulated instrument as a plain GeoCOM client sees it: literal request → literal reply."""

from __future__ import annotations

import re
import socket

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from drivers.tracker.geocom.protocol import add_crc
from drivers.tracker.geometry import polar_to_cartesian
from mocks.geocom import NOISELESS, GeoComInstrument, GeoComSimulator, InstrumentConfig, StaticTarget

TRUE = np.array([1.0, 2.0, 0.5])


@pytest.fixture
def inst() -> GeoComInstrument:
    # true air = the instrument's reference air, so distances carry no ppm error
    config = InstrumentConfig(noise=NOISELESS, true_temperature_c=12.0)
    return GeoComInstrument(StaticTarget(TRUE.copy()), config)


@pytest.mark.parametrize(
    ("request_line", "reply"),
    [
        (b"%R1Q,5004:", b'%R1P,0,0:0,"AT960-SIM"'),
        (b"%R1Q,5003,12:", b"%R1P,0,12:0,960001"),
        (b"\n%R1Q,110,3:", b"%R1P,0,3:0,1,50,0"),  # leading LF = buffer clear
        (b"%R1Q,0:", b"%R1P,0,0:0"),
        (b"%R1Q,108,4:", b"%R1P,0,4:0,15"),
        (b"%R1Q,6021,5:", b"%R1P,0,5:0,1"),
        (b"%R1Q,4242,6:", b"%R1P,0,6:3081"),  # unknown RPC: GRC_COM_PROC_UNAVAIL
        (b"%R1Q,2108,7:abc,1", b"%R1P,0,7:2"),  # bad parameter: GRC_IVPARAM
        (b"%R1Q,2108,8:", b"%R1P,0,8:2"),  # missing parameters
        (b"%R1Q,x:", b"%R1P,0,0:3080"),  # undecodable header
        (b"%R1Q,2108,9:100,1", b"%R1P,0,9:1285,"),  # no distance program yet: angles only (prefix)
    ],
)
def test_literal_exchanges(inst: GeoComInstrument, request_line: bytes, reply: bytes) -> None:
    got = inst.handle_line(request_line)
    assert got is not None and got.startswith(reply)
    if not reply.endswith(b","):
        assert got == reply


def test_line_noise_gets_no_answer(inst: GeoComInstrument) -> None:
    assert inst.handle_line(b"hello") is None
    assert inst.handle_line(b"") is None


def test_crc_request_gets_crc_reply_and_bad_crc_is_refused(inst: GeoComInstrument) -> None:
    assert inst.handle_line(add_crc(b"%R1Q,5003,2:")) == add_crc(b"%R1P,0,2:0,960001")
    assert inst.handle_line(b"%R1Q,5003,2:;0000") == add_crc(b"%R1P,3101,2:0")


def test_measurement_follows_program_and_convention(inst: GeoComInstrument) -> None:
    assert inst.handle_line(b"%R1Q,2008,1:8,1") == b"%R1P,0,1:0"
    reply = inst.handle_line(b"%R1Q,2108,2:100,1")
    assert reply is not None
    hz, v, d = (float(x) for x in reply.decode().split(":")[1].split(",")[1:4])
    np.testing.assert_allclose(polar_to_cartesian(hz, v, d), TRUE, atol=1e-12)
    coord = inst.handle_line(b"%R1Q,2082,3:100,1")
    assert coord is not None
    e, n, h = (float(x) for x in coord.decode().split(":")[1].split(",")[1:4])
    np.testing.assert_allclose([e, n, h], TRUE, atol=1e-12)


def test_precision_setting_changes_reply_digits(inst: GeoComInstrument) -> None:
    inst.handle_line(b"%R1Q,2008,1:8,1")
    assert inst.handle_line(b"%R1Q,107,2:4") == b"%R1P,0,2:0"
    reply = inst.handle_line(b"%R1Q,2108,3:100,1")
    assert reply is not None
    assert all(len(x.split(".")[1]) <= 4 for x in reply.decode().split(":")[1].split(",")[1:4])


def test_lost_lock_needs_lock_in(inst: GeoComInstrument) -> None:
    inst.handle_line(b"%R1Q,2008,1:8,1")
    inst.faults.lose_target(checks=1)
    assert inst.handle_line(b"%R1Q,2108,2:100,1", ).startswith(b"%R1P,0,2:1292,")  # type: ignore[union-attr]
    assert inst.handle_line(b"%R1Q,2108,3:100,1").startswith(b"%R1P,0,3:1292,")  # type: ignore[union-attr]
    assert inst.handle_line(b"%R1Q,9013,4:") == b"%R1P,0,4:0"
    assert inst.handle_line(b"%R1Q,2108,5:100,1").startswith(b"%R1P,0,5:0,")  # type: ignore[union-attr]


def test_invisible_target_cannot_be_locked() -> None:
    target = StaticTarget(TRUE.copy(), visible=False, reason="arm blocks the beam")
    inst = GeoComInstrument(target)
    assert inst.handle_line(b"%R1Q,9013,1:") == b"%R1P,0,1:8710"
    assert inst.handle_line(b"%R1Q,9029,2:0.1,0.1,0") == b"%R1P,0,2:8710"
    assert inst.handle_line(b"%R1Q,6021,3:") == b"%R1P,0,3:0,0"


@given(st.binary(max_size=120))
def test_fuzz_instrument_never_crashes(data: bytes) -> None:
    inst = GeoComInstrument(StaticTarget(TRUE.copy()))
    reply = inst.handle_line(data)
    assert reply is None or re.match(rb"^%R1P,[0-9]+,[0-9]+:[0-9]+", reply)


def test_independent_raw_client_over_tcp() -> None:
    """A few lines of plain-socket code, no project driver: what "an independent client" means."""
    sim = GeoComSimulator(StaticTarget(TRUE.copy())).start()
    with socket.create_connection(("127.0.0.1", sim.port), 2) as s:
        s.settimeout(2)
        f = s.makefile("rwb")
        f.write(b"%R1Q,5004:\r\n%R1Q,9013:\r\n%R1Q,2008:1,1\r\n%R1Q,2108:500,1\r\n")
        f.flush()
        lines = [f.readline() for _ in range(4)]
    sim.stop()
    assert lines[0] == b'%R1P,0,0:0,"AT960-SIM"\r\n'
    assert lines[1] == b"%R1P,0,0:0\r\n" and lines[2] == b"%R1P,0,0:0\r\n"
    _hz, _v, d = (float(x) for x in lines[3].decode().strip().split(":")[1].split(",")[1:4])
    assert abs(d - np.linalg.norm(TRUE)) < 1e-4


def test_simulator_refuses_non_loopback() -> None:
    from mocks.geocom import SimulatorConfig

    with pytest.raises(ValueError, match="loopback"):
        GeoComSimulator(StaticTarget(), SimulatorConfig(address="0.0.0.0")).start()


def test_any_loopback_address_and_clean_stop() -> None:
    from mocks.geocom import SimulatorConfig

    sim = GeoComSimulator(StaticTarget(), SimulatorConfig(address="127.0.0.2", serve_pty=False)).start()
    assert sim.url.startswith("socket://127.0.0.2:") and sim.pty_path is None
    sim.stop()
    with pytest.raises(OSError):
        socket.create_connection(("127.0.0.2", sim.port), 0.5).close()
