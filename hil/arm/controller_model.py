"""The robot controller's own kinematic model: UR's nominal DH plus its factory calibration deltas.

A UR controller cannot load hil's model. It moves, reports ``actual_TCP_pose`` and solves FK/IK with
the nominal DH table plus per-robot deltas (θ, a, d, α per joint) measured at the factory — the
numbers of its ``calibration.conf``, published on the primary/secondary interfaces as the
KinematicsInfo package (full DH values, i.e. nominal + delta, plus a checksum per joint and a
calibration status). Compensation needs that model beside hil's accurate one: a target is solved with
the accurate model and sent as the pose the controller's model maps those joints to.

The DH chain T = Π Rz(θi + qi)·Tz(di)·Tx(ai)·Rx(αi) is a `Geometry` like any other: Rz(θi + qi)·Tz(di)
= Tz(di)·Rz(qi)·Rz(θi), so joint 1's origin is Tz(d1), joint i+1's is Rz(θi)·Tx(ai)·Rx(αi)·Tz(di+1)
and the flange is Rz(θ6)·Tx(a6)·Rx(α6). With zero deltas this is exactly `Geometry.nominal`, so one
kinematics engine (pinocchio, `hil.arm.kinematics`) evaluates both models.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pinocchio as pin

from hil.arm.catalog import RobotSpec, get_robot
from hil.arm.geometry import Geometry, pose
from hil.errors import InputError
from hil.files.quantities import quantity

#: The four DH quantities of a UR calibration, in the order of the contract and of KinematicsInfo.
DELTA_KEYS: tuple[str, ...] = ("delta_theta", "delta_a", "delta_d", "delta_alpha")
#: Plausible size of a factory delta. Real calibrations are not all small: on the parallel joints 2–4
#: UR's calibration moves the DH frames along nearly parallel axes, so d deltas of hundreds of *metres*
#: occur there, and they cancel (a UR5's calibration.conf in ur_modern_driver issue #108 has delta_d of
#: +232.67, −229.36 and −3.31 m on joints 2–4, summing to 0.00 m, and a delta_theta of −0.77 rad;
#: ur_calibration's documentation shows d2 ≈ 439 m). Every other length delta is a physical offset of
#: millimetres. So: a and the d of joints 1, 5, 6 within `MAX_DELTA_LENGTH`; each d of joints 2–4 within
#: `MAX_PARALLEL_D` and their sum within `MAX_DELTA_LENGTH`. Beyond, a value is a unit mistake (millimetres
#: for metres) or a corrupted file.
MAX_DELTA_LENGTH = quantity("controller length delta").high  # m
MAX_PARALLEL_D = quantity("controller parallel d delta").high  # m
PARALLEL_JOINTS = (1, 2, 3)  # 0-based: joints 2, 3 and 4
MAX_DELTA_ANGLE = quantity("controller angle delta").high  # rad


@dataclass(frozen=True)
class ControllerCalibration:
    """Deltas a UR controller adds to its nominal DH (radians and metres, 6 each)."""

    delta_theta: np.ndarray = field(default_factory=lambda: np.zeros(6))
    delta_a: np.ndarray = field(default_factory=lambda: np.zeros(6))
    delta_d: np.ndarray = field(default_factory=lambda: np.zeros(6))
    delta_alpha: np.ndarray = field(default_factory=lambda: np.zeros(6))

    def __post_init__(self) -> None:
        for key in DELTA_KEYS:
            value = np.array(getattr(self, key), dtype=float).reshape(6)
            value.setflags(write=False)
            object.__setattr__(self, key, value)

    # --- the full DH table the controller uses (what KinematicsInfo publishes) -----------------
    def dh(self, robot: str | RobotSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(θ, a, d, α) = nominal + deltas, as KinematicsInfo's dh_theta, dh_a, dh_d, dh_alpha."""
        spec = robot if isinstance(robot, RobotSpec) else get_robot(robot)
        return (self.delta_theta.copy(),
                np.asarray(spec.dh.a, float) + self.delta_a,
                np.asarray(spec.dh.d, float) + self.delta_d,
                np.asarray(spec.dh.alpha, float) + self.delta_alpha)

    @classmethod
    def from_dh(cls, robot: str | RobotSpec, theta: Sequence[float], a: Sequence[float],
                d: Sequence[float], alpha: Sequence[float]) -> ControllerCalibration:
        """The deltas of a full DH table (KinematicsInfo) relative to the robot's nominal one."""
        spec = robot if isinstance(robot, RobotSpec) else get_robot(robot)
        return cls(np.asarray(theta, float), np.asarray(a, float) - np.asarray(spec.dh.a, float),
                   np.asarray(d, float) - np.asarray(spec.dh.d, float),
                   np.asarray(alpha, float) - np.asarray(spec.dh.alpha, float))

    def checksums(self) -> list[int]:
        """Per-joint uint32 checksums (CRC-32 of that joint's four deltas, big-endian doubles).

        A real controller's KinematicsInfo checksum identifies each joint's stored calibration; this
        one does the same job for a simulated controller: it changes whenever a joint's deltas do.
        """
        return [zlib.crc32(struct.pack(">4d", *(getattr(self, k)[j] for k in DELTA_KEYS)))
                for j in range(6)]

    def is_zero(self) -> bool:
        return all(not np.any(getattr(self, k)) for k in DELTA_KEYS)

    # --- as a geometry -------------------------------------------------------------------------
    def geometry(self, robot: str | RobotSpec, smr: Sequence[float] = (0.0, 0.0, 0.0),
                 tracker: pin.SE3 | None = None) -> Geometry:
        """The controller's model as a `Geometry` (see the module docstring for the regrouping)."""
        spec = robot if isinstance(robot, RobotSpec) else get_robot(robot)
        theta, a, d, alpha = self.dh(spec)

        def link(i: int, d_next: float) -> pin.SE3:
            return (pose((0.0, 0.0, 0.0), (0.0, 0.0, theta[i])) * pose((a[i], 0.0, 0.0), (alpha[i], 0.0, 0.0))
                    * pose((0.0, 0.0, d_next)))

        joints = [pose((0.0, 0.0, d[0]))] + [link(i, d[i + 1]) for i in range(5)]
        return Geometry(spec.name, joints, link(5, 0.0), np.asarray(smr, float),
                        pin.SE3.Identity() if tracker is None else tracker)

    # --- the JSON "controller" block (docs/design.md, Contracts: the controller's own calibration) ---
    def to_dict(self) -> dict[str, list[float]]:
        return {k: [float(v) for v in getattr(self, k)] for k in DELTA_KEYS}

    @classmethod
    def from_dict(cls, data: Any, source: str = "controller") -> ControllerCalibration:
        """Parse a ``controller`` block; InputError naming the field when it is missing or wrong."""
        if not isinstance(data, Mapping):
            raise InputError(f"{source}: expected an object with {', '.join(DELTA_KEYS)}")
        values: dict[str, np.ndarray] = {}
        for key in DELTA_KEYS:
            if key not in data:
                raise InputError(f"{source}: missing field '{key}'")
            raw = data[key]
            if not isinstance(raw, list) or len(raw) != 6:
                raise InputError(f"{source}: field '{key}' must be a list of 6 numbers")
            angle = key in ("delta_theta", "delta_alpha")
            out = np.empty(6)
            for i, v in enumerate(raw):
                name = ("controller angle delta" if angle else "controller parallel d delta"
                        if key == "delta_d" and i in PARALLEL_JOINTS else "controller length delta")
                out[i] = quantity(name).json(v, f"{source}: {key}[{i}]")
            values[key] = out
        net = float(sum(values["delta_d"][i] for i in PARALLEL_JOINTS))
        if abs(net) > MAX_DELTA_LENGTH:
            raise InputError(f"{source}: delta_d[1] + delta_d[2] + delta_d[3] = {net:.6g} m: the parallel "
                             "joints' d deltas cancel on a real calibration "
                             f"(beyond ±{MAX_DELTA_LENGTH:g} m)")
        return cls(**values)


def controller_geometry(robot: str, calibration: ControllerCalibration | None) -> Geometry:
    """The controller's model of `robot` (nominal when no calibration is known)."""
    return (calibration or ControllerCalibration()).geometry(robot)
