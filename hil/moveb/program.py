"""MOVEB programs: one ``MOVEB X Y Z I J K U V W D E`` per line, parsed and validated.

Units are millimetres for X Y Z D E (docs/design.md, Contracts: MOVEB files); I J K is the unit tool
Z axis and U V W the unit tool
X axis, both in the robot base frame. ``#`` starts a comment, blank lines are ignored, the keyword is
case-insensitive. Every problem raises `InputError` naming the file and line, so the CLI prints one
line and exits 2.

Choices the seed leaves open, and why:

* Unit length and orthogonality are checked to ``AXIS_TOLERANCE`` (1e-3): programs written by hand or
  exported with 4–6 decimals must pass, a typo (a swapped sign, a missing digit) must not.
* Two consecutive points closer than ``MIN_SEGMENT`` (1 µm) are refused: a zero-length segment has
  no direction, so neither the bridge of its corner nor the tool-axis interpolation is defined.
* Coordinates beyond ``MAX_COORDINATE`` (5 m) of the base are refused: the largest UR reaches 1.75 m,
  so such a point is a unit mistake (metres for millimetres read the other way) or a corrupted file,
  and planning toward it would allocate samples for kilometres of path.
* D and E must lie in [``MIN_TOLERANCE``, ``MAX_TOLERANCE``] (0.1 µm to 100 mm): below the first no
  arm or tracker resolves the difference, above the second a "tolerance" is larger than the parts a
  UR handles and the path it allows has nothing to do with the program.
* A turn of more than ``MAX_TURN_DEG`` (179°) is refused: at a reversal the bridge degenerates to a
  cusp (the two Bezier halves meet head-on) and no error-bounded smooth path exists; the user must
  split the program there.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass

import numpy as np

from hil.errors import InputError
from hil.files.inputs import read_input_text
from hil.files.quantities import quantity, real

AXIS_TOLERANCE = 1e-3
MIN_SEGMENT = 1e-3  # mm
MAX_TURN_DEG = 179.0
#: The quantity of each field (rows of `hil.files.quantities`, where the ranges and their reasons are);
#: the axis components I J K U V W are only real numbers here: their quantity is the axis's unit
#: length, checked below.
FIELD_QUANTITY = {"X": "program coordinate", "Y": "program coordinate", "Z": "program coordinate",
                  "D": "path tolerance", "E": "path tolerance"}
FIELD_LABEL = {"D": "D (chord-height error)", "E": "E (point error)"}
MAX_COORDINATE = quantity("program coordinate").high  # mm, |X|, |Y|, |Z|
MIN_TOLERANCE = quantity("path tolerance").low  # mm, D and E
MAX_TOLERANCE = quantity("path tolerance").high  # mm, D and E
KEYWORD = "MOVEB"
FIELDS = ("X", "Y", "Z", "I", "J", "K", "U", "V", "W", "D", "E")


@dataclass(frozen=True)
class MovebPoint:
    """One program line: position (mm), tool Z and X axes (unit), thresholds D and E (mm)."""

    line: int
    position: np.ndarray
    z_axis: np.ndarray
    x_axis: np.ndarray
    d: float
    e: float


@dataclass(frozen=True)
class Program:
    """A validated MOVEB program (at least two points)."""

    points: tuple[MovebPoint, ...]
    source: str = "<program>"

    @property
    def positions(self) -> np.ndarray:
        """(N, 3) positions in mm."""
        return np.array([p.position for p in self.points])

    @property
    def z_axes(self) -> np.ndarray:
        return np.array([p.z_axis for p in self.points])

    @property
    def x_axes(self) -> np.ndarray:
        return np.array([p.x_axis for p in self.points])

    @property
    def d(self) -> np.ndarray:
        return np.array([p.d for p in self.points])

    @property
    def e(self) -> np.ndarray:
        return np.array([p.e for p in self.points])

    @property
    def lines(self) -> np.ndarray:
        return np.array([p.line for p in self.points])

    def groups(self) -> list[range]:
        """Index ranges of consecutive points with equal D and E (the seed's interpolation groups)."""
        out: list[range] = []
        start = 0
        for i in range(1, len(self.points) + 1):
            if i == len(self.points) or (self.points[i].d, self.points[i].e) != (
                    self.points[start].d, self.points[start].e):
                out.append(range(start, i))
                start = i
        return out


def _value(name: str, word: str, where: str) -> float:
    """One field of a MOVEB line: its quantity's row for X Y Z D E, a real number for an axis component."""
    label = f"{where}: {FIELD_LABEL.get(name, name)}"
    if name in FIELD_QUANTITY:
        return quantity(FIELD_QUANTITY[name]).parse(word, label)
    try:
        value = float(word)
    except ValueError:
        raise InputError(f"{label}: {word!r} is not a number") from None
    return real(value, label, word)


def _fail(source: str, line: int, message: str) -> InputError:
    return InputError(f"{source}: line {line}: {message}")


def parse_program(text: str, source: str = "<program>") -> Program:
    """Parse and validate program text; InputError naming the line on the first problem."""
    points: list[MovebPoint] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        content = raw.split("#", 1)[0].strip()
        if not content:
            continue
        words = content.split()
        if words[0].upper() != KEYWORD:
            raise _fail(source, number, f"expected {KEYWORD} X Y Z I J K U V W D E, got {words[0]!r}")
        if len(words) != 1 + len(FIELDS):
            raise _fail(source, number, f"{KEYWORD} needs {len(FIELDS)} numbers "
                                        f"({' '.join(FIELDS)}), got {len(words) - 1}")
        where = f"{source}: line {number}"
        values = [_value(name, word, where) for name, word in zip(FIELDS, words[1:], strict=True)]
        position = np.array(values[0:3])
        z, x = np.array(values[3:6]), np.array(values[6:9])
        d, e = values[9], values[10]
        for name, axis in (("I J K", z), ("U V W", x)):
            if abs(float(np.linalg.norm(axis)) - 1.0) > AXIS_TOLERANCE:
                raise _fail(source, number, f"the tool axis {name} must have unit length, "
                                            f"got length {np.linalg.norm(axis):.6g}")
        if abs(float(z @ x)) > AXIS_TOLERANCE:
            raise _fail(source, number, f"the tool axes I J K and U V W must be orthogonal, "
                                        f"got a dot product of {z @ x:.6g}")
        if points and np.linalg.norm(position - points[-1].position) < MIN_SEGMENT:
            raise _fail(source, number, f"the point repeats the previous one (line {points[-1].line}); "
                                        "a zero-length segment has no direction")
        if len(points) >= 2:
            a = points[-1].position - points[-2].position
            b = position - points[-1].position
            cos = float(a @ b / (np.linalg.norm(a) * np.linalg.norm(b)))
            if math.degrees(math.acos(max(-1.0, min(1.0, cos)))) > MAX_TURN_DEG:
                raise _fail(source, points[-1].line, f"the path reverses here (turn above "
                                                     f"{MAX_TURN_DEG:g}°), which cannot be blended; "
                                                     "split the program at this point")
        points.append(MovebPoint(number, position, z / np.linalg.norm(z), x / np.linalg.norm(x), d, e))
    if len(points) < 2:
        raise InputError(f"{source}: a MOVEB program needs at least two points, got {len(points)}")
    return Program(tuple(points), source)


def load_program(path: str | os.PathLike[str]) -> Program:
    """Read and validate a program file (InputError naming the file when it cannot be read)."""
    return parse_program(read_input_text(path, "a MOVEB program"), str(path))


def format_program(positions: np.ndarray, z_axes: np.ndarray, x_axes: np.ndarray,
                   d: float | np.ndarray, e: float | np.ndarray) -> str:
    """Program text for arrays of points (examples, benchmarks, tests)."""
    n = len(positions)
    d = np.broadcast_to(np.asarray(d, float), (n,))
    e = np.broadcast_to(np.asarray(e, float), (n,))
    rows = []
    for i in range(n):
        nums = [*positions[i], *z_axes[i], *x_axes[i], d[i], e[i]]
        rows.append(f"{KEYWORD} " + " ".join(f"{v:.9g}" for v in nums))
    return "\n".join(rows) + "\n"
