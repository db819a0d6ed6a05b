"""The command line's option types and parsers, shared by the subcommands: every number in a physical
range, every count and seed bounded, so bad input is one usage line (exit 2) before anything runs."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from hil.errors import InputError

if TYPE_CHECKING:
    import numpy as np


def triplet_or_none(text: str | None, option: str, *, max_length: float | None = None,
                    where: str = "") -> np.ndarray | None:
    """An optional "X,Y,Z" option as a vector (InputError naming the option when malformed, or longer
    than `max_length` metres: a position `where`, e.g. "of the flange")."""
    import math

    from hil.arm.geometry import parse_triplet  # pinocchio: not for commands that only print help

    if text is None:
        return None
    vector = parse_triplet(text, option)
    if max_length is not None and math.hypot(*vector) > max_length:
        raise InputError(f"{option}: must be within {max_length:g} m {where}, got {math.hypot(*vector):g} m "
                         "away (the value is in metres)")
    return vector


PAYLOAD_HELP = ("what the arm carries: MASS (kg) or MASS,X,Y,Z with its centre of mass in the flange frame "
                "(m); 0 for nothing")


def payload_or_none(text: str | None, option: str = "--payload") -> Any:
    """An optional ``--payload MASS[,X,Y,Z]`` as a `hil.arm.payload.Payload` (InputError naming the
    option when malformed); ``0`` is an empty flange."""
    from hil.arm.payload import Payload

    if text is None:
        return None
    parts = [p.strip() for p in str(text).split(",")]
    try:
        values = [float(p) for p in parts]
    except ValueError:
        raise InputError(f"{option}: expected MASS or MASS,X,Y,Z (kg, m), got {text!r}") from None
    if len(values) not in (1, 4):
        raise InputError(f"{option}: expected MASS or MASS,X,Y,Z (kg, m), got {len(values)} numbers")
    com = values[1:] if len(values) == 4 else [0.0, 0.0, 0.0]
    return Payload.from_dict({"mass": values[0], "com": com}, option)


#: ``--joint-units``: the unit of joint columns whose names carry no unit suffix (docs/design.md, Contracts:
#: Measurements CSV). Declared, never guessed from the values.
JOINT_UNITS: tuple[str, ...] = ("rad", "deg")
JOINT_UNITS_HELP = ("unit of the joint columns whose names carry no unit suffix (default rad; a header "
                    "q1_deg..q6_deg declares degrees itself)")


def add_joint_units(parser: Any) -> None:
    """The ``--joint-units rad|deg`` option of every command that reads joint angles from a CSV."""
    parser.add_argument("--joint-units", choices=JOINT_UNITS, default=None, help=JOINT_UNITS_HELP)


#: Largest plausible RMS acceptance threshold (m): a calibrated arm is judged on tenths of a millimetre,
#: so a larger value is a threshold typed in millimetres (``--accept 0.1`` would pass at 100 mm).
MAX_RMS_THRESHOLD = 0.01
RMS_THRESHOLD_HELP = "in METRES, e.g. 0.0001 for 0.1 mm, at most 0.01 = 10 mm"


def rms_threshold(text: str) -> float:
    """argparse ``type`` of an RMS acceptance threshold in metres (``--accept``, ``--max-rms``):
    a positive finite number up to `MAX_RMS_THRESHOLD`; anything else is a one-line usage error."""
    import argparse
    import math

    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number of metres") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"must be a positive number of metres, got {text}")
    if value > MAX_RMS_THRESHOLD:
        raise argparse.ArgumentTypeError(
            f"{text} m ({value * 1e3:g} mm) is not a plausible RMS threshold: the value is in metres "
            f"and at most {MAX_RMS_THRESHOLD:g} ({MAX_RMS_THRESHOLD * 1e3:g} mm); for 0.1 mm give 0.0001")
    return value


def _span(lo: float, hi: float, lo_open: bool, hi_open: bool, unit: str) -> str:
    """``(0, 100] rad/s``: the allowed range as the error message shows it."""
    lo_text, hi_text = (str(x) if isinstance(x, int) else f"{x:g}" for x in (lo, hi))  # seeds: no 4.3e+09
    span = f"{'(' if lo_open else '['}{lo_text}, {hi_text}{')' if hi_open else ']'}"
    return span + (f" {unit}" if unit else "")


def finite_float(lo: float, hi: float, unit: str = "", *, lo_open: bool = False,
                 hi_open: bool = False) -> Callable[[str], float]:
    """argparse ``type`` of a number in a physical range: NaN, infinities and values outside it are a
    one-line usage error naming the option and the range (exit 2), before anything runs. A bare
    ``type=float`` lets ``inf`` hang a loop and ``1e30`` ask numpy for terabytes (exit 70)."""

    def parse(text: str) -> float:
        import argparse
        import math

        value = float(text)  # ValueError: argparse's own "invalid float value: 'x'"
        inside = (math.isfinite(value) and (lo < value if lo_open else lo <= value)
                  and (value < hi if hi_open else value <= hi))
        if not inside:
            span = _span(lo, hi, lo_open, hi_open, unit)
            raise argparse.ArgumentTypeError(f"must be in {span}, got {text}")
        return value

    parse.__name__ = "float"  # what argparse calls the type in its own messages
    return parse


def bounded_int(lo: int, hi: int, unit: str = "") -> Callable[[str], int]:
    """argparse ``type`` of a whole number in ``[lo, hi]`` (one-line usage error otherwise): counts and
    seeds that would exhaust memory (``--candidates 1e9``) or that numpy refuses (``--seed -1``) are bad
    input, refused before anything starts, not an internal error halfway through."""

    def parse(text: str) -> int:
        import argparse

        value = int(text)  # ValueError: argparse's own "invalid int value: '1.5'"
        if not lo <= value <= hi:
            raise argparse.ArgumentTypeError(f"must be in {_span(lo, hi, False, False, unit)}, got {text}")
        return value

    parse.__name__ = "int"
    return parse


#: Random seeds: numpy's generators take any non-negative integer, and 32 bits are all a seed needs to
#: tell runs apart (``--seed -1`` made numpy raise deep inside the simulator: exit 70).
SEED = bounded_int(0, 2**32 - 1)

#: Fast-time factor of the simulated station (``--speed``): the simulated controller runs its 500 Hz
#: loop on the real clock, so at 1000 one 2 ms tick is already 2 simulated seconds, about one move
#: between poses (a campaign still passes there); beyond, moves happen between ticks. ``inf`` hung
#: ``hil calibrate --sim`` and 0 or NaN stop simulated time.
SIM_SPEED = finite_float(0, 1000, lo_open=True)

#: Poses of a campaign or a selection (``--poses``, ``--validation``, ``--count``): at ~10 s a pose,
#: 1000 poses are a day of measuring, ten times any calibration in the literature (Nubiola & Bonev use
#: 1000 only to *validate*); the configuration's ``campaign.*_poses`` keys have the same ceiling.
POSE_COUNT = bounded_int(1, 1000)

#: Visits of each validation pose (``--cycles``): ISO 9283 measures pose repeatability over 30 cycles;
#: a hundred is more than any acceptance test asks, and a million was a week of motion.
CYCLES = bounded_int(1, 100)

#: Cycles of the ISO 9283 pose test (``hil verify --cycles``, ``hil calibrate --verify-cycles``):
#: repeatability's S_l divides by n − 1, so two at least; the standard's 30 is the default.
VERIFY_CYCLES = bounded_int(2, 100)

#: Candidate configurations for the selector (``--candidates``): each keeps a 3 x n Jacobian (~650
#: bytes), so 200 000 are ~130 MB and a few minutes of drawing; 1e9 asked numpy for 107 GiB (exit 70).
#: Same ceiling as the configuration's ``campaign.candidates`` (`hil.station.config.MAX_CANDIDATES`).
MAX_CANDIDATES = 200_000
CANDIDATES = bounded_int(1, MAX_CANDIDATES)
