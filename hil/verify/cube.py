"""The ISO 9283 test cube, its measuring plane and the five test poses P1–P5.

ISO 9283:1998 (§6.2–6.3, as publicly summarised, e.g. by RoboDK's "Robot validation ISO 9283" page and
Slamani, Nubiola & Bonev, *Industrial Robot* 39(1), 2012, pp. 57–68; the standard's own text was not
at hand) places the tests in a cube with edges parallel to the base frame, as large as the part of the
working space with the most use allows. Its corners are C1–C8 and the poses lie in the diagonal plane
C1-C2-C7-C8: P1 at the cube's centre (where the plane's diagonals cross) and P2–P5 on those diagonals,
(10 ± 2) % of the diagonal's length L in from its ends. The plane's diagonals are the cube's space
diagonals C1–C7 and C2–C8, so L = √3 · edge and P2–P5 lie 0.4 · L from P1.

Corner numbering used here (the standard's figure numbers the bottom face C1–C4 and the top face
C5–C8 above them, so C1-C2 and C7-C8 are opposite, parallel edges): with unit offsets from the centre,
C1 (−,−,−), C2 (+,−,−), C3 (+,+,−), C4 (−,+,−), C5 (−,−,+), C6 (+,−,+), C7 (+,+,+), C8 (−,+,+).
P2–P5 sit near C1, C2, C7 and C8 in that order.

One cycle visits P1, P5, P4, P3, P2 (ISO 9283 §7.2.1, each pose approached from the same side every
time: the unidirectional approach); the pose test repeats the cycle 30 times.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from hil.errors import InputError

POSE_NAMES: tuple[str, ...] = ("P1", "P2", "P3", "P4", "P5")
#: The order of one cycle (ISO 9283 §7.2.1).
CYCLE_ORDER: tuple[str, ...] = ("P1", "P5", "P4", "P3", "P2")
#: ISO 9283's cycles of the pose test.
ISO_CYCLES = 30
#: P2–P5 lie this fraction of the diagonal in from its corners (the standard allows 10 ± 2 %).
CORNER_FRACTION = 0.10
#: Unit offsets of C1–C8 from the centre (see the module docstring).
CORNER_SIGNS = np.array([(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1),
                         (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)], dtype=float)
#: P2–P5: (the corner each is near, the corner at the other end of its diagonal), 0-based C indices.
_NEAR_CORNER = ((0, 6), (1, 7), (6, 0), (7, 1))  # C1→C7, C2→C8, C7→C1, C8→C2


@dataclass(frozen=True)
class Cube:
    """The test cube: centre (robot base frame, m) and edge length (m), edges along the base axes."""

    centre: np.ndarray
    edge: float

    def __post_init__(self) -> None:
        centre = np.array(self.centre, dtype=float).reshape(3)
        if not np.all(np.isfinite(centre)) or not (np.isfinite(self.edge) and self.edge > 0):
            raise InputError(f"test cube: centre {centre.tolist()} and edge {self.edge} must be finite, "
                             "the edge positive")
        centre.setflags(write=False)
        object.__setattr__(self, "centre", centre)
        object.__setattr__(self, "edge", float(self.edge))

    @property
    def diagonal(self) -> float:
        """Length L of the measuring plane's diagonals (the cube's space diagonal)."""
        return float(np.sqrt(3.0) * self.edge)

    def corners(self) -> np.ndarray:
        """(8, 3) corners C1–C8 in the base frame."""
        return self.centre + 0.5 * self.edge * CORNER_SIGNS

    def poses(self) -> np.ndarray:
        """(5, 3) positions of P1–P5 in the base frame, in `POSE_NAMES` order."""
        c = self.corners()
        near = [c[a] + CORNER_FRACTION * (c[b] - c[a]) for a, b in _NEAR_CORNER]
        return np.vstack([self.centre, *near])

    def plane_normal(self) -> np.ndarray:
        """Unit normal of the measuring plane C1-C2-C7-C8."""
        c = self.corners()
        n = np.cross(c[1] - c[0], c[7] - c[0])
        return n / np.linalg.norm(n)

    def to_dict(self) -> dict[str, Any]:
        return {"centre": [float(v) for v in self.centre], "edge": self.edge}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Cube:
        return cls(np.asarray(data["centre"], dtype=float), float(data["edge"]))


def pose_index(name: str) -> int:
    """0-based position of a pose name in `POSE_NAMES` (``"P3"`` → 2)."""
    return POSE_NAMES.index(name)
