"""ISO 9283 position accuracy AP and repeatability RP of one pose from its attained positions.

The formulas of ISO 9283:1998 §7.2.1 (accuracy) and §7.2.2 (repeatability), for n attained positions
(x_j, y_j, z_j) of a pose commanded at (x_c, y_c, z_c):

* barycentre x̄ = (1/n) Σ x_j (likewise ȳ, z̄);
* AP_x = x̄ − x_c, AP_y = ȳ − y_c, AP_z = z̄ − z_c and AP_P = √(AP_x² + AP_y² + AP_z²);
* l_j = √((x_j − x̄)² + (y_j − ȳ)² + (z_j − z̄)²), l̄ = (1/n) Σ l_j,
  S_l = √(Σ (l_j − l̄)² / (n − 1)) and RP_l = l̄ + 3 · S_l.

AP's components are along the robot base frame's axes, as the standard states them; the tracker
measures in its own frame, so the barycentre's offset is turned into the base frame by the tracker's
orientation. RP is a distance and needs no frame. Orientation accuracy and repeatability (AP_a/b/c,
RP_a/b/c) need the tool's orientation, which one SMR does not give.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class PoseAccuracy:
    """AP and RP of one pose (metres)."""

    n: int  # attained positions
    commanded: np.ndarray  # (3,) in the measuring frame
    barycentre: np.ndarray  # (3,) in the measuring frame
    ap: np.ndarray  # (3,) AP_x, AP_y, AP_z along the base frame's axes
    ap_p: float  # AP_P
    l_mean: float  # l̄
    s_l: float  # S_l (n − 1 in the denominator)
    rp_l: float  # RP_l = l̄ + 3·S_l

    def as_dict(self) -> dict[str, Any]:
        return {"n": self.n, "commanded": [float(v) for v in self.commanded],
                "barycentre": [float(v) for v in self.barycentre],
                "AP_x": float(self.ap[0]), "AP_y": float(self.ap[1]), "AP_z": float(self.ap[2]),
                "AP_P": self.ap_p, "l_mean": self.l_mean, "S_l": self.s_l, "RP_l": self.rp_l}


def pose_accuracy(attained: np.ndarray, commanded: np.ndarray,
                  to_base: np.ndarray | None = None) -> PoseAccuracy:
    """AP and RP of `attained` (n, 3) against `commanded` (3,), both in the measuring frame.

    `to_base` (3×3) turns a vector of the measuring frame into the base frame (the tracker's rotation
    in the base frame); None: they are the same frame. Needs n ≥ 2 (S_l divides by n − 1).
    """
    pts = np.asarray(attained, dtype=float).reshape(-1, 3)
    if len(pts) < 2:
        raise ValueError(f"ISO 9283 repeatability needs at least 2 attained positions, got {len(pts)}")
    commanded = np.asarray(commanded, dtype=float).reshape(3)
    bary = pts.mean(axis=0)
    offset = bary - commanded
    ap = offset if to_base is None else np.asarray(to_base, dtype=float) @ offset
    dist = np.linalg.norm(pts - bary, axis=1)
    l_mean = float(dist.mean())
    s_l = float(np.sqrt(np.sum((dist - l_mean) ** 2) / (len(pts) - 1)))
    return PoseAccuracy(len(pts), commanded, bary, ap, float(np.linalg.norm(offset)), l_mean, s_l,
                        l_mean + 3.0 * s_l)
