"""UR tool poses as the controller writes them, and the few numbers a compensation starts from.

A UR pose is ``[x, y, z, rx, ry, rz]``: position in metres and a rotation vector (axis times angle,
radians), as ``actual_TCP_pose``, URScript's ``p[...]`` and the CSV of targets use it (URScript manual,
module motion: "the last three an axis-angle"). Converting is Rodrigues' formula, pinocchio's
``exp3``/``log3``; a pose written back by `format_number` parses to the very same doubles, so a
compensated file loses nothing.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from hil.errors import InputError
from hil.files.quantities import check_vector, real

#: The configuration the first target's branch is chosen by when nothing else says (``--near``):
#: upper arm up, forearm level, wrist pointing the tool down — elbow up, wrist down, the arrangement of
#: most UR cells, and away from the three UR singularities (elbow straight q3 = 0, wrist q5 = 0, wrist
#: centre on the base axis).
CANONICAL_NEAR: tuple[float, ...] = (0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0)
#: The quantities of a UR pose vector's parts (rows of `hil.files.quantities`): a target's distance
#: from the base, a TCP's from the flange, and the rotation vector's length (its angle).
TARGET_DISTANCE = "target distance"
TCP_OFFSET = "tool offset"
ROTATION = "rotation vector angle"


def to_se3(values: Sequence[float]) -> pin.SE3:
    """A UR pose vector as an SE(3) placement."""
    v = np.asarray(values, dtype=float).reshape(6)
    return pin.SE3(pin.exp3(v[3:]), v[:3].copy())


def to_vector(M: pin.SE3) -> np.ndarray:
    """An SE(3) placement as a UR pose vector (rotation angle in [0, π])."""
    return np.r_[M.translation, pin.log3(M.rotation)]


def format_number(value: float) -> str:
    """Shortest text that parses back to exactly `value`, without an exponent.

    Positional digits are what every UR tool writes (Polyscope writes ``.1``, ``-0.0001``); an exponent
    (Python's repr of 1e-05) is not something to bet a robot program on.
    """
    return np.format_float_positional(float(value), unique=True, trim="0")


def check_pose(values: Sequence[float], where: str, distance: str = TARGET_DISTANCE,
               origin: str = "the base") -> np.ndarray:
    """A UR pose vector (x, y, z m; rx, ry, rz a rotation vector, rad) whose numbers are physical: every
    one real (no NaN, inf or denormal), the position within `distance`'s range and the rotation angle
    within a turn, so a pose written in millimetres or degrees is refused naming the unit."""
    v = [float(x) for x in values]
    check_vector(v[:3], distance, f"{where}: position (x, y, z) from {origin}", norm=True)
    check_vector(v[3:], ROTATION, f"{where}: rotation vector (rx, ry, rz)", norm=True)
    return np.array(v)


def parse_six(text: str, option: str, *, unit: str) -> np.ndarray:
    """Six comma-separated finite numbers (``--near``, ``--tcp``); InputError naming the option."""
    parts = [p.strip() for p in str(text).split(",")]
    try:
        values = np.array([float(p) for p in parts])
    except ValueError:
        values = np.array([])
    if values.shape != (6,) or not np.all(np.isfinite(values)):
        raise InputError(f"{option}: expected six finite numbers separated by commas ({unit}), got {text!r}")
    for i, v in enumerate(values):
        real(float(v), f"{option}[{i}]")
    return values


def parse_near(text: str | None, lower: np.ndarray, upper: np.ndarray, option: str = "--near") -> np.ndarray:
    """``--near q1,..,q6`` (radians, inside the joint limits), or `CANONICAL_NEAR` when not given."""
    if text is None:
        return np.array(CANONICAL_NEAR)
    q = parse_six(text, option, unit="radians")
    outside = np.flatnonzero((q < lower) | (q > upper))
    if outside.size:
        j = int(outside[0])
        raise InputError(f"{option}: q{j + 1} = {q[j]:g} rad is outside the joint limits "
                         f"[{lower[j]:.4g}, {upper[j]:.4g}] (the value is in radians)")
    return q


def parse_tcp(text: str | None, option: str = "--tcp") -> pin.SE3:
    """``--tcp x,y,z,rx,ry,rz`` (the TCP in the flange frame, m and rad), or the flange itself."""
    if text is None:
        return pin.SE3.Identity()
    v = parse_six(text, option, unit="metres and a rotation vector in radians")
    return to_se3(check_pose(v, option, TCP_OFFSET, "the flange"))
