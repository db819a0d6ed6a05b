"""Reading and writing measurement and joint CSV files (docs/design.md, Contracts: measurements CSV).

A measurements file has the header ``q1,q2,q3,q4,q5,q6,x,y,z`` (joint radians, SMR position in the
tracker frame in metres) and optionally ``d1..d6``, the sign of each joint's last motion before the
reading (−1, 0 or +1: lost motion, `hil.arm.joint_errors`); other columns are allowed and ignored.
Every problem is reported as an InputError naming the file, the line and the column, because these
files come from other tools and people and the first thing a user needs is where to look.
"""

from __future__ import annotations

import hashlib
import math
import os
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from hil.arm.catalog import ROBOT_NAMES, get_robot
from hil.errors import InputError
from hil.files.inputs import csv_rows, decode_input_text, read_input_bytes
from hil.files.outputs import atomic_write_text, format_csv

JOINT_COLUMNS: tuple[str, ...] = ("q1", "q2", "q3", "q4", "q5", "q6")
POINT_COLUMNS: tuple[str, ...] = ("x", "y", "z")
#: Optional: each joint's direction of approach (sign of its last motion) — all six or none.
DIRECTION_COLUMNS: tuple[str, ...] = ("d1", "d2", "d3", "d4", "d5", "d6")

#: Farthest a laser tracker measures (m): the Leica AT960's range is 80 m in radius, the longest of
#: the trackers hil drives. A coordinate beyond it is a unit mistake or a corrupted file.
TRACKER_RANGE = 80.0
#: How far (rad) a joint reading may lie beyond the joint limits before it is refused: readings at a
#: limit overshoot it by encoder noise at most, so anything past this was not read from a UR arm.
JOINT_LIMIT_MARGIN = 0.1


def _column_ranges() -> dict[str, tuple[float, float, str]]:
    """The plausible range of every column hil knows, and its unit.

    A file does not say which arm it came from, so a joint column accepts what any catalog arm's
    limits allow (plus `JOINT_LIMIT_MARGIN`); the points must lie within a tracker's range.
    """
    specs = [get_robot(n) for n in ROBOT_NAMES]
    out = {c: (float(min(s.lower[j] for s in specs)) - JOINT_LIMIT_MARGIN,
               float(max(s.upper[j] for s in specs)) + JOINT_LIMIT_MARGIN, "rad")
           for j, c in enumerate(JOINT_COLUMNS)}
    out.update({c: (-TRACKER_RANGE, TRACKER_RANGE, "m") for c in POINT_COLUMNS})
    return out


COLUMN_RANGES = _column_ranges()


@dataclass(frozen=True)
class Table:
    """Numeric columns read from a CSV file, with the file line number of every row."""

    source: str
    columns: dict[str, np.ndarray]
    lines: np.ndarray  # 1-based line numbers in the file
    sha256: str

    def __len__(self) -> int:
        return len(self.lines)


@dataclass(frozen=True)
class Measurements:
    """Joint configurations and the tracker's SMR positions, one row per pose."""

    q: np.ndarray  # (m, 6) radians
    p: np.ndarray  # (m, 3) metres, tracker frame
    lines: np.ndarray  # (m,) 1-based line numbers in the source file
    source: str = "<memory>"
    sha256: str = ""
    #: (m, 6) sign of each joint's last motion before the reading, or None when the data do not say
    directions: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.q)

    def subset(self, mask: np.ndarray) -> Measurements:
        d = None if self.directions is None else self.directions[mask]
        return Measurements(self.q[mask], self.p[mask], self.lines[mask], self.source, self.sha256, d)

    @classmethod
    def from_arrays(cls, q: np.ndarray, p: np.ndarray, source: str = "<memory>",
                    lines: np.ndarray | None = None,
                    directions: np.ndarray | None = None) -> Measurements:
        """Measurements from arrays, hashed by `measurements_sha256`; line numbers as in that CSV
        unless `lines` names the poses otherwise (a campaign names them by pose index)."""
        q = np.asarray(q, dtype=float).reshape(-1, 6)
        p = np.asarray(p, dtype=float).reshape(-1, 3)
        lines = np.arange(2, len(q) + 2) if lines is None else np.asarray(lines, dtype=int)
        d = None if directions is None else np.asarray(directions, dtype=float).reshape(-1, 6)
        return cls(q, p, lines, source, measurements_sha256(q, p), d)


def measurements_sha256(q: np.ndarray, p: np.ndarray) -> str:
    """The sha256 of measurements held in memory (a campaign's): that of the measurements CSV
    `write_measurements` writes for them (header q1..q6,x,y,z, full-precision rows, "\\n" line ends).

    `hil identify` hashes the bytes of the CSV it reads; measurements that never were a file are
    hashed as the file they would be, so writing them out and running ``sha256sum`` gives the same
    digest, and a model always names the data it was fitted to.
    """
    rows = np.hstack([np.asarray(q, dtype=float).reshape(-1, 6), np.asarray(p, dtype=float).reshape(-1, 3)])
    return hashlib.sha256(format_csv(JOINT_COLUMNS + POINT_COLUMNS, rows).encode("utf-8")).hexdigest()


def read_table(path: str | os.PathLike[str], required: Sequence[str],
               optional: Sequence[str] = ()) -> Table:
    """Read a CSV file whose header includes `required` numeric columns (others are ignored); the
    `optional` ones are read too when the header has every one of them (some but not all: an error)."""
    name = str(path)
    raw = read_input_bytes(path, "a CSV file")
    text = decode_input_text(raw, name)
    rows = [(n, row) for n, row in csv_rows(text, name)
            if row and any(c.strip() for c in row) and not row[0].lstrip().startswith("#")]
    if not rows:
        raise InputError(f"{name}: empty file, expected a header with {','.join(required)}")
    header_line, header = rows[0]
    header = [h.strip() for h in header]
    present = [c for c in optional if c in header]
    if present and len(present) < len(optional):
        raise InputError(f"{name}: line {header_line}: column(s) {', '.join(present)} without "
                         f"{', '.join(c for c in optional if c not in header)} (give all of "
                         f"{','.join(optional)} or none)")
    required = [*required, *optional] if present else list(required)
    missing = [c for c in required if c not in header]
    if missing:
        raise InputError(f"{name}: line {header_line}: missing column(s) {', '.join(missing)} "
                         f"(the header must include {','.join(required)})")
    dupes = sorted({c for c in required if header.count(c) > 1})
    if dupes:
        raise InputError(f"{name}: line {header_line}: column(s) {', '.join(dupes)} appear twice")
    where = {c: header.index(c) for c in required}
    data = np.empty((len(rows) - 1, len(required)))
    lines = np.empty(len(rows) - 1, dtype=int)
    for k, (line, row) in enumerate(rows[1:]):
        if len(row) != len(header):
            raise InputError(f"{name}: line {line}: expected {len(header)} fields, got {len(row)}")
        for j, col in enumerate(required):
            cell = row[where[col]].strip()
            try:
                value = float(cell)
            except ValueError:
                raise InputError(f"{name}: line {line}, column {col}: {cell!r} is not a number") from None
            if not math.isfinite(value):
                raise InputError(f"{name}: line {line}, column {col}: {cell!r} is not a finite number")
            if col in COLUMN_RANGES and not COLUMN_RANGES[col][0] <= value <= COLUMN_RANGES[col][1]:
                raise InputError(f"{name}: line {line}, column {col}: {_out_of_range(col, value)}")
            if col in DIRECTION_COLUMNS and value not in (-1.0, 0.0, 1.0):
                raise InputError(f"{name}: line {line}, column {col}: {cell!r} is not a direction "
                                 "(-1, 0 or 1: the sign of the joint's last motion)")
            data[k, j] = value
        lines[k] = line
    if len(lines) == 0:
        raise InputError(f"{name}: no data rows after the header")
    columns = {c: data[:, j] for j, c in enumerate(required)}
    return Table(name, columns, lines, hashlib.sha256(raw).hexdigest())


def _out_of_range(col: str, value: float) -> str:
    low, high, unit = COLUMN_RANGES[col]
    what = ("beyond the joint limits of every UR arm" if unit == "rad"
            else "beyond a laser tracker's range")
    return f"{value:g} {unit} is {what} ({low:.4g} to {high:.4g} {unit})"


def read_joints(path: str | os.PathLike[str]) -> tuple[np.ndarray, np.ndarray]:
    """Joint configurations (m, 6) and their line numbers from a CSV with columns q1..q6."""
    table = read_table(path, JOINT_COLUMNS)
    return np.column_stack([table.columns[c] for c in JOINT_COLUMNS]), table.lines


def read_measurements(path: str | os.PathLike[str]) -> Measurements:
    """A measurements CSV (q1..q6, x, y, z, optionally d1..d6) as `Measurements`."""
    table = read_table(path, JOINT_COLUMNS + POINT_COLUMNS, DIRECTION_COLUMNS)
    q = np.column_stack([table.columns[c] for c in JOINT_COLUMNS])
    p = np.column_stack([table.columns[c] for c in POINT_COLUMNS])
    d = (np.column_stack([table.columns[c] for c in DIRECTION_COLUMNS])
         if DIRECTION_COLUMNS[0] in table.columns else None)
    return Measurements(q, p, table.lines, table.source, table.sha256, d)


def write_measurements(path: str | os.PathLike[str], q: np.ndarray, p: np.ndarray,
                       directions: np.ndarray | None = None) -> None:
    """Write a measurements CSV (q1..q6, x, y, z, and d1..d6 when `directions` are given)."""
    if directions is None:
        atomic_write_text(path, format_csv(JOINT_COLUMNS + POINT_COLUMNS, np.hstack([q, p])))
    else:
        atomic_write_text(path, format_csv(JOINT_COLUMNS + POINT_COLUMNS + DIRECTION_COLUMNS,
                                           np.hstack([q, p, directions])))
