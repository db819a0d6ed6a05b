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

#: The configuration the first target's branch is chosen by when nothing else says (``--near``):
#: upper arm up, forearm level, wrist pointing the tool down — elbow up, wrist down, the arrangement of
#: most UR cells, and away from the three UR singularities (elbow straight q3 = 0, wrist q5 = 0, wrist
#: centre on the base axis).
CANONICAL_NEAR: tuple[float, ...] = (0.0, -math.pi / 2, math.pi / 2, -math.pi / 2, -math.pi / 2, 0.0)
#: Longest TCP offset accepted from ``--tcp`` (m): UR's heaviest tools stay within a metre of the flange
#: (as the SMR offset of a model, `hil.calibration.model_file.MAX_SMR_OFFSET`); more is a unit mistake.
MAX_TCP_OFFSET = 1.0
#: Farthest a target may lie from the base (m): beyond every UR's reach (UR20: 1.75 m) with room to
#: spare; a CSV in millimetres has targets hundreds of metres away and is named as such.
MAX_TARGET_DISTANCE = 5.0


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


def parse_six(text: str, option: str, *, unit: str) -> np.ndarray:
    """Six comma-separated finite numbers (``--near``, ``--tcp``); InputError naming the option."""
    parts = [p.strip() for p in str(text).split(",")]
    try:
        values = np.array([float(p) for p in parts])
    except ValueError:
        values = np.array([])
    if values.shape != (6,) or not np.all(np.isfinite(values)):
        raise InputError(f"{option}: expected six finite numbers separated by commas ({unit}), "
                         f"got {text!r}")
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
    if float(np.linalg.norm(v[:3])) > MAX_TCP_OFFSET:
        raise InputError(f"{option}: the TCP lies {np.linalg.norm(v[:3]):g} m from the flange, more than "
                         f"{MAX_TCP_OFFSET:g} m (the values are in metres)")
    return to_se3(v)
