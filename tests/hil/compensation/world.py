"""A calibrated arm beside its controller's model, and the checks every compensation test makes."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from hil.arm.controller_model import ControllerCalibration
from hil.arm.geometry import Geometry
from hil.calibration.synthetic import random_truth
from hil.compensation.poses import CANONICAL_NEAR
from hil.compensation.solve import Compensator

ROBOT = "ur5e"
#: How exactly a compensated target must land (m, rad): the issue's round-trip bound.
EXACT = 1e-9


@dataclass
class World:
    truth: Geometry  # what hil's model says the arm is (here: exactly)
    controller: ControllerCalibration  # what the controller moves by
    rng: np.random.Generator

    def compensator(self, tcp: pin.SE3 | None = None) -> Compensator:
        tool = pin.SE3.Identity() if tcp is None else tcp
        return Compensator(self.truth, self.controller.geometry(ROBOT), tool)

    def configurations(self, count: int, spread: float = 0.5) -> np.ndarray:
        """Joints around the canonical elbow-up, tool-down configuration (one branch, no singularity)."""
        return np.asarray(CANONICAL_NEAR) + self.rng.uniform(-spread, spread, (count, 6))


def random_controller(rng: np.random.Generator, cancelling: bool = False) -> ControllerCalibration:
    """Factory deltas of a plausible size (mrad, mm); `cancelling`: the hundreds of millimetres of
    opposite d on joints 2-4 a real calibration.conf shows (docs/design.md, Facts: identification)."""
    dd = rng.normal(0, 1e-3, 6)
    if cancelling:
        dd[1:4] += np.array([0.2, -0.35, 0.15])
    return ControllerCalibration(rng.normal(0, 1e-3, 6), rng.normal(0, 1e-3, 6), dd, rng.normal(0, 1e-3, 6))


def make_world(seed: int, cancelling: bool = False) -> World:
    rng = np.random.default_rng(seed)
    # a rigid arm: these tests are about the controller's model, not the sag (compensating a compliant
    # model is its own subject)
    return World(random_truth(ROBOT, rng, rigid=True), random_controller(rng, cancelling), rng)


def assert_lands(comp: Compensator, command: pin.SE3, near: np.ndarray, target: pin.SE3) -> np.ndarray:
    """The controller solves `command` by its own model (near `near`); the accurate model then puts the
    tool at `target` to `EXACT`. Returns the controller's joints."""
    q = comp.controller_joints(command, near)
    assert_same_pose(comp.accurate_pose(q), target)
    return q


def assert_same_pose(got: pin.SE3, want: pin.SE3) -> None:
    assert np.linalg.norm(got.translation - want.translation) < EXACT
    assert np.linalg.norm(pin.log3(want.rotation.T @ got.rotation)) < EXACT
