"""Benchmark: MOVEB (G2, G3) against circular-arc blending (G1) and an interpolating cubic spline.

    python bench/moveb.py [--points 1000] [--seed 1]

Same paths, same thresholds (D, E) and the same Cartesian limits for all methods. Reported per
method: max curvature, the largest curvature jump at a piece junction, cycle time (the same feed
profile code: v, a, jerk, normal acceleration and normal jerk), compute time (the curve only,
not sampling or timing; for MOVEB the whole of `plan_program`, see the printed footnote), and the
two errors MOVEB controls: max distance from an original point to the curve and max deviation from
the polyline. Planning time is also reported per 1,000 points.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from hil.moveb.baselines import Profile, arc_blend, cubic_spline
from hil.moveb.path_plan import plan_program
from hil.moveb.program import format_program, parse_program
from hil.moveb.timing import Limits, feed_profile

LIMITS = Limits(velocity=250.0, acceleration=2000.0, jerk=20000.0, normal_acceleration=2000.0)
RATE = 500.0


def polyline(rng: np.random.Generator, n: int, max_turn_deg: float, planar: bool) -> np.ndarray:
    d = np.array([1.0, 0.0, 0.0])
    pts = [np.zeros(3)]
    for _ in range(n - 1):
        axis = np.array([0, 0, 1.0]) if planar else rng.normal(size=3)
        axis -= (axis @ d) * d
        axis /= np.linalg.norm(axis)
        ang = np.radians(rng.uniform(-max_turn_deg, max_turn_deg))
        d = d * np.cos(ang) + np.cross(axis, d) * np.sin(ang)
        pts.append(pts[-1] + d * rng.uniform(5, 40))
    return np.array(pts)


def deviations(P: np.ndarray, pos: np.ndarray) -> tuple[float, float]:
    """(max distance of an original point to the samples' polyline, max distance of a sample to P's
    polyline) — via a KD-tree on densified copies (0.02 mm), accurate to about 1 µm."""
    from scipy.spatial import cKDTree

    def densify(V: np.ndarray, step: float = 0.02) -> np.ndarray:
        seg = np.diff(V, axis=0)
        n = np.maximum(np.ceil(np.linalg.norm(seg, axis=1) / step).astype(int), 1)
        idx = np.repeat(np.arange(len(seg)), n)
        frac = np.concatenate([np.arange(k) / k for k in n])
        return np.r_[V[idx] + seg[idx] * frac[:, None], V[-1:]]

    point_err = cKDTree(densify(pos)).query(P)[0].max()
    chord = cKDTree(densify(P)).query(pos)[0].max()
    return float(point_err), float(chord)


def metrics(name: str, P: np.ndarray, prof: Profile, seconds: float, jump: float) -> dict[str, object]:
    law = feed_profile(prof.s, prof.curvature, LIMITS, RATE)
    point_err, chord = deviations(P, prof.position)
    return {"method": name, "kmax": float(prof.curvature.max()), "jump": jump,
            "cycle": law.cycle_time, "ms": seconds * 1e3, "point_err": point_err, "chord": chord}


def run_case(label: str, P: np.ndarray, D: float, E: float) -> list[dict[str, object]]:
    n = len(P)
    prog = parse_program(format_program(P, np.tile([0, 0, -1.0], (n, 1)), np.tile([1.0, 0, 0], (n, 1)), D, E))
    rows = []
    for cont in ("G2", "G3"):
        plan_program(prog, cont)  # warm-up (imports, HiGHS)
        cpu = []
        for _ in range(3):
            # CPU time (the benchmark machine may be shared) of the whole process, so that work on
            # helper threads (a multithreaded BLAS, a solver's pool) would be counted too
            t0 = time.process_time()
            best = plan_program(prog, cont)
            cpu.append(time.process_time() - t0)
        grid = best.sample_grid(0.05, per_bridge=64)
        ev = best.curve.evaluate(grid)
        junctions = np.r_[best.curve._s0[1:], best.curve.point_arclength()[1:-1]]
        left, right = best.curve.evaluate(junctions - 1e-7), best.curve.evaluate(junctions + 1e-7)
        jump = float(np.max(np.abs(right["curvature"] - left["curvature"])))
        prof = Profile(grid, ev["position"], ev["curvature"], min(cpu), junctions)
        row = metrics(f"MOVEB {cont}", P, prof, min(cpu), jump)
        row["iterations"] = best.solution.iterations
        rows.append(row)
    arc = arc_blend(P, min(D, E))  # .seconds: the curve only, not its sampling
    rows.append(metrics("arc blend G1", P, arc, arc.seconds, float(arc.curvature.max())))  # 0 → 1/r
    cub = cubic_spline(P)
    rows.append(metrics("cubic spline", P, cub, cub.seconds, 0.0))  # C2 by construction
    for r in rows:
        r["case"] = label
    return rows


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--points", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--D", type=float, default=0.5)
    ap.add_argument("--E", type=float, default=0.2)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    cases = [("planar, turns ≤ 90°", polyline(rng, args.points, 90.0, True)),
             ("3-D, turns ≤ 120°", polyline(rng, args.points, 120.0, False))]
    print(f"{args.points} points per path, D = {args.D} mm, E = {args.E} mm; "
          f"limits v {LIMITS.velocity} mm/s, "
          f"a {LIMITS.acceleration} mm/s², j {LIMITS.jerk} mm/s³, a_n {LIMITS.normal_acceleration} mm/s²; "
          f"{RATE:.0f} Hz\n")
    print("| path | method | max κ (1/mm) | max κ jump (1/mm) | cycle time (s) | compute (ms) "
          "| max point error (mm) | max chord dev. (mm) | iterations |")
    print("|---|---|---|---|---|---|---|---|---|")
    t0 = time.perf_counter()
    for label, P in cases:
        for r in run_case(label, P, args.D, args.E):
            print(f"| {r['case']} | {r['method']} | {r['kmax']:.3f} | {r['jump']:.3g} | {r['cycle']:.2f} "
                  f"| {r['ms']:.1f} | {r['point_err']:.3f} | {r['chord']:.3f} | {r.get('iterations', '')} |")
    print(f"\n(total {time.perf_counter() - t0:.0f} s; MOVEB compute = the whole of plan_program, "
          "best of 3 runs after a warm-up, process CPU time: reading the program's arrays, every LP "
          "solve of the point-error iteration, the curve (control points, arc-length tables of all "
          "bridges, piece table: everything Plan.at needs) and the orientation splines; not the dense "
          "sampling or the time law, which come after planning)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
