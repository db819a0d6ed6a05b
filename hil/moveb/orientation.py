"""Tool orientations along the path: B-spline interpolation of the tool axes, then orthonormalisation.

The seed interpolates the tool axes "piecewise with G2/G3 B-splines" and re-orthonormalises each
frame; the details are lost. Our reading:

* the keys are the program points' tool Z and X axes, placed at the arc length where the position
  curve passes each point (the bridge apex Q, or the point itself at the ends and straight points),
  so the orientation shares the position curve's parameter;
* each axis is interpolated component-wise by an interpolating B-spline of degree 3 (G2: C2 in s)
  or 5 (G3: C4 ⊃ C3), `scipy.interpolate.make_interp_spline`; with fewer keys than the degree needs
  the degree drops (two keys: linear, a constant axis stays exactly constant);
* each sample is re-orthonormalised by Gram–Schmidt with Z first (the tool axis is what a process
  and the SMR's acceptance cone care about): z ← z/|z|, x ← (x − (x·z)z)/|…|, y = z × x.
  Frames are orthonormal to ~1e-15. An interpolated axis that collapses (|z| or the rejected x
  nearly zero, i.e. keys about 180° apart with nothing in between) is refused: add a point.
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import BSpline, make_interp_spline

from hil.errors import InputError

DEGREE = {"G2": 3, "G3": 5}


def axis_splines(s_keys: np.ndarray, z: np.ndarray, x: np.ndarray, continuity: str
                 ) -> tuple[BSpline, BSpline]:
    """Interpolating splines of the tool Z and X axes over the key arc lengths."""
    k = min(DEGREE[continuity], len(s_keys) - 1)
    # one interpolation with six right-hand sides (same knots, same collocation matrix, one
    # factorisation), split into the two axes
    both = make_interp_spline(s_keys, np.column_stack([z, x]), k=k)
    return (BSpline.construct_fast(both.t, np.ascontiguousarray(both.c[:, :3]), k, both.extrapolate),
            BSpline.construct_fast(both.t, np.ascontiguousarray(both.c[:, 3:]), k, both.extrapolate))


def orthonormal_frames(z: np.ndarray, x: np.ndarray, where: str = "path") -> tuple[np.ndarray, np.ndarray]:
    """Gram–Schmidt with Z first: (unit z, unit x ⟂ z) per row."""
    zn = np.linalg.norm(z, axis=1)
    if np.any(zn < 1e-6):
        raise InputError(f"{where}: the interpolated tool axis I J K vanishes (keys about 180° apart); "
                         "add an intermediate point")
    z = z / zn[:, None]
    x = x - np.einsum("ij,ij->i", x, z)[:, None] * z
    xn = np.linalg.norm(x, axis=1)
    if np.any(xn < 1e-6):
        raise InputError(f"{where}: the interpolated tool axis U V W becomes parallel to I J K; "
                         "add an intermediate point")
    x = x / xn[:, None]
    # one more pass removes the rounding of the first (orthonormal to ~1e-16)
    x = x - np.einsum("ij,ij->i", x, z)[:, None] * z
    x = x / np.linalg.norm(x, axis=1)[:, None]
    return z, x


def rotation_matrices(z: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(N, 3, 3) rotations with columns x, y = z × x, z."""
    return np.stack([x, np.cross(z, x), z], axis=2)
