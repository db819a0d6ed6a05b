"""emScon TPI packets against the struct layouts of Leica's ``ES_C_API_Def.h`` (TPI/SDK 3.6).

The expected bytes are assembled here field by field from the header's structs (``#pragma pack(4)``;
``long``, ``int``, enums and ``ES_BOOL`` are 4-byte little-endian integers, doubles 8 bytes, strings 32
UTF-16 units; ``lPacketSize`` counts the whole packet, header included). Nothing below reuses the module's
own tables or ``struct.Struct`` objects to build an expectation, so a layout slip in the module shows.
"""

from __future__ import annotations

import contextlib
import itertools
import struct
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from drivers.tracker.emscon import packets
from drivers.tracker.emscon.packets import (
    Answer,
    CommandRequest,
    ErrorResponse,
    MeasValue,
    MultiMeasResult,
    PacketError,
    PacketReader,
    ReflectorPosResult,
    SingleMeasResult,
    StatusChange,
    decode_reply,
    decode_request,
    encode_answer,
    encode_command,
    encode_error,
    encode_multi,
    encode_reflector_pos,
    encode_single,
    encode_status_change,
)

FUZZ = settings(max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow])

# ``enum ES_DataType`` (numbers as in the header)
ES_DT_Command = 0
ES_DT_Error = 1
ES_DT_SingleMeasResult = 2
ES_DT_MultiMeasResult = 3
ES_DT_NivelResult = 6
ES_DT_ReflectorPosResult = 7
ES_DT_SystemStatusChange = 8
ES_DT_SingleMeasResult2 = 9
ES_DT_MultiMeasResult2 = 10
ES_DT_ProbePosResult = 11

# ``enum ES_Command`` (the ones used below)
ES_C_ExitApplication = 0
ES_C_GetSystemStatus = 1
ES_C_GetTrackerStatus = 2
ES_C_SetUnits = 5
ES_C_GetUnits = 6
ES_C_Initialize = 7
ES_C_SwitchLaser = 11
ES_C_SetEnvironmentParams = 20
ES_C_GetEnvironmentParams = 21
ES_C_SetMeasurementMode = 24
ES_C_GetMeasurementMode = 25
ES_C_SetCoordinateSystemType = 26
ES_C_GetCoordinateSystemType = 27
ES_C_SetStationaryModeParams = 28
ES_C_GetStationaryModeParams = 29
ES_C_SetContinuousTimeModeParams = 30
ES_C_GetContinuousTimeModeParams = 31
ES_C_SetReflector = 40
ES_C_GetReflector = 41
ES_C_GetReflectors = 42
ES_C_SetSearchParams = 43
ES_C_GetSearchParams = 44
ES_C_StartMeasurement = 49
ES_C_StopMeasurement = 52
ES_C_FindReflector = 63
ES_C_SetStatisticMode = 80
ES_C_GetMeasurementStatusInfo = 122
ES_C_ClearCommandQueue = 130
ES_C_GetTrackerInfo = 132
ES_C_GetSystemSoftwareVersion = 142
UNKNOWN_COMMAND = 777  # not an ES_Command hil tables

ES_RS_AllOK = 0
ES_RS_NoTrackerConnected = 38


# --- the header's types, by hand --------------------------------------------------------------------
def i32(*values: int) -> bytes:
    """``long`` / ``int`` / enum / ``ES_BOOL``: 4 bytes little-endian each."""
    return b"".join(struct.pack("<i", v) for v in values)


def f64(*values: float) -> bytes:
    """``double``: 8 bytes little-endian each."""
    return b"".join(struct.pack("<d", v) for v in values)


def utf16_units(text: str) -> list[int]:
    """UTF-16 code units of ``text`` (surrogate pairs for characters beyond the BMP)."""
    units: list[int] = []
    for char in text:
        code = ord(char)
        if code < 0x10000:
            units.append(code)
        else:
            code -= 0x10000
            units += [0xD800 + (code >> 10), 0xDC00 + (code & 0x3FF)]
    return units


def name32(units: list[int]) -> bytes:
    """``unsigned short c...[32]``: the given units, NUL padded to 32."""
    assert len(units) <= 32
    return b"".join(struct.pack("<H", u) for u in units + [0] * (32 - len(units)))


def packet(data_type: int, body: bytes) -> bytes:
    """``PacketHeaderT {long lPacketSize; enum ES_DataType type;}`` then the body."""
    return i32(8 + len(body), data_type) + body


def command_ct(command: int, params: bytes = b"") -> bytes:
    """``BasicCommandCT`` (header, ``ES_Command``) then the command's parameter struct."""
    return packet(ES_DT_Command, i32(command) + params)


def command_rt(command: int, status: int, results: bytes = b"") -> bytes:
    """``BasicCommandRT`` (header, ``ES_Command``, ``ES_ResultStatus``) then the results."""
    return packet(ES_DT_Command, i32(command, status) + results)


# --- enum numbers ------------------------------------------------------------------------------------
def test_enum_numbers_are_the_headers() -> None:
    assert {t.name: int(t) for t in packets.DataType} == {
        "COMMAND": 0, "ERROR": 1, "SINGLE_MEAS_RESULT": 2, "MULTI_MEAS_RESULT": 3, "NIVEL_RESULT": 6,
        "REFLECTOR_POS_RESULT": 7, "SYSTEM_STATUS_CHANGE": 8, "SINGLE_MEAS_RESULT2": 9}
    C = packets.Command
    assert [int(c) for c in (
        C.EXIT_APPLICATION, C.GET_SYSTEM_STATUS, C.GET_TRACKER_STATUS, C.SET_UNITS, C.GET_UNITS,
        C.INITIALIZE, C.SWITCH_LASER, C.SET_ENVIRONMENT_PARAMS, C.GET_ENVIRONMENT_PARAMS,
        C.SET_MEASUREMENT_MODE, C.GET_MEASUREMENT_MODE, C.SET_COORDINATE_SYSTEM_TYPE,
        C.GET_COORDINATE_SYSTEM_TYPE, C.SET_STATIONARY_MODE_PARAMS, C.GET_STATIONARY_MODE_PARAMS,
        C.SET_CONTINUOUS_TIME_MODE_PARAMS, C.GET_CONTINUOUS_TIME_MODE_PARAMS, C.SET_REFLECTOR,
        C.GET_REFLECTOR, C.GET_REFLECTORS, C.SET_SEARCH_PARAMS, C.GET_SEARCH_PARAMS, C.START_MEASUREMENT,
        C.STOP_MEASUREMENT, C.FIND_REFLECTOR, C.SET_STATISTIC_MODE, C.GET_MEASUREMENT_STATUS_INFO,
        C.CLEAR_COMMAND_QUEUE, C.GET_TRACKER_INFO, C.GET_SYSTEM_SOFTWARE_VERSION)] == [
        0, 1, 2, 5, 6, 7, 11, 20, 21, 24, 25, 26, 27, 28, 29, 30, 31, 40, 41, 42, 43, 44, 49, 52, 63, 80,
        122, 130, 132, 142]
    R = packets.ResultStatus
    assert (R.AllOK, R.NoTPFound, R.UsageConflict, R.NoTrackerConnected, R.MeteoDataOutOfRange,
            R.InvalidInputData) == (0, 26, 35, 38, 57, 98)
    # ES_API_ERROR_OFFSET + n with ES_API_ERROR_OFFSET = 10000
    assert (R.MeasurementStatusNotReady, R.ADMStartUpBusy, R.NoStationaryResult,
            R.CommunicationWithSensorFailed) == (10004, 10005, 10009, 10015)
    assert packets.status_name(38) == "ES_RS_NoTrackerConnected"
    assert packets.status_name(12345) == "ES_RS_12345"
    assert [int(s) for s in packets.SystemStatusChange] == [2, 6, 7, 17, 25, 26, 27, 998, 999]
    assert [int(s) for s in packets.MeasurementStatus] == [0, 1, 2, 3, 4]
    assert (packets.MeasurementStatusInfo.REFLECTOR_FOUND, packets.MeasurementStatusInfo.IN_FACE1,
            packets.MeasurementStatusInfo.INITIALIZED) == (2048, 4096, 65536)
    assert (packets.CoordinateSystemType.RHR, packets.CoordinateSystemType.SCW) == (0, 6)
    assert [int(t) for t in packets.TargetType] == list(range(10))


# --- commands (client -> server) ------------------------------------------------------------------
# (struct, ES_Command, parameters, the parameter struct by hand, sizeof the ...CT struct)
COMMANDS: list[tuple[str, int, tuple[Any, ...], bytes, int]] = [
    ("GetSystemStatusCT", ES_C_GetSystemStatus, (), b"", 12),
    ("InitializeCT", ES_C_Initialize, (), b"", 12),
    ("StartMeasurementCT", ES_C_StartMeasurement, (), b"", 12),
    ("GetTrackerInfoCT", ES_C_GetTrackerInfo, (), b"", 12),
    # SystemUnitsDataT: lenUnitType, angUnitType, tempUnitType, pressUnitType, humUnitType
    ("SetUnitsCT", ES_C_SetUnits, (5, 2, 1, 6, 0), i32(5, 2, 1, 6, 0), 32),
    # EnvironmentDataT: dTemperature, dPressure, dHumidity
    ("SetEnvironmentParamsCT", ES_C_SetEnvironmentParams, (21.5, 1013.25, 45.0),
     f64(21.5, 1013.25, 45.0), 36),
    # StationaryModeDataT: lMeasTime, bUseADM
    ("SetStationaryModeParamsCT", ES_C_SetStationaryModeParams, (2500, 1), i32(2500, 1), 20),
    # ContinuousTimeModeDataT: lTimeSeparation, lNumberOfPoints, bUseRegion, regionType
    ("SetContinuousTimeModeParamsCT", ES_C_SetContinuousTimeModeParams, (250, 40, 0, 1),
     i32(250, 40, 0, 1), 28),
    ("SetReflectorCT", ES_C_SetReflector, (8,), i32(8), 16),  # iInternalReflectorId
    ("FindReflectorCT", ES_C_FindReflector, (3.75,), f64(3.75), 20),  # dAproxDistance
    # SearchParamsDataT: dSearchRadius, lTimeOut (12 bytes under pack(4))
    ("SetSearchParamsCT", ES_C_SetSearchParams, (0.125, 7000), f64(0.125) + i32(7000), 24),
    ("SwitchLaserCT", ES_C_SwitchLaser, (1,), i32(1), 16),  # bIsOn
    ("SetMeasurementModeCT", ES_C_SetMeasurementMode, (1,), i32(1), 16),
    ("SetCoordinateSystemTypeCT", ES_C_SetCoordinateSystemType, (6,), i32(6), 16),
    # stationaryMeasurements, continuousMeasurements
    ("SetStatisticModeCT", ES_C_SetStatisticMode, (0, 1), i32(0, 1), 20),
    ("ClearCommandQueueCT", ES_C_ClearCommandQueue, (1,), i32(1), 16),  # clearQueueType
]


@pytest.mark.parametrize(("name", "command", "params", "param_bytes", "size"), COMMANDS,
                         ids=[c[0] for c in COMMANDS])
def test_command_bytes_match_header(name: str, command: int, params: tuple[Any, ...], param_bytes: bytes,
                                    size: int) -> None:
    expected = command_ct(command, param_bytes)
    assert len(expected) == size
    assert expected[:4] == i32(size)
    assert encode_command(command, *params) == expected
    assert encode_command(packets.Command(command), *params) == expected
    request = decode_request(expected)
    assert request == CommandRequest(command, params)
    assert [type(v) for v in request.params] == [type(v) for v in params]


def test_unknown_command_still_frames() -> None:
    assert encode_command(UNKNOWN_COMMAND) == i32(12, ES_DT_Command, UNKNOWN_COMMAND)
    assert decode_request(i32(12, ES_DT_Command, UNKNOWN_COMMAND)) == CommandRequest(UNKNOWN_COMMAND)
    raw = bytes(range(1, 11))
    assert decode_request(command_ct(UNKNOWN_COMMAND, raw)) == CommandRequest(UNKNOWN_COMMAND, (raw,))
    with pytest.raises(PacketError):
        encode_command(UNKNOWN_COMMAND, 1)


def test_command_parameter_count_is_checked() -> None:
    with pytest.raises(PacketError):
        encode_command(ES_C_SetUnits, 0, 0, 0, 0)
    with pytest.raises(PacketError):
        encode_command(ES_C_GetSystemStatus, 1)


@pytest.mark.parametrize("bad", [
    b"",
    i32(8),  # half a header
    i32(8, ES_DT_Command),  # no command
    i32(10, ES_DT_Command) + b"\x01\x00",  # half a command
    command_ct(ES_C_SetUnits, i32(0, 0, 0, 0)),  # SystemUnitsDataT one field short
    command_ct(ES_C_SetUnits, i32(0, 0, 0, 0, 0, 0)),  # one field long
    command_ct(ES_C_GetSystemStatus, i32(0)),  # a parameterless command with a parameter
    command_ct(ES_C_FindReflector, f64(1.0)[:7]),
    i32(16, ES_DT_Command, ES_C_SetReflector, 1)[:-1],  # lPacketSize disagrees with the length
    i32(15, ES_DT_Command, ES_C_SetReflector, 1),
    i32(17, ES_DT_Command, ES_C_SetReflector, 1),
    packet(ES_DT_Error, i32(ES_C_SetReflector, 0)),  # a client sends type 0 only
])
def test_request_refusals(bad: bytes) -> None:
    with pytest.raises(PacketError):
        decode_request(bad)


# --- answers (server -> client) -------------------------------------------------------------------
TRACKER_INFO = (
    13,  # trackerType
    "AT960-MR #750123",  # cTrackerName[32]
    750123,  # lSerialNumber
    42,  # lCompensationIdNumber
    1, 0, 2,  # bHasADM, bHasOverviewCamera, bHasNivel (ES_BOOL is an int; distinct so a swap shows)
    0.045, 160.0, 0.8,  # dNivelMountOffset, dMaxDistance, dMinDistance
    1000, 3,  # iMaxDataRate, iNumberOfFaces
    360.0, 145.0,  # dHzAngleRange, dVtAngleRange
    4, 7, 12,  # accuracyModel, iMajLCPFirmwareVersion, iMinLCPFirmwareVersion
)
TRACKER_INFO_BYTES = (i32(13) + name32(utf16_units("AT960-MR #750123")) + i32(750123, 42, 1, 0, 2)
                      + f64(0.045, 160.0, 0.8) + i32(1000, 3) + f64(360.0, 145.0) + i32(4, 7, 12))

# (struct, ES_Command, results, the result fields by hand, sizeof the ...RT struct)
ANSWERS: list[tuple[str, int, tuple[Any, ...], bytes, int]] = [
    # lastResultStatus, trackerProcessorStatus, laserStatus, admStatus,
    # ESVersionNumberT {iMajorVersionNumber, iMinorVersionNumber, iBuildNumber},
    # weatherMonitorStatus, lFlagsValue, lTrackerSerialNumber
    ("GetSystemStatusRT", ES_C_GetSystemStatus, (41, 5, 2, 1, 3, 6, 1042, 4, 16, 750123),
     i32(41, 5, 2, 1, 3, 6, 1042, 4, 16, 750123), 56),
    ("GetTrackerStatusRT", ES_C_GetTrackerStatus, (2,), i32(2), 20),
    ("GetUnitsRT", ES_C_GetUnits, (5, 2, 1, 6, 0), i32(5, 2, 1, 6, 0), 36),
    ("GetEnvironmentParamsRT", ES_C_GetEnvironmentParams, (19.75, 987.5, 61.25), f64(19.75, 987.5, 61.25),
     40),
    ("GetMeasurementModeRT", ES_C_GetMeasurementMode, (2,), i32(2), 20),
    ("GetCoordinateSystemTypeRT", ES_C_GetCoordinateSystemType, (6,), i32(6), 20),
    ("GetStationaryModeParamsRT", ES_C_GetStationaryModeParams, (1500, 1), i32(1500, 1), 24),
    ("GetContinuousTimeModeParamsRT", ES_C_GetContinuousTimeModeParams, (250, 40, 0, 1),
     i32(250, 40, 0, 1), 32),
    ("GetReflectorRT", ES_C_GetReflector, (9,), i32(9), 20),
    # iTotalReflectors, iInternalReflectorId, targetType, dSurfaceOffset, cReflectorName[32]
    ("GetReflectorsRT", ES_C_GetReflectors, (6, 2, 7, 0.0125, "RRR 1.5in"),
     i32(6, 2, 7) + f64(0.0125) + name32(utf16_units("RRR 1.5in")), 100),
    ("GetSearchParamsRT", ES_C_GetSearchParams, (0.25, 5000), f64(0.25) + i32(5000), 28),
    # lastResultStatus, lMeasurementStatusInfo
    ("GetMeasurementStatusInfoRT", ES_C_GetMeasurementStatusInfo, (3, 0x11803), i32(3, 0x11803), 24),
    ("GetSystemSoftwareVersionRT", ES_C_GetSystemSoftwareVersion, ("3.6.1042",),
     name32(utf16_units("3.6.1042")), 80),
    ("GetTrackerInfoRT", ES_C_GetTrackerInfo, TRACKER_INFO, TRACKER_INFO_BYTES, 164),
]


@pytest.mark.parametrize(("name", "command", "values", "result_bytes", "size"), ANSWERS,
                         ids=[a[0] for a in ANSWERS])
def test_answer_bytes_match_header(name: str, command: int, values: tuple[Any, ...], result_bytes: bytes,
                                   size: int) -> None:
    expected = command_rt(command, ES_RS_AllOK, result_bytes)
    assert len(expected) == size
    assert expected[:4] == i32(size)
    assert encode_answer(command, ES_RS_AllOK, *values) == expected
    answer = decode_reply(expected)
    assert answer == Answer(command, ES_RS_AllOK, values)
    assert [type(v) for v in answer.values] == [type(v) for v in values]
    assert answer.ok


@pytest.mark.parametrize("command", [ES_C_SetUnits, ES_C_SetReflector, ES_C_Initialize, ES_C_StartMeasurement,
                                     ES_C_StopMeasurement, ES_C_ExitApplication])
def test_basic_answer_is_16_bytes(command: int) -> None:
    expected = i32(16, ES_DT_Command, command, ES_RS_AllOK)
    assert encode_answer(command, ES_RS_AllOK) == expected
    assert decode_reply(expected) == Answer(command, ES_RS_AllOK)


def test_failed_answer_carries_no_results() -> None:
    expected = i32(16, ES_DT_Command, ES_C_GetTrackerInfo, ES_RS_NoTrackerConnected)
    assert encode_answer(ES_C_GetTrackerInfo, ES_RS_NoTrackerConnected) == expected
    answer = decode_reply(expected)
    assert answer == Answer(ES_C_GetTrackerInfo, ES_RS_NoTrackerConnected, ())
    assert not answer.ok
    assert packets.status_name(answer.status) == "ES_RS_NoTrackerConnected"


def test_answer_to_unknown_command_still_frames() -> None:
    assert encode_answer(UNKNOWN_COMMAND, 3) == i32(16, ES_DT_Command, UNKNOWN_COMMAND, 3)
    assert decode_reply(i32(16, ES_DT_Command, UNKNOWN_COMMAND, 3)) == Answer(UNKNOWN_COMMAND, 3)
    raw = bytes(range(20, 32))
    assert decode_reply(command_rt(UNKNOWN_COMMAND, 0, raw)) == Answer(UNKNOWN_COMMAND, 0, (raw,))


def test_answer_value_count_is_checked() -> None:
    with pytest.raises(PacketError):
        encode_answer(ES_C_GetUnits, ES_RS_AllOK, 0, 0, 0, 0)
    with pytest.raises(PacketError):
        encode_answer(ES_C_SetUnits, ES_RS_AllOK, 0)


# --- UTF-16 names ----------------------------------------------------------------------------------
NAMES = [
    ("ascii", "RRR 1.5in", utf16_units("RRR 1.5in")),
    ("latin-and-symbols", "Réflecteur Ø½ – №5 µm", [
        0x52, 0xE9, 0x66, 0x6C, 0x65, 0x63, 0x74, 0x65, 0x75, 0x72, 0x20, 0xD8, 0xBD, 0x20, 0x2013, 0x20,
        0x2116, 0x35, 0x20, 0xB5, 0x6D]),
    ("cjk", "反射器", [0x53CD, 0x5C04, 0x5668]),
    ("surrogate-pair", "Ziel 🎯", [0x5A, 0x69, 0x65, 0x6C, 0x20, 0xD83C, 0xDFAF]),
    ("exactly-31-units", "r" * 31, [0x72] * 31),
    ("empty", "", []),
]


@pytest.mark.parametrize(("text", "units"), [n[1:] for n in NAMES], ids=[n[0] for n in NAMES])
def test_names_are_utf16_nul_padded(text: str, units: list[int]) -> None:
    assert utf16_units(text) == units
    results = i32(1, 0, 1) + f64(0.0) + name32(units)
    expected = command_rt(ES_C_GetReflectors, ES_RS_AllOK, results)
    assert encode_answer(ES_C_GetReflectors, ES_RS_AllOK, 1, 0, 1, 0.0, text) == expected
    assert decode_reply(expected).values[-1] == text


@pytest.mark.parametrize("length", [32, 33, 40, 100])
def test_overlong_name_is_truncated_to_31_units_and_a_nul(length: int) -> None:
    text = "".join(chr(0x41 + i % 26) for i in range(length - 1)) + "é"
    expected = command_rt(ES_C_GetSystemSoftwareVersion, ES_RS_AllOK, name32([*utf16_units(text)[:31], 0]))
    assert expected[-2:] == b"\x00\x00"
    assert encode_answer(ES_C_GetSystemSoftwareVersion, ES_RS_AllOK, text) == expected
    assert decode_reply(expected).values == (text[:31],)


def test_truncation_does_not_split_a_surrogate_pair() -> None:
    text = "a" * 30 + "🎯"  # 32 units: the pair sits on units 30 and 31
    encoded = encode_answer(ES_C_GetSystemSoftwareVersion, ES_RS_AllOK, text)
    assert encoded == command_rt(ES_C_GetSystemSoftwareVersion, ES_RS_AllOK, name32([0x61] * 30))


def test_name_decoding_is_tolerant() -> None:
    full = name32([0x5A] * 32)  # no terminating NUL: all 32 units are the name
    assert decode_reply(command_rt(ES_C_GetSystemSoftwareVersion, 0, full)).values == ("Z" * 32,)
    after_nul = name32([0x41, 0x42, 0, 0x43, 0x44])  # whatever follows the NUL is not the name
    assert decode_reply(command_rt(ES_C_GetSystemSoftwareVersion, 0, after_nul)).values == ("AB",)
    lone = name32([0x41, 0xD800, 0x42])  # a lone surrogate from the server is replaced, not an exception
    assert decode_reply(command_rt(ES_C_GetSystemSoftwareVersion, 0, lone)).values == ("A\ufffdB",)


# --- asynchronous packets ----------------------------------------------------------------------------
def test_error_response_is_16_bytes() -> None:
    expected = i32(16, ES_DT_Error, ES_C_StartMeasurement, ES_RS_NoTrackerConnected)
    assert encode_error(ES_C_StartMeasurement, ES_RS_NoTrackerConnected) == expected
    assert decode_reply(expected) == ErrorResponse(ES_C_StartMeasurement, ES_RS_NoTrackerConnected)


def test_system_status_change_is_12_bytes() -> None:
    expected = i32(12, ES_DT_SystemStatusChange, 998)  # ES_SSC_ServerClosing
    assert encode_status_change(998) == expected
    assert encode_status_change(packets.SystemStatusChange.SERVER_CLOSING) == expected
    assert decode_reply(expected) == StatusChange(998)


def test_reflector_pos_result_is_36_bytes() -> None:
    # ReflectorPosResultT: ReturnDataT {header, status}, dVal1..3
    expected = packet(ES_DT_ReflectorPosResult, i32(0) + f64(1.5, -2.25, 0.375))
    assert len(expected) == 36
    assert encode_reflector_pos(ReflectorPosResult(0, (1.5, -2.25, 0.375))) == expected
    assert decode_reply(expected) == ReflectorPosResult(0, (1.5, -2.25, 0.375))


SINGLE = SingleMeasResult(
    status=7, mode=2, try_mode=True,
    position=(1.5, -2.25, 3.125), std=(1e-5, 2e-5, 3e-5), std_total=4e-5,
    pointing_error=(-0.5, 0.25, -0.125), apriori_std=(5e-6, 6e-6, 7e-6), apriori_std_total=8e-6,
    temperature=20.5, pressure=1013.25, humidity=45.75)
# SingleMeasResultT: ReturnDataT {header, status}, measMode, bIsTryMode, dVal1..3, dStd1..3, dStdTotal,
# dPointingError1..3, dAprioriStd1..3, dAprioriStdTotal, dTemperature, dPressure, dHumidity
SINGLE_BYTES = packet(ES_DT_SingleMeasResult, i32(7, 2, 1) + f64(
    1.5, -2.25, 3.125, 1e-5, 2e-5, 3e-5, 4e-5, -0.5, 0.25, -0.125, 5e-6, 6e-6, 7e-6, 8e-6,
    20.5, 1013.25, 45.75))


def test_single_meas_result_is_156_bytes() -> None:
    assert len(SINGLE_BYTES) == 8 + 4 + 4 + 4 + 17 * 8 == 156
    assert encode_single(SINGLE) == SINGLE_BYTES
    decoded = decode_reply(SINGLE_BYTES)
    assert decoded == SINGLE
    assert decoded.try_mode is True


def multi_bytes(status: int, mode: int, try_mode: int, env: tuple[float, float, float],
                samples: list[tuple[int, int, int, float, float, float]], count: int | None = None) -> bytes:
    """MultiMeasResultT: ReturnDataT {header, status}, lNumberOfResults, measMode, bIsTryMode,
    dTemperature, dPressure, dHumidity, then MeasValueT {status, lTime1, lTime2, dVal1..3} per sample."""
    body = i32(status, len(samples) if count is None else count, mode, try_mode) + f64(*env)
    for s_status, t1, t2, x, y, z in samples:
        body += i32(s_status, t1, t2) + f64(x, y, z)
    return packet(ES_DT_MultiMeasResult, body)


SAMPLES = [(0, 1700000000, 250000, 1.25, -0.5, 2.75), (1, 1700000001, 999999, -3.5, 4.0625, 0.125),
           (4, 1700000002, 17, 5.5, 6.25, -7.75)]


@pytest.mark.parametrize("n", [0, 1, 3])
def test_multi_meas_result_is_48_plus_36_per_sample(n: int) -> None:
    expected = multi_bytes(3, 1, 0, (18.25, 996.5, 38.0), SAMPLES[:n])
    assert len(expected) == 48 + 36 * n
    result = MultiMeasResult(3, 1, False, 18.25, 996.5, 38.0,
                             tuple(MeasValue(s[0], s[1], s[2], s[3:]) for s in SAMPLES[:n]))
    assert encode_multi(result) == expected
    assert decode_reply(expected) == result


def test_meas_value_seconds() -> None:
    assert MeasValue(0, 12, 500000, (0.0, 0.0, 0.0)).seconds == pytest.approx(12.5)


def test_multi_sample_limit() -> None:
    limit = packets.MAX_SAMPLES
    assert 48 + 36 * limit <= packets.MAX_PACKET < 48 + 36 * (limit + 1)
    many = tuple(MeasValue(0, i, i, (float(i), -float(i), 0.5)) for i in range(limit))
    result = MultiMeasResult(0, 1, False, 20.0, 1000.0, 50.0, many)
    assert decode_reply(encode_multi(result)) == result
    with pytest.raises(PacketError):
        encode_multi(MultiMeasResult(0, 1, False, 20.0, 1000.0, 50.0, (*many, many[0])))


# --- refusals -------------------------------------------------------------------------------------
def _resized(data: bytes, size: int) -> bytes:
    return i32(size) + data[4:]


REFUSED = {
    "empty": b"",
    "short-header": SINGLE_BYTES[:7],
    "size-says-one-more": _resized(SINGLE_BYTES, 157),
    "size-says-one-less": _resized(SINGLE_BYTES, 155),
    "size-says-zero": _resized(SINGLE_BYTES, 0),
    "size-negative": _resized(SINGLE_BYTES, -156),
    "single-one-byte-short": _resized(SINGLE_BYTES[:-1], 155),
    "single-one-byte-long": _resized(SINGLE_BYTES + b"\x00", 157),
    "single-one-double-short": _resized(SINGLE_BYTES[:-8], 148),
    "single-header-only": i32(8, ES_DT_SingleMeasResult),
    "multi-count-one-more": multi_bytes(0, 1, 0, (20.0, 1000.0, 50.0), SAMPLES[:2], count=3),
    "multi-count-one-less": multi_bytes(0, 1, 0, (20.0, 1000.0, 50.0), SAMPLES[:2], count=1),
    "multi-count-zero-with-samples": multi_bytes(0, 1, 0, (20.0, 1000.0, 50.0), SAMPLES[:1], count=0),
    "multi-count-negative": multi_bytes(0, 1, 0, (20.0, 1000.0, 50.0), [], count=-1),
    "multi-count-minus-one-with-sample": multi_bytes(0, 1, 0, (20.0, 1000.0, 50.0), SAMPLES[:1], count=-1),
    "multi-count-huge": multi_bytes(0, 1, 0, (20.0, 1000.0, 50.0), SAMPLES, count=2**31 - 1),
    "multi-count-beyond-a-packet": multi_bytes(0, 1, 0, (20.0, 1000.0, 50.0), SAMPLES,
                                               count=packets.MAX_SAMPLES + 1),
    "multi-half-sample": _resized(multi_bytes(0, 1, 0, (20.0, 1000.0, 50.0), SAMPLES[:1])[:-18], 66),
    "multi-head-truncated": _resized(multi_bytes(0, 1, 0, (20.0, 1000.0, 50.0), [])[:-8], 40),
    "error-12-bytes": i32(12, ES_DT_Error, ES_C_StartMeasurement),
    "error-20-bytes": i32(20, ES_DT_Error, ES_C_StartMeasurement, 0, 0),
    "status-change-8-bytes": i32(8, ES_DT_SystemStatusChange),
    "status-change-16-bytes": i32(16, ES_DT_SystemStatusChange, 998, 0),
    "reflector-pos-short": packet(ES_DT_ReflectorPosResult, i32(0) + f64(1.0, 2.0)),
    "answer-without-status": i32(12, ES_DT_Command, ES_C_GetUnits),
    "answer-results-one-short": command_rt(ES_C_GetUnits, 0, i32(0, 0, 0, 0)),
    "answer-results-one-long": command_rt(ES_C_GetUnits, 0, i32(0, 0, 0, 0, 0, 0)),
    "answer-results-for-basic-command": command_rt(ES_C_SetUnits, 0, i32(0)),
    "tracker-info-one-byte-short": command_rt(ES_C_GetTrackerInfo, 0, TRACKER_INFO_BYTES[:-1]),
    "nivel-result": packet(ES_DT_NivelResult, i32(0) + f64(0.0, 0.0, 0.0)),
    "single-meas-result-2": packet(ES_DT_SingleMeasResult2, SINGLE_BYTES[8:] + f64(0.0) * 8),
    "multi-meas-result-2": packet(ES_DT_MultiMeasResult2, SINGLE_BYTES[8:]),
    "probe-pos-result": packet(ES_DT_ProbePosResult, SINGLE_BYTES[8:]),
    "type-4": packet(4, SINGLE_BYTES[8:]),
    "type-42": packet(42, SINGLE_BYTES[8:]),
    "type-negative": packet(-2, SINGLE_BYTES[8:]),
}


@pytest.mark.parametrize("bad", list(REFUSED.values()), ids=list(REFUSED))
def test_reply_refusals(bad: bytes) -> None:
    with pytest.raises(PacketError):
        decode_reply(bad)


# --- framing -------------------------------------------------------------------------------------
def _stream_packets() -> list[bytes]:
    return [
        SINGLE_BYTES,
        multi_bytes(0, 1, 0, (20.0, 1000.0, 50.0), SAMPLES[:2]),
        command_rt(ES_C_GetReflectors, 0, i32(6, 2, 7) + f64(0.0125) + name32(utf16_units("Ziel 🎯"))),
        i32(16, ES_DT_Error, ES_C_StartMeasurement, ES_RS_NoTrackerConnected),
        i32(12, ES_DT_SystemStatusChange, 27),
        i32(16, ES_DT_Command, ES_C_SetUnits, 0),
        multi_bytes(0, 1, 0, (20.0, 1000.0, 50.0), []),
        i32(8, ES_DT_Command),  # the smallest frame (not a valid answer, but a whole packet)
    ]


def test_reader_one_cut_at_every_byte() -> None:
    parts = _stream_packets()
    stream = b"".join(parts)
    for cut in range(len(stream) + 1):
        reader = PacketReader()
        got = reader.feed(stream[:cut])
        assert reader.pending == cut - sum(len(p) for p in got)
        got += reader.feed(stream[cut:])
        assert got == parts, cut
        assert reader.pending == 0


def test_reader_two_cuts_at_every_pair_of_bytes() -> None:
    parts = _stream_packets()[3:]
    stream = b"".join(parts)
    for first in range(len(stream) + 1):
        for second in range(first, len(stream) + 1):
            reader = PacketReader()
            got = reader.feed(stream[:first]) + reader.feed(stream[first:second])
            got += reader.feed(stream[second:])
            assert got == parts, (first, second)


def test_reader_byte_by_byte_and_pending() -> None:
    parts = _stream_packets()
    stream = b"".join(parts)
    reader = PacketReader()
    got: list[bytes] = []
    ends = {sum(len(p) for p in parts[: i + 1]) for i in range(len(parts))}
    for i in range(len(stream)):
        out = reader.feed(stream[i : i + 1])
        if i + 1 in ends:
            assert len(out) == 1 and reader.pending == 0
        else:
            assert out == [] and reader.pending > 0
        got += out
    assert got == parts
    assert [type(decode_reply(p)) for p in got[:-1]] == [
        SingleMeasResult, MultiMeasResult, Answer, ErrorResponse, StatusChange, Answer, MultiMeasResult]


def test_reader_pending_counts_buffered_bytes() -> None:
    reader = PacketReader()
    assert reader.pending == 0
    assert reader.feed(b"") == []
    assert reader.feed(SINGLE_BYTES[:5]) == [] and reader.pending == 5
    assert reader.feed(SINGLE_BYTES[5:100]) == [] and reader.pending == 100
    assert reader.feed(SINGLE_BYTES[100:] + SINGLE_BYTES[:30]) == [SINGLE_BYTES]
    assert reader.pending == 30


@pytest.mark.parametrize("size", [-(2**31), -1, 0, 1, 7, packets.MAX_PACKET + 1, 2**31 - 1])
def test_reader_refuses_impossible_sizes(size: int) -> None:
    reader = PacketReader()
    assert reader.feed(i32(size, ES_DT_SingleMeasResult)[:7]) == []  # not judged before the header is whole
    with pytest.raises(PacketError):
        reader.feed(i32(size, ES_DT_SingleMeasResult)[7:])
    with pytest.raises(PacketError):  # and the stream stays refused
        reader.feed(SINGLE_BYTES)


@pytest.mark.parametrize("size", [8, 12, packets.MAX_PACKET])
def test_reader_accepts_sizes_at_the_limits(size: int) -> None:
    frame = i32(size, 99) + bytes(size - 8)
    reader = PacketReader()
    assert reader.feed(frame[:-1]) == []
    assert reader.feed(frame[-1:]) == [frame]


def test_max_packet_is_64_kib() -> None:
    assert packets.MAX_PACKET == 65536


# --- hypothesis: values --------------------------------------------------------------------------
INT32 = st.integers(-(2**31), 2**31 - 1)
FINITE = st.floats(allow_nan=False, allow_infinity=False)
# names that survive the 32-unit field whole: no NUL, at most 31 UTF-16 units
NAME = st.text(st.characters(exclude_characters="\x00", exclude_categories=("Cs",)), max_size=31).filter(
    lambda s: len(utf16_units(s)) <= 31)
TRIPLE = st.tuples(FINITE, FINITE, FINITE)

# What a measurement can hold (packets refuses the rest as a stream out of step; see the refusal tests)
COORD = st.floats(-1e6, 1e6)
SPREAD = st.floats(0.0, 1e6)
POSITION = st.tuples(COORD, COORD, COORD)
STATUS = st.integers(0, 20000)
MODE = st.integers(0, 11)
TEMPERATURE, PRESSURE, HUMIDITY = st.floats(-100.0, 200.0), st.floats(0.0, 2000.0), st.floats(0.0, 100.0)
SINGLES = st.builds(SingleMeasResult, STATUS, MODE, st.booleans(), POSITION,
                    st.tuples(SPREAD, SPREAD, SPREAD), SPREAD, TRIPLE, TRIPLE, FINITE, TEMPERATURE,
                    PRESSURE, HUMIDITY)
SAMPLE = st.builds(MeasValue, st.integers(0, 4), st.integers(0, 2**31 - 1), st.integers(0, 999_999),
                   POSITION)


def multis(max_samples: int) -> st.SearchStrategy[MultiMeasResult]:
    return st.builds(MultiMeasResult, STATUS, MODE, st.booleans(), TEMPERATURE, PRESSURE, HUMIDITY,
                     st.lists(SAMPLE, max_size=max_samples).map(tuple))


# The result and parameter structs as transcribed from the header ("i": 4-byte integer, "d": double,
# "U": unsigned short[32]); used to draw values of the right types.
HEADER_RESULTS = {
    ES_C_GetSystemStatus: "iiii" + "iii" + "iii",
    ES_C_GetTrackerStatus: "i",
    ES_C_GetUnits: "iiiii",
    ES_C_GetEnvironmentParams: "ddd",
    ES_C_GetMeasurementMode: "i",
    ES_C_GetCoordinateSystemType: "i",
    ES_C_GetStationaryModeParams: "ii",
    ES_C_GetContinuousTimeModeParams: "iiii",
    ES_C_GetReflector: "i",
    ES_C_GetReflectors: "iiidU",
    ES_C_GetSearchParams: "di",
    ES_C_GetMeasurementStatusInfo: "ii",
    ES_C_GetSystemSoftwareVersion: "U",
    ES_C_GetTrackerInfo: "iU" + "ii" + "iii" + "ddd" + "ii" + "dd" + "iii",
}
HEADER_PARAMETERS = {
    ES_C_SetUnits: "iiiii",
    ES_C_SetEnvironmentParams: "ddd",
    ES_C_SetMeasurementMode: "i",
    ES_C_SetCoordinateSystemType: "i",
    ES_C_SetStationaryModeParams: "ii",
    ES_C_SetContinuousTimeModeParams: "iiii",
    ES_C_SetReflector: "i",
    ES_C_SetSearchParams: "di",
    ES_C_FindReflector: "d",
    ES_C_SwitchLaser: "i",
    ES_C_SetStatisticMode: "ii",
    ES_C_ClearCommandQueue: "i",
}
KIND = {"i": INT32, "d": FINITE, "U": NAME}


def test_module_tables_agree_with_header() -> None:
    assert {int(c): f for c, f in packets.RESULTS.items()} == HEADER_RESULTS
    assert {int(c): f for c, f in packets.PARAMETERS.items()} == HEADER_PARAMETERS


def values_for(fields: str) -> st.SearchStrategy[tuple[Any, ...]]:
    return st.tuples(*(KIND[k] for k in fields))


@FUZZ
@given(SINGLES)
def test_single_round_trip(result: SingleMeasResult) -> None:
    data = encode_single(result)
    assert len(data) == 156
    assert decode_reply(data) == result


@FUZZ
@given(multis(50))
def test_multi_round_trip(result: MultiMeasResult) -> None:
    data = encode_multi(result)
    assert len(data) == 48 + 36 * len(result.samples)
    assert decode_reply(data) == result


@FUZZ
@given(st.data(), st.sampled_from(sorted(packets.RESULTS)), INT32)
def test_answer_round_trip(data: st.DataObject, command: packets.Command, status: int) -> None:
    values = data.draw(values_for(HEADER_RESULTS[int(command)]))
    assert decode_reply(encode_answer(command, status, *values)) == Answer(command, status, values)
    assert decode_reply(encode_answer(command, status)) == Answer(command, status)


@FUZZ
@given(st.data(), st.sampled_from(sorted(packets.PARAMETERS)))
def test_command_round_trip(data: st.DataObject, command: packets.Command) -> None:
    params = data.draw(values_for(HEADER_PARAMETERS[int(command)]))
    assert decode_request(encode_command(command, *params)) == CommandRequest(command, params)


@FUZZ
@given(INT32, INT32)
def test_error_and_status_change_round_trip(command: int, status: int) -> None:
    assert decode_reply(encode_error(command, status)) == ErrorResponse(command, status)
    assert decode_reply(encode_status_change(status)) == StatusChange(status)


# --- hypothesis: garbage -------------------------------------------------------------------------
@st.composite
def framed_garbage(draw: st.DrawFn) -> bytes:
    """A header whose size usually matches, a known or unknown type, and any body."""
    body = draw(st.binary(max_size=400))
    kind = draw(st.one_of(st.integers(-2, 12), INT32))
    size = draw(st.one_of(st.just(8 + len(body)), st.integers(-10, 500)))
    return i32(size, kind) + body


@st.composite
def valid_packets(draw: st.DrawFn) -> bytes:
    choice = draw(st.integers(0, 4))
    if choice == 0:
        return encode_single(draw(SINGLES))
    if choice == 1:
        return encode_multi(draw(multis(5)))
    if choice == 2:
        command = draw(st.sampled_from(sorted(packets.RESULTS)))
        return encode_answer(command, 0, *draw(values_for(HEADER_RESULTS[int(command)])))
    if choice == 3:
        return encode_error(draw(INT32), draw(INT32))
    return encode_status_change(draw(INT32))


STREAMS = st.lists(st.one_of(st.binary(max_size=64), framed_garbage(), valid_packets()), max_size=6).map(
    b"".join)


def chunked(stream: bytes, cuts: list[int]) -> list[bytes]:
    bounds = [0, *sorted(c % (len(stream) + 1) for c in cuts), len(stream)]
    return [stream[a:b] for a, b in itertools.pairwise(bounds)]


@pytest.mark.timeout(60)
@FUZZ
@given(STREAMS, st.lists(st.integers(0, 10_000), max_size=8))
def test_garbage_raises_only_packet_error(stream: bytes, cuts: list[int]) -> None:
    for decode in (decode_reply, decode_request):
        with contextlib.suppress(PacketError):
            decode(stream)
    reader = PacketReader()
    for chunk in chunked(stream, cuts):
        try:
            frames = reader.feed(chunk)
        except PacketError:
            return
        assert all(8 <= len(f) <= packets.MAX_PACKET for f in frames)
        for frame in frames:
            assert struct.unpack_from("<i", frame)[0] == len(frame)
            for decode in (decode_reply, decode_request):
                with contextlib.suppress(PacketError):
                    decode(frame)


# --- hypothesis: a desynchronised stream is refused, not misread ----------------------------------
def coordinates(reply: Any) -> list[tuple[float, float, float]]:
    if isinstance(reply, SingleMeasResult):
        return [reply.position]
    if isinstance(reply, MultiMeasResult):
        return [s.position for s in reply.samples]
    return []


def read_until_error(stream: bytes, cuts: list[int]) -> list[tuple[int, int, Any]]:
    """(start, end, reply) of every packet the reader and decoder yield before the first PacketError."""
    reader = PacketReader()
    out: list[tuple[int, int, Any]] = []
    offset = 0
    for chunk in chunked(stream, cuts):
        try:
            frames = reader.feed(chunk)
        except PacketError:
            return out
        for frame in frames:
            try:
                reply = decode_reply(frame)
            except PacketError:
                return out
            out.append((offset, offset + len(frame), reply))
            offset += len(frame)
    return out


MEASUREMENTS = st.lists(st.one_of(SINGLES, multis(4)), min_size=1, max_size=5)


def encode_measurement(result: SingleMeasResult | MultiMeasResult) -> bytes:
    return encode_single(result) if isinstance(result, SingleMeasResult) else encode_multi(result)


@settings(FUZZ, max_examples=100)
@given(MEASUREMENTS, st.integers(0, 10_000), st.lists(st.integers(0, 10_000), max_size=5))
def test_truncated_stream_yields_only_whole_original_packets(
        results: list[SingleMeasResult | MultiMeasResult], cut: int, cuts: list[int]) -> None:
    ends = list(itertools.accumulate(len(encode_measurement(r)) for r in results))
    stream = b"".join(encode_measurement(r) for r in results)
    truncated = stream[: cut % (len(stream) + 1)]
    whole = sum(end <= len(truncated) for end in ends)
    assert [reply for _, _, reply in read_until_error(truncated, cuts)] == results[:whole]


@st.composite
def mutated_streams(draw: st.DrawFn) -> tuple[list[Any], bytes, str, int, int]:
    """Valid measurement packets with one truncation, insertion or deletion of bytes at a random place.

    Returns the results, the mutated stream, the operation and the mutated span [start, end) in the
    mutated stream (a deletion leaves an empty span at the junction)."""
    results = draw(MEASUREMENTS)
    stream = b"".join(encode_measurement(r) for r in results)
    op = draw(st.sampled_from(["truncate", "insert", "delete"]))
    at = draw(st.integers(0, len(stream)))
    if op == "truncate":
        return results, stream[:at], op, at, at
    if op == "delete":
        count = draw(st.integers(1, 200))
        return results, stream[:at] + stream[at + count :], op, at, at
    inserted = draw(st.one_of(st.binary(min_size=1, max_size=200), valid_packets().map(lambda p: p[:-1])))
    return results, stream[:at] + inserted + stream[at:], op, at, at + len(inserted)


@FUZZ
@given(mutated_streams(), st.lists(st.integers(0, 10_000), max_size=5))
def test_desynchronised_stream_yields_no_foreign_coordinate(
        case: tuple[list[Any], bytes, str, int, int], cuts: list[int]) -> None:
    """After an insertion or deletion nothing read out of step passes as a measurement.

    The one packet whose bytes the mutation falls inside is exempt: TPI has no checksum, so a packet that
    lost (or gained) bytes and is filled up from its neighbour has the right size and type and cannot be
    told from a good one (see `test_byte_lost_inside_a_packet_is_misread`). Every packet read wholly before
    the mutation must be the original, and every packet read after the hit one must be refused (reader or
    decoder) or carry original coordinates.
    """
    results, stream, op, start, end = case
    original = {c for r in results for c in coordinates(r)}
    for index, (s, e, reply) in enumerate(read_until_error(stream, cuts)):
        if e <= start:  # wholly before the mutation: the original packet, in order
            assert reply == results[index]
            continue
        hit = (s < start < e) if start == end else (s < end and start < e)
        if not hit:
            for c in coordinates(reply):
                assert c in original, (op, start, end, s, e)


def _two_singles() -> tuple[SingleMeasResult, SingleMeasResult]:
    first = SingleMeasResult(0, 0, False, (1.25, 2.5, -0.75), (1e-5, 1e-5, 1e-5), 2e-5, (0.0, 0.0, 0.0),
                             (1e-5, 1e-5, 1e-5), 2e-5, 20.5, 1013.25, 45.0)
    second = SingleMeasResult(0, 0, False, (3.0, 4.0, 5.0), (1e-5, 1e-5, 1e-5), 2e-5, (0.0, 0.0, 0.0),
                              (1e-5, 1e-5, 1e-5), 2e-5, 20.5, 1013.25, 45.0)
    return first, second


def test_byte_lost_inside_a_packet_is_refused_not_misread() -> None:
    first, second = _two_singles()
    stream = encode_single(first) + encode_single(second)
    damaged = stream[:20] + stream[21:]  # one byte of dVal1 of the first packet lost
    reader = PacketReader()
    frames = reader.feed(damaged[:156])  # the next segment has not arrived yet
    assert frames == [damaged[:156]]
    with pytest.raises(PacketError):
        decode_reply(frames[0])


def test_out_of_step_header_shaped_payload_is_refused() -> None:
    first, _ = _two_singles()
    # lTime1 = 156 s and lTime2 = 2 µs read as lPacketSize 156, type ES_DT_SingleMeasResult
    samples = (MeasValue(0, 156, 2, (0.5, 0.25, 0.125)),
               *(MeasValue(0, 157 + i, 0, (1.0 + i, 2.0, 3.0)) for i in range(4)))
    second = MultiMeasResult(0, 1, False, 20.0, 1000.0, 50.0, samples)
    stream = encode_single(first) + encode_multi(second)
    damaged = stream[:20] + stream[72:]  # 52 bytes lost inside the first packet: the reader lands on lTime1
    reader = PacketReader()
    reader.feed(damaged[:156])  # the hit packet (exempt, see above)
    frames = reader.feed(damaged[156:312])
    assert frames == [damaged[156:312]]
    with pytest.raises(PacketError):
        decode_reply(frames[0])


def test_byte_inserted_into_the_last_packet_is_refused() -> None:
    first, _ = _two_singles()
    stream = encode_single(first)
    damaged = stream[:20] + b"\x00" + stream[20:]
    reader = PacketReader()
    frames = reader.feed(damaged)
    assert reader.pending == 1  # the displaced last byte waits; the packet itself is refused
    with pytest.raises(PacketError):
        decode_reply(frames[0])


_GOOD = SingleMeasResult(0, 0, False, (1.0, 2.0, 3.0), (1e-5, 2e-5, 3e-5), 4e-5, (0.0, 0.0, 0.0),
                         (1e-5, 1e-5, 1e-5), 2e-5, 20.0, 1013.25, 50.0)


@pytest.mark.parametrize("change", [
    {"status": -1}, {"status": 20001}, {"mode": 12}, {"mode": -1}, {"position": (1.0, 2e6, 3.0)},
    {"position": (float("nan"), 0.0, 0.0)}, {"std": (-1e-6, 0.0, 0.0)}, {"std_total": float("inf")},
    {"pointing_error": (float("nan"), 0.0, 0.0)}, {"temperature": 300.0}, {"pressure": -1.0},
    {"humidity": 101.0},
], ids=lambda c: next(iter(c)))
def test_an_implausible_measurement_is_refused(change: dict[str, Any]) -> None:
    """Every field of a measurement has a range; outside it the bytes were not a measurement."""
    import dataclasses

    with pytest.raises(PacketError):
        decode_reply(encode_single(dataclasses.replace(_GOOD, **change)))
    assert decode_reply(encode_single(_GOOD)) == _GOOD


@pytest.mark.parametrize("sample", [MeasValue(5, 0, 0, (0.0, 0.0, 0.0)), MeasValue(0, -1, 0, (0.0, 0.0, 0.0)),
                                    MeasValue(0, 0, 1_000_000, (0.0, 0.0, 0.0)),
                                    MeasValue(0, 0, 0, (0.0, 0.0, -1e7))], ids=str)
def test_an_implausible_continuous_sample_is_refused(sample: MeasValue) -> None:
    with pytest.raises(PacketError):
        decode_reply(encode_multi(MultiMeasResult(0, 1, False, 20.0, 1013.25, 50.0, (sample,))))
