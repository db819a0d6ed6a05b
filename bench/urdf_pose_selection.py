"""Poses selected vs random at equal count for arms read from their URDFs: the held-out truth
error after identification. Not a test: it prints a table and asserts nothing.

    python bench/urdf_pose_selection.py [--trials 4] [--count 40] [--candidates 3000] [--seed 1] [--plain]
        [--arms panda,kinova,z1] [--draws 8] [--per-trial]

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
joint 2's [0.82, 5.46] rad); the Cramér–Rao prediction is √(trace(J_v C J_vᵀ)/500) on the truth's
Jacobian, with C the least-squares covariance (JᵀJ)⁻¹ Jᵀ Σ J (JᵀJ)⁻¹ under each pose's full noise
Σ_i = σ²·I + σ_q²·S_i S_iᵀ (S_i the SMR's motion per radian of each joint: the encoders' noise too).
Errors pooled over trials as root-mean-square.

How sure a figure is: one trial's held-out mean square error is a quadratic form δᵀAδ of the
parameter error δ ~ N(0, C) (A the held-out poses' mean J_vᵀJ_v), so its spread is predicted too:
variance 2·trace((AC)²), a few directions of A·C carrying most of it. The table gives, beside each
pooled ratio, its predicted 1-σ spread (delta method on the two pooled mean squares) and the ratio
the Cramér–Rao predictions alone give; `--per-trial` prints every trial's figures.

Why `--draws` (default 8): with one noise draw per pose set, four trials cannot tell the designs
apart. On the Kinova (`--draws 1`, seed 1, 4 trials) the selected sets ended at 24.2 µm against their
19.5 µm prediction and random at 21.2 µm (ratio 0.88 ± 0.15 predicted, against 1.31 from the
predictions); two of the four selected sets drew 2.1–2.3× their predicted mean square. Measured 12
times more, those same two sets averaged 0.86–1.10× it, with or without the encoders' noise and with
or without the prior: the designs were as predicted, the draws unlucky. One draw's mean square
scatters by about ±45 % of its expectation (a few directions of A·C carry it), so a design is judged
by its expected error: `--draws N` measures each chosen set N times. The encoders' noise moves the
prediction by about 1 % (5 µm RMS per point against 20 µm per axis of the tracker's), which is why
weighting the selector's information by each pose's full covariance was not needed.
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
from hil.calibration.synthetic import ENCODER_SIGMA, Noise, measure, random_truth
from selector.candidates import Constraints, sampling_box
from selector.search import select
from tests.hil.robot_urdfs import arm

SIGMA = 20e-6
ARMS = ("panda", "kinova", "z1")


def trial(name: str, count: int, candidates: int, rng: np.random.Generator,
          prior: bool = True, draws: int = 1) -> dict[str, float]:
    """Mean squared held-out errors (m²) and CR predictions of one station, selected and random, each
    pose set measured and identified `draws` times (the error averaged over them)."""
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
        errors, seconds, kept = [], [], np.ones(len(q), dtype=bool)
        for _ in range(draws):  # the same poses measured again: fresh noise, same design
            q_read, p = measure(truth, q, Noise(SIGMA), rng)
            t0 = time.perf_counter()
            fit = identify(Measurements.from_arrays(q_read, p), chain, prior=prior)
            seconds.append(time.perf_counter() - t0)
            errors.append(float(np.mean(np.sum((Kinematics(fit.geometry).points(qv) - true_v) ** 2, axis=1))))
            kept &= fit.used
        out[f"{method}_seconds"] = float(np.mean(seconds))
        out[method] = float(np.mean(errors))
        C = least_squares_covariance(truth_kin, q[kept], idx)
        A = np.einsum("nji,njk->ik", Jv, Jv) / len(qv)  # held-out mean JvᵀJv
        AC = A @ C
        out[f"{method}_cr"] = float(np.trace(AC))
        out[f"{method}_cr_var"] = float(2.0 * np.trace(AC @ AC)) / draws
    return out


def least_squares_covariance(kin: Kinematics, q: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """The parameters' covariance of a least-squares fit at poses `q` whose points err by σ per axis
    and whose joints read with the encoders' σ_q (module docstring): (JᵀJ)⁻¹ Jᵀ Σ J (JᵀJ)⁻¹."""
    J = kin.jacobian(q, idx)  # (N, 3, p)
    S = kin.joint_sensitivities(q)  # (N, 3, dof)
    Jf = J.reshape(-1, len(idx))
    inv = np.linalg.pinv(Jf.T @ Jf)
    SJ = np.einsum("nij,nik->njk", S, J)  # (N, dof, p): Sᵢᵀ Jᵢ
    meat = SIGMA**2 * Jf.T @ Jf + ENCODER_SIGMA**2 * np.einsum("nji,njk->ik", SJ, SJ)
    return inv @ meat @ inv


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=4)
    parser.add_argument("--count", type=int, default=40)
    parser.add_argument("--candidates", type=int, default=3000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--plain", action="store_true", help="plain least squares instead of the MAP fit")
    parser.add_argument("--arms", default=",".join(ARMS), help=f"comma-separated, of {', '.join(ARMS)}")
    parser.add_argument("--draws", type=int, default=8,
                        help="measure and identify each chosen pose set this many times (fresh noise)")
    parser.add_argument("--per-trial", action="store_true", help="print every trial's figures too")
    args = parser.parse_args()
    print(f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; {args.trials} trials per arm, "
          f"{args.count} poses from {args.candidates} candidates, each set measured {args.draws} times, "
          f"500 held-out poses, σ = 20 µm, "
          f"{'plain least squares' if args.plain else 'MAP fit (hil default)'}")
    print(f"{'arm':8} {'params':>6} {'selected µm':>11} {'CR µm':>7} {'random µm':>9} {'CR µm':>7} "
          f"{'random/selected':>15} {'± 1σ':>5} {'CR ratio':>8} {'fit s':>6}")
    for name in args.arms.split(","):
        rng = np.random.default_rng(args.seed)
        rows = []
        for k in range(args.trials):
            rows.append(trial(name, args.count, args.candidates, rng, not args.plain, args.draws))
            if args.per_trial:
                r = rows[-1]
                said = ", ".join(f"{label} {np.sqrt(r[m]) * 1e6:.1f} µm "
                                 f"(CR {np.sqrt(r[m + '_cr']) * 1e6:.1f}, "
                                 f"mean square {r[m] / r[m + '_cr']:.2f} ± "
                                 f"{np.sqrt(r[m + '_cr_var']) / r[m + '_cr']:.2f} of CR's)"
                                 for label, m in (("selected", "tabu"), ("random", "random")))
                print(f"  {name} trial {k}: {said}", flush=True)

        def rms(key: str, rows: list[dict[str, float]] = rows) -> float:
            return float(np.sqrt(np.mean([r[key] for r in rows]))) * 1e6

        seconds = np.mean([r["tabu_seconds"] for r in rows])
        ratio = rms("random") / rms("tabu")
        spread = ratio * ratio_spread(rows)
        print(f"{name:8} {rows[0]['parameters']:6.0f} {rms('tabu'):11.1f} {rms('tabu_cr'):7.1f} "
              f"{rms('random'):9.1f} {rms('random_cr'):7.1f} {ratio:15.2f} {spread:5.2f} "
              f"{rms('random_cr') / rms('tabu_cr'):8.2f} {seconds:6.2f}", flush=True)


def ratio_spread(rows: list[dict[str, float]]) -> float:
    """Predicted relative 1-σ spread of the pooled RMS ratio random/selected: each pooled mean square's
    predicted variance (sum of the trials' 2·trace((AC)²)) over its predicted mean, halved for the
    square root, the two added in quadrature (delta method; module docstring)."""
    rel = [np.sqrt(sum(r[f"{m}_cr_var"] for r in rows)) / sum(r[f"{m}_cr"] for r in rows)
           for m in ("tabu", "random")]
    return 0.5 * float(np.hypot(*rel))


if __name__ == "__main__":
    main()
