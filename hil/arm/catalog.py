"""The robot catalog: nominal geometry and limits of the Universal Robots arms hil calibrates.

Every UR arm shares one kinematic structure (standard DH, α = [π/2, 0, 0, π/2, −π/2, 0], a1 = a4 =
a5 = a6 = 0, d2 = d3 = 0), so a model is six numbers plus its limits. The DH values are Universal
Robots' published ones; speed limits are the datasheet maxima per joint. The elbow is limited to ±π,
as in ``ur_description`` (beyond it the arm folds into itself); every other joint to ±2π.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from math import pi, radians

import numpy as np

from hil.errors import UnknownRobotError

ALPHA: tuple[float, ...] = (pi / 2, 0.0, 0.0, pi / 2, -pi / 2, 0.0)
JOINT_NAMES: tuple[str, ...] = (
    "shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3",
)


@dataclass(frozen=True)
class DH:
    """Standard Denavit–Hartenberg parameters of one arm (metres, radians)."""

    d: tuple[float, ...]
    a: tuple[float, ...]
    alpha: tuple[float, ...] = ALPHA


@dataclass(frozen=True)
class RobotSpec:
    """One catalog entry: what the rest of hil needs to know about an arm type."""

    name: str
    title: str
    series: str  # "e" (e-series, UR20/UR30 too) or "cb3"
    dh: DH
    max_joint_speed: np.ndarray = field(repr=False)  # rad/s, per joint
    reach: float  # metres, datasheet
    effort: tuple[float, ...] = (150.0, 150.0, 150.0, 28.0, 28.0, 28.0)  # N·m, as in ur_description
    lower: np.ndarray = field(repr=False, default_factory=lambda: _limits()[0])
    upper: np.ndarray = field(repr=False, default_factory=lambda: _limits()[1])

    @property
    def rate_hz(self) -> float:
        """Controller cycle rate: servoJ/servoL stream at this rate."""
        return 500.0 if self.series == "e" else 125.0

    def within_limits(self, q: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """Boolean mask (per configuration) of joint vectors inside the limits shrunk by `margin`."""
        q = np.atleast_2d(np.asarray(q, dtype=float))
        return np.all((q >= self.lower + margin) & (q <= self.upper - margin), axis=1)


def _limits() -> tuple[np.ndarray, np.ndarray]:
    upper = np.array([2 * pi, 2 * pi, pi, 2 * pi, 2 * pi, 2 * pi])
    return -upper, upper


def _speeds(*deg_per_s: float) -> np.ndarray:
    return np.array([radians(v) for v in deg_per_s])


def _dh(d1: float, a2: float, a3: float, d4: float, d5: float, d6: float) -> DH:
    return DH(d=(d1, 0.0, 0.0, d4, d5, d6), a=(0.0, a2, a3, 0.0, 0.0, 0.0))


_CATALOG: dict[str, RobotSpec] = {
    spec.name: spec
    for spec in (
        RobotSpec("ur3e", "UR3e", "e", _dh(0.15185, -0.24355, -0.2132, 0.13105, 0.08535, 0.0921),
                  _speeds(180, 180, 180, 360, 360, 360), 0.500, (56.0, 56.0, 28.0, 12.0, 12.0, 12.0)),
        RobotSpec("ur5e", "UR5e", "e", _dh(0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996),
                  _speeds(180, 180, 180, 180, 180, 180), 0.850),
        RobotSpec("ur10e", "UR10e", "e", _dh(0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655),
                  _speeds(120, 120, 180, 180, 180, 180), 1.300, (330.0, 330.0, 150.0, 56.0, 56.0, 56.0)),
        RobotSpec("ur16e", "UR16e", "e", _dh(0.1807, -0.4784, -0.36, 0.17415, 0.11985, 0.11655),
                  _speeds(120, 120, 180, 180, 180, 180), 0.900, (330.0, 330.0, 150.0, 56.0, 56.0, 56.0)),
        RobotSpec("ur20", "UR20", "e", _dh(0.2363, -0.862, -0.7287, 0.201, 0.1593, 0.1543),
                  _speeds(120, 120, 150, 210, 210, 210), 1.750, (738.0, 738.0, 433.0, 107.0, 107.0, 107.0)),
        RobotSpec("ur30", "UR30", "e", _dh(0.2363, -0.637, -0.5037, 0.201, 0.1593, 0.1543),
                  _speeds(120, 120, 150, 210, 210, 210), 1.300, (738.0, 738.0, 433.0, 107.0, 107.0, 107.0)),
        RobotSpec("ur3", "UR3 (CB3)", "cb3", _dh(0.1519, -0.24365, -0.21325, 0.11235, 0.08535, 0.0819),
                  _speeds(180, 180, 180, 360, 360, 360), 0.500, (56.0, 56.0, 28.0, 12.0, 12.0, 12.0)),
        RobotSpec("ur5", "UR5 (CB3)", "cb3", _dh(0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823),
                  _speeds(180, 180, 180, 180, 180, 180), 0.850),
        RobotSpec("ur10", "UR10 (CB3)", "cb3", _dh(0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922),
                  _speeds(120, 120, 180, 180, 180, 180), 1.300, (330.0, 330.0, 150.0, 54.0, 54.0, 54.0)),
    )
}

ROBOT_NAMES: tuple[str, ...] = tuple(_CATALOG)


def get_robot(name: str) -> RobotSpec:
    """The catalog entry for `name` (case-insensitive, "UR5e" or "ur5e"); UnknownRobotError otherwise."""
    key = str(name).strip().lower().replace(" ", "").replace("-", "")
    try:
        return _CATALOG[key]
    except KeyError:
        raise UnknownRobotError(
            f"unknown robot {name!r}: choose one of {', '.join(ROBOT_NAMES)}") from None
