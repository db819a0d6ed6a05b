"""Benchmark of the pose selector. Not a test: it prints a table and asserts nothing.

    python bench/pose_selection.py [--quick]

Station: UR5e, SMR 30/−20/45 mm off the flange centre, tracker at (2.5, 0.5, 0.5) m, every candidate
constraint on. Rows:

1. the headline — 30 poses from 20 000 candidates, tabu vs DETMAX exchange vs random, O1 as a
   percentage of the certified D-optimal bound, seconds, over three seeds;
2. candidate generation time with all constraints;
3. time against the candidate count (5k / 20k / 100k) and the pose count (15 / 30 / 60);
4. the Cramér–Rao prediction of the identification error (RMS over 2 000 validation poses of
   σ·√tr(J_v (JᵀJ)⁻¹ J_vᵀ), σ = 20 µm per axis, unscaled Jacobian in metres) for the chosen poses
   against random poses of the same count.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hil.calibration.selection import SelectionModel
from selector.bound import d_optimal_bound
from selector.candidates import Constraints, generate_candidates
from selector.exchange import exchange_select
from selector.indices import scale_columns
from selector.random_selection import random_select
from selector.tabu import tabu_select

TRACKER = (2.5, 0.5, 0.5)
SMR = (0.03, -0.02, 0.045)
SIGMA = 20e-6


def predicted_error(J: np.ndarray, chosen: np.ndarray, Jv: np.ndarray) -> float:
    """RMS over validation poses of the CR-predicted 3-D position error (m)."""
    X = J[chosen].reshape(-1, J.shape[2])
    C = np.linalg.inv(X.T @ X)
    per_pose = np.einsum("vij,jk,vik->v", Jv, C, Jv)
    return float(SIGMA * np.sqrt(per_pose.mean()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="skip the 100k-candidate row")
    args = parser.parse_args()
    print(f"cores: {os.cpu_count()}, numpy {np.__version__}")
    model = SelectionModel("ur5e", SMR, TRACKER)
    constraints = Constraints(tracker=TRACKER)

    t0 = time.perf_counter()
    cands = generate_candidates(model, 20_000, constraints, seed=0)
    gen = time.perf_counter() - t0
    G = scale_columns(cands.jacobian, "expected", model.parameter_scale)
    t0 = time.perf_counter()
    bound = d_optimal_bound(G)
    bound_s = time.perf_counter() - t0

    print("\n## UR5e, 30 poses from 20 000 candidates (all constraints), 3 seeds")
    print(f"candidates: {gen:.2f} s ({cands.sampled} drawn); bound: {bound_s:.2f} s, certified gap "
          f"{100 * bound.gap:.2f} %")
    print("| method | O1 % of bound (seeds 0, 1, 2) | mean % | max seconds |")
    print("|---|---|---|---|")
    chosen: dict[str, np.ndarray] = {}
    for name, fn in (("tabu", tabu_select), ("exchange", exchange_select), ("random", random_select)):
        pct, secs = [], []
        for seed in range(3):
            s = fn(G, 30, seed=seed)
            pct.append(100 * s.o1 / bound.value)
            secs.append(s.seconds)
            if seed == 0:
                chosen[name] = s.chosen
        print(f"| {name} | {', '.join(f'{p:.2f}' for p in pct)} | {np.mean(pct):.2f} | {max(secs):.2f} |")

    print("\n## time against the candidate count (30 poses, seed 0)")
    print("| candidates | generation s | tabu s | tabu % of bound | exchange s | exchange % | bound s |")
    print("|---|---|---|---|---|---|---|")
    for n in (5_000, 20_000) + (() if args.quick else (100_000,)):
        t0 = time.perf_counter()
        c = cands if n == 20_000 else generate_candidates(model, n, constraints, seed=0)
        g = gen if n == 20_000 else time.perf_counter() - t0
        Gn = scale_columns(c.jacobian, "expected", model.parameter_scale)
        t0 = time.perf_counter()
        b = d_optimal_bound(Gn)
        bs = time.perf_counter() - t0
        t, e = tabu_select(Gn, 30, seed=0), exchange_select(Gn, 30, seed=0)
        print(f"| {n} | {g:.2f} | {t.seconds:.2f} | {100 * t.o1 / b.value:.2f} | {e.seconds:.2f} | "
              f"{100 * e.o1 / b.value:.2f} | {bs:.2f} |")

    print("\n## time against the pose count (20 000 candidates, seed 0)")
    print("| poses | tabu s | tabu % of bound | exchange s | exchange % of bound |")
    print("|---|---|---|---|---|")
    for m in (15, 30, 60):
        t, e = tabu_select(G, m, seed=0), exchange_select(G, m, seed=0)
        print(f"| {m} | {t.seconds:.2f} | {100 * t.o1 / bound.value:.2f} | {e.seconds:.2f} | "
              f"{100 * e.o1 / bound.value:.2f} |")

    print("\n## Cramér–Rao predicted identification error (σ = 20 µm, 2 000 validation poses)")
    J = cands.jacobian  # metres per parameter unit
    val = generate_candidates(model, 2_000, constraints, seed=99)
    print("| poses | tabu µm | exchange µm | random µm (median of 20 draws) | random / tabu |")
    print("|---|---|---|---|---|")
    for m in (15, 30, 60):
        t = tabu_select(G, m, seed=0).chosen
        e = exchange_select(G, m, seed=0).chosen
        r = np.median([predicted_error(J, random_select(G, m, seed=s).chosen, val.jacobian)
                       for s in range(20)])
        et = predicted_error(J, t, val.jacobian)
        print(f"| {m} | {1e6 * et:.2f} | {1e6 * predicted_error(J, e, val.jacobian):.2f} | "
              f"{1e6 * r:.2f} | {r / et:.2f} |")


if __name__ == "__main__":
    main()
