"""How well a calibrated model predicts held-out poses on the simulated arms, against a real UR's figure.

Real UR5 data (Leica tracker, 39 poses, 13-fold cross-validation) give 0.215 mm held-out for a
geometry-only fit and 0.187 mm with compliance (docs/design.md, Facts: what real arms reach). For each
robot and seed: a random truth (`hil.calibration.synthetic.random_truth`), ideal (placement errors,
compliance, payload) and realistic (plus the joint errors and lost motion of `hil.arm.joint_physics`);
`--poses` random poses with the upper arm above the base, every pose approached from below in every
joint (as the campaign engine does), 20 µm tracker noise; `hil.calibration.identification.identify`
geometry-only and with compliance; the RMS of the model's error against the truth over 300 held-out
poses (the truth error, so noise-free: a cross-validation on measured points adds the tracker's noise,
about 0.03 mm in quadrature).

Run: python bench/realistic_arm.py [--seeds 6] [--poses 40] [--robots ur5e,ur10e]
"""

from __future__ import annotations

import argparse

import numpy as np

from hil.arm.kinematics import Kinematics
from hil.calibration.identification import identify
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth, true_points

HELD_OUT = 300


def poses(robot: str, count: int, rng: np.random.Generator) -> np.ndarray:
    q = random_configurations(robot, count, rng)
    q[:, 1] = rng.uniform(-np.pi, 0.0, count)  # the upper arm above the base, as a floor arm works
    return q


def held_out(robot: str, seed: int, count: int, ideal: bool, compliance: bool) -> float:
    """Truth RMS (m) over held-out poses of one station's fit."""
    rng = np.random.default_rng(seed)
    truth = random_truth(robot, rng, ideal=ideal)
    q = poses(robot, count, rng)
    up = np.ones(6)
    _, p = measure(truth, q, Noise(), rng, directions=up)
    fit = identify(Measurements.from_arrays(q, p), robot, reject_outliers=False, compliance=compliance,
                   payload=truth.payload if compliance else None)
    qv = poses(robot, HELD_OUT, rng)
    err = Kinematics(fit.geometry).points(qv) - true_points(truth, qv, directions=up)
    return float(np.sqrt(np.mean(np.sum(err**2, axis=1))))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=6)
    ap.add_argument("--poses", type=int, default=40)
    ap.add_argument("--robots", default="ur5e,ur10e")
    args = ap.parse_args()
    print(f"held-out truth RMS (mm), {args.poses} poses, {args.seeds} seeds; real UR5: geometry 0.215, "
          "+ compliance 0.187")
    print(f"{'robot':7} {'arm':10} {'fit':12} {'mean':>6} {'min':>6} {'max':>6}")
    for robot in args.robots.split(","):
        for ideal in (True, False):
            for compliance in (False, True):
                rms = np.array([held_out(robot, s, args.poses, ideal, compliance)
                                for s in range(args.seeds)]) * 1e3
                print(f"{robot:7} {'ideal' if ideal else 'realistic':10} "
                      f"{'+ compliance' if compliance else 'geometry':12} "
                      f"{rms.mean():6.3f} {rms.min():6.3f} {rms.max():6.3f}")


if __name__ == "__main__":
    main()
