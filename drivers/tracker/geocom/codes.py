"""GeoCOM return codes the driver and the simulator use (values from Leica's GeoCOM reference).

Only the codes this project acts on are members; `describe` names any other integer so a log line
never loses the number.
"""

from __future__ import annotations

from enum import IntEnum


class ReturnCode(IntEnum):
    """GeoCOM GRC_* return codes (RPC return codes and communication return codes share one space)."""

    OK = 0
    UNDEFINED = 1
    IVPARAM = 2
    IVRESULT = 3
    FATAL = 4
    NOT_IMPL = 5
    TIME_OUT = 6
    NA = 27
    TMC_NO_FULL_CORRECTION = 1283
    TMC_ACCURACY_GUARANTEE = 1284
    TMC_ANGLE_OK = 1285
    TMC_ANGLE_NOT_FULL_CORR = 1288
    TMC_ANGLE_NO_ACC_GUARANTY = 1289
    TMC_ANGLE_ERROR = 1290
    TMC_DIST_PPM = 1291
    TMC_DIST_ERROR = 1292
    TMC_BUSY = 1293
    TMC_SIGNAL_ERROR = 1294
    MOT_NOT_LOCK = 1799
    COM_CANT_ENCODE = 3073
    COM_CANT_DECODE = 3074
    COM_CANT_SEND = 3075
    COM_CANT_RECV = 3076
    COM_TIMEDOUT = 3077
    COM_WRONG_FORMAT = 3078
    COM_CANT_DECODE_REQ = 3080
    COM_PROC_UNAVAIL = 3081
    COM_CANT_ENCODE_REP = 3082
    COM_SYSTEM_ERR = 3083
    COM_FAILED = 3085
    COM_TR_ID_MISMATCH = 3093
    COM_NOT_GEOCOM = 3094
    COM_SRVR_RX_CHECKSUM_ERROR = 3101
    COM_CLNT_RX_CHECKSUM_ERROR = 3102
    COM_NO_CHECKSUM = 3110
    AUT_TIMEOUT = 8704
    AUT_ANGLE_ERROR = 8706
    AUT_MOTOR_ERROR = 8707
    AUT_NO_TARGET = 8710
    AUT_MULTIPLE_TARGETS = 8711
    AUT_BAD_ENVIRONMENT = 8712
    AUT_NOT_ENABLED = 8714
    AUT_NO_LOCK = 8725


#: Codes whose reply values are valid but flagged (accuracy not guaranteed / not fully corrected).
WARNING_CODES: frozenset[int] = frozenset(
    {ReturnCode.TMC_NO_FULL_CORRECTION, ReturnCode.TMC_ACCURACY_GUARANTEE}
)

#: Codes that mean "no distance to the SMR". GeoCOM has no "beam broken" code; these are it.
TARGET_LOST_CODES: frozenset[int] = frozenset(
    {
        ReturnCode.TMC_ANGLE_OK,
        ReturnCode.TMC_DIST_ERROR,
        ReturnCode.TMC_SIGNAL_ERROR,
        ReturnCode.AUT_NO_TARGET,
        ReturnCode.AUT_NO_LOCK,
        ReturnCode.MOT_NOT_LOCK,
    }
)


def describe(code: int) -> str:
    """``"1292 TMC_DIST_ERROR"`` for known codes, the bare number otherwise."""
    try:
        return f"{code} {ReturnCode(code).name}"
    except ValueError:
        return str(code)
