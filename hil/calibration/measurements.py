"""Reading and writing measurement and joint CSV files (docs/design.md, Contracts: measurements CSV).

hil writes the header ``q1,q2,q3,q4,q5,q6,x,y,z`` (joint radians, SMR position in the tracker frame in
metres), optionally ``d1..d6``, the sign of each joint's last motion before the reading (−1, 0 or +1:
lost motion, `hil.arm.joint_errors`); it reads that and the other forms real instruments write
(`measurement_forms`: joints in degrees or under the URDF's names, polar tracker readings, an
orientation per pose, several reflectors); extra columns are allowed and ignored. Every problem is
reported as an InputError naming the file, the line and the column, because these files come from
other tools and people and the first thing a user needs is where to look.
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass

import numpy as np

from hil.arm.chain import Chain
from hil.calibration import measurement_forms as forms
from hil.files.outputs import atomic_write_text, format_csv

JOINT_COLUMNS: tuple[str, ...] = ("q1", "q2", "q3", "q4", "q5", "q6")
POINT_COLUMNS: tuple[str, ...] = ("x", "y", "z")
#: Optional: each joint's direction of approach (sign of its last motion) — all six or none.
DIRECTION_COLUMNS: tuple[str, ...] = ("d1", "d2", "d3", "d4", "d5", "d6")

@dataclass(frozen=True)
class Measurements:
    """Joint configurations and the tracker's SMR positions, one row per pose.

    `rotation` and `reflectors` are there when the file had them: the orientation of the measured frame
    (a camera's, a 6-DoF probe's) in the instrument frame, and every reflector of a pose when it
    carried several (FIGAROH's markers). `p` is always the first reflector's position, so a caller that
    knows only positions reads every file the same way.
    """

    q: np.ndarray  # (m, 6) radians (m, N for an arm of N joints from its URDF)
    p: np.ndarray  # (m, 3) metres, tracker frame
    lines: np.ndarray  # (m,) 1-based line numbers in the source file
    source: str = "<memory>"
    sha256: str = ""
    rotation: np.ndarray | None = None  # (m, 3, 3) measured frame -> instrument frame
    reflectors: np.ndarray | None = None  # (m, R, 3) metres; reflectors[:, 0] == p
    #: (m, 6) sign of each joint's last motion before the reading, or None when the data do not say
    directions: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.q)

    def subset(self, mask: np.ndarray) -> Measurements:
        return Measurements(self.q[mask], self.p[mask], self.lines[mask], self.source, self.sha256,
                            None if self.rotation is None else self.rotation[mask],
                            None if self.reflectors is None else self.reflectors[mask],
                            None if self.directions is None else self.directions[mask])

    @classmethod
    def from_arrays(cls, q: np.ndarray, p: np.ndarray, source: str = "<memory>",
                    lines: np.ndarray | None = None,
                    directions: np.ndarray | None = None) -> Measurements:
        """Measurements from arrays, hashed by `measurements_sha256`; line numbers as in that CSV
        unless `lines` names the poses otherwise (a campaign names them by pose index)."""
        q = np.asarray(q, dtype=float)
        q = q.reshape(-1, q.shape[-1] if q.ndim == 2 else 6)
        p = np.asarray(p, dtype=float).reshape(-1, 3)
        lines = np.arange(2, len(q) + 2) if lines is None else np.asarray(lines, dtype=int)
        d = None if directions is None else np.asarray(directions, dtype=float).reshape(-1, 6)
        return cls(q, p, lines, source, measurements_sha256(q, p), directions=d)


def measurements_sha256(q: np.ndarray, p: np.ndarray) -> str:
    """The sha256 of measurements held in memory (a campaign's): that of the measurements CSV
    `write_measurements` writes for them (header q1..q6,x,y,z, full-precision rows, "\\n" line ends).

    `hil identify` hashes the bytes of the CSV it reads; measurements that never were a file are
    hashed as the file they would be, so writing them out and running ``sha256sum`` gives the same
    digest, and a model always names the data it was fitted to.
    """
    Q = np.asarray(q, dtype=float)
    Q = Q.reshape(-1, Q.shape[-1] if Q.ndim == 2 else 6)
    rows = np.hstack([Q, np.asarray(p, dtype=float).reshape(-1, 3)])
    text = format_csv(joint_columns(Q.shape[1]) + POINT_COLUMNS, rows)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def joint_columns(dof: int) -> tuple[str, ...]:
    """The joint columns hil writes for an arm of `dof` joints: q1..q6 for a UR, q1..qN for any arm."""
    return JOINT_COLUMNS if dof == 6 else tuple(f"q{k + 1}" for k in range(dof))


def read_joints(path: str | os.PathLike[str], joint_units: str | None = None,
                chain: Chain | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Joint configurations (m, 6) in radians and their line numbers from a CSV with a joint form
    (q1..q6 or the URDF's names; degrees declared by a ``_deg`` suffix or `joint_units` "deg"); for an
    arm from its URDF (`chain`), (m, N) from q1..qN (`forms.chain_joints`)."""
    if chain is not None and not chain.is_ur:
        return forms.chain_joints(forms.read_rows(path), chain.joint_names, chain.kinds, chain.lower,
                                  chain.upper, f"{chain.name} (URDF)", joint_units)
    return forms.joints(forms.read_rows(path), joint_units)


def read_measurements(path: str | os.PathLike[str], joint_units: str | None = None,
                      chain: Chain | None = None) -> Measurements:
    """A measurements CSV in any form `measurement_forms` knows (with optional d1..d6), as
    `Measurements` in radians and metres; `joint_units` ("rad" or "deg") declares the unit of joint
    columns without a suffix.

    For an arm from its URDF (`chain`, not a UR) the joints are ``q1..qN`` (`forms.chain_joints`: a
    count that is not the chain's is one line naming the file and line), the positions any position
    form, and orientations and several reflectors are read as for a UR (the 6-D fit,
    `hil.calibration.pose_identification`, takes any chain); approach directions ``d1..d6`` are a UR
    joint's lost motion and are not read."""
    if chain is not None and not chain.is_ur:
        rows = forms.read_rows(path)
        forms.choose(rows.header, forms.POSITION_FORMS, required=True, expected=forms.POSITIONS_EXPECTED)
        forms.choose(rows.header, forms.ORIENTATION_FORMS, required=False, expected="")
        q, lines = forms.chain_joints(rows, chain.joint_names, chain.kinds, chain.lower, chain.upper,
                                      f"{chain.name} (URDF)", joint_units)
        p, reflectors, _ = forms.positions(rows, lines)
        rotation, _ = forms.rotations(rows, lines)
        return Measurements(q, p, lines, rows.header.source, rows.sha256, rotation, reflectors)
    rows = forms.read_rows(path)
    forms.check_measurements_header(rows)
    q, lines = forms.joints(rows, joint_units)
    p, reflectors, _ = forms.positions(rows, lines)
    rotation, _ = forms.rotations(rows, lines)
    directions = forms.directions(rows, lines)
    return Measurements(q, p, lines, rows.header.source, rows.sha256, rotation, reflectors, directions)


def unused_by_position_fit(meas: Measurements, user: str = "the fit") -> list[str]:
    """One sentence for each part of a file that a fit of positions leaves unused: the orientations
    of a 6-D file, the reflectors after the first. Said rather than dropped silently, so a user knows
    the figures rest on the positions of the first reflector alone."""
    notes = []
    if meas.rotation is not None:
        notes.append(f"{meas.source}: {len(meas)} orientations read but not used: {user} uses the "
                     f"positions only")
    if meas.reflectors is not None and meas.reflectors.shape[1] > 1:
        notes.append(f"{meas.source}: {meas.reflectors.shape[1]} reflectors per pose read; {user} uses "
                     f"the first (x1,y1,z1) only")
    return notes


def write_measurements(path: str | os.PathLike[str], q: np.ndarray, p: np.ndarray,
                       directions: np.ndarray | None = None) -> None:
    """Write a measurements CSV (q1..q6, x, y, z, and d1..d6 when `directions` are given; q1..qN for an
    arm of N joints)."""
    if directions is None:
        atomic_write_text(path, format_csv(joint_columns(np.shape(q)[1]) + POINT_COLUMNS, np.hstack([q, p])))
    else:
        atomic_write_text(path, format_csv(JOINT_COLUMNS + POINT_COLUMNS + DIRECTION_COLUMNS,
                                           np.hstack([q, p, directions])))
