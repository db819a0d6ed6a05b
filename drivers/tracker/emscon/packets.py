"""emScon TPI packets: the C structs of Leica's ``ES_C_API_Def.h`` (TPI/SDK 3.6) as bytes, both ways.

Facts taken from the header (read, not copied):

* every packet starts with ``PacketHeaderT {long lPacketSize; enum ES_DataType type;}``; the size counts
  the whole packet, header included;
* the structs are packed to 4 bytes (``#pragma pack(4)``), ``long``, ``int``, enums and ``ES_BOOL`` are
  4-byte integers and the server is little-endian, so every field sits at the next 4-byte boundary and
  Python's ``struct`` with ``<`` (no alignment) reproduces the layouts exactly;
* a command (``BasicCommandCT``) carries its ``ES_Command`` after the header, then its parameters; the
  server's answer (``BasicCommandRT``) repeats the command and adds an ``ES_ResultStatus``, then results;
* asynchronous packets: ``ErrorResponseT`` (type 1: command, status), ``SingleMeasResultT`` (type 2),
  ``MultiMeasResultT`` (type 3: a head, then ``lNumberOfResults`` × ``MeasValueT``),
  ``ReflectorPosResultT`` (type 7) and ``SystemStatusChangeT`` (type 8);
* strings (reflector and tracker names, software version) are 32 UTF-16 code units, NUL padded.

Only the commands hil uses and a typical client sends are tabled here (`PARAMETERS`, `RESULTS`); any
other command still frames and pairs (it carries no parameters and its answer's results are kept raw).
A packet whose size disagrees with its type's layout is refused (`PacketError`), never zero-padded or
truncated into a coordinate.
"""

from __future__ import annotations

import enum
import math
import struct
from dataclasses import dataclass, field
from typing import Any

HEADER = struct.Struct("<ii")  # lPacketSize, ES_DataType
HEADER_SIZE = HEADER.size
MAX_PACKET = 64 * 1024  # far above the largest TPI packet; a bigger size means a desynchronised stream
NAME_UNITS = 32  # unsigned short c...Name[32]


class PacketError(ValueError):
    """Bytes that are not a valid TPI packet (size, type or layout)."""


class DataType(enum.IntEnum):
    COMMAND = 0
    ERROR = 1
    SINGLE_MEAS_RESULT = 2
    MULTI_MEAS_RESULT = 3
    NIVEL_RESULT = 6
    REFLECTOR_POS_RESULT = 7
    SYSTEM_STATUS_CHANGE = 8
    SINGLE_MEAS_RESULT2 = 9


class Command(enum.IntEnum):
    EXIT_APPLICATION = 0
    GET_SYSTEM_STATUS = 1
    GET_TRACKER_STATUS = 2
    SET_UNITS = 5
    GET_UNITS = 6
    INITIALIZE = 7
    SWITCH_LASER = 11
    SET_ENVIRONMENT_PARAMS = 20
    GET_ENVIRONMENT_PARAMS = 21
    SET_MEASUREMENT_MODE = 24
    GET_MEASUREMENT_MODE = 25
    SET_COORDINATE_SYSTEM_TYPE = 26
    GET_COORDINATE_SYSTEM_TYPE = 27
    SET_STATIONARY_MODE_PARAMS = 28
    GET_STATIONARY_MODE_PARAMS = 29
    SET_CONTINUOUS_TIME_MODE_PARAMS = 30
    GET_CONTINUOUS_TIME_MODE_PARAMS = 31
    SET_REFLECTOR = 40
    GET_REFLECTOR = 41
    GET_REFLECTORS = 42
    SET_SEARCH_PARAMS = 43
    GET_SEARCH_PARAMS = 44
    START_MEASUREMENT = 49
    STOP_MEASUREMENT = 52
    GO_BIRD_BATH = 54
    FIND_REFLECTOR = 63
    SET_STATISTIC_MODE = 80
    GET_MEASUREMENT_STATUS_INFO = 122
    CLEAR_COMMAND_QUEUE = 130
    GET_TRACKER_INFO = 132
    GET_SYSTEM_SOFTWARE_VERSION = 142


class ResultStatus(enum.IntEnum):
    """``ES_ResultStatus``: the answer's verdict (names as in the header, without the ES_RS_ prefix)."""

    AllOK = 0
    ServerBusy = 1
    NotImplemented = 2
    WrongParameter = 3
    WrongParameter1 = 4
    WrongParameter2 = 5
    WrongParameter3 = 6
    WrongCurrentReflector = 23
    NoTPFound = 26
    NoWeathermonitorFound = 27
    NoLastMeasuredPoint = 28
    NoAdm = 30
    UsageConflict = 35
    Unknown = 36
    NoDistanceSet = 37
    NoTrackerConnected = 38
    TrackerNotInitialized = 39
    ModuleNotStarted = 40
    ModuleTimedOut = 41
    MeteoDataOutOfRange = 57
    InvalidInputData = 98
    MeasurementStatusNotReady = 10004
    ADMStartUpBusy = 10005
    NoStationaryResult = 10009
    MultiConnectionsNotAllowed = 10011
    SensorNotWarmedUp = 10012
    SensorNotStable = 10013
    SystemNotReadyForMeasurement = 10014
    CommunicationWithSensorFailed = 10015


def status_name(code: int) -> str:
    """``ES_RS_<name>`` for a known status, ``ES_RS_<code>`` otherwise (for one-line errors)."""
    try:
        return f"ES_RS_{ResultStatus(code).name}"
    except ValueError:
        return f"ES_RS_{code}"


class MeasMode(enum.IntEnum):
    STATIONARY = 0
    CONTINUOUS_TIME = 1
    CONTINUOUS_DISTANCE = 2


class TargetType(enum.IntEnum):
    UNKNOWN = 0
    CORNER_CUBE = 1
    CATS_EYE = 2
    GLASS_PRISM = 3
    RFI_PRISM = 4
    RRR15 = 5
    RRR05 = 6
    BRR15 = 7
    BRR05 = 8
    TBR05 = 9


class TrackerStatus(enum.IntEnum):
    NOT_READY = 0
    BUSY = 1
    READY = 2


class SystemStatusChange(enum.IntEnum):
    ENVIRONMENT_PARAMS_CHANGED = 2
    UNITS_CHANGED = 6
    REFLECTOR_CHANGED = 7
    MEASUREMENT_MODE_CHANGED = 17
    MEAS_STATUS_NOT_READY = 25
    MEAS_STATUS_BUSY = 26
    MEAS_STATUS_READY = 27
    SERVER_CLOSING = 998
    SERVER_STARTED = 999


class MeasurementStatus(enum.IntEnum):
    """``ES_MeasurementStatus`` of one continuous sample."""

    ALL_OK = 0
    SPEED_WARNING = 1
    SPEED_EXCEEDED = 2
    PRISM_ERROR = 3
    TRIGGER_TIME_VIOLATION = 4


class MeasurementStatusInfo(enum.IntFlag):
    """``ES_MeasurementStatusInfo`` bits (GetMeasurementStatusInfo)."""

    TRACKER_FOUND = 1
    TRACKER_COMPENSATION_FOUND = 2
    ADM_FOUND = 4
    ADM_COMPENSATION_FOUND = 8
    REFLECTOR_FOUND = 2048
    IN_FACE1 = 4096
    INITIALIZED = 65536


class TrackerProcessorStatus(enum.IntEnum):
    NO_TP_FOUND = 0
    TP_FOUND = 1
    BOOTED = 3
    COMPENSATION_SET = 4
    INITIALIZED = 5


class LengthUnit(enum.IntEnum):
    METER = 0
    MILLIMETER = 1


class AngleUnit(enum.IntEnum):
    RADIAN = 0
    DEGREE = 1


class TemperatureUnit(enum.IntEnum):
    CELSIUS = 0


class PressureUnit(enum.IntEnum):
    MBAR = 0


class HumidityUnit(enum.IntEnum):
    RH = 0


class CoordinateSystemType(enum.IntEnum):
    RHR = 0  # right-handed Cartesian
    SCW = 6  # spherical, clockwise


class StatisticMode(enum.IntEnum):
    STANDARD = 0
    EXTENDED = 1


# Parameters after ``BasicCommandCT`` (client -> server) and results after ``BasicCommandRT``.
# "U" stands for a 32-unit UTF-16 string.
PARAMETERS: dict[Command, str] = {
    Command.SET_UNITS: "iiiii",  # SystemUnitsDataT: length, angle, temperature, pressure, humidity
    Command.SET_ENVIRONMENT_PARAMS: "ddd",  # EnvironmentDataT: °C, mbar, %RH
    Command.SET_MEASUREMENT_MODE: "i",
    Command.SET_COORDINATE_SYSTEM_TYPE: "i",
    Command.SET_STATIONARY_MODE_PARAMS: "ii",  # StationaryModeDataT: lMeasTime (ms), bUseADM
    # ContinuousTimeModeDataT: lTimeSeparation (ms), lNumberOfPoints (0: until stopped), bUseRegion, region
    Command.SET_CONTINUOUS_TIME_MODE_PARAMS: "iiii",
    Command.SET_REFLECTOR: "i",  # iInternalReflectorId
    Command.SET_SEARCH_PARAMS: "di",  # SearchParamsDataT: dSearchRadius, lTimeOut (ms)
    Command.FIND_REFLECTOR: "d",  # dAproxDistance
    Command.SWITCH_LASER: "i",
    Command.SET_STATISTIC_MODE: "ii",
    Command.CLEAR_COMMAND_QUEUE: "i",
}

RESULTS: dict[Command, str] = {
    # lastResultStatus, trackerProcessorStatus, laserStatus, admStatus, ESVersionNumberT (3 ints),
    # weatherMonitorStatus, lFlagsValue, lTrackerSerialNumber
    Command.GET_SYSTEM_STATUS: "iiiiiiiiii",
    Command.GET_TRACKER_STATUS: "i",
    Command.GET_UNITS: "iiiii",
    Command.GET_ENVIRONMENT_PARAMS: "ddd",
    Command.GET_MEASUREMENT_MODE: "i",
    Command.GET_COORDINATE_SYSTEM_TYPE: "i",
    Command.GET_STATIONARY_MODE_PARAMS: "ii",
    Command.GET_CONTINUOUS_TIME_MODE_PARAMS: "iiii",
    Command.GET_REFLECTOR: "i",
    # iTotalReflectors, iInternalReflectorId, targetType, dSurfaceOffset, cReflectorName[32]
    Command.GET_REFLECTORS: "iiidU",
    Command.GET_SEARCH_PARAMS: "di",
    Command.GET_MEASUREMENT_STATUS_INFO: "ii",  # lastResultStatus, lMeasurementStatusInfo
    Command.GET_SYSTEM_SOFTWARE_VERSION: "U",
    # trackerType, cTrackerName, lSerialNumber, lCompensationIdNumber, bHasADM, bHasOverviewCamera,
    # bHasNivel, dNivelMountOffset, dMaxDistance, dMinDistance, iMaxDataRate, iNumberOfFaces,
    # dHzAngleRange, dVtAngleRange, accuracyModel, iMajLCPFirmwareVersion, iMinLCPFirmwareVersion
    Command.GET_TRACKER_INFO: "iUiiiiidddiiddiii",
}


def _struct(fields: str) -> struct.Struct:
    return struct.Struct("<" + fields.replace("U", f"{NAME_UNITS}H"))


def _pack_values(fields: str, values: tuple[Any, ...]) -> bytes:
    flat: list[Any] = []
    for kind, value in zip(fields, values, strict=True):
        if kind == "U":
            units = list(str(value).encode("utf-16-le"))
            codes = [units[i] | units[i + 1] << 8 for i in range(0, len(units), 2)][:NAME_UNITS - 1]
            if codes and 0xD800 <= codes[-1] <= 0xDBFF:  # never cut a surrogate pair in half
                codes.pop()
            flat.extend(codes + [0] * (NAME_UNITS - len(codes)))
        else:
            flat.append(value)
    return _struct(fields).pack(*flat)


def _unpack_values(fields: str, data: bytes) -> tuple[Any, ...]:
    flat = list(_struct(fields).unpack(data))
    out: list[Any] = []
    for kind in fields:
        if kind == "U":
            codes, flat = flat[:NAME_UNITS], flat[NAME_UNITS:]
            raw = b"".join(c.to_bytes(2, "little") for c in codes)
            out.append(raw.decode("utf-16-le", errors="replace").split("\0", 1)[0])
        else:
            out.append(flat.pop(0))
    return tuple(out)


def _frame(kind: DataType, body: bytes) -> bytes:
    return HEADER.pack(HEADER_SIZE + len(body), int(kind)) + body


# --- what a client sends ---------------------------------------------------------------------------
@dataclass(frozen=True)
class CommandRequest:
    """A ``...CT`` packet: the command and its parameters."""

    command: int
    params: tuple[Any, ...] = ()


def encode_command(command: Command | int, *params: Any) -> bytes:
    fields = _layout(PARAMETERS, command)
    if len(params) != len(fields):
        raise PacketError(f"{_command_name(command)} takes {len(fields)} parameters, got {len(params)}")
    return _frame(DataType.COMMAND, struct.pack("<i", int(command)) + _pack_values(fields, params))


def decode_request(packet: bytes) -> CommandRequest:
    """A client's packet (server side). Unknown commands decode with their raw parameter bytes."""
    kind, body = _split(packet)
    if kind != DataType.COMMAND:
        raise PacketError(f"a client sends commands (type 0), got type {kind}")
    if len(body) < 4:
        raise PacketError("command packet without a command")
    (command,) = struct.unpack_from("<i", body)
    rest = body[4:]
    try:
        fields = PARAMETERS.get(Command(command), "")
    except ValueError:
        return CommandRequest(command, (rest,) if rest else ())
    if len(rest) != _struct(fields).size:
        raise PacketError(f"{_command_name(command)}: {len(rest)} parameter bytes, the header says "
                          f"{_struct(fields).size}")
    return CommandRequest(command, _unpack_values(fields, rest))


# --- what a server sends ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Answer:
    """A ``...RT`` packet: the command answered, its status and results."""

    command: int
    status: int
    values: tuple[Any, ...] = ()

    @property
    def ok(self) -> bool:
        return self.status == ResultStatus.AllOK


@dataclass(frozen=True)
class ErrorResponse:
    """``ErrorResponseT``: a command failed after (or instead of) its answer."""

    command: int
    status: int


@dataclass(frozen=True)
class SingleMeasResult:
    """``SingleMeasResultT``: one stationary measurement (units as set; hil sets m, rad, °C, mbar)."""

    status: int
    mode: int
    try_mode: bool
    position: tuple[float, float, float]
    std: tuple[float, float, float]
    std_total: float
    pointing_error: tuple[float, float, float]
    apriori_std: tuple[float, float, float]
    apriori_std_total: float
    temperature: float
    pressure: float
    humidity: float


@dataclass(frozen=True)
class MeasValue:
    """``MeasValueT``: one continuous sample (``lTime1`` s and ``lTime2`` µs of the tracker's clock)."""

    status: int
    time1: int
    time2: int
    position: tuple[float, float, float]

    @property
    def seconds(self) -> float:
        return self.time1 + self.time2 * 1e-6


@dataclass(frozen=True)
class MultiMeasResult:
    """``MultiMeasResultT``: a batch of continuous samples."""

    status: int
    mode: int
    try_mode: bool
    temperature: float
    pressure: float
    humidity: float
    samples: tuple[MeasValue, ...] = field(default_factory=tuple)


@dataclass(frozen=True)
class ReflectorPosResult:
    status: int
    position: tuple[float, float, float]


@dataclass(frozen=True)
class StatusChange:
    """``SystemStatusChangeT``: an event of the server (beam lost/found, settings changed, closing)."""

    change: int


Reply = Answer | ErrorResponse | SingleMeasResult | MultiMeasResult | ReflectorPosResult | StatusChange

_SINGLE = struct.Struct("<iii17d")  # status, measMode, bIsTryMode, 17 doubles
_MULTI_HEAD = struct.Struct("<iiii3d")  # status, lNumberOfResults, measMode, bIsTryMode, T, p, h
_MEAS_VALUE = struct.Struct("<iii3d")  # status, lTime1, lTime2, x, y, z
_POS = struct.Struct("<i3d")
MAX_SAMPLES = (MAX_PACKET - HEADER_SIZE - _MULTI_HEAD.size) // _MEAS_VALUE.size


def encode_answer(command: Command | int, status: ResultStatus | int, *values: Any) -> bytes:
    """A server's answer; results are sent only with an OK status (as the server does)."""
    fields = _layout(RESULTS, command)
    body = struct.pack("<ii", int(command), int(status))
    if values:
        if len(values) != len(fields):
            raise PacketError(f"{_command_name(command)} answers {len(fields)} values, got {len(values)}")
        body += _pack_values(fields, values)
    return _frame(DataType.COMMAND, body)


def encode_error(command: Command | int, status: ResultStatus | int) -> bytes:
    return _frame(DataType.ERROR, struct.pack("<ii", int(command), int(status)))


def encode_single(result: SingleMeasResult) -> bytes:
    r = result
    return _frame(DataType.SINGLE_MEAS_RESULT, _SINGLE.pack(
        r.status, r.mode, int(r.try_mode), *r.position, *r.std, r.std_total, *r.pointing_error,
        *r.apriori_std, r.apriori_std_total, r.temperature, r.pressure, r.humidity))


def encode_multi(result: MultiMeasResult) -> bytes:
    r = result
    if len(r.samples) > MAX_SAMPLES:
        raise PacketError(f"{len(r.samples)} samples exceed one packet ({MAX_SAMPLES})")
    body = _MULTI_HEAD.pack(r.status, len(r.samples), r.mode, int(r.try_mode), r.temperature, r.pressure,
                            r.humidity)
    body += b"".join(_MEAS_VALUE.pack(s.status, s.time1, s.time2, *s.position) for s in r.samples)
    return _frame(DataType.MULTI_MEAS_RESULT, body)


def encode_reflector_pos(result: ReflectorPosResult) -> bytes:
    return _frame(DataType.REFLECTOR_POS_RESULT, _POS.pack(result.status, *result.position))


def encode_status_change(change: SystemStatusChange | int) -> bytes:
    return _frame(DataType.SYSTEM_STATUS_CHANGE, struct.pack("<i", int(change)))


def decode_reply(packet: bytes) -> Reply:
    """A server's packet (client side); a layout that does not match its type is a `PacketError`."""
    kind, body = _split(packet)
    if kind == DataType.COMMAND:
        if len(body) < 8:
            raise PacketError(f"answer of {len(body)} bytes: command and status need 8")
        command, status = struct.unpack_from("<ii", body)
        rest = body[8:]
        try:
            fields = RESULTS.get(Command(command), "")
        except ValueError:
            return Answer(command, status, (rest,) if rest else ())
        if not rest:
            return Answer(command, status)
        if len(rest) != _struct(fields).size:
            raise PacketError(f"answer to {_command_name(command)}: {len(rest)} result bytes, the header "
                              f"says {_struct(fields).size}")
        return Answer(command, status, _unpack_values(fields, rest))
    if kind == DataType.ERROR:
        _exact(body, 8, "ErrorResponseT")
        return ErrorResponse(*struct.unpack("<ii", body))
    if kind == DataType.SINGLE_MEAS_RESULT:
        _exact(body, _SINGLE.size, "SingleMeasResultT")
        v = _SINGLE.unpack(body)
        d = v[3:]
        _plausible_head(v[0], v[1], v[2], "SingleMeasResultT")
        _plausible_values(d[0:3], d[3:14], d[14:17], "SingleMeasResultT")
        return SingleMeasResult(v[0], v[1], bool(v[2]), d[0:3], d[3:6], d[6], d[7:10], d[10:13], d[13],
                                d[14], d[15], d[16])
    if kind == DataType.MULTI_MEAS_RESULT:
        if len(body) < _MULTI_HEAD.size:
            raise PacketError(f"MultiMeasResultT of {len(body)} bytes is shorter than its head")
        status, n, mode, try_mode, temp, press, hum = _MULTI_HEAD.unpack_from(body)
        if not 0 <= n <= MAX_SAMPLES:
            raise PacketError(f"MultiMeasResultT announces {n} samples")
        _exact(body, _MULTI_HEAD.size + n * _MEAS_VALUE.size, f"MultiMeasResultT with {n} samples")
        _plausible_head(status, mode, try_mode, "MultiMeasResultT")
        _plausible_values((), (), (temp, press, hum), "MultiMeasResultT")
        rows = [_MEAS_VALUE.unpack_from(body, _MULTI_HEAD.size + i * _MEAS_VALUE.size) for i in range(n)]
        for s in rows:
            if not (0 <= s[0] <= _MAX_SAMPLE_STATUS and s[1] >= 0 and 0 <= s[2] < 1_000_000):
                raise PacketError(f"MultiMeasResultT sample status {s[0]} / time {s[1]} s {s[2]} µs is not "
                                  "a sample: stream out of step")
            _plausible_values(s[3:6], (), (), "MeasValueT")
        samples = tuple(MeasValue(s[0], s[1], s[2], s[3:6]) for s in rows)
        return MultiMeasResult(status, mode, bool(try_mode), temp, press, hum, samples)
    if kind == DataType.REFLECTOR_POS_RESULT:
        _exact(body, _POS.size, "ReflectorPosResultT")
        v = _POS.unpack(body)
        return ReflectorPosResult(v[0], v[1:4])
    if kind == DataType.SYSTEM_STATUS_CHANGE:
        _exact(body, 4, "SystemStatusChangeT")
        return StatusChange(struct.unpack("<i", body)[0])
    raise PacketError(f"packet type {kind} is not one hil reads")


# --- framing ---------------------------------------------------------------------------------------
class PacketReader:
    """Whole packets out of a byte stream (TCP delivers any split). A bad size is a `PacketError`.

    After a `PacketError` the stream cannot be trusted (there is no resynchronisation marker in TPI):
    the caller drops the connection.
    """

    def __init__(self) -> None:
        self._buffer = bytearray()

    def feed(self, data: bytes) -> list[bytes]:
        self._buffer += data
        out: list[bytes] = []
        while len(self._buffer) >= HEADER_SIZE:
            size, _kind = HEADER.unpack_from(self._buffer)
            if not HEADER_SIZE <= size <= MAX_PACKET:
                raise PacketError(f"packet size {size} outside {HEADER_SIZE}..{MAX_PACKET}: "
                                  "stream out of step")
            if len(self._buffer) < size:
                break
            out.append(bytes(self._buffer[:size]))
            del self._buffer[:size]
        return out

    @property
    def pending(self) -> int:
        return len(self._buffer)


def _split(packet: bytes) -> tuple[int, bytes]:
    if len(packet) < HEADER_SIZE:
        raise PacketError(f"{len(packet)} bytes: shorter than the packet header")
    size, kind = HEADER.unpack_from(packet)
    if size != len(packet):
        raise PacketError(f"packet says {size} bytes, has {len(packet)}")
    return kind, bytes(packet[HEADER_SIZE:])


#: Plausibility of measurement packets. TPI has no checksum and no sync marker: a stream that lost
#: or gained bytes can frame a packet of the right size and type from the wrong bytes. Every field of
#: a measurement has a known range, so such a packet is refused instead of read as a coordinate.
_MAX_STATUS = 2 * 10_000  # ES_ResultStatus values lie below ES_API_ERROR_OFFSET + 100
_MAX_MODE = 11  # ES_MeasMode: ES_MM_Stationary .. ES_MM_6DCircleCenter
_MAX_SAMPLE_STATUS = 4  # ES_MeasurementStatus: ES_MS_AllOK .. ES_MS_TriggerTimeViolation
_MAX_COORDINATE = 1e6  # |x|: a kilometre in millimetres; the longest-range trackers reach 160 m
_AIR = ((-100.0, 200.0), (0.0, 2000.0), (0.0, 100.0))  # °C or °F, any pressure unit, %RH


def _plausible_head(status: int, mode: int, try_mode: int, what: str) -> None:
    if not (0 <= status <= _MAX_STATUS and 0 <= mode <= _MAX_MODE and try_mode in (0, 1)):
        raise PacketError(f"{what} with status {status}, mode {mode}, try mode {try_mode} is not a "
                          "measurement: stream out of step")


def _plausible_values(position: tuple[float, ...], spreads: tuple[float, ...], air: tuple[float, ...],
                      what: str) -> None:
    if not all(math.isfinite(x) and abs(x) <= _MAX_COORDINATE for x in position):
        raise PacketError(f"{what} coordinate {position} is not a position: stream out of step")
    if not all(math.isfinite(x) and 0.0 <= x <= _MAX_COORDINATE for x in spreads[:4]) or not all(
            math.isfinite(x) for x in spreads):
        raise PacketError(f"{what} standard deviations {spreads[:4]} are not: stream out of step")
    for value, (lo, hi) in zip(air, _AIR, strict=False):
        if not (math.isfinite(value) and lo <= value <= hi):
            raise PacketError(f"{what} air {air} is not plausible: stream out of step")


def _exact(body: bytes, size: int, what: str) -> None:
    if len(body) != size:
        raise PacketError(f"{what}: {len(body) + HEADER_SIZE} bytes, the header says {size + HEADER_SIZE}")


def _layout(table: dict[Command, str], command: int) -> str:
    try:
        return table.get(Command(command), "")
    except ValueError:
        return ""


def _command_name(command: int) -> str:
    try:
        return f"ES_C_{Command(command).name}"
    except ValueError:
        return f"ES_C_{command}"
