"""The simulated world: the true arm (with hidden errors), where the tracker stands, what it can see.

The robot simulator owns the joints; the tracker simulator asks this world where the SMR truly is
(`target`, the GeoCOM simulator's `TargetSource`). The true flange pose comes from the *truth*
geometry, never from the nominal model the controller reports with, so a calibration has real
errors to find. The SMR is visible when its opening axis (the flange z axis) points within the
acceptance half-angle of the line to the tracker.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from hil.geometry import Geometry
from hil.kinematics import Kinematics
from mocks.geocom.target import TargetState


@dataclass
class World:
    """Truth + the arm's joints → the true SMR position in the tracker frame, and its visibility."""

    truth: Geometry
    joints: Callable[[], np.ndarray]
    acceptance_deg: float = 30.0
    blocked: str = ""  # non-empty: something (a person, a cable) is in the beam, and what
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def __post_init__(self) -> None:
        self._kin = Kinematics(self.truth)

    def state(self, q: np.ndarray) -> tuple[np.ndarray, float]:
        """(SMR in the tracker frame, angle in degrees between its axis and the line to the tracker)."""
        with self._lock:  # one pinocchio Data: the simulator's threads take turns
            F = self._kin.flange_poses(q)[0]
        p_base = F[:3, :3] @ self.truth.smr + F[:3, 3]
        T = self.truth.tracker
        to_tracker = T.translation - p_base
        cos = float(F[:3, 2] @ to_tracker / np.linalg.norm(to_tracker))
        p_tracker = T.rotation.T @ (p_base - T.translation)
        return p_tracker, float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))

    def target(self) -> TargetState:
        p, angle = self.state(np.asarray(self.joints(), dtype=float))
        if self.blocked:
            return TargetState(p, False, self.blocked)
        if angle > self.acceptance_deg:
            return TargetState(p, False, f"SMR faces away ({angle:.0f}° > {self.acceptance_deg:.0f}° "
                                         "acceptance)")
        return TargetState(p, True)

    def block_beam(self, on: bool = True, reason: str = "something is in the beam") -> None:
        """Fault injection: interrupt (or restore) the line of sight."""
        self.blocked = reason if on else ""

    def home_pose(self, rng: np.random.Generator, samples: int = 20000) -> np.ndarray:
        """A start pose where the operator would lock the beam: SMR facing the tracker, arm bent.

        Chosen among random configurations with the upper arm above horizontal, the elbow and wrist
        away from singularities and the elbow and SMR at least 20 cm above the base, as the one facing
        the tracker most directly.
        """
        q = rng.uniform(-np.pi, np.pi, (samples, 6))
        q[:, 1] = rng.uniform(-2.6, -0.5, samples)  # upper arm well above horizontal
        q[:, 2] = rng.uniform(0.6, 2.2, samples) * rng.choice([-1.0, 1.0], samples)
        q[:, 4] = rng.uniform(0.5, 2.6, samples) * rng.choice([-1.0, 1.0], samples)
        kin = Kinematics(self.truth)
        F = kin.flange_poses(q)
        p = np.einsum("nij,j->ni", F[:, :3, :3], self.truth.smr) + F[:, :3, 3]
        to_tracker = self.truth.tracker.translation - p
        cos = np.einsum("ni,ni->n", F[:, :3, 2], to_tracker) / np.linalg.norm(to_tracker, axis=1)
        elbow = kin.joint_frames(q)[:, 2, :3, 3]
        cos[(p[:, 2] < 0.2) | (elbow[:, 2] < 0.2)] = -2.0
        return q[int(np.argmax(cos))]
