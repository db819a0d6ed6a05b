"""Compensation time per 1,000 targets: a CSV of poses and a URScript program, as `hil compensate`
does them (the library calls, no process start-up).

A simulated UR5e: hil's model is a random truth (0.5 mm / 1 mrad placement errors per joint), the
controller's model nominal DH + random factory deltas (1 mrad, 1 mm). The targets follow a cell's
motion: each a small joint step from the previous one, so each is seeded by its predecessor as in a
real program. The program holds the same targets as ``movel(p[...])`` lines between comments, a
``set_tcp`` and a move relative to a feature, so the tokenizer sees a realistic mix.

Run: python bench/compensation.py [--targets 1000] [--repeats 3] [--seed 1]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from hil.arm.controller_model import ControllerCalibration
from hil.calibration.synthetic import random_truth
from hil.compensation.poses import CANONICAL_NEAR, format_number, to_vector
from hil.compensation.solve import Compensator
from hil.compensation.targets_csv import compensate_csv
from hil.compensation.urscript import compensate_program, scan_program

ROBOT = "ur5e"


def inputs(n: int, rng: np.random.Generator) -> tuple[Compensator, str, str]:
    """The compensator, a CSV and a program of `n` targets."""
    truth = random_truth(ROBOT, rng)
    controller = ControllerCalibration(*(rng.normal(0, 1e-3, 6) for _ in range(4)))
    comp = Compensator(truth, controller.geometry(ROBOT))
    Q = np.asarray(CANONICAL_NEAR) + np.cumsum(rng.uniform(-0.02, 0.02, (n, 6)), axis=0)
    poses = [to_vector(comp.accurate_pose(q)) for q in Q]
    csv = "x,y,z,rx,ry,rz,label\n" + "".join(
        ",".join(repr(float(v)) for v in p) + f",t{i}\n" for i, p in enumerate(poses))
    lines = ["def cell():", "  set_tcp(p[0, 0, 0, 0, 0, 0])  # flange",
             "  global Plane_1 = p[.3, -.1, .05, 0, 0, 0]",
             f"  movej([{', '.join(repr(float(v)) for v in Q[0])}], a=1.4, v=1.05)"]
    for i, p in enumerate(poses):
        if i % 50 == 0:
            lines.append(f'  textmsg("block {i}: p[...] targets")  # comment')
            lines.append("  movel(pose_trans(Plane_1, p[0, 0, .01, 0, 0, 0]), a=1.2, v=0.25)")
        lines.append(f"  movel(p[{', '.join(format_number(v) for v in p)}], a=1.2, v=0.25, r=0.001)")
    program = "\n".join([*lines, "end", ""])
    return comp, csv, program


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--targets", type=int, default=1000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args()
    comp, csv, program = inputs(args.targets, np.random.default_rng(args.seed))
    near = np.asarray(CANONICAL_NEAR)
    runs = {"CSV": lambda: compensate_csv(csv, "bench.csv", comp, near),
            "CSV --joints": lambda: compensate_csv(csv, "bench.csv", comp, near, joints=True),
            "URScript": lambda: compensate_program(program, "bench.script", comp, near),
            "URScript --joints": lambda: compensate_program(program, "bench.script", comp, near, joints=True)}
    print(f"{'input':<18} {'targets':>8} {'best s':>8} {'s / 1000 targets':>17} {'ms / target':>12}")
    for name, run in runs.items():
        best = np.inf
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            _, summary = run()
            best = min(best, time.perf_counter() - t0)
        n = len(summary.moved)
        print(f"{name:<18} {n:>8} {best:>8.3f} {best / n * 1000:>17.3f} {best / n * 1e3:>12.3f}")
    # the scanner alone (tokens, calls, assignments, targets): what a long program costs before any IK
    # about 2 MB: the same lines over and over
    big = program.replace("end\n", "") * max(1, int(2e6 // len(program))) + "end\n"
    best = np.inf
    for _ in range(args.repeats):
        t0 = time.perf_counter()
        scan_program(big, "bench.script", comp.tcp)
        best = min(best, time.perf_counter() - t0)
    print(f"URScript scanner: {len(big) / 1e6:.1f} MB in {best:.2f} s, {len(big) / 1e6 / best:.2f} MB/s")


if __name__ == "__main__":
    main()
