"""Identification accuracy against the Cramér–Rao prediction, and identification speed.

Simulated UR5e: 0.5 mm / 1 mrad random placement errors on every joint origin and the flange, an
unknown tracker pose (2–4 m away) and SMR offset (no guess given), 20 µm per-axis tracker noise.
For each pose count, `--trials` independent stations are calibrated on random poses; the validation
RMS is the distance between the calibrated model and the hidden truth over 500 held-out poses, and
the Cramér–Rao prediction for the same poses is σ²·trace(J_v (JᵀJ)⁻¹ J_vᵀ) / 500. Both are pooled
over trials as root-mean-square (one trial's RMS scatters by ~15 % by itself).

Run: python bench/identification.py [--trials 20] [--seed 1]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hil.arm.kinematics import Kinematics, identifiable_parameters
from hil.calibration.identification import identify
from hil.calibration.measurements import Measurements
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth

ROBOT = "ur5e"
SIGMA = 20e-6


def trial(m: int, rng: np.random.Generator) -> tuple[float, float, float, float]:
    """(validation MS, Cramér–Rao MS, MS before calibration, seconds) of one simulated station."""
    truth = random_truth(ROBOT, rng)
    q = random_configurations(ROBOT, m, rng)
    _, p = measure(truth, q, Noise(SIGMA), rng)
    t0 = time.perf_counter()
    fit = identify(Measurements.from_arrays(q, p), ROBOT)
    seconds = time.perf_counter() - t0
    qv = random_configurations(ROBOT, 500, rng)
    true_v = Kinematics(truth).points(qv)
    err = Kinematics(fit.geometry).points(qv) - true_v
    before = Kinematics(fit.baseline).points(qv) - true_v
    idx = identifiable_parameters(ROBOT)
    kin = Kinematics(truth)
    J = kin.jacobian(q[fit.used], idx).reshape(-1, len(idx))
    Jv = kin.jacobian(qv, idx)
    C = np.linalg.inv(J.T @ J)
    cr = SIGMA**2 * np.mean(np.einsum("nij,jk,nik->n", Jv, C, Jv))
    return (float(np.mean(np.sum(err**2, 1))), float(cr), float(np.mean(np.sum(before**2, 1))), seconds)


def speed(m: int, rng: np.random.Generator, repeats: int) -> list[float]:
    """Wall-clock seconds of `identify` on `m` poses, per repeat."""
    out = []
    for _ in range(repeats):
        truth = random_truth(ROBOT, rng)
        q = random_configurations(ROBOT, m, rng)
        _, p = measure(truth, q, Noise(SIGMA), rng)
        meas = Measurements.from_arrays(q, p)
        t0 = time.perf_counter()
        identify(meas, ROBOT)
        out.append(time.perf_counter() - t0)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    identifiable_parameters(ROBOT)  # warm the cache outside the timings
    print(f"UR5e, 0.5 mm / 1 mrad placement errors, {SIGMA * 1e6:.0f} µm noise, unknown tracker and SMR, "
          f"{args.trials} trials per row, 500 held-out poses")
    print(f"{'poses':>5} | {'before (mm)':>11} | {'validation RMS (µm)':>19} | {'Cramér–Rao (µm)':>15} "
          f"| {'ratio':>5} | {'within 10%':>10}")
    print("-" * 84)
    for m in (15, 30, 50):
        rows = np.array([trial(m, rng) for _ in range(args.trials)])
        val, cr, before = (np.sqrt(rows[:, k].mean()) for k in range(3))
        ratio = val / cr
        print(f"{m:>5} | {before * 1e3:>11.3f} | {val * 1e6:>19.2f} | {cr * 1e6:>15.2f} | {ratio:>5.3f} "
              f"| {'yes' if abs(ratio - 1) <= 0.10 else 'NO':>10}")
    times = speed(100, rng, 20)
    print(f"\nidentify, 100 poses: median {np.median(times) * 1e3:.1f} ms, max {max(times) * 1e3:.1f} ms "
          f"over {len(times)} runs (target < 300 ms)")


if __name__ == "__main__":
    main()
