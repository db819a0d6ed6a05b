"""Synthetic truths and measurements: a robot with hidden errors, for tests, benchmarks and demos.

The same generator seeds the simulators' random "truth", so a benchmark and a simulated station
describe an arm the same way: every joint origin and the flange carry a random 6-D placement error
(σ 0.5 mm per translation axis, 1 mrad per rotation axis by default), the SMR sits a few centimetres
off the flange axis, and the tracker stands 2–4 m from the base facing it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry, look_at_tracker
from hil.arm.kinematics import N_PARAMETERS, SMR_SLICE, TRACKER_SLICE, Kinematics, apply_update

DEFAULT_SMR = (0.0, 0.0, 0.045)  # flange-mounted SMR nest, 45 mm out along the flange axis


@dataclass(frozen=True)
class Noise:
    """Measurement noise of a simulated station."""

    tracker_sigma: float = 20e-6  # m, per axis (isotropic Gaussian)
    encoder_sigma: float = 0.0  # rad, per joint reading

    def as_dict(self) -> dict[str, float]:
        return {"tracker_sigma": self.tracker_sigma, "encoder_sigma": self.encoder_sigma}


def random_truth(robot: str, rng: np.random.Generator, *, translation_sigma: float = 0.5e-3,
                 rotation_sigma: float = 1e-3, smr: np.ndarray | None = None,
                 tracker_distance: tuple[float, float] = (2.0, 4.0)) -> Geometry:
    """A realistic true geometry: nominal + random placement errors, an SMR and a tracker pose."""
    spec = get_robot(robot)
    if smr is None:
        smr = np.array([rng.uniform(-0.04, 0.04), rng.uniform(-0.04, 0.04), rng.uniform(0.02, 0.06)])
    heading = rng.uniform(-np.pi, np.pi)
    dist = rng.uniform(*tracker_distance) * max(spec.reach / 0.85, 1.0) ** 0.5
    position = np.array([dist * np.cos(heading), dist * np.sin(heading), rng.uniform(-0.3, 0.6)])
    tracker = look_at_tracker(position) * pin.exp6(np.r_[np.zeros(3), rng.normal(0, 0.02, 3)])
    errors = np.zeros(N_PARAMETERS)
    placements = np.r_[np.tile(np.r_[np.full(3, translation_sigma), np.full(3, rotation_sigma)], 7)]
    errors[: placements.size] = rng.normal(0.0, placements)
    errors[SMR_SLICE] = 0.0
    errors[TRACKER_SLICE] = 0.0
    return apply_update(Geometry.nominal(spec, smr=smr, tracker=tracker), errors)


def random_configurations(robot: str, count: int, rng: np.random.Generator) -> np.ndarray:
    """Joint vectors uniformly spread over ±π per joint (inside every UR joint limit)."""
    get_robot(robot)
    return rng.uniform(-np.pi, np.pi, size=(count, 6))


def measure(truth: Geometry, q: np.ndarray, noise: Noise, rng: np.random.Generator
            ) -> tuple[np.ndarray, np.ndarray]:
    """Simulated readings at configurations `q`: (joint readings, tracker points with noise)."""
    q = np.asarray(q, dtype=float)
    p = Kinematics(truth).points(q) + rng.normal(0.0, noise.tracker_sigma, size=(len(q), 3))
    q_read = q + rng.normal(0.0, noise.encoder_sigma, size=q.shape) if noise.encoder_sigma else q.copy()
    return q_read, p
