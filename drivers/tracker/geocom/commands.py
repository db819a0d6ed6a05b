"""One small typed method per GeoCOM RPC the tracker driver needs.

Each method checks the reply's return code: OK and the two "valid but flagged" warnings return
data, the lost-target codes raise `TargetLost`, anything else raises `GeoComError`. Values are
never returned from a failed RPC.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import IntEnum
from typing import TypeVar

from drivers.tracker.errors import GarbledReply, GeoComError, TargetLost
from drivers.tracker.geocom.codes import TARGET_LOST_CODES, WARNING_CODES, ReturnCode, describe
from drivers.tracker.geocom.protocol import (
    GeoComClient,
    Param,
    Reply,
    decode_double,
    decode_int,
    decode_string,
)

log = logging.getLogger(__name__)
T = TypeVar("T")


class RPC(IntEnum):
    """GeoCOM RPC numbers used here."""

    COM_NullProc = 0
    COM_SetDoublePrecision = 107
    COM_GetDoublePrecision = 108
    COM_GetSWVersion = 110
    TMC_DoMeasure = 2008
    TMC_SetAtmCorr = 2028
    TMC_GetAtmCorr = 2029
    TMC_GetCoordinate = 2082
    TMC_GetSimpleMea = 2108
    CSV_GetInstrumentNo = 5003
    CSV_GetInstrumentName = 5004
    CSV_GetSWVersion = 5034
    MOT_ReadLockStatus = 6021
    AUT_LockIn = 9013
    AUT_Search = 9029
    AUT_FineAdjust = 9037
    BAP_MeasDistanceAngle = 17017


class MeasureProgram(IntEnum):
    """TMC_MEASURE_PRG of TMC_DoMeasure."""

    STOP = 0
    DEF_DIST = 1
    CLEAR = 3
    SIGNAL = 4
    DO_MEASURE = 6
    RTRK_DIST = 8
    RED_TRK_DIST = 10
    FREQUENCY = 11


class InclineMode(IntEnum):
    """TMC_INCLINE_PRG."""

    MEA_INC = 0
    AUTO_INC = 1
    PLANE_INC = 2


class LockStatus(IntEnum):
    """MOT_LOCK_STATUS of MOT_ReadLockStatus."""

    LOCKED_OUT = 0
    LOCKED_IN = 1
    PREDICTION = 2


class DistanceMode(IntEnum):
    """BAP_MEASURE_PRG of BAP_MeasDistanceAngle."""

    NO_MEAS = 0
    NO_DIST = 1
    DEF_DIST = 2
    CLEAR_DIST = 5
    STOP_TRK = 6


@dataclass(frozen=True)
class PolarReading:
    """One raw reading: Hz, V (zenith) in radians, slope distance in metres, and its return code."""

    hz: float
    v: float
    distance: float
    rc: int = ReturnCode.OK

    @property
    def warning(self) -> bool:
        """True when the instrument flagged the values (accuracy / correction not guaranteed)."""
        return self.rc in WARNING_CODES


@dataclass(frozen=True)
class AtmosphericCorrection:
    """TMC_SetAtmCorr parameters: EDM wavelength [m], pressure [mbar], dry and wet temperature [°C]."""

    wavelength_m: float
    pressure_mbar: float
    dry_temperature_c: float
    wet_temperature_c: float


@dataclass(frozen=True)
class Coordinate:
    """TMC_GetCoordinate's east, north, height (metres) and its return code."""

    east: float
    north: float
    height: float
    rc: int = ReturnCode.OK


def _typed(reply: Reply, decoders: Sequence[Callable[[str], T]], rpc: int) -> list[T]:
    """Decode the first len(decoders) values; a short or malformed list is a garbled reply."""
    if len(reply.values) < len(decoders):
        raise GarbledReply(f"RPC {rpc}: expected {len(decoders)} values, got {len(reply.values)}")
    try:
        return [dec(text) for dec, text in zip(decoders, reply.values, strict=False)]
    except ValueError as exc:
        raise GarbledReply(f"RPC {rpc}: {exc}") from exc


class TrackerCommands:
    """Typed GeoCOM calls on top of a `GeoComClient`."""

    def __init__(self, client: GeoComClient) -> None:
        self.client = client

    def _call(self, rpc: RPC, params: Sequence[Param] = (), *, timeout: float | None = None) -> Reply:
        reply = self.client.call(int(rpc), params, timeout=timeout)
        rc = reply.rc
        if rc == ReturnCode.OK:
            return reply
        if rc in WARNING_CODES:
            log.info("%s: %s (values valid)", rpc.name, describe(rc))
            return reply
        if rc in TARGET_LOST_CODES:
            raise TargetLost(f"{rpc.name}: target lost ({describe(rc)})", rc, int(rpc))
        raise GeoComError(f"{rpc.name} failed: {describe(rc)}", rc, int(rpc))

    # --- communication / identity
    def null_proc(self) -> None:
        """COM_NullProc: is anybody there?"""
        self._call(RPC.COM_NullProc)

    def get_double_precision(self) -> int:
        """COM_GetDoublePrecision: decimals the instrument sends for doubles."""
        return _typed(self._call(RPC.COM_GetDoublePrecision), [decode_int], RPC.COM_GetDoublePrecision)[0]

    def set_double_precision(self, digits: int) -> None:
        """COM_SetDoublePrecision: 0..15 decimals for doubles in both directions."""
        if not 0 <= digits <= 15:
            raise ValueError("double precision must be 0..15 digits")
        self._call(RPC.COM_SetDoublePrecision, [int(digits)])
        self.client.precision = digits

    def get_geocom_version(self) -> tuple[int, int, int]:
        """COM_GetSWVersion: GeoCOM release, version, subversion."""
        r, v, s = _typed(self._call(RPC.COM_GetSWVersion), [decode_int] * 3, RPC.COM_GetSWVersion)
        return r, v, s

    def get_firmware_version(self) -> tuple[int, int, int]:
        """CSV_GetSWVersion: instrument firmware release, version, subversion."""
        r, v, s = _typed(self._call(RPC.CSV_GetSWVersion), [decode_int] * 3, RPC.CSV_GetSWVersion)
        return r, v, s

    def get_instrument_number(self) -> int:
        """CSV_GetInstrumentNo: the serial number."""
        return _typed(self._call(RPC.CSV_GetInstrumentNo), [decode_int], RPC.CSV_GetInstrumentNo)[0]

    def get_instrument_name(self) -> str:
        """CSV_GetInstrumentName: the model name."""
        return _typed(self._call(RPC.CSV_GetInstrumentName), [decode_string], RPC.CSV_GetInstrumentName)[0]

    # --- measurement
    def do_measure(self, program: MeasureProgram, incline: InclineMode = InclineMode.AUTO_INC) -> None:
        """TMC_DoMeasure: start/stop/clear the distance measurement program."""
        self._call(RPC.TMC_DoMeasure, [int(program), int(incline)])

    def get_simple_measurement(
        self, wait_ms: int = 100, incline: InclineMode = InclineMode.AUTO_INC
    ) -> PolarReading:
        """TMC_GetSimpleMea: Hz, V, slope distance (waits up to ``wait_ms`` for a distance)."""
        reply = self._call(RPC.TMC_GetSimpleMea, [int(wait_ms), int(incline)])
        hz, v, d = _typed(reply, [decode_double] * 3, RPC.TMC_GetSimpleMea)
        return PolarReading(hz, v, d, reply.rc)

    def get_coordinate(self, wait_ms: int = 100, incline: InclineMode = InclineMode.AUTO_INC) -> Coordinate:
        """TMC_GetCoordinate: east, north, height of the target (the first of its two triples)."""
        reply = self._call(RPC.TMC_GetCoordinate, [int(wait_ms), int(incline)])
        e, n, h = _typed(reply, [decode_double] * 3, RPC.TMC_GetCoordinate)
        return Coordinate(e, n, h, reply.rc)

    def measure_distance_angle(self, mode: DistanceMode = DistanceMode.DEF_DIST) -> PolarReading:
        """BAP_MeasDistanceAngle: measure and return Hz, V, slope distance in one RPC."""
        reply = self._call(RPC.BAP_MeasDistanceAngle, [int(mode)])
        hz, v, d = _typed(reply, [decode_double] * 3, RPC.BAP_MeasDistanceAngle)
        return PolarReading(hz, v, d, reply.rc)

    def set_atmospheric_correction(self, atm: AtmosphericCorrection) -> None:
        """TMC_SetAtmCorr."""
        self._call(
            RPC.TMC_SetAtmCorr,
            [float(atm.wavelength_m), float(atm.pressure_mbar), float(atm.dry_temperature_c),
             float(atm.wet_temperature_c)],
        )

    def get_atmospheric_correction(self) -> AtmosphericCorrection:
        """TMC_GetAtmCorr."""
        lam, p, dry, wet = _typed(self._call(RPC.TMC_GetAtmCorr), [decode_double] * 4, RPC.TMC_GetAtmCorr)
        return AtmosphericCorrection(lam, p, dry, wet)

    # --- automation / motorisation
    def lock_in(self) -> None:
        """AUT_LockIn: lock onto the target (ATR must see it)."""
        self._call(RPC.AUT_LockIn, timeout=max(self.client.timeout, 5.0))

    def search(self, hz_range: float, v_range: float) -> None:
        """AUT_Search: search the window of ``hz_range`` × ``v_range`` radians around the line of sight."""
        self._call(
            RPC.AUT_Search, [float(hz_range), float(v_range), False], timeout=max(self.client.timeout, 10.0)
        )

    def fine_adjust(self, hz_range: float, v_range: float) -> None:
        """AUT_FineAdjust: centre the telescope on the target within the given search window."""
        self._call(
            RPC.AUT_FineAdjust, [float(hz_range), float(v_range)], timeout=max(self.client.timeout, 5.0)
        )

    def read_lock_status(self) -> LockStatus:
        """MOT_ReadLockStatus."""
        code = _typed(self._call(RPC.MOT_ReadLockStatus), [decode_int], RPC.MOT_ReadLockStatus)[0]
        try:
            return LockStatus(code)
        except ValueError as exc:
            raise GarbledReply(f"MOT_ReadLockStatus: unknown lock status {code}") from exc
