"""A simulated robot's factory calibration: the DH deltas its controller was shipped with.

A real UR controller does not move with the nominal DH table: each arm is measured at the factory and
its controller adds per-joint deltas (θ, a, d, α) to the nominal table (its calibration.conf, published
as the KinematicsInfo package). Those deltas make the controller's model better than nominal but not
exact, because

* the DH chain cannot represent every error of a real arm: the tilt and offset of joint 1 against the
  base, the flange's offsets off the DH axes (4 + 2 parameters of the 30 a 6R arm has), and the
  near-singular parallel joints 2–4, whose exact fit needs cancelling d deltas of hundreds of metres
  (a real calibration.conf shows ``delta_d = [.., 232.67, -229.36, -3.31, ..]`` on a UR5,
  ros-industrial-attic/ur_modern_driver#108); the fit here keeps them bounded with a small ridge
  term, as the product's model limits expect (`hil.arm.controller_model.MAX_DELTA_LENGTH`);
* the factory measured the arm with errors of its own (rig, fixture, temperature) and the arm has
  moved since (shipping, mounting): modelled as a random placement error of every joint and of the
  flange, added to the truth before the fit.

`factory_calibration(truth, seed)` fits the 24 deltas to the flange poses of the perturbed truth over
random configurations (scipy least squares) and sizes the factory-rig perturbation so that the
controller model's flange position error against the truth, RMS over the workspace, is
`TARGET_RMS`. Where the DH chain alone already misses by more, no perturbation is
added: the controller is then the best bounded DH fit, still neither the truth nor nominal.

`TARGET_RMS` is an *assumed* figure: Universal Robots publish no absolute accuracy, and no measured
figure of a factory-calibrated UR's absolute accuracy could be verified from the sources available
when this was written. What was checked: UR say arms differ by "multiple millimeters" at full
stretch without calibration (universal-robots.com, "Kinematic Robot Calibration", 2025); a UR5's
factory model differs from the nominal URDF by up to about 3 mm (ur_modern_driver#108) — the fits
here differ from nominal by 3–6 mm at most over the whole joint space, the same order.
Replace `TARGET_RMS` with a cited figure when one is at hand.

Without a truth (a bare controller), `random_factory_calibration(robot, seed)` draws deltas of the
same size directly. Both are deterministic per seed.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares

from hil.arm.catalog import get_robot
from hil.arm.controller_model import ControllerCalibration
from hil.arm.geometry import Geometry
from hil.arm.kinematics import N_PARAMETERS, Kinematics, apply_update
from hil.calibration.synthetic import random_configurations

#: Assumed RMS flange position error of a factory-calibrated UR's controller model against the real
#: arm, over its whole workspace (see the module docstring: not a verified published figure). Not
#: scaled by reach: the simulated truths' own errors are not either (`random_truth`).
TARGET_RMS = 1.5e-3  # m
#: Size of one unit of factory-rig/shipping error per joint origin and flange: translation per axis
#: and rotation per axis. The fit scales it (`factory_calibration`), so only the ratio matters; it is
#: the ratio of the truths' own placement errors (`hil.calibration.synthetic.random_truth`).
RIG_TRANSLATION = 1e-3  # m
RIG_ROTATION = 2e-3  # rad
#: Size of a bare controller's random deltas: of the order the fits give (θ, α a few mrad; a, d a
#: few tenths of a millimetre to millimetres with the ridge below).
BARE_ANGLE_SIGMA = 1e-3  # rad
BARE_LENGTH_SIGMA = 0.5e-3  # m
#: Ridge weight on the deltas (per metre / radian). Small against millimetre residuals, so it only
#: picks the bounded solution among the near-equivalent ones of the parallel joints 2–4.
RIDGE = 1e-2
#: Metres per radian when flange orientation errors join position errors in the fit (a 0.1 m tool).
ORIENTATION_WEIGHT = 0.1
FIT_POSES = 48
CHECK_POSES = 200
#: Mixed into the seed so the factory draw is independent of every other draw made from the seed
#: (the truth, the start pose, encoder noise).
_STREAM = 0x46414354


def _rng(seed: int) -> np.random.Generator:
    return np.random.default_rng([int(seed) & 0xFFFFFFFF, _STREAM])


#: Deltas a UR calibration leaves at zero: a6 and α6 (UR's published UR10e KinematicsInfo example and
#: ur_calibration's output have dh_a[5] = dh_alpha[5] = 0 — the flange is placed by θ6 and d6 alone), so
#: the fit keeps them zero and the ROS kinematics YAML can hold every simulated controller.
_FIXED = (6 + 5, 18 + 5)
_FREE = np.setdiff1d(np.arange(24), _FIXED)


def _calibration(free: np.ndarray) -> ControllerCalibration:
    x = np.zeros(24)
    x[_FREE] = free
    return ControllerCalibration(x[0:6], x[6:12], x[12:18], x[18:24])


def _flanges(cal: ControllerCalibration, robot: str, Q: np.ndarray) -> np.ndarray:
    return Kinematics(cal.geometry(robot)).flange_poses(Q)


def fit_deltas(robot: str, target: np.ndarray, Q: np.ndarray) -> ControllerCalibration:
    """The bounded DH deltas whose flange poses best match `target` (N, 4, 4) at configurations `Q`."""

    def residual(x: np.ndarray) -> np.ndarray:
        F = _flanges(_calibration(x), robot, Q)
        dp = F[:, :3, 3] - target[:, :3, 3]
        M = np.einsum("nji,njk->nik", F[:, :3, :3], target[:, :3, :3])  # R_model^T R_target
        dw = 0.5 * np.stack([M[:, 2, 1] - M[:, 1, 2], M[:, 0, 2] - M[:, 2, 0], M[:, 1, 0] - M[:, 0, 1]], 1)
        return np.concatenate([dp.ravel(), ORIENTATION_WEIGHT * dw.ravel(), RIDGE * x])

    return _calibration(least_squares(residual, np.zeros(_FREE.size)).x)


def position_errors(cal: ControllerCalibration, truth: Geometry, Q: np.ndarray) -> np.ndarray:
    """(N, 3) flange position of the controller model minus the truth's, at configurations `Q`."""
    return _flanges(cal, truth.robot, Q)[:, :3, 3] - Kinematics(truth).flange_poses(Q)[:, :3, 3]


def rms(errors: np.ndarray) -> float:
    """RMS length of (N, 3) position errors."""
    return float(np.sqrt(np.mean(np.sum(np.asarray(errors) ** 2, axis=1))))


def factory_calibration(truth: Geometry, seed: int) -> ControllerCalibration:
    """The controller calibration a factory would have given the arm `truth` (deterministic per seed).

    Three fits: to the truth itself, to the truth with one unit of rig error, and to the truth with
    the rig error scaled so the model's RMS error reaches `TARGET_RMS` (the error is close to linear
    in the scale at millimetre sizes, so the scale comes from the first two).
    """
    rng = _rng(seed)
    robot = truth.robot
    Q = random_configurations(robot, FIT_POSES, rng)
    Qc = random_configurations(robot, CHECK_POSES, rng)
    unit = np.zeros(N_PARAMETERS)
    sizes = np.tile(np.r_[np.full(3, RIG_TRANSLATION), np.full(3, RIG_ROTATION)], 7)
    unit[: sizes.size] = rng.normal(0.0, sizes)  # the six joint origins and the flange

    def fitted(scale: float) -> ControllerCalibration:
        seen = apply_update(truth, scale * unit) if scale else truth
        return fit_deltas(robot, Kinematics(seen).flange_poses(Q), Q)

    base = fitted(0.0)
    e0 = position_errors(base, truth, Qc).ravel()
    goal = TARGET_RMS ** 2 * len(Qc)
    if e0 @ e0 >= goal:
        return base
    d = position_errors(fitted(1.0), truth, Qc).ravel() - e0
    a, b, c = d @ d, 2 * e0 @ d, e0 @ e0 - goal
    if a <= 0:
        return base
    scale = (-b + np.sqrt(b * b - 4 * a * c)) / (2 * a)
    return fitted(float(scale))


def random_factory_calibration(robot: str, seed: int) -> ControllerCalibration:
    """Deltas of a factory calibration's size for a controller that simulates no particular arm."""
    rng = _rng(seed)
    get_robot(robot)
    angle = rng.normal(0.0, BARE_ANGLE_SIGMA, (2, 6))
    length = rng.normal(0.0, BARE_LENGTH_SIGMA, (2, 6))
    length[0, 5] = angle[1, 5] = 0.0  # a6 and α6 stay zero, as on a real UR (see _FIXED)
    return ControllerCalibration(delta_theta=angle[0], delta_a=length[0], delta_d=length[1],
                                 delta_alpha=angle[1])
