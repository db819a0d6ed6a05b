"""Poses selected vs random at equal count for arms read from their URDFs: the held-out truth
error after identification. Not a test: it prints a table and asserts nothing.

    python bench/urdf_pose_selection.py [--trials 4] [--count 40] [--candidates 3000] [--seed 1] [--plain]

For the Franka Panda, the Kinova Jaco 2 and the Unitree Z1 of example-robot-data
(tests/hil/robot_urdfs.py), each trial draws a rigid synthetic truth (`random_truth`: 0.5 mm / 1 mrad
placement errors on every joint and the flange, an unknown tracker 2–4 m away, an SMR offset),
draws the feasible candidates once (`design_space`: inside the URDF's limits, the SMR facing the tracker
within 30°, the beam clear of the links, no self-collision on the URDF's meshes), and picks `count`
poses from them twice: by the tabu search on O1 (method 000) and at random. Each set is measured
(20 µm per axis, the UR's encoder noise) and identified (`identify`, hil's default MAP fit toward the
nominal geometry; `--plain`: plain least squares, what the Cramér–Rao prediction is for); the error
is the RMS distance between the identified model and the truth over 500 held-out configurations drawn
inside the limits (over the range the candidates are drawn from, `sampling_box`: all of a Kinova
joint 2's [0.82, 5.46] rad); the Cramér–Rao prediction is σ·√(trace(J_v (JᵀJ)⁻¹ J_vᵀ)/500) on the truth's
Jacobian. Errors pooled over trials as root-mean-square.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hil.arm.kinematics import Kinematics, identifiable_parameters
from hil.arm.urdf_chain import chain_from_urdf
from hil.calibration.identification import identify
from hil.calibration.measurements import Measurements
from hil.calibration.selection import design_space
from hil.calibration.synthetic import Noise, measure, random_truth
from selector.candidates import Constraints, sampling_box
from selector.search import select
from tests.hil.robot_urdfs import arm

SIGMA = 20e-6
ARMS = ("panda", "kinova", "z1")


def trial(name: str, count: int, candidates: int, rng: np.random.Generator,
          prior: bool = True) -> dict[str, float]:
    """Mean squared held-out errors (m²) and CR predictions of one station, selected and random."""
    path, tip = arm(name)
    chain = chain_from_urdf(path, tip=tip)
    truth = random_truth(chain, rng, rigid=True)
    tracker = tuple(float(v) for v in truth.tracker.translation)
    model, cands, G = design_space(chain, count, candidates=candidates, seed=int(rng.integers(1 << 30)),
                                   smr=truth.smr, constraints=Constraints(tracker=tracker),
                                   scaling="expected", compliance=False, payload=None, gravity=None,
                                   say=lambda _p, _t: None, urdf_path=str(path))
    lo, hi = sampling_box(model, Constraints())  # the range the candidates are drawn from
    qv = rng.uniform(lo, hi, size=(500, chain.dof))
    truth_kin = Kinematics(truth)
    true_v = truth_kin.points(qv)
    idx = identifiable_parameters(chain)
    Jv = truth_kin.jacobian(qv, idx)
    out: dict[str, float] = {"parameters": len(model.parameters)}
    for method in ("tabu", "random"):
        chosen = select(G, count, method=method, index="O1", seed=int(rng.integers(1 << 30))).chosen
        q = cands.q[chosen]
        q_read, p = measure(truth, q, Noise(SIGMA), rng)
        t0 = time.perf_counter()
        fit = identify(Measurements.from_arrays(q_read, p), chain, prior=prior)
        out[f"{method}_seconds"] = time.perf_counter() - t0
        out[method] = float(np.mean(np.sum((Kinematics(fit.geometry).points(qv) - true_v) ** 2, axis=1)))
        J = truth_kin.jacobian(q[fit.used], idx).reshape(-1, len(idx))
        C = np.linalg.pinv(J.T @ J)
        out[f"{method}_cr"] = float(SIGMA**2 * np.mean(np.einsum("nij,jk,nik->n", Jv, C, Jv)))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=4)
    parser.add_argument("--count", type=int, default=40)
    parser.add_argument("--candidates", type=int, default=3000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--plain", action="store_true", help="plain least squares instead of the MAP fit")
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; {args.trials} trials per arm, "
          f"{args.count} poses from {args.candidates} candidates, 500 held-out poses, σ = 20 µm, "
          f"{'plain least squares' if args.plain else 'MAP fit (hil default)'}")
    print(f"{'arm':8} {'params':>6} {'selected µm':>11} {'CR µm':>7} {'random µm':>9} {'CR µm':>7} "
          f"{'random/selected':>15} {'fit s':>6}")
    for name in ARMS:
        rng = np.random.default_rng(args.seed)
        rows = [trial(name, args.count, args.candidates, rng, not args.plain) for _ in range(args.trials)]

        def rms(key: str, rows: list[dict[str, float]] = rows) -> float:
            return float(np.sqrt(np.mean([r[key] for r in rows]))) * 1e6

        seconds = np.mean([r["tabu_seconds"] for r in rows])
        ratio = rms("random") / rms("tabu")
        print(f"{name:8} {rows[0]['parameters']:6.0f} {rms('tabu'):11.1f} {rms('tabu_cr'):7.1f} "
              f"{rms('random'):9.1f} {rms('random_cr'):7.1f} {ratio:15.2f} {seconds:6.2f}")


if __name__ == "__main__":
    main()
