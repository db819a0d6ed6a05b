"""Typed errors of the tracker driver.

Callers (the campaign engine's suspenders, the CLI) decide what to do from the *type* alone: a
`TargetLost` pauses a run until the beam is back, a `LinkError` is worth one retry after the link
resynchronised, a `ConnectionLost` is not. `drivers` never imports `hil`, so these do not derive
from `hil.errors`; the orchestrator maps them.
"""

from __future__ import annotations


class TrackerError(Exception):
    """Base of every error the tracker driver raises on purpose."""


class ConnectionLost(TrackerError):
    """The serial device or socket could not be opened, or vanished (unplugged, closed, EOF)."""


class LinkError(TrackerError):
    """A transient link fault; the protocol layer has already arranged to resynchronise."""


class TrackerTimeout(LinkError):
    """No complete, matching reply arrived before the deadline."""


class GarbledReply(LinkError):
    """A reply line started like GeoCOM but could not be decoded (noise, truncation, bad escapes)."""


class ChecksumError(LinkError):
    """CRC-16 is enabled and the reply's checksum is missing or wrong (GRC_COM_CLNT_RX_CHECKSUM_ERROR)."""


class ProtocolError(TrackerError):
    """The instrument answered with a communication-layer error (RC_COM != 0), e.g. unknown RPC."""

    def __init__(self, message: str, rc_com: int = 0) -> None:
        super().__init__(message)
        self.rc_com = rc_com


class InstrumentError(TrackerError):
    """The instrument ran a command and refused it: `rc` its code, `rpc` the command's number."""

    def __init__(self, message: str, rc: int, rpc: int) -> None:
        super().__init__(message)
        self.rc = rc
        self.rpc = rpc


class GeoComError(InstrumentError):
    """The RPC ran and returned a non-OK return code that is not a lost target."""



class EmsconError(InstrumentError):
    """An emScon command answered a status that is not a lost target (`rc`: ES_ResultStatus,
    `rpc`: ES_Command; the message names both)."""


class TargetLost(GeoComError):
    """No distance to the SMR. GeoCOM: rc 1285/1292/1294/8710/8725 or lock status 0 (no code says "beam
    broken"); emScon: ES_RS_MeasurementStatusNotReady, ES_RS_NoStationaryResult, a failed
    ES_C_FindReflector, or the server's MeasStatus_NotReady event (`rc`/`rpc` then hold the emScon status
    and command)."""


class NotReady(TrackerError):
    """The instrument cannot measure yet: laser warming up, not initialized, sensor not stable."""


class UnstablePoint(TrackerError):
    """The samples of one point spread more than the configured stability threshold."""

    def __init__(self, message: str, spread_m: tuple[float, float, float]) -> None:
        super().__init__(message)
        self.spread_m = spread_m
