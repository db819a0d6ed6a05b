"""The physical quantities hil reads, one row each: unit, range, and where the range comes from.

Every number a user gives hil — in a file (measurements CSV, model or truth JSON, station TOML, pose
CSV, URScript, MOVEB program) or on the command line — is checked against the row of the quantity it
is, so one quantity has one range whether it arrives in a file or an option, and the refusal reads the
same everywhere: one line naming the file/line/field or option, the value and the quantity's range,
and, when the value would be in range in a unit people mix up with this one (degrees for radians,
millimetres for metres), that unit. NaN, ±inf and denormal numbers (non-zero, smaller in magnitude than
``sys.float_info.min``: no instrument or person writes 1e-320, a tool that underflowed does) are
refused for every quantity .

Ranges are wide on purpose: they catch unit mistakes and garbage, not unusual but real cells. Each
row says its source (a datasheet, a standard, a driver's own limit) or, where there is none, that it
is an assumption and why that value.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from hil.errors import InputError

#: The smallest normal float; a non-zero number below it in magnitude is a denormal.
SMALLEST_NORMAL = sys.float_info.min

#: Units people type by mistake for a quantity's own unit: words and the factor that turns a value in
#: that unit into the quantity's unit (a radian quantity given 90 "degrees" is 90 × π/180 rad).
DEGREES = ("degrees", math.pi / 180)
MILLIMETRES = ("millimetres", 1e-3)
MICROMETRES = ("micrometres", 1e-6)
MILLISECONDS = ("milliseconds", 1e-3)
GRAMS = ("grams", 1e-3)
UNIT_WORDS = {"rad": "radians", "m": "metres", "s": "seconds", "kg": "kilograms"}


@dataclass(frozen=True)
class Quantity:
    """One physical quantity: its unit, its range, why that range, and the units it is confused with."""

    name: str
    unit: str
    low: float
    high: float
    source: str
    low_open: bool = False
    high_open: bool = False
    integer: bool = False
    confused: tuple[tuple[str, float], ...] = ()

    def span(self) -> str:
        """``(0, 3.14] rad/s``: the range as every message shows it."""
        lo, hi = (str(int(x)) if self.integer or (float(x).is_integer() and abs(x) < 1e15) else f"{x:g}"
                  for x in (self.low, self.high))
        text = f"{'(' if self.low_open else '['}{lo}, {hi}{')' if self.high_open else ']'}"
        return f"{text} {self.unit}" if self.unit else text

    def inside(self, value: float) -> bool:
        """Whether a finite `value` lies in the range (denormals and NaN are judged by `problem`)."""
        above = self.low < value if self.low_open else self.low <= value
        below = value < self.high if self.high_open else value <= self.high
        return above and below

    def problem(self, value: float, shown: str | None = None) -> str | None:
        """Why `value` is not a value of this quantity (None when it is): not finite, a denormal,
        a fraction where a count is meant, or out of range (with the unit it looks typed in)."""
        text = shown if shown is not None else _shown(value)
        unit = UNIT_WORDS.get(self.unit, self.unit)
        note = f"; the value is in {unit}" if self.confused else ""  # a unit people get wrong: say it
        if not math.isfinite(value):
            return f"expected a finite number in {self.span()}, got {text}{note}"
        if value != 0 and abs(value) < SMALLEST_NORMAL:
            return (f"got {text}, a denormal number (non-zero, below {SMALLEST_NORMAL:.3g}), not a physical "
                    f"value; expected a value in {self.span()}{note}")
        if self.integer and not float(value).is_integer():
            return f"must be a whole number in {self.span()}, got {text}"
        if self.inside(value):
            return None
        hint = next((f"; {text} looks like {words}: the value is in {unit}"
                     for words, factor in self.confused if self.inside(value * factor)), note)
        return f"must be in {self.span()}, got {text}{hint}"

    def check(self, value: float, where: str, shown: str | None = None) -> float:
        """`value` when it is one of this quantity; InputError ``where: why`` otherwise."""
        why = self.problem(value, shown)
        if why is not None:
            raise InputError(f"{where}: {why}")
        return value

    def parse(self, text: str, where: str) -> float:
        """`text` (a CSV cell, a TOML or program token, an option) as a checked value."""
        stripped = text.strip()
        try:
            value = float(stripped)
        except ValueError:
            raise InputError(f"{where}: {stripped!r} is not a number ({self.span()})") from None
        return self.check(value, where, stripped)

    def json(self, value: Any, where: str) -> float:
        """A JSON or TOML value as a checked number: `true` and ``"1"`` are not numbers (Python's float
        takes them, but a file holding them was not written by a tool that meant a number)."""
        if isinstance(value, bool) or not isinstance(value, int | float):
            plain = isinstance(value, str | bool) or value is None
            shown = json.dumps(value) if plain else type(value).__name__
            if len(shown) > 40:
                shown = shown[:37] + "..."
            raise InputError(f"{where}: expected a number, got {shown}")
        try:
            number = float(value)
        except OverflowError:  # an integer with hundreds of digits
            raise InputError(f"{where}: expected a finite number, got an integer of "
                             f"{len(str(abs(value)))} digits") from None
        return self.check(number, where)

    def option(self) -> Callable[[str], Any]:
        """This quantity as an argparse ``type``: a one-line usage error naming the option (exit 2)."""

        def parse(text: str) -> Any:
            import argparse

            try:
                value = int(text) if self.integer else float(text)
            except ValueError:
                if self.confused:  # the unit is the likely mistake: say it
                    raise argparse.ArgumentTypeError(
                        f"{text!r} is not a number of {UNIT_WORDS.get(self.unit, self.unit)}") from None
                raise ValueError(text) from None  # argparse's own "invalid float value: 'x'"
            why = self.problem(float(value), text)
            if why is not None:
                raise argparse.ArgumentTypeError(why)
            return value

        parse.__name__ = "int" if self.integer else "float"  # what argparse calls the type
        return parse


def _shown(value: float) -> str:
    return str(int(value)) if float(value).is_integer() and abs(value) < 1e15 else f"{value:g}"


_TURN = 2 * math.pi

#: The table, one row per quantity (name → row). Sources: UR's technical specifications and DH
#: parameter page (universal-robots.com), Leica's AT960 datasheet, ur_rtde's documented limits, ISO 9283.
QUANTITIES: dict[str, Quantity] = {q.name: q for q in (
    # --- geometry of the arm and the cell (metres, radians)
    Quantity("link offset", "m", -1.5, 1.5,
             "UR's DH parameters: the longest link is UR20's upper arm, a2 = -0.862 m; 1.5 m is an "
             "assumption "
             "leaving room for any UR-like arm while a value in millimetres (862) is refused",
             confused=(MILLIMETRES,)),
    Quantity("link angle", "rad", -_TURN, _TURN,
             "an angle is written within one turn either way (hil writes [-π, π]); beyond it is degrees",
             confused=(DEGREES,)),
    Quantity("tool offset", "m", -1.0, 1.0,
             "an SMR, reflector or TCP on a tool: UR's heaviest grippers and tools stay within a metre of "
             "the flange (assumption: half a UR10e's reach)", confused=(MILLIMETRES,)),
    Quantity("tracker position", "m", -80.0, 80.0,
             "Leica's datasheets: the AT403 measures to 160 m diameter and the AT960 to 80 m, the "
             "longest of the trackers hil drives; no coordinate of the tracker or of a point it measures "
             "lies farther", confused=(MILLIMETRES,)),
    Quantity("measured angle", "rad", -_TURN, _TURN,
             "a tracker's Hz and V or a measured frame's roll, pitch, yaw: every form wraps within one turn "
             "either side of zero (a face-II zenith angle reaches 2π); beyond is degrees or gon",
             confused=(DEGREES, ("gon", math.pi / 200))),
    Quantity("tracker distance from the base", "m", 0.0, 21.75,
             "the selector keeps the SMR within the AT960's 0.8-20 m six-DoF range "
             "(selector.candidates.Constraints) and within the arm's reach (1.75 m, UR20) of the base",
             confused=(MILLIMETRES,)),
    Quantity("smr offset", "m", 0.0, 0.5,
             "a nest or a short tool holds the SMR a few centimetres out; half a metre is a tool as long as "
             "a UR5e's upper arm (assumption)", confused=(MILLIMETRES,)),
    Quantity("keep-in corner", "m", -5.0, 5.0,
             "UR20 reaches 1.75 m (UR datasheet); a corner beyond 5 m keeps nothing in (assumption)",
             confused=(MILLIMETRES,)),
    Quantity("cube centre distance", "m", 0.0, 2.0,
             "every UR reaches within 1.75 m (UR20 datasheet); an ISO 9283 cube centre beyond 2 m is mm",
             confused=(MILLIMETRES,)),
    Quantity("cube edge", "m", 0.05, 2.0,
             "ISO 9283's cube fills the used workspace: under 5 cm a tracker's noise hides it, over 2 m "
             "no UR reaches its corners", confused=(MILLIMETRES,)),
    Quantity("target distance", "m", 0.0, 5.0,
             "a compensated target within every UR's reach (UR20: 1.75 m) with room to spare (assumption)",
             confused=(MILLIMETRES,)),
    Quantity("rotation vector angle", "rad", 0.0, _TURN,
             "UR's pose rotation vector (axis × angle): UR writes angles in [0, π]; up to a full turn is "
             "the same rotation, beyond it a value in degrees", confused=(DEGREES,)),
    Quantity("mounting angle", "rad", -_TURN, _TURN,
             "Polyscope's Mounting tilt and rotation as roll, pitch, yaw (a ceiling arm is π): within a "
             "turn; 90 is degrees", confused=(DEGREES,)),
    Quantity("mounting surface height", "m", -5.0, 5.0, "as keep-in corners: beyond 5 m is millimetres",
             confused=(MILLIMETRES,)),
    # --- non-geometric errors and the controller's own calibration (model and truth JSON)
    Quantity("harmonic amplitude", "rad", -1e-2, 1e-2,
             "a joint-angle harmonic: published UR-class joints show tens of µrad "
             "(hil.calibration.synthetic); a hundred times that is the ceiling, beyond it degrees or a "
             "broken file", confused=(DEGREES,)),
    Quantity("lost motion", "rad", -3e-2, 3e-2,
             "Harmonic Drive CSF catalog, hysteresis loss: about 1 arc-min = 2.9e-4 rad is its largest "
             "figure; a hundred times that is the ceiling", confused=(DEGREES,)),
    Quantity("controller angle delta", "rad", -math.pi, math.pi,
             "a UR calibration.conf's delta_theta/delta_alpha: an angle within half a turn (ur_modern_driver "
             "issue #108 shows -0.77 rad)", confused=(DEGREES,)),
    Quantity("controller length delta", "m", -0.1, 0.1,
             "a UR calibration.conf's a and d deltas are physical offsets of millimetres; beyond 10 cm a "
             "unit mistake", confused=(MILLIMETRES,)),
    Quantity("controller parallel d delta", "m", -10_000.0, 10_000.0,
             "the d deltas of UR's parallel joints 2-4 cancel and reach hundreds of metres (ur_modern_driver "
             "issue #108: +232.67 m; ur_calibration's documentation: ~439 m)"),
    Quantity("joint compliance", "rad/Nm", -1e-2, 1e-2,
             "a cobot's strain-wave joint yields about 1e-5 rad/Nm (hil.arm.physical); a thousand times "
             "that folds the arm under its own weight; a fitted value may be slightly negative"),
    Quantity("thermal expansion", "1/K", 0.0, 2e-4,
             "linear expansion coefficients from invar (~1e-6 /K) to plastics (~2e-4 /K); UR links are "
             "aluminium, 2.3e-5 /K"),
    Quantity("temperature rise", "K", 0.0, 60.0,
             "a running arm's joints warm by a few kelvin (hil.arm.thermal); 60 K is the most any motor "
             "housing reaches (assumption)"),
    Quantity("warm-up time constant", "s", 1.0, 86_400.0,
             "a joint's warm-up time constant is ~15 min (hil.arm.thermal); between a second and a day"),
    # --- what the arm carries
    Quantity("payload mass", "kg", 0.0, 100.0,
             "UR's datasheets: the largest rated payload is 30 kg (UR30); a few times that is grams",
             confused=(GRAMS,)),
    Quantity("payload centre of mass", "m", -2.0, 2.0,
             "a payload's centre of mass lies on a tool within reach of the flange (assumption: 2 m, "
             "beyond any UR's rated payload arm)", confused=(MILLIMETRES,)),
    # --- motion
    Quantity("joint speed", "rad/s", 0.0, 3.14,
             "ur_rtde's moveJ: UR_JOINT_VELOCITY_MAX = 3.14 rad/s", low_open=True),
    Quantity("sweep tool speed", "m/s", 0.0, 3.0,
             "UR's datasheets: TCP speed 1 m/s typical, joint limits allow ~3 m/s at the reach's end",
             low_open=True),
    Quantity("joint acceleration", "rad/s²", 0.0, 40.0,
             "ur_rtde's moveJ: UR_JOINT_ACCELERATION_MAX = 40 rad/s²", low_open=True),
    Quantity("approach distance", "rad", 0.0, 0.1,
             "a last leg from below each pose; above 0.1 rad it costs more than any lost motion (a "
             "milliradian at most) warrants", confused=(DEGREES,)),
    # --- noise and thresholds
    Quantity("rms threshold", "m", 0.0, 0.01,
             "a calibrated arm is judged on tenths of a millimetre; above 10 mm is a value in millimetres",
             low_open=True, confused=(MILLIMETRES, MICROMETRES)),
    Quantity("point spread", "m", 0.0, 1e-3,
             "Leica AT960: 15 µm + 6 µm/m MPE; a spread or drift above 1 mm no longer says the SMR was "
             "still, and 10 is micrometres", low_open=True, confused=(MICROMETRES,)),
    Quantity("tracker noise", "m", 0.0, 0.01,
             "a simulated σ per axis: 1 cm is hundreds of times the AT960's 7.5 µm (assumption)",
             confused=(MILLIMETRES, MICROMETRES)),
    Quantity("position noise", "m", 0.0, 0.1,
             "a stated σ per axis of a measured position: a camera on a chessboard ~2 mm "
             "(hil.calibration.pose_identification), a tracker µm; 10 cm measures nothing (assumption)",
             low_open=True, confused=(MILLIMETRES,)),
    Quantity("orientation noise", "rad", 0.0, 0.5,
             "a stated σ per axis of a measured orientation: ~2 mrad for a camera; half a radian "
             "measures nothing (assumption)", low_open=True, confused=(DEGREES,)),
    Quantity("angle noise", "rad", 0.0, 0.01,
             "a simulated σ per joint reading or tracker angle: 10 mrad is thousands of times a UR "
             "encoder's or the AT960's 3 µrad (assumption)"),
    Quantity("encoder noise", "rad", 0.0, 1e-3,
             "a simulated joint reading's σ: a UR's encoders resolve about 1e-5 rad (assumption: a "
             "hundred times that)"),
    Quantity("margin angle", "degrees", 0.0, 90.0,
             "a distance kept from a singularity, as an angle: a right angle leaves no workspace",
             high_open=True),
    Quantity("clearance", "m", 0.0, 1.0,
             "a distance kept from the base axis: a metre is most of a UR's reach (assumption)",
             confused=(MILLIMETRES,)),
    # --- MOVEB paths (millimetres, as MOVEB files are)
    Quantity("path step", "mm", 0.01, 1000.0,
             "a sample spacing along a path: 10 µm is below any arm's repeatability (UR: ±0.03 mm), a "
             "metre skips the path"),
    Quantity("tool speed", "mm/s", 1.0, 3000.0,
             "UR's datasheets: TCP speed 1 m/s typical, joint limits allow ~3 m/s at the reach's end"),
    Quantity("tool acceleration", "mm/s²", 1.0, 150_000.0,
             "UR's TCP acceleration limit in Polyscope is 150 m/s² (assumption: the safety setting's top)"),
    Quantity("tool jerk", "mm/s³", 1.0, 1e8, "a jerk limit beyond 1e5 m/s³ is no limit (assumption)"),
    Quantity("program coordinate", "mm", -5000.0, 5000.0,
             "a MOVEB point within 5 m of the base: UR20 reaches 1.75 m (UR datasheet), so beyond is a unit "
             "mistake or a corrupted file, and planning toward it allocates kilometres of samples"),
    Quantity("path tolerance", "mm", 1e-4, 100.0,
             "a MOVEB D or E: below 0.1 µm no arm or tracker resolves the difference (AT960: 15 µm MPE), "
             "above 100 mm it is larger than the parts a UR handles"),
    # --- rates
    Quantity("tracker rate", "Hz", 0.0, 1000.0,
             "Leica AT960 datasheet: output rate up to 1000 points per second", low_open=True),
    Quantity("controller rate", "Hz", 1.0, 1000.0,
             "UR e-Series controllers run at 500 Hz, CB3 at 125 Hz; 1 kHz bounds any arm hil drives"),
    # --- time
    Quantity("settle time", "s", 0.0, 60.0,
             "a UR is steady within a fraction of a second of arriving; a minute is milliseconds",
             confused=(MILLISECONDS,)),
    Quantity("settle limit", "s", 0.0, 60.0,
             "a UR's ring dies out within a second or two (mocks.ringing); a minute is a fault",
             low_open=True, confused=(MILLISECONDS,)),
    Quantity("reply timeout", "s", 0.0, 300.0,
             "a GeoCOM/emScon reply takes milliseconds, a search seconds: beyond 5 min a dead link hides",
             low_open=True, confused=(MILLISECONDS,)),
    Quantity("measure time", "s", 0.0, 60.0,
             "emScon stationary measurement: a fraction of a second to a few seconds", low_open=True,
             confused=(MILLISECONDS,)),
    Quantity("laser warm-up", "s", 0.0, 7200.0,
             "a cold AT9xx laser is ready within minutes; two hours is a fault", confused=(MILLISECONDS,)),
    Quantity("time budget", "s", 0.0, 86_400.0, "a campaign's robot time: a day is milliseconds",
             low_open=True, confused=(MILLISECONDS,)),
    Quantity("search time", "s", 0.0, 3600.0,
             "bench/cycle_time.py: the robot time still falls ~1 % from 10 to 20 s of search; an hour is "
             "a value in the wrong unit", low_open=True, confused=(MILLISECONDS,)),
    Quantity("dwell", "s", 0.0, 120.0, "a pose's measuring dwell: two minutes is milliseconds",
             confused=(MILLISECONDS,)),
    Quantity("warm-up interval", "s", 10.0, 3600.0,
             "a joint's warm-up time constant is ~15 min (hil.arm.thermal): 2 min gives 7 points each",
             confused=(MILLISECONDS,)),
    Quantity("warm-up time", "s", 10.0, 4 * 3600.0,
             "the warm-up fit is trusted after three time constants (45 min for a UR)",
             confused=(MILLISECONDS,)),
    Quantity("short timeout", "s", 0.0, 600.0, "connecting or measuring: ten minutes is a dead device",
             low_open=True, confused=(MILLISECONDS,)),
    Quantity("move timeout", "s", 0.0, 3600.0,
             "the longest UR move (half a turn at 0.01 rad/s) takes about five minutes", low_open=True,
             confused=(MILLISECONDS,)),
    Quantity("operator timeout", "s", 0.0, 8 * 3600.0,
             "an operator clearing a stop, a database restarted: at most a shift (8 h)", low_open=True,
             confused=(MILLISECONDS,)),
    # --- the air the tracker measures in
    Quantity("air temperature", "°C", -20.0, 50.0,
             "Leica's trackers operate within -15..+45 °C (AT403, the widest)"),
    Quantity("air pressure", "hPa", 500.0, 1100.0,
             "at most 5500 m above sea level (about 500 hPa); the sea-level record is 1084 hPa"),
    Quantity("relative humidity", "%", 0.0, 100.0, "relative humidity is a percentage"),
    Quantity("acceptance angle", "degrees", 0.0, 90.0,
             "an SMR's acceptance half-angle (Leica's 1.5\" RRR: ±30°); 90° would be a flat mirror",
             low_open=True, high_open=True),
    # --- dimensionless
    Quantity("fraction", "", 0.0, 1.0, "a fraction of a whole (a margin, a speed slider)",
             low_open=True),
    Quantity("fraction or none", "", 0.0, 1.0, "a fraction of a whole, 0 allowed"),
    Quantity("simulated speed", "", 0.0, 1000.0,
             "the simulated controller's 500 Hz loop on the real clock: at 1000 one tick is 2 s",
             low_open=True),
    Quantity("sigmas", "σ", 0.0, 1000.0, "an outlier threshold in standard deviations", low_open=True),
    # --- counts
    Quantity("pose count", "", 1, 1000,
             "at ~10 s a pose 1000 are a day of measuring (Nubiola & Bonev validate on 1000)",
             integer=True),
    Quantity("pose count or none", "", 0, 1000, "as pose count, 0 for none", integer=True),
    Quantity("bootstrap poses", "", 4, 8, "the bootstrap has 8 arm moves and makes at least 4",
             integer=True),
    Quantity("samples", "", 1, 100, "tracker samples per point: 100 already averages the noise away",
             integer=True),
    Quantity("joint samples", "", 1, 1000, "RTDE at 500 Hz: 1000 readings are 2 s per pose", integer=True),
    Quantity("candidates", "", 1, 200_000,
             "each candidate keeps a 3 x n Jacobian (~650 bytes): 200 000 are ~130 MB", integer=True),
    Quantity("seed", "", 0, 2**32 - 1, "numpy takes non-negative seeds; 32 bits tell runs apart",
             integer=True),
    Quantity("baud rate", "baud", 300, 921_600,
             "GeoCOM instruments run at 2400-115200 baud, USB adapters up to 921600", integer=True),
    Quantity("cycles", "", 2, 100, "ISO 9283 §7.2: 30 cycles; S_l needs 2", integer=True),
    Quantity("visits", "", 1, 100,
             "visits of a validation pose: ISO 9283 repeats a pose 30 times, a million was a week",
             integer=True),
    Quantity("synthetic poses", "", 1, 100_000,
             "a synthetic table: ten times the rows hil reads (hil.files.inputs.MAX_TABLE_ROWS)",
             integer=True),
    Quantity("synthetic poses or none", "", 0, 100_000, "as synthetic poses, 0 for none", integer=True),
    Quantity("listed rows", "", 1, 1_000_000, "rows a listing prints: a million is the whole store",
             integer=True),
    Quantity("tcp port", "", 0, 65_535, "a TCP port (RFC 793: 16 bits); 0 lets the system choose",
             integer=True),
    Quantity("lost in a row", "", 1, 100, "poses in a row that lose the beam: 100 is a day lost",
             integer=True),
)}


def quantity(name: str) -> Quantity:
    """The row of `name` (KeyError for a name not in the table: a programming error)."""
    return QUANTITIES[name]


def real(value: float, where: str, shown: str | None = None) -> float:
    """`value` when it is a real number (finite, not a denormal), whatever its quantity: the part of
    every row's check that holds for a component of a vector whose length is the quantity."""
    text = shown if shown is not None else _shown(value)
    if not math.isfinite(value):
        raise InputError(f"{where}: expected a finite number, got {text}")
    if value != 0 and abs(value) < SMALLEST_NORMAL:
        raise InputError(f"{where}: got {text}, a denormal number (non-zero, below {SMALLEST_NORMAL:.3g}), "
                         "not a physical value")
    return value


def check_vector(values: Sequence[float], name: str, where: str, *, norm: bool = False) -> tuple[float, ...]:
    """A vector of quantity `name`: every component a real number (finite, not a denormal) and each
    within the range, or (``norm=True``) its Euclidean length within it (a distance, a rotation angle)."""
    row = QUANTITIES[name]
    if not norm:
        return tuple(row.check(float(v), f"{where}[{i}]") for i, v in enumerate(values))
    out = tuple(real(float(v), f"{where}[{i}]") for i, v in enumerate(values))
    why = row.problem(math.hypot(*out))
    if why is not None:
        raise InputError(f"{where}: its length ({row.name}) {why}")
    return out
