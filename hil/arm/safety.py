"""Is a motion target safe for this arm? Joint limits and the keep-in box, checked before any motion.

Shared by the campaign (its plans are checked step by step before the arm moves) and MOVEB (every
streamed target): an unsafe target is refused with a one-line error, never clamped.
"""

from __future__ import annotations

import numpy as np

from hil.arm.catalog import RobotSpec
from hil.arm.geometry import Geometry
from hil.arm.kinematics_cache import kinematics_of
from hil.errors import InputError

#: Points along a move's joint-space path at which the UR driver checks the keep-in zone with the
#: controller's kinematics (`drivers.robot.model.RobotConfig.keep_in_checks`' default: s = k/7). The
#: planner checks these fractions too, so a move it passes is never refused there for falling
#: between its own points (a campaign once failed mid-run "at 57 % of the way", s = 4/7).
DRIVER_PATH_CHECKS = 8


def path_fractions(path_checks: int) -> np.ndarray:
    """Fractions of a move's path the planner checks: `path_checks` evenly spaced, and the driver's."""
    return np.union1d(np.linspace(0.0, 1.0, path_checks), np.linspace(0.0, 1.0, DRIVER_PATH_CHECKS))


def check_target(q: np.ndarray, spec: RobotSpec, keep_in: tuple[np.ndarray, np.ndarray] | None = None,
                 model: Geometry | None = None, start: np.ndarray | None = None,
                 path_checks: int = 16) -> None:
    """Raise InputError if `q` is outside the joint limits, or the SMR leaves the keep-in box.

    With `start`, the straight joint-space path from `start` to `q` (how moveJ travels) is checked at
    `path_checks` points and at the UR driver's own (`path_fractions`) too. Nothing is clamped: an unsafe
    target is refused. The model's kinematics is built once per geometry content and thread
    (`hil.arm.kinematics_cache`): a route's twenty-odd checks would otherwise spend most of their time
    rebuilding it.
    """
    q = np.asarray(q, dtype=float)
    if q.shape != (6,) or not np.all(np.isfinite(q)):
        raise InputError(f"motion target {q.tolist()} is not six finite joint angles")
    low = np.flatnonzero(q < spec.lower)
    high = np.flatnonzero(q > spec.upper)
    for j in (*low, *high):
        raise InputError(f"motion target q{j + 1} = {q[j]:.4f} rad is outside the joint limits "
                         f"[{spec.lower[j]:.4f}, {spec.upper[j]:.4f}]")
    if keep_in is None or model is None:
        return
    lo, hi = keep_in
    path = q[None] if start is None else start + path_fractions(path_checks)[:, None] * (q - start)
    pts = kinematics_of(model).points(path, frame="base")
    outside = np.flatnonzero(np.any((pts < lo) | (pts > hi), axis=1))
    if outside.size:
        p = pts[outside[0]]
        where = "target" if start is None or outside[0] == len(path) - 1 else "path to the target"
        raise InputError(f"motion {where} {np.round(q, 4).tolist()} puts the SMR at "
                         f"{np.round(p, 4).tolist()} m, outside the keep-in box {lo.tolist()}..{hi.tolist()}")
