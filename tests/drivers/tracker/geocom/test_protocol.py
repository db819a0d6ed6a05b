"""GeoCOM framing, codec, CRC and the client's transaction-id / resync logic."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from drivers.tracker.errors import (
    ChecksumError,
    GarbledReply,
    ProtocolError,
    TrackerTimeout,
)
from drivers.tracker.geocom.protocol import (
    Byte,
    GeoComClient,
    Reply,
    add_crc,
    build_request,
    crc16,
    decode_byte,
    decode_double,
    decode_int,
    decode_string,
    find_reply_frame,
    format_double,
    parse_reply,
    quote_string,
    split_values,
)
from tests.drivers.tracker.geocom.scripted import ScriptedTransport


# ----------------------------------------------------------------------------------- codec
def test_crc16_is_arc_with_standard_check_value() -> None:
    assert crc16(b"123456789") == 0xBB3D
    assert crc16(b"") == 0
    assert add_crc(b"%R1Q,0,1:") == b"%R1Q,0,1:;" + b"%04X" % crc16(b"%R1Q,0,1:")


@pytest.mark.parametrize(
    ("value", "text"),
    [(1.5, "1.5"), (0.0, "0.0"), (-0.0, "0.0"), (3.0, "3.0"), (6.58e-7, "0.000000658"), (-2.25, "-2.25")],
)
def test_format_double(value: float, text: str) -> None:
    assert format_double(value) == text


def test_format_double_rejects_non_finite() -> None:
    with pytest.raises(ValueError):
        format_double(float("nan"))


def test_build_request_exact_bytes() -> None:
    assert build_request(5004) == b"%R1Q,5004:"
    assert build_request(2108, [100, 1], 7) == b"%R1Q,2108,7:100,1"
    assert build_request(9029, [0.05, 0.1, False], 3) == b"%R1Q,9029,3:0.05,0.1,0"
    assert build_request(1, ['a"b%c\\~', Byte(0x2F)], 2) == b'%R1Q,1,2:"a\\"b\\%c\\\\\\~",\'2F\''


def test_string_round_trip_with_non_printables() -> None:
    text = 'tab\there "q" 100% back\\slash ~ \x9a'
    quoted = quote_string(text)
    assert "\t" not in quoted and "\\x09" in quoted and "\\x9A" in quoted
    assert decode_string(quoted) == text


@pytest.mark.parametrize("bad", ['"abc', 'abc"', '"a"b"', '"\\x4"', '"dangling\\"'])
def test_decode_string_rejects_malformed(bad: str) -> None:
    with pytest.raises(ValueError):
        decode_string(bad)


def test_number_decoders() -> None:
    assert decode_int("0x1F") == 31 and decode_int("-12") == -12
    assert decode_double("1.25") == 1.25 and decode_double("-3e-4") == -3e-4
    assert decode_byte("'2f'") == 0x2F
    for bad in ("nan", "inf", "1.2.3", "", "0x", "1,2"):
        with pytest.raises(ValueError):
            decode_double(bad)


def test_split_values_respects_strings() -> None:
    assert split_values('1,"a,b",2.5') == ("1", '"a,b"', "2.5")
    assert split_values('"x\\"y,z"') == ('"x\\"y,z"',)
    assert split_values("") == ()
    with pytest.raises(ValueError):
        split_values('"open,1')


def test_parse_reply_forms() -> None:
    assert parse_reply(b"%R1P,0,0:0") == Reply(0, 0, 0, ())
    assert parse_reply(b"%R1P,0:0,1") == Reply(0, None, 0, ("1",))
    assert parse_reply(b"%R1P,0,7:1285,1.5,1.2,0.0") == Reply(0, 7, 1285, ("1.5", "1.2", "0.0"))
    assert parse_reply(b"%R1P,0,0:0,1996,'07','19'").values == ("1996", "'07'", "'19'")


@pytest.mark.parametrize(
    "frame", [b"", b"%R1P", b"%R1P,0,0", b"%R1P,a,0:0", b"%R1P,0,0:0,\"open", b"%R1P,0,0:0,1\x00", b"\xff"]
)
def test_parse_reply_rejects_garbage(frame: bytes) -> None:
    with pytest.raises(GarbledReply):
        parse_reply(frame)


def test_crc_checked_when_enabled() -> None:
    good = add_crc(b"%R1P,0,3:0,1.5")
    assert parse_reply(good, crc=True).values == ("1.5",)
    with pytest.raises(ChecksumError):
        parse_reply(b"%R1P,0,3:0,1.5", crc=True)
    flipped = good.replace(b"1.5", b"1.6")
    with pytest.raises(ChecksumError):
        parse_reply(flipped, crc=True)


def test_find_reply_frame_drops_stale_prefix() -> None:
    assert find_reply_frame(b"R1P,0,3:0,1.2") is None
    assert find_reply_frame(b"%R1P,0,3:0,1.2%R1P,0,4:0,9.9") == b"%R1P,0,4:0,9.9"
    assert find_reply_frame(b"noise%R1P,0,4:0") == b"%R1P,0,4:0"


# ---------------------------------------------------------------------------------- client
def test_first_request_clears_instrument_buffer_and_trids_increment() -> None:
    t = ScriptedTransport(
        [
            (b"\n%R1Q,5003,1:\r\n", [b"%R1P,0,1:0,960001"]),
            (b"%R1Q,0,2:\r\n", [b"%R1P,0,2:0"]),
        ]
    )
    client = GeoComClient(t, timeout=0.1)
    assert client.call(5003).values == ("960001",)
    assert client.call(0).rc == 0
    assert t.done() and t.discards == 1


def test_stale_and_junk_lines_are_skipped() -> None:
    t = ScriptedTransport(
        [(b"\n%R1Q,2108,1:100,1\r\n", [b"34,5.6", b"%R1P,0,9:0,9.0,9.0,9.0", b"%R1P,0,1:0,1.0,2.0,3.0"])]
    )
    reply = GeoComClient(t, timeout=0.1).call(2108, [100, 1])
    assert reply.values == ("1.0", "2.0", "3.0")


def test_only_stale_replies_time_out_and_next_request_resyncs() -> None:
    t = ScriptedTransport(
        [
            (b"\n%R1Q,2108,1:100,1\r\n", [b"%R1P,0,2:0,9.0,9.0,9.0"]),
            (b"\n%R1Q,2108,2:100,1\r\n", [b"%R1P,0,2:0,1.0,2.0,3.0"]),
        ]
    )
    client = GeoComClient(t, timeout=0.1)
    with pytest.raises(TrackerTimeout):
        client.call(2108, [100, 1])
    assert client.call(2108, [100, 1]).values == ("1.0", "2.0", "3.0")
    assert t.discards == 2


def test_reply_without_trid_does_not_match_numbered_request() -> None:
    t = ScriptedTransport([(b"\n%R1Q,0,1:\r\n", [b"%R1P,0:0"])])
    with pytest.raises(TrackerTimeout):
        GeoComClient(t, timeout=0.1).call(0)


def test_communication_errors_are_typed() -> None:
    t = ScriptedTransport(
        [
            (b"\n%R1Q,0,1:\r\n", [b"%R1P,3081,1:0"]),
            (b"%R1Q,0,2:\r\n", [b"%R1P,3101,2:0"]),
            (b"\n%R1Q,0,3:\r\n", [b"%R1P,0,3:0,\x01"]),
        ]
    )
    client = GeoComClient(t, timeout=0.1)
    with pytest.raises(ProtocolError) as info:
        client.call(0)
    assert info.value.rc_com == 3081
    with pytest.raises(ChecksumError):
        client.call(0)
    with pytest.raises(GarbledReply):
        client.call(0)


def test_crc_client_signs_requests_and_checks_replies() -> None:
    req = add_crc(b"%R1Q,5003,1:")
    t = ScriptedTransport([(b"\n" + req + b"\r\n", [add_crc(b"%R1P,0,1:0,42")])])
    assert GeoComClient(t, timeout=0.1, crc=True).call(5003).values == ("42",)


def test_trid_wraps_to_one_never_zero() -> None:
    client = GeoComClient(ScriptedTransport([]), timeout=0.1)
    client._trid = 32767
    assert client.next_trid() == 1


# ------------------------------------------------------------------------------------ fuzz
@given(st.binary(max_size=200))
def test_fuzz_parse_reply_only_raises_typed_errors(data: bytes) -> None:
    for crc in (False, True):
        try:
            reply = parse_reply(data, crc=crc)
        except (GarbledReply, ChecksumError):
            continue
        assert isinstance(reply.rc, int) and all(isinstance(v, str) for v in reply.values)


_value = st.one_of(
    st.integers(-(2**31), 2**31 - 1).map(str),
    st.floats(-1e6, 1e6, allow_nan=False).map(lambda x: format_double(x, 9)),
    st.text(st.characters(min_codepoint=1, max_codepoint=255), max_size=20).map(quote_string),
)


@given(
    st.integers(0, 65535), st.one_of(st.none(), st.integers(0, 32767)), st.integers(0, 65535),
    st.lists(_value, max_size=8), st.booleans(),
)
def test_fuzz_valid_replies_round_trip(
    rc_com: int, trid: int | None, rc: int, values: list[str], crc: bool
) -> None:
    head = f"%R1P,{rc_com}" + ("" if trid is None else f",{trid}") + f":{rc}"
    frame = (head + "".join("," + v for v in values)).encode("ascii")
    if crc:
        frame = add_crc(frame)
    assert parse_reply(frame, crc=crc) == Reply(rc_com, trid, rc, tuple(values))


@given(st.lists(st.binary(max_size=40).filter(lambda b: b"\r\n" not in b and b"%R1P," not in b), max_size=5))
def test_fuzz_junk_before_reply_never_changes_the_answer(junk: list[bytes]) -> None:
    t = ScriptedTransport([(b"\n%R1Q,2108,1:100,1\r\n", [*junk, b"%R1P,0,1:0,1.0,2.0,3.0"])])
    assert GeoComClient(t, timeout=0.1).call(2108, [100, 1]).values == ("1.0", "2.0", "3.0")
