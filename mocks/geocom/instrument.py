"""The instrument side of GeoCOM: request line in, reply line out. No I/O here.

Behaviour a plain GeoCOM client can rely on:

* requests with or without transaction id (the reply echoes it, 0 when absent); a leading LF is
  the client's buffer clear and is ignored; lines that are not ``%R1Q`` requests are line noise
  and get no answer;
* an unknown RPC answers ``%R1P,0,<id>:3081`` (GRC_COM_PROC_UNAVAIL), wrong parameters
  ``…:2`` (GRC_IVPARAM), an undecodable header ``%R1P,0,0:3080``;
* the opt-in CRC-16 suffix of `drivers.tracker.geocom.protocol` is checked when present (a bad one answers
  ``%R1P,3101,<id>:0``) and then added to the reply; requests without it get plain replies.

Optics: a measurement asks the `TargetSource` for the truth, converts it with the shared
`drivers.tracker.geometry.cartesian_to_polar`, scales the distance by the atmospheric ppm error
(true air vs the TMC_SetAtmCorr setting) and adds `NoiseSpec` noise.
"""

from __future__ import annotations

import logging
import re
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from drivers.tracker.geocom.codes import ReturnCode
from drivers.tracker.geocom.protocol import (
    crc16,
    decode_double,
    decode_int,
    format_double,
    quote_string,
    split_values,
)
from drivers.tracker.geometry import cartesian_to_polar, polar_to_cartesian
from mocks.geocom.faults import FaultInjector
from mocks.geocom.noise import NoiseSpec, atmospheric_ppm
from mocks.geocom.target import TargetSource

log = logging.getLogger(__name__)

_REQUEST_RE = re.compile(r"^%R1Q,([0-9]{1,5})(?:,([0-9]{1,5}))?:(.*)$", re.DOTALL)
_CRC_SUFFIX_RE = re.compile(rb";([0-9A-F]{4})$")

# TMC_DoMeasure programs (see drivers.tracker.geocom.commands.MeasureProgram)
_PROG_STOP, _PROG_DEF_DIST, _PROG_CLEAR, _PROG_DO_MEASURE, _PROG_RTRK, _PROG_RED_TRK = 0, 1, 3, 6, 8, 10


@dataclass(frozen=True)
class InstrumentIdentity:
    """What the identity RPCs answer."""

    name: str = "AT960-SIM"
    serial_number: int = 960_001
    firmware: tuple[int, int, int] = (1, 4, 2)  # CSV_GetSWVersion
    geocom: tuple[int, int, int] = (1, 50, 0)  # COM_GetSWVersion


@dataclass(frozen=True)
class InstrumentConfig:
    """Physics and identity of the simulated instrument."""

    identity: InstrumentIdentity = field(default_factory=InstrumentIdentity)
    noise: NoiseSpec = field(default_factory=NoiseSpec)
    seed: int | None = 0
    true_temperature_c: float = 20.0
    true_pressure_mbar: float = 1013.25
    wavelength_m: float = 6.58e-7
    processing_s: float = 0.0  # time one measurement RPC takes inside the instrument


#: Wall seconds a reading waits at most for the source's record to reach its instant (`_wait_for_record`).
RECORD_WAIT_S = 1.0


class _BadParamsError(Exception):
    """A handler could not decode its parameters (answered with GRC_IVPARAM)."""


class GeoComInstrument:
    """State and RPC handlers of the simulated tracker (thread-safe: one request at a time)."""

    def __init__(
        self,
        source: TargetSource,
        config: InstrumentConfig | None = None,
        faults: FaultInjector | None = None,
        sleep: Callable[[float], None] = time.sleep,
        now: Callable[[], float] | None = None,
    ) -> None:
        self.source = source
        self.config = config or InstrumentConfig()
        self.faults = faults or FaultInjector()
        self._sleep = sleep
        # the simulated clock `sleep` runs on: with it and a source that keeps its past
        # (`positions_at`), a reading is of the instant its measuring time ends (`_measure`)
        self._now = now
        # measurements taken and the seconds they took (`processing_s` each): the benches' robot time
        self.measurements = 0
        self.measuring_seconds = 0.0
        self._rng = np.random.default_rng(self.config.seed)
        self._lock = threading.Lock()
        self.precision = 15
        self.locked = True
        self.program = _PROG_CLEAR
        self._stored: tuple[float, float, float] | None = None  # last single-shot distance reading
        self._pointing = (0.0, np.pi / 2)
        # instrument's stored atmosphere: the reference air (≈0 ppm) until a client sets it
        self.atm = (self.config.wavelength_m, 1013.25, 12.0, 12.0)
        self.requests = 0
        self._handlers: dict[int, Callable[[list[str]], tuple[int, list[str]]]] = {
            0: self._null_proc,
            107: self._set_precision,
            108: self._get_precision,
            110: self._geocom_version,
            2008: self._do_measure,
            2028: self._set_atm,
            2029: self._get_atm,
            2082: self._get_coordinate,
            2107: self._get_angle,
            2108: self._get_simple_mea,
            5003: self._instrument_no,
            5004: self._instrument_name,
            5034: self._firmware_version,
            6021: self._lock_status,
            9013: self._lock_in,
            9029: self._search,
            9037: self._fine_adjust,
            17017: self._meas_distance_angle,
        }

    # ------------------------------------------------------------------------------ framing
    def handle_line(self, line: bytes) -> bytes | None:
        """The reply frame (no terminator) to one received line, or None to stay silent."""
        line = line.split(b"\n")[-1]  # a bare LF clears the receive buffer
        start = line.find(b"%R1Q,")
        if start < 0:
            if line.strip():
                log.debug("ignoring line noise %r", line[:60])
            return None
        line = line[start:]
        with_crc = False
        match = _CRC_SUFFIX_RE.search(line)
        if match:
            with_crc = True
            body = line[: match.start()]
            if crc16(body) != int(match.group(1), 16):
                trid = self._peek_trid(body)
                return self._frame(ReturnCode.COM_SRVR_RX_CHECKSUM_ERROR, trid, 0, [], True)
            line = body
        try:
            text = line.decode("ascii")
            req = _REQUEST_RE.match(text)
            if req is None:
                raise ValueError(text)
        except (UnicodeDecodeError, ValueError):
            return self._frame(0, 0, ReturnCode.COM_CANT_DECODE_REQ, [], with_crc)
        rpc, trid = int(req.group(1)), int(req.group(2) or 0)
        try:
            params = list(split_values(req.group(3)))
        except ValueError:
            return self._frame(0, trid, ReturnCode.COM_CANT_DECODE_REQ, [], with_crc)
        handler = self._handlers.get(rpc)
        if handler is None:
            return self._frame(0, trid, ReturnCode.COM_PROC_UNAVAIL, [], with_crc)
        with self._lock:
            self.requests += 1
            try:
                rc, values = handler(params)
            except _BadParamsError:
                rc, values = ReturnCode.IVPARAM, []
        return self._frame(0, trid, rc, values, with_crc)

    @staticmethod
    def _peek_trid(body: bytes) -> int:
        match = re.match(rb"^%R1Q,[0-9]{1,5},([0-9]{1,5}):", body)
        return int(match.group(1)) if match else 0

    @staticmethod
    def _frame(rc_com: int, trid: int, rc: int, values: list[str], with_crc: bool) -> bytes:
        text = f"%R1P,{int(rc_com)},{trid}:{int(rc)}" + "".join("," + v for v in values)
        frame = text.encode("ascii")
        return frame + b";%04X" % crc16(frame) if with_crc else frame

    # ------------------------------------------------------------------------------ helpers
    def _d(self, x: float) -> str:
        return format_double(float(x), self.precision)

    @staticmethod
    def _ints(params: list[str], n: int) -> list[int]:
        if len(params) < n:
            raise _BadParamsError
        try:
            return [decode_int(p) for p in params[:n]]
        except ValueError as exc:
            raise _BadParamsError from exc

    @staticmethod
    def _doubles(params: list[str], n: int) -> list[float]:
        if len(params) < n:
            raise _BadParamsError
        try:
            return [decode_double(p) for p in params[:n]]
        except ValueError as exc:
            raise _BadParamsError from exc

    def _visible(self, at: float | None = None) -> tuple[bool, np.ndarray | None]:
        """One optical check: (beam reaches the SMR, true position). `at`: the simulated instant the
        reading ends, the position then from the source's record (`_measure`)."""
        state = self.source.target()
        position = state.position
        recorded = getattr(self.source, "positions_at", None)
        if at is not None and recorded is not None:
            self._wait_for_record(at)
            position = np.asarray(recorded(np.array([at])), dtype=float).reshape(3)
        if self.faults.beam_broken():
            return False, position
        if not state.visible:
            log.debug("target not visible: %s", state.reason)
        return state.visible, position

    def _wait_for_record(self, at: float) -> None:
        """Wait (a second of wall time at most) until the source has recorded the arm at `at`: its
        controller thread may lag behind the clock on a loaded machine."""
        known = getattr(self.source, "known_until", None)
        deadline = time.monotonic() + RECORD_WAIT_S
        while known is not None and time.monotonic() < deadline:
            newest = known()
            if newest is None or newest >= at:
                return
            time.sleep(0.0005)

    def _reading(self, position: np.ndarray) -> tuple[float, float, float]:
        """A noisy (hz, v, d) of the true position, distance scaled by the atmospheric ppm error."""
        hz, v, d = cartesian_to_polar(position)
        cfg = self.config
        _, p_set, t_set, _ = self.atm
        true_ppm = atmospheric_ppm(cfg.true_temperature_c, cfg.true_pressure_mbar)
        ppm_error = atmospheric_ppm(t_set, p_set) - true_ppm
        d *= 1.0 + ppm_error * 1e-6
        hz, v, d = cfg.noise.perturb(hz, v, d, self._rng)
        self._pointing = (hz, v)
        return hz, v, d

    def _measure(self) -> tuple[int, tuple[float, float, float]]:
        """(rc, (hz, v, d)) for the measuring RPCs, following lock and measurement program."""
        # the reading ends `processing_s` of simulated time after the request arrived, whenever this
        # thread wakes from its sleep: in fast time a late wake-up (a loaded host) would otherwise be
        # simulated time by which the reading comes later after the arm's last move
        at = None if self._now is None else self._now() + self.config.processing_s
        if self.config.processing_s > 0:
            self._sleep(self.config.processing_s)
            self.measuring_seconds += self.config.processing_s  # the instrument's own account
        self.measurements += 1
        visible, position = self._visible(at)
        if not visible:
            self.locked = False
        if not self.locked or position is None:
            return ReturnCode.TMC_DIST_ERROR, (*self._pointing, 0.0)
        reading = self._reading(position)
        if self.program in (_PROG_RTRK, _PROG_RED_TRK):
            return ReturnCode.OK, reading
        if self.program in (_PROG_DEF_DIST, _PROG_DO_MEASURE) and self._stored is not None:
            return ReturnCode.OK, (reading[0], reading[1], self._stored[2])
        return ReturnCode.TMC_ANGLE_OK, (reading[0], reading[1], 0.0)

    # ------------------------------------------------------------------------------ RPCs
    def _null_proc(self, params: list[str]) -> tuple[int, list[str]]:
        return ReturnCode.OK, []

    def _set_precision(self, params: list[str]) -> tuple[int, list[str]]:
        (digits,) = self._ints(params, 1)
        if not 0 <= digits <= 15:
            raise _BadParamsError
        self.precision = digits
        return ReturnCode.OK, []

    def _get_precision(self, params: list[str]) -> tuple[int, list[str]]:
        return ReturnCode.OK, [str(self.precision)]

    def _geocom_version(self, params: list[str]) -> tuple[int, list[str]]:
        return ReturnCode.OK, [str(x) for x in self.config.identity.geocom]

    def _firmware_version(self, params: list[str]) -> tuple[int, list[str]]:
        return ReturnCode.OK, [str(x) for x in self.config.identity.firmware]

    def _instrument_no(self, params: list[str]) -> tuple[int, list[str]]:
        return ReturnCode.OK, [str(self.config.identity.serial_number)]

    def _instrument_name(self, params: list[str]) -> tuple[int, list[str]]:
        return ReturnCode.OK, [quote_string(self.config.identity.name)]

    def _do_measure(self, params: list[str]) -> tuple[int, list[str]]:
        prog, _inc = self._ints(params, 2)
        if prog in (_PROG_STOP, _PROG_CLEAR):
            self.program = prog
            if prog == _PROG_CLEAR:
                self._stored = None
            return ReturnCode.OK, []
        if prog not in (_PROG_DEF_DIST, _PROG_DO_MEASURE, _PROG_RTRK, _PROG_RED_TRK):
            raise _BadParamsError
        self.program = prog
        visible, position = self._visible()
        if visible and self.locked and position is not None:
            self._stored = self._reading(position)
        else:
            self.locked = self.locked and visible
            self._stored = None
        return ReturnCode.OK, []

    def _set_atm(self, params: list[str]) -> tuple[int, list[str]]:
        lam, p, dry, wet = self._doubles(params, 4)
        if not (lam > 0 and 300 < p < 1200 and -40 < dry < 60 and -40 < wet < 60):
            raise _BadParamsError
        self.atm = (lam, p, dry, wet)
        return ReturnCode.OK, []

    def _get_atm(self, params: list[str]) -> tuple[int, list[str]]:
        return ReturnCode.OK, [self._d(x) for x in self.atm]

    def _get_simple_mea(self, params: list[str]) -> tuple[int, list[str]]:
        self._ints(params, 2)
        rc, (hz, v, d) = self._measure()
        return rc, [self._d(hz), self._d(v), self._d(d)]

    def _get_angle(self, params: list[str]) -> tuple[int, list[str]]:
        self._ints(params, 1)
        _, (hz, v, _) = self._measure()
        return ReturnCode.OK, [self._d(hz), self._d(v)]

    def _get_coordinate(self, params: list[str]) -> tuple[int, list[str]]:
        self._ints(params, 2)
        rc, (hz, v, d) = self._measure()
        if rc != ReturnCode.OK:
            e = n = h = 0.0
        else:
            e, n, h = (float(c) for c in polar_to_cartesian(hz, v, d))
        stamp = str(int(time.monotonic() * 1000) % 2**31)
        triple = [self._d(e), self._d(n), self._d(h), stamp]
        return rc, triple + triple

    def _meas_distance_angle(self, params: list[str]) -> tuple[int, list[str]]:
        (mode,) = self._ints(params, 1)
        saved = self.program
        self.program = _PROG_RTRK  # one fresh distance
        rc, (hz, v, d) = self._measure()
        self.program = saved
        return rc, [self._d(hz), self._d(v), self._d(d), str(mode)]

    def _lock_status(self, params: list[str]) -> tuple[int, list[str]]:
        visible, _ = self._visible()
        if not visible:
            self.locked = False
        return ReturnCode.OK, [str(int(self.locked))]

    def _lock_in(self, params: list[str]) -> tuple[int, list[str]]:
        visible, _ = self._visible()
        self.locked = visible
        return (ReturnCode.OK if visible else ReturnCode.AUT_NO_TARGET), []

    def _search(self, params: list[str]) -> tuple[int, list[str]]:
        self._doubles(params, 2)
        visible, position = self._visible()
        if not visible or position is None:
            return ReturnCode.AUT_NO_TARGET, []
        hz, v, _ = cartesian_to_polar(position)
        self._pointing = (hz, v)
        return ReturnCode.OK, []

    def _fine_adjust(self, params: list[str]) -> tuple[int, list[str]]:
        self._doubles(params, 2)
        visible, _ = self._visible()
        return (ReturnCode.OK if visible else ReturnCode.AUT_NO_TARGET), []
