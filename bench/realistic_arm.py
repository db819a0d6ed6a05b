"""How well a calibrated model predicts held-out poses on the simulated arms, against a real UR's figure.

Real UR5 data (Leica tracker, 39 poses, 13-fold cross-validation) give 0.215 mm held-out for a
geometry-only fit and 0.187 mm with compliance (docs/design.md, Facts: what real arms reach). For each
robot and seed: a random truth (`hil.calibration.synthetic.random_truth`), ideal (placement errors,
compliance, payload) and realistic (plus the joint errors and lost motion of `hil.arm.joint_physics`);
`--poses` random poses with the upper arm above the base, every pose approached from below in every
joint (as the campaign engine does), 20 µm tracker noise; `hil.calibration.identification.identify`
geometry-only, with compliance, and with compliance and the low-order joint errors cross-validation keeps
(`--joint-errors auto`); the RMS of the model's error against the truth over 300 held-out poses (the
truth error, noise-free) and the fit's own 10-fold cross-validated RMS (`hil.calibration.cross_validation`,
on the measured points). The last column compares the two: CV against √(truth² + 3σ²), the error a
held-out *measured* point shows (σ = 20 µm per axis).

Run: python bench/realistic_arm.py [--seeds 6] [--poses 40] [--robots ur5e,ur10e]
"""

from __future__ import annotations

import argparse

import numpy as np

from hil.arm.kinematics import Kinematics
from hil.calibration.cross_validation import cross_validate
from hil.calibration.joint_error_request import JointErrorRequest
from hil.calibration.joint_error_selection import identify_with_joint_errors
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth, true_points

HELD_OUT = 300


def poses(robot: str, count: int, rng: np.random.Generator) -> np.ndarray:
    q = random_configurations(robot, count, rng)
    q[:, 1] = rng.uniform(-np.pi, 0.0, count)  # the upper arm above the base, as a floor arm works
    return q


FITS = (("geometry", False, "none"), ("+ compliance", True, "none"), ("+ joint errors", True, "auto"))


def held_out(robot: str, seed: int, count: int, ideal: bool, compliance: bool,
             joint_errors: str = "none") -> tuple[float, float]:
    """(truth RMS over held-out poses, the fit's cross-validated RMS) in metres, of one station's fit."""
    rng = np.random.default_rng(seed)
    truth = random_truth(robot, rng, ideal=ideal)
    q = poses(robot, count, rng)
    up = np.ones(6)
    q_read, p = measure(truth, q, Noise(20e-6), rng, directions=up)
    meas = Measurements.from_arrays(q_read, p)
    fit = identify_with_joint_errors(meas, robot, request=JointErrorRequest(joint_errors),
                                     reject_outliers=False, compliance=compliance,
                                     payload=truth.payload if compliance else None)
    qv = poses(robot, HELD_OUT, rng)
    err = Kinematics(fit.geometry).points(qv) - true_points(truth, qv, directions=up)
    cv = cross_validate(meas, fit)
    return float(np.sqrt(np.mean(np.sum(err**2, axis=1)))), cv.calibrated.rms


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=6)
    ap.add_argument("--poses", type=int, default=40)
    ap.add_argument("--robots", default="ur5e,ur10e")
    args = ap.parse_args()
    print(f"held-out truth RMS (mm), {args.poses} poses, {args.seeds} seeds; real UR5: geometry 0.215, "
          "+ compliance 0.187")
    sigma3 = 3 * 20e-6**2
    print(f"{'robot':7} {'arm':10} {'fit':15} {'mean':>6} {'min':>6} {'max':>6} {'CV':>6} {'CV/meas':>8}")
    for robot in args.robots.split(","):
        for ideal in (True, False):
            for name, compliance, joint_errors in FITS:
                runs = np.array([held_out(robot, s, args.poses, ideal, compliance, joint_errors)
                                 for s in range(args.seeds)])
                rms, cv = runs[:, 0], runs[:, 1]
                ratio = cv / np.sqrt(rms**2 + sigma3)
                print(f"{robot:7} {'ideal' if ideal else 'realistic':10} {name:15} "
                      f"{rms.mean() * 1e3:6.3f} {rms.min() * 1e3:6.3f} {rms.max() * 1e3:6.3f} "
                      f"{cv.mean() * 1e3:6.3f} {ratio.min():4.2f}–{ratio.max():4.2f}")


if __name__ == "__main__":
    main()
