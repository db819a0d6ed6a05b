"""A simulated cell for the verification's tests: a true arm, the controller's own model (nominal DH
plus factory deltas that are not the truth), a tracker, and the pose test designed for them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hil.arm.controller_model import ControllerCalibration
from hil.arm.geometry import Geometry, pose
from hil.calibration.synthetic import random_truth
from hil.compensation.solve import Compensator
from hil.verify.design import MODES, Design, default_cube, design_test
from mocks.world import World

KEEP_IN = (np.array([-2.0, -2.0, 0.0]), np.array([2.0, 2.0, 2.0]))


@dataclass
class Cell:
    truth: Geometry
    controller: Geometry
    compensator: Compensator
    world: World
    home: np.ndarray

    def design(self, cycles: int = 3, modes: tuple[str, ...] = MODES, turn: float = 0.0) -> Design:
        cube = default_cube(self.truth.robot, self.truth.tracker.translation, turn)
        return design_test(self.compensator, cube, self.truth.smr, self.truth.tracker.translation,
                           tracker_source="model", modes=modes, cycles=cycles, keep_in=KEEP_IN,
                           acceptance_angle=30.0, start=self.home)


def cell(robot: str = "ur5e", seed: int = 3) -> Cell:
    rng = np.random.default_rng(seed)
    truth = random_truth(robot, rng, rigid=True)  # the ISO 9283 test is the subject, not the sag
    deltas = ControllerCalibration(rng.normal(0, 1e-3, 6), rng.normal(0, 3e-4, 6), rng.normal(0, 3e-4, 6),
                                   rng.normal(0, 1e-3, 6))
    controller = deltas.geometry(robot)
    world = World(truth, lambda: np.zeros(6))
    home = world.home_pose(rng)
    return Cell(truth, controller, Compensator(truth, controller, pose(truth.smr)), world, home)
