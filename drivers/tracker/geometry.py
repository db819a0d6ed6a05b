"""Polar ↔ Cartesian conversion of tracker readings: the single source of truth.

The driver converts what the instrument reports and the simulator converts the true SMR position
with the *same* functions, so a convention mistake cannot hide in one of them.

Convention (Leica surveying, the one TMC_GetCoordinate uses for East/North/Height):

* ``hz`` — horizontal angle in radians, measured **clockwise** (seen from above) from the
  tracker's +y axis ("north") towards +x ("east"), in [0, 2π);
* ``v`` — zenith angle in radians: 0 straight up along +z, π/2 horizontal;
* ``d`` — slope distance in metres from the tracker's centre to the SMR centre.

    x = d·sin(v)·sin(hz)      (east)
    y = d·sin(v)·cos(hz)      (north)
    z = d·cos(v)              (up)

The tracker frame (x east, y north, z up) is right-handed, so the orchestrator can use it directly
as ``T_base_tracker``'s child frame.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

TWO_PI = 2.0 * math.pi


def polar_to_cartesian(hz: ArrayLike, v: ArrayLike, d: ArrayLike) -> NDArray[np.float64]:
    """Tracker-frame position(s) in metres from Hz, V (zenith) and slope distance.

    Scalars give shape (3,); arrays of shape S give shape S + (3,).
    """
    hz_a = np.asarray(hz, dtype=float)
    v_a = np.asarray(v, dtype=float)
    d_a = np.asarray(d, dtype=float)
    sin_v = np.sin(v_a)
    return np.stack((d_a * sin_v * np.sin(hz_a), d_a * sin_v * np.cos(hz_a), d_a * np.cos(v_a)), axis=-1)


def cartesian_to_polar(xyz: ArrayLike) -> tuple[float, float, float]:
    """(hz, v, d) of one tracker-frame point; hz in [0, 2π), v in [0, π].

    Raises ValueError for the origin, where the angles are undefined.
    """
    x, y, z = (float(c) for c in np.asarray(xyz, dtype=float).reshape(3))
    d = math.sqrt(x * x + y * y + z * z)
    if d == 0.0:
        raise ValueError("the tracker's own centre has no direction")
    hz = math.atan2(x, y) % TWO_PI
    if hz >= TWO_PI:  # -tiny % 2π rounds to exactly 2π
        hz = 0.0
    v = math.atan2(math.hypot(x, y), z)  # stable near the zenith, unlike acos(z/d)
    return hz, v, d
