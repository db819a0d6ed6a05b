"""The column forms a measurements or joints CSV may take, read into SI arrays (docs/design.md,
Contracts: Measurements CSV).

Real instruments and the software around them do not all write ``q1..q6,x,y,z`` in radians and metres:
a controller log has joints in degrees, a ROS bag the URDF's joint names, a Leica tracker's software
polar readings (horizontal angle, zenith angle, slope distance), a camera or a 6-DoF probe an
orientation beside the position, FIGAROH several markers per pose (``x1,y1,z1,x2,…``). The header says
which: every column is recognised by its name, and an angle or a length by the unit suffix on that name
(``q1_deg``, ``hz_gon``, ``d_mm``). Nothing is guessed from the values: a radian column that holds
degrees is refused by the joint-limit check, with a hint about declaring degrees.

A header has exactly one joint form and, for a measurements file, exactly one position form and at most
one orientation form; two complete forms of one kind (``x,y,z`` beside ``hz,v,d``) are refused rather
than one of them silently preferred. Columns that belong to no form are ignored, as before.

Every problem is an `InputError` naming the file, the line and the column, in one line.
"""

from __future__ import annotations

import hashlib
import math
import os
import re
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from hil.arm.catalog import ROBOT_NAMES, get_robot
from hil.errors import InputError
from hil.files.inputs import csv_rows, decode_input_text, read_input_bytes
from hil.files.quantities import quantity, real

#: Farthest a laser tracker measures (m): the "tracker position" row of `hil.files.quantities` (the
#: Leica AT960's 80 m). A coordinate beyond it is a unit mistake or a corrupted file. The table's rows
#: set these limits; the checks below apply them to whole columns at once.
TRACKER_RANGE = quantity("tracker position").high
#: How far (rad) a joint reading may lie beyond the joint limits before it is refused: readings at a
#: limit overshoot it by encoder noise at most, so anything past this was not read from a UR arm.
JOINT_LIMIT_MARGIN = 0.1
#: How far a unit quaternion's norm may stray from 1 (a file's rounding to 6 digits moves it by ~1e-6;
#: 1e-3 leaves room for 4-digit files). Beyond it the four numbers are not a rotation.
QUATERNION_NORM_TOLERANCE = 1e-3
#: Largest magnitude (rad) an angle other than a joint's may have: every form here wraps within one
#: turn either side of zero (a zenith angle in face II reaches 2π), so a larger value is in degrees or
#: gon with no suffix saying so.
ANGLE_RANGE = quantity("measured angle").high

#: Unit suffixes (``q1_deg``) and their factor to SI; a column without a suffix is in SI (rad, m).
ANGLE_UNITS: dict[str, float] = {"rad": 1.0, "deg": math.pi / 180.0, "gon": math.pi / 200.0}
LENGTH_UNITS: dict[str, float] = {"m": 1.0, "mm": 1e-3}

JOINT_NAMES: tuple[str, ...] = ("q1", "q2", "q3", "q4", "q5", "q6")
#: The joint names of UR's URDF (Universal_Robots_ROS2_Description, ur_macro.xacro), which ROS tools
#: and FIGAROH write as column names.
URDF_JOINT_NAMES: tuple[str, ...] = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                     "wrist_1_joint", "wrist_2_joint", "wrist_3_joint")


@dataclass(frozen=True)
class Form:
    """One way of writing a quantity: its column names (lower case, without unit suffix), what each
    holds ("angle", "length" or "number"), and how it is named in messages."""

    kind: str  # "joint", "position" or "orientation"
    name: str
    columns: tuple[str, ...]
    quantities: tuple[str, ...]

    @property
    def shown(self) -> str:
        return ",".join(self.columns)


JOINT_FORMS: tuple[Form, ...] = (
    Form("joint", "q1..q6", JOINT_NAMES, ("angle",) * 6),
    Form("joint", "URDF joint names", URDF_JOINT_NAMES, ("angle",) * 6),
)
CARTESIAN = Form("position", "Cartesian", ("x", "y", "z"), ("length",) * 3)
MARKERS = Form("position", "markers (FIGAROH)", ("x1", "y1", "z1"), ("length",) * 3)
#: Leica's polar reading: Hz (horizontal angle, clockwise), V (zenith angle), slope distance; GeoCOM's
#: TMC_GetSimpleMea and emScon's spherical clockwise system (ES_CS_SCW) report these three.
POLAR = Form("position", "polar", ("hz", "v", "d"), ("angle", "angle", "length"))
POSITION_FORMS: tuple[Form, ...] = (CARTESIAN, MARKERS, POLAR)
RPY = Form("orientation", "roll-pitch-yaw", ("roll", "pitch", "yaw"), ("angle",) * 3)
RPY_FIGAROH = Form("orientation", "FIGAROH roll-pitch-yaw", ("phix1", "phiy1", "phiz1"), ("angle",) * 3)
ROTATION_VECTOR = Form("orientation", "rotation vector", ("rx", "ry", "rz"), ("angle",) * 3)
QUATERNION = Form("orientation", "quaternion", ("qw", "qx", "qy", "qz"), ("number",) * 4)
ORIENTATION_FORMS: tuple[Form, ...] = (RPY, RPY_FIGAROH, ROTATION_VECTOR, QUATERNION)
#: Optional: the sign of each joint's last motion before the reading (−1, 0, +1), which lost motion
#: needs (`hil.arm.joint_errors`); all six or none.
DIRECTIONS = Form("direction", "directions", ("d1", "d2", "d3", "d4", "d5", "d6"), ("number",) * 6)

_UNITS = {"angle": ANGLE_UNITS, "length": LENGTH_UNITS, "number": {}}
_SUFFIX = re.compile(r"^(?P<base>.+)_(?P<unit>rad|deg|gon|mm|m)$")
_MARKER = re.compile(r"^(?P<axis>[xyz])(?P<k>[1-9][0-9]*)$")
#: A joint column of an arm with any number of joints (an arm from its URDF): q1..qN.
_JOINT = re.compile(r"^q(?P<k>[1-9][0-9]*)$")


def _quantity_of(base: str) -> str | None:
    """What a known column holds, or None for a column no form uses (ignored)."""
    for form in (*JOINT_FORMS, *POSITION_FORMS, *ORIENTATION_FORMS, DIRECTIONS):
        if base in form.columns:
            return form.quantities[form.columns.index(base)]
    if _MARKER.match(base):
        return "length"
    if _JOINT.match(base):
        return "angle"  # q7.. of an arm from its URDF (a prismatic joint's metres are read as written)
    return None


def _joint_ranges() -> list[tuple[float, float]]:
    """The plausible range (rad) of each joint: what any catalog arm's limits allow, plus
    `JOINT_LIMIT_MARGIN`, because a file does not say which arm it came from."""
    specs = [get_robot(n) for n in ROBOT_NAMES]
    return [(float(min(s.lower[j] for s in specs)) - JOINT_LIMIT_MARGIN,
             float(max(s.upper[j] for s in specs)) + JOINT_LIMIT_MARGIN) for j in range(6)]


JOINT_RANGES = _joint_ranges()


@dataclass(frozen=True)
class Column:
    """A header cell hil knows: where it is, its label as written, and its unit."""

    index: int
    label: str
    unit: str  # "rad", "deg", "gon", "m", "mm" or "" (a number)
    declared: bool  # the label carries the unit suffix

    @property
    def factor(self) -> float:
        return {**ANGLE_UNITS, **LENGTH_UNITS}.get(self.unit, 1.0)


@dataclass(frozen=True)
class Header:
    """A CSV's header line, read: the known columns by their base name (lower case)."""

    source: str
    line: int
    width: int
    columns: dict[str, Column]

    def where(self, text: str) -> str:
        return f"{self.source}: line {self.line}: {text}"


@dataclass(frozen=True)
class Rows:
    """A CSV's data: its header and its rows (fields as text) with their line numbers."""

    header: Header
    rows: list[tuple[int, list[str]]]
    sha256: str


def read_rows(path: str | os.PathLike[str]) -> Rows:
    """The header and data rows of a CSV file (comments and blank lines dropped), and its sha256."""
    name = str(path)
    raw = read_input_bytes(path, "a CSV file")
    text = decode_input_text(raw, name, "a CSV file")
    rows = [(n, row) for n, row in csv_rows(text, name)
            if row and any(c.strip() for c in row) and not row[0].lstrip().startswith("#")]
    if not rows:
        raise InputError(f"{name}: empty file, expected a header naming the joints and the positions "
                         f"(q1,q2,q3,q4,q5,q6,x,y,z)")
    line, cells = rows[0]
    return Rows(parse_header(name, line, cells), rows[1:], hashlib.sha256(raw).hexdigest())


def parse_header(source: str, line: int, cells: Sequence[str]) -> Header:
    """The known columns of a header line; two cells naming one column (``q1`` and ``Q1_deg``) are
    refused, since either could be the one meant."""
    found: dict[str, Column] = {}
    twice: list[str] = []
    for i, cell in enumerate(cells):
        label = cell.strip()
        key = label.lower()
        m = _SUFFIX.match(key)
        base, unit, declared = (m["base"], m["unit"], True) if m else (key, "", False)
        quantity = _quantity_of(base)
        if quantity is None or (declared and unit not in _UNITS[quantity]):
            continue  # a column no form uses (or a unit that does not fit it): ignored
        if not declared:
            unit = {"angle": "rad", "length": "m", "number": ""}[quantity]
        if base in found:
            twice.append(base)
            continue
        found[base] = Column(i, label, unit, declared)
    if twice:
        raise InputError(f"{source}: line {line}: column(s) {', '.join(sorted(set(twice)))} appear twice")
    return Header(source, line, len(cells), found)


def choose(header: Header, forms: Sequence[Form], *, required: bool, expected: str) -> Form | None:
    """The one form of `forms` whose columns the header has all of.

    None when no column of any form is there and the kind is optional; an error naming what is missing
    when a form is there in part, naming both when two are complete, naming `expected` when a required
    kind is absent.
    """
    present = header.columns
    complete = [f for f in forms if all(c in present for c in f.columns)]
    if len(complete) > 1:
        a, b = complete[0], complete[1]
        raise InputError(header.where(f"both {a.name} ({a.shown}) and {b.name} ({b.shown}) columns: "
                                      f"keep one {a.kind} form, hil does not choose between them"))
    if complete:
        return complete[0]
    partial = [(sum(c in present for c in f.columns), -k, f) for k, f in enumerate(forms)]
    count, _, best = max(partial, key=lambda t: (t[0], t[1]))
    if count:
        missing = [c for c in best.columns if c not in present]
        raise InputError(header.where(f"missing column(s) {', '.join(missing)} "
                                      f"(the {best.name} form needs {best.shown})"))
    if required:
        raise InputError(header.where(f"no {forms[0].kind} columns: expected {expected}"))
    return None


def joint_unit(header: Header, form: Form, declared: str | None) -> str:
    """The one unit of the joint columns: a suffix on every column (``q1_deg``), or none and the
    declaration `declared` ("rad" or "deg", as ``--joint-units`` gives it; radians by default).
    Mixed suffixes, or a suffix that contradicts the declaration, are refused."""
    cols = [header.columns[c] for c in form.columns]
    suffixed = {c.unit for c in cols if c.declared}
    plain = [c.label for c in cols if not c.declared]
    if len(suffixed) > 1 or (suffixed and plain):
        units = ", ".join(f"{c.label} ({c.unit})" for c in cols)
        raise InputError(header.where(f"the joint columns mix units: {units}; give all six one unit"))
    if suffixed:
        unit = next(iter(suffixed))
        if declared is not None and declared != unit:
            raise InputError(header.where(f"the header declares the joints in {unit} ({cols[0].label}) "
                                          f"but --joint-units says {declared}"))
        return unit
    return declared or "rad"


def _cell(rows: Rows, line: int, row: list[str], col: Column) -> float:
    cell = row[col.index].strip()
    try:
        value = float(cell)
    except ValueError:
        raise InputError(f"{rows.header.source}: line {line}, column {col.label}: {cell!r} is not a number") \
            from None
    # finite and not a denormal here; each column's range where its unit is known (`numbers`' callers)
    return real(value, f"{rows.header.source}: line {line}, column {col.label}", cell)


def numbers(rows: Rows, labels: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """The values (as written, in the file's units) of the known columns `labels` (base names) in every
    row, shape (m, len(labels)), and the rows' line numbers."""
    header = rows.header
    cols = [header.columns[c] for c in labels]
    data = np.empty((len(rows.rows), len(cols)))
    lines = np.empty(len(rows.rows), dtype=int)
    for k, (line, row) in enumerate(rows.rows):
        if len(row) != header.width:
            raise InputError(f"{header.source}: line {line}: expected {header.width} fields, got {len(row)}")
        for j, col in enumerate(cols):
            data[k, j] = _cell(rows, line, row, col)
        lines[k] = line
    if len(lines) == 0:
        raise InputError(f"{header.source}: no data rows after the header")
    return data, lines


def _first_bad(mask: np.ndarray) -> tuple[int, int] | None:
    """(row, column) of the first True of a 2-D mask, row by row as the file reads."""
    bad = np.argwhere(mask)
    return None if len(bad) == 0 else (int(bad[0][0]), int(bad[0][1]))


#: What a header without a joint or a position form is told to have.
JOINTS_EXPECTED = ("q1..q6 or shoulder_pan_joint..wrist_3_joint (radians; degrees as q1_deg..q6_deg or "
                   "with --joint-units deg)")
POSITIONS_EXPECTED = ("x,y,z (m), x1,y1,z1[,x2,y2,z2…] (FIGAROH's markers) or hz,v,d (Leica polar: "
                      "horizontal angle, zenith angle, slope distance)")


def check_measurements_header(rows: Rows) -> None:
    """Refuse a measurements header that lacks a joint or a position form, or names one in part,
    before any row is read: a file whose header is wrong is told so, whatever its rows hold. A UR's
    file with joint columns beyond q6 (q7.., an arm of more joints) is refused too: dropping a joint
    would fit the wrong arm."""
    header = rows.header
    extra = sorted(int(m["k"]) for c in header.columns if (m := _JOINT.match(c)) and int(m["k"]) > 6)
    if extra:
        raise InputError(header.where(f"joint columns up to q{extra[-1]}, but a UR has 6 joints "
                                      "(q1..q6); an arm of more joints is read with --urdf"))
    choose(header, JOINT_FORMS, required=True, expected=JOINTS_EXPECTED)
    choose(header, POSITION_FORMS, required=True, expected=POSITIONS_EXPECTED)
    choose(header, ORIENTATION_FORMS, required=False, expected="")
    choose(header, (DIRECTIONS,), required=False, expected="")


def joints(rows: Rows, declared: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Joint angles (m, 6) in radians and the line numbers, from the header's one joint form.

    A value beyond every catalog arm's limits (plus `JOINT_LIMIT_MARGIN`) is refused naming its line
    and column; when the file is read as radians and the value would be a valid angle in degrees, the
    message says how to declare degrees.
    """
    header = rows.header
    form = choose(header, JOINT_FORMS, required=True,
                  expected=JOINTS_EXPECTED)
    assert form is not None
    unit = joint_unit(header, form, declared)
    values, lines = numbers(rows, form.columns)
    q = values * ANGLE_UNITS[unit]
    low = np.array([r[0] for r in JOINT_RANGES])
    high = np.array([r[1] for r in JOINT_RANGES])
    bad = _first_bad((q < low) | (q > high))
    if bad is not None:
        i, j = bad
        f = ANGLE_UNITS[unit]
        text = (f"{values[i, j]:g} {unit} is beyond the joint limits of every UR arm "
                f"({low[j] / f:.4g} to {high[j] / f:.4g} {unit})")
        if unit == "rad" and low[j] <= math.radians(values[i, j]) <= high[j]:
            text += ("; if the file is in degrees, declare it: name the columns q1_deg..q6_deg or pass "
                     "--joint-units deg")
        raise InputError(f"{header.source}: line {lines[i]}, column {header.columns[form.columns[j]].label}: "
                         f"{text}")
    return q, lines


def chain_joints(rows: Rows, names: Sequence[str], kinds: Sequence[str], lower: np.ndarray,
                 upper: np.ndarray, arm: str, declared: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Joint values (m, N) of an arm from its URDF and the line numbers, from columns ``q1..qN``
    (radians, or degrees by suffix or `declared`; a prismatic joint in metres, as its URDF gives it).

    The header must hold exactly q1..qN for the N joints (`names` are the URDF's joint names, shown in
    the error): another count is one line naming the file and the header line. A value beyond the
    URDF's limits by more than `JOINT_LIMIT_MARGIN` is refused naming its line and column.
    """
    header = rows.header
    present = sorted(int(m["k"]) for c in header.columns if (m := _JOINT.match(c)))
    n = len(names)
    if present != list(range(1, n + 1)):
        found = ",".join(f"q{k}" for k in present) or "none"
        raise InputError(header.where(f"joint columns {found}, but the {arm} has {n} joints "
                                      f"({', '.join(names)}): expected q1..q{n}"))
    form = Form("joint", f"q1..q{n}", tuple(f"q{k}" for k in range(1, n + 1)), ("angle",) * n)
    unit = joint_unit(header, form, declared)
    values, lines = numbers(rows, form.columns)
    factor = np.array([ANGLE_UNITS[unit] if kind == "RZ" else 1.0 for kind in kinds])
    q = values * factor
    margin = np.array([JOINT_LIMIT_MARGIN if kind == "RZ" else 0.0 for kind in kinds])
    bad = _first_bad((q < lower - margin) | (q > upper + margin))
    if bad is not None:
        i, j = bad
        raise InputError(f"{header.source}: line {lines[i]}, column {header.columns[form.columns[j]].label}: "
                         f"{values[i, j]:g} is beyond the URDF's limits of {names[j]} "
                         f"({lower[j] / factor[j]:.4g} to {upper[j] / factor[j]:.4g})")
    return q, lines


def _si(rows: Rows, names: Sequence[str]) -> np.ndarray:
    values, _ = numbers(rows, names)
    return values * np.array([rows.header.columns[c].factor for c in names])


def _check(rows: Rows, lines: np.ndarray, names: Sequence[str], values: np.ndarray, bad: np.ndarray,
           why: str) -> None:
    """Refuse the first value flagged in `bad` (m, len(names)), naming its line, column and `why`."""
    first = _first_bad(bad)
    if first is not None:
        i, j = first
        col = rows.header.columns[names[j]]
        shown = values[i, j] / col.factor
        raise InputError(f"{rows.header.source}: line {lines[i]}, column {col.label}: {shown:g} "
                         f"{col.unit} {why}")


def _angles_in_range(rows: Rows, lines: np.ndarray, names: Sequence[str], values: np.ndarray) -> None:
    """Refuse an angle (rad, in `values`) of more than a turn; for a column read as radians the
    message says how to declare degrees or gon, the likely mistake."""
    for j, c in enumerate(names):
        bad = np.zeros_like(values, dtype=bool)
        bad[:, j] = np.abs(values[:, j]) > ANGLE_RANGE
        read_as_radians = rows.header.columns[c].unit == "rad"
        hint = "; declare degrees or gon with a suffix (_deg, _gon)" if read_as_radians else ""
        _check(rows, lines, names, values, bad, f"is more than a turn ({math.degrees(ANGLE_RANGE):g}°){hint}")


def positions(rows: Rows, lines: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, Form]:
    """Tracker-frame positions (m, 3) in metres of the header's position form, all reflectors
    (m, R, 3) when the form is FIGAROH's markers (None otherwise), and the form read.

    Polar readings are converted by `drivers.tracker.geometry.polar_to_cartesian`, the one conversion
    the GeoCOM driver and the simulated trackers use, so a polar file lands in the frame a live tracker
    measures in.
    """
    header = rows.header
    form = choose(header, POSITION_FORMS, required=True,
                  expected=POSITIONS_EXPECTED)
    assert form is not None
    if form is POLAR:
        from drivers.tracker.geometry import polar_to_cartesian

        names = POLAR.columns
        hvd = _si(rows, names)
        _angles_in_range(rows, lines, names[:2], hvd[:, :2])
        _check(rows, lines, names, hvd, np.column_stack([np.zeros((len(hvd), 2), bool),
                                                         (hvd[:, 2] <= 0) | (hvd[:, 2] > TRACKER_RANGE)]),
               f"is not a distance a laser tracker measures (0 to {TRACKER_RANGE:g} m)")
        return polar_to_cartesian(hvd[:, 0], hvd[:, 1], hvd[:, 2]).reshape(-1, 3), None, form
    if form is CARTESIAN:
        names = CARTESIAN.columns
        p = _si(rows, names)
        _check(rows, lines, names, p, np.abs(p) > TRACKER_RANGE,
               f"is beyond a laser tracker's range (-{TRACKER_RANGE:g} to {TRACKER_RANGE:g} m)")
        return p, None, form
    count = marker_count(header)
    names = tuple(f"{a}{k}" for k in range(1, count + 1) for a in "xyz")
    flat = _si(rows, names)
    _check(rows, lines, names, flat, np.abs(flat) > TRACKER_RANGE,
           f"is beyond a tracker's or camera's range (-{TRACKER_RANGE:g} to {TRACKER_RANGE:g} m)")
    markers = flat.reshape(len(flat), count, 3)
    return markers[:, 0].copy(), markers, form


def marker_count(header: Header) -> int:
    """How many markers ``x<k>,y<k>,z<k>`` the header has, numbered from 1 without gaps; a marker named
    in part, or one after a gap, is refused (it would otherwise be silently dropped)."""
    numbered = sorted({int(m["k"]) for c in header.columns if (m := _MARKER.match(c))})
    count = 0
    for k in numbered:
        names = [f"{a}{k}" for a in "xyz"]
        missing = [n for n in names if n not in header.columns]
        if missing:
            raise InputError(header.where(f"marker {k} is missing column(s) {', '.join(missing)}"))
        if k != count + 1:
            raise InputError(header.where(f"marker {k} follows marker {count}: markers are numbered "
                                          f"1, 2, … without gaps"))
        count = k
    return count


def rotations(rows: Rows, lines: np.ndarray) -> tuple[np.ndarray | None, Form | None]:
    """Per-pose rotation matrices (m, 3, 3) of the header's orientation form, or None without one.

    The matrix maps the measured frame (a camera's optical frame, a probe's) into the instrument's
    frame. Roll, pitch, yaw (``roll,pitch,yaw`` or FIGAROH's ``phix1,phiy1,phiz1``) compose as
    R = Rz(yaw)·Ry(pitch)·Rx(roll), the URDF/ROS convention FIGAROH writes (pinocchio's rpyToMatrix);
    ``rx,ry,rz`` is a rotation vector (axis × angle, UR's pose convention); ``qw,qx,qy,qz`` a unit
    quaternion. scipy's Rotation does the conversions.
    """
    form = choose(rows.header, ORIENTATION_FORMS, required=False, expected="")
    if form is None:
        return None, None
    from scipy.spatial.transform import Rotation

    names = form.columns
    values = _si(rows, names)
    if form is QUATERNION:
        norm = np.linalg.norm(values, axis=1)
        bad = np.zeros_like(values, dtype=bool)
        bad[:, 0] = np.abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE
        first = _first_bad(bad)
        if first is not None:
            i = first[0]
            raise InputError(f"{rows.header.source}: line {lines[i]}, columns {','.join(names)}: norm "
                             f"{norm[i]:.6g} is not a unit quaternion's (1 ± {QUATERNION_NORM_TOLERANCE:g})")
        wxyz = values / norm[:, None]
        return Rotation.from_quat(wxyz[:, [1, 2, 3, 0]]).as_matrix(), form
    _angles_in_range(rows, lines, names, values)
    if form is ROTATION_VECTOR:
        return Rotation.from_rotvec(values).as_matrix(), form
    return Rotation.from_euler("xyz", values).as_matrix(), form  # extrinsic x, y, z: Rz·Ry·Rx


def directions(rows: Rows, lines: np.ndarray) -> np.ndarray | None:
    """(m, 6) joint approach directions from ``d1..d6`` (each −1, 0 or +1), or None without them."""
    form = choose(rows.header, (DIRECTIONS,), required=False, expected="")
    if form is None:
        return None
    values, _ = numbers(rows, form.columns)
    first = _first_bad(~np.isin(values, (-1.0, 0.0, 1.0)))
    if first is not None:
        i, j = first
        raise InputError(f"{rows.header.source}: line {lines[i]}, column "
                         f"{rows.header.columns[form.columns[j]].label}: '{values[i, j]:g}' is not a "
                         f"direction (-1, 0 or +1)")
    return values
