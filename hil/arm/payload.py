"""What the arm carries and how it is mounted: the inputs of its gravity torques.

A compliant arm sags by compliance × the gravity torque each joint holds
(docs/design.md, "Contracts: non-geometric
errors"), so every prediction needs the payload and the direction of gravity. The payload is the mass
on the flange and its centre of mass in the flange frame (as Polyscope's "Payload" setting and URScript's
``set_target_payload`` give it); gravity is (0, 0, −9.81) m/s² in the base frame for a floor-mounted
arm and is turned with the base for any other mounting (``robot.mounting``, roll-pitch-yaw of the base
in the world, as Polyscope's "Mounting" tilt and rotation).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin

from hil.errors import InputError
from hil.files.quantities import quantity

#: Standard gravity (m/s²; ISO 80000-3), along −z of a floor-mounted base.
STANDARD_GRAVITY = 9.81
FLOOR_GRAVITY = np.array([0.0, 0.0, -STANDARD_GRAVITY])


@dataclass(frozen=True)
class Payload:
    """The mass on the flange (kg) and its centre of mass in the flange frame (m)."""

    mass: float
    com: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:  # hashable and plain whatever the caller passed
        object.__setattr__(self, "mass", float(self.mass))
        object.__setattr__(self, "com", tuple(float(v) for v in self.com))

    def to_dict(self) -> dict[str, Any]:
        return {"mass": float(self.mass), "com": [float(v) for v in self.com]}

    @classmethod
    def from_dict(cls, data: Any, source: str = "payload") -> Payload:
        """Parse ``{"mass": kg, "com": [x, y, z]}``; InputError naming the field when wrong."""
        if not isinstance(data, Mapping):
            raise InputError(f"{source}: expected an object with 'mass' and 'com'")
        if "mass" not in data:
            raise InputError(f"{source}: missing field 'mass'")
        # the ranges: the "payload mass" and "payload centre of mass" rows of hil.files.quantities
        mass = quantity("payload mass").json(data["mass"], f"{source}.mass")
        com = data.get("com", [0.0, 0.0, 0.0])
        if not isinstance(com, list | tuple) or len(com) != 3:
            raise InputError(f"{source}.com: expected a list of 3 numbers (m, flange frame)")
        row = quantity("payload centre of mass")
        c = tuple(row.json(v, f"{source}.com[{i}]") for i, v in enumerate(com))
        return cls(mass, c)  # type: ignore[arg-type]


def gravity_of_mounting(rpy: Sequence[float] = (0.0, 0.0, 0.0)) -> np.ndarray:
    """Gravity (m/s²) in the base frame of an arm whose base is turned by `rpy` (rad) in the world."""
    R = pin.rpy.rpyToMatrix(*map(float, rpy))
    return R.T @ FLOOR_GRAVITY


def parse_gravity(value: Any, source: str = "gravity") -> np.ndarray:
    """A gravity vector field (m/s², base frame): three finite numbers of about 9.81 m/s² length."""
    if not isinstance(value, list | tuple) or len(value) != 3:
        raise InputError(f"{source}: expected a list of 3 numbers (m/s², base frame)")
    g = np.array([_number(v, source) for v in value])
    if abs(np.linalg.norm(g) - STANDARD_GRAVITY) > 0.1:
        raise InputError(f"{source}: {g.tolist()} is not gravity (its length must be about "
                         f"{STANDARD_GRAVITY} m/s²)")
    return g


def _number(value: Any, source: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not np.isfinite(value):
        raise InputError(f"{source}: expected a finite number, got {value!r}")
    return float(value)
