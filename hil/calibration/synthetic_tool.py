"""Synthetic 6-D and several-reflector measurements: a true arm carrying a measured tool, for tests.

`random_tool` puts a tool on a truth (`hil.calibration.synthetic.random_truth`): a frame tilted at
random (a camera is mounted however its bracket allows) and further reflectors a few centimetres from
the SMR; `measure_tool` reads it as an instrument would, every position with Gaussian noise σ_p per
axis and the orientation turned by a Gaussian rotation vector of σ_o per axis (R = exp(n)·R_true, the
residual convention of `hil.arm.tool_frame`); `write_tool_csv` writes the FIGAROH form hil reads
(``x1,y1,z1[,x2…],phix1,phiy1,phiz1`` and the URDF joint names).
"""

from __future__ import annotations

import os

import numpy as np
import pinocchio as pin

from hil.arm import tool_frame as tf
from hil.arm.geometry import Geometry
from hil.calibration.measurement_forms import URDF_JOINT_NAMES
from hil.calibration.measurements import Measurements, joint_columns
from hil.files.outputs import atomic_write_text, format_csv


def random_tool(truth: Geometry, rng: np.random.Generator, reflectors: int = 1,
                orientation: bool = True) -> Geometry:
    """`truth` carrying a tool: a random frame orientation (with `orientation`) and `reflectors` − 1
    further reflectors within ±6 cm of the SMR."""
    out = truth.copy()
    if orientation:
        out.tool_rotation = pin.exp3(rng.normal(0.0, 1.0, 3))
    if reflectors > 1:
        rows = [out.smr] + [out.smr + rng.uniform(-0.06, 0.06, 3) for _ in range(reflectors - 1)]
        out.reflectors = np.array(rows)
    return out


def measure_tool(truth: Geometry, q: np.ndarray, rng: np.random.Generator, position_noise: float,
                 orientation_noise: float | None, source: str = "<synthetic>") -> Measurements:
    """What an instrument reads of `truth`'s tool at configurations `q` (module docstring);
    `orientation_noise` None: positions only."""
    p, R = tf.predict(truth, q)
    p = p + rng.normal(0.0, position_noise, p.shape)
    rotation = None
    if orientation_noise is not None:
        rotation = np.array([pin.exp3(rng.normal(0.0, orientation_noise, 3)) @ Rk for Rk in R])
    q = np.asarray(q, dtype=float)
    return Measurements(q, p[:, 0].copy(), np.arange(2, len(q) + 2), source, "", rotation,
                        p if p.shape[1] > 1 else None)


def write_tool_csv(path: str | os.PathLike[str], meas: Measurements, joints: tuple[str, ...] | None = None
                   ) -> None:
    """`meas` as a FIGAROH-form CSV: markers ``x<k>,y<k>,z<k>``, then ``phix1,phiy1,phiz1`` (roll,
    pitch, yaw of R = Rz·Ry·Rx) when it has orientations, then the joints (radians) under `joints`:
    by default a UR's URDF joint names, ``q1..qN`` for an arm of N ≠ 6 joints (an arm from its URDF
    reads ``q1..qN``, so pass `joint_columns(6)` for one of six)."""
    points = meas.p[:, None, :] if meas.reflectors is None else meas.reflectors
    header = [f"{a}{k + 1}" for k in range(points.shape[1]) for a in "xyz"]
    parts = [points.reshape(len(points), -1)]
    if meas.rotation is not None:
        header += ["phix1", "phiy1", "phiz1"]
        parts.append(np.array([pin.rpy.matrixToRpy(R) for R in meas.rotation]))
    if joints is None:
        joints = URDF_JOINT_NAMES if meas.q.shape[1] == 6 else joint_columns(meas.q.shape[1])
    header += list(joints)
    parts.append(meas.q)
    atomic_write_text(path, format_csv(tuple(header), np.hstack(parts)))
