"""Compensating a CSV of tool poses: ``x,y,z,rx,ry,rz`` in, the same table with commands out.

The input's header names ``x,y,z,rx,ry,rz`` (base frame, metres, UR rotation vector: the TCP pose
wanted); other columns pass through as they are. Optional ``q1..q6`` columns give each row's
configuration (the joints its branch is chosen near); without them each row is seeded by the previous
row's solution, the first by ``near``. The output keeps the columns and rows, with the six pose cells
replaced by the compensated pose (full float precision), or — ``joints`` — by ``q1..q6`` joint targets
in their place (the input's q columns, only seeds, are then dropped).
"""

from __future__ import annotations

import csv
import io
from collections.abc import Sequence

import numpy as np

from hil.arm.ik import UnreachableError
from hil.compensation.poses import check_pose, to_se3, to_vector
from hil.compensation.solve import Compensator
from hil.compensation.summary import Summary
from hil.errors import InputError
from hil.files.inputs import csv_rows
from hil.files.quantities import real

POSE_COLUMNS: tuple[str, ...] = ("x", "y", "z", "rx", "ry", "rz")
JOINT_COLUMNS: tuple[str, ...] = ("q1", "q2", "q3", "q4", "q5", "q6")


def looks_like_csv(text: str) -> bool:
    """Whether `text` starts with a header naming the six pose columns (what tells a CSV from a program)."""
    for line in text.splitlines():
        if line.strip():
            return set(POSE_COLUMNS) <= {c.strip() for c in line.split(",")}
    return False


def _cell(row: list[str], index: int, name: str, line: int, column: str) -> float:
    text = row[index].strip()
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"{name}: line {line}, column {column}: {text!r} is not a number") from None
    return real(value, f"{name}: line {line}, column {column}", text)


def compensate_csv(text: str, name: str, compensator: Compensator, near: Sequence[float],
                   *, joints: bool = False) -> tuple[str, Summary]:
    """The compensated table (text) and its summary; InputError naming the line on bad input or an
    unreachable target (nothing is returned then, so nothing is written)."""
    rows = [(n, row) for n, row in csv_rows(text, name) if row and any(c.strip() for c in row)]
    if not rows:
        raise InputError(f"{name}: empty file, expected a header with {','.join(POSE_COLUMNS)}")
    header_line, header = rows[0]
    names = [h.strip() for h in header]
    missing = [c for c in POSE_COLUMNS if c not in names]
    if missing:
        raise InputError(f"{name}: line {header_line}: missing column(s) {', '.join(missing)} "
                         f"(the header must include {','.join(POSE_COLUMNS)})")
    twice = sorted({c for c in (*POSE_COLUMNS, *JOINT_COLUMNS) if names.count(c) > 1})
    if twice:
        raise InputError(f"{name}: line {header_line}: column(s) {', '.join(twice)} appear twice")
    pose_at = [names.index(c) for c in POSE_COLUMNS]
    seeded = [c for c in JOINT_COLUMNS if c in names]
    if seeded and len(seeded) != 6:
        raise InputError(f"{name}: line {header_line}: joint columns {','.join(seeded)} without the rest of "
                         "q1..q6 (give all six, or none)")
    joint_at = [names.index(c) for c in JOINT_COLUMNS] if seeded else []
    lower, upper = compensator.accurate.spec.lower, compensator.accurate.spec.upper

    summary = Summary(name, "csv", joints=joints)
    q = np.asarray(near, dtype=float)
    results: list[np.ndarray] = []
    for line, row in rows[1:]:
        if len(row) != len(header):
            raise InputError(f"{name}: line {line}: expected {len(header)} fields, got {len(row)}")
        values = np.array([_cell(row, i, name, line, c) for i, c in zip(pose_at, POSE_COLUMNS, strict=True)])
        check_pose(values, f"{name}: line {line}")
        if joint_at:
            q = np.array([_cell(row, i, name, line, c) for i, c in zip(joint_at, JOINT_COLUMNS, strict=True)])
            outside = np.flatnonzero((q < lower) | (q > upper))
            if outside.size:
                j = int(outside[0])
                raise InputError(f"{name}: line {line}, column q{j + 1}: {q[j]:g} rad is outside the joint "
                                 "limits (the values are in radians)")
        try:
            c = compensator.solve(to_se3(values), q)
        except UnreachableError as exc:
            raise UnreachableError(f"{name}: line {line}: {exc}") from None
        summary.add(line, "row", c)
        results.append(c.q if joints else to_vector(c.command))
        q = c.q

    if joints:  # the pose columns become q1..q6 in their place; the seed columns go
        first = min(pose_at)
        keep = [i for i in range(len(names)) if i not in pose_at and i not in joint_at]
        before = [i for i in keep if i < first]
        after = [i for i in keep if i > first]
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\r\n" if "\r\n" in text else "\n")

    def write(row: list[str], new: list[str]) -> None:
        if joints:
            writer.writerow([row[i] for i in before] + new + [row[i] for i in after])
        else:
            cells = list(row)
            for i, v in zip(pose_at, new, strict=True):
                cells[i] = v
            writer.writerow(cells)

    write(header, list(JOINT_COLUMNS if joints else [header[i] for i in pose_at]))
    for (_, row), result in zip(rows[1:], results, strict=True):
        write(row, [repr(float(v)) for v in result])
    summary.as_joints = len(results) if joints else 0
    return out.getvalue(), summary
