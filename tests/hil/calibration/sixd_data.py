"""The synthetic 6-D data the tests share: a known truth carrying a camera-like tool, and the small
committed CSV (`data/ur10e_sixd.csv`) generated from it, so `hil identify` is tested on a file."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from hil.arm.geometry import Geometry
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import random_configurations, random_truth
from hil.calibration.synthetic_tool import measure_tool, random_tool, write_tool_csv

SIXD_CSV = Path(__file__).parent / "data" / "ur10e_sixd.csv"
SEED = 30
POSES = 30
POSITION_NOISE = 0.5e-3  # m
ORIENTATION_NOISE = 0.5e-3  # rad


def tool_truth(robot: str, rng: np.random.Generator, reflectors: int, orientation: bool,
               placement: float = 1.0) -> Geometry:
    """A rigid random truth with a tool, its joint-6 origin and flange as drawn: what the tool's
    rotation and offsets absorb of them is then zero, so the tool itself can be compared. `placement`
    scales the joints' placement errors (0: the arm exactly as drawn)."""
    arm = random_truth(robot, rng, rigid=True, translation_sigma=0.5e-3 * placement,
                       rotation_sigma=1e-3 * placement)
    truth = random_tool(arm, rng, reflectors, orientation)
    nominal = Geometry.nominal(robot)
    truth.joints[5], truth.flange = nominal.joints[5], nominal.flange
    return truth


def sixd_set(seed: int = SEED, poses: int = POSES, reflectors: int = 1, orientation: bool = True,
             robot: str = "ur10e", position_noise: float = POSITION_NOISE,
             orientation_noise: float = ORIENTATION_NOISE,
             placement: float = 1.0) -> tuple[Geometry, Measurements]:
    rng = np.random.default_rng(seed)
    truth = tool_truth(robot, rng, reflectors, orientation, placement)
    q = random_configurations(robot, poses, rng)
    return truth, measure_tool(truth, q, rng, position_noise, orientation_noise if orientation else None)


def write_sixd_csv(path: Path = SIXD_CSV) -> None:
    """(Re)write the committed file: ``python -c 'from tests.hil.calibration.sixd_data import *;
    write_sixd_csv()'``."""
    write_tool_csv(path, sixd_set()[1])
