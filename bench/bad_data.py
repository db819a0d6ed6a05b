"""Does `hil identify` ever export a model that makes the arm worse? Bad data and good data, counted.

The promise: *a fit can never silently make the robot worse*. On bad data (few poses, a
camera's noise on a tracker's job, an outlier or two) the MAP fit shrinks toward nominal and
cross-validation must say whether what is left is better than the nominal model; a model it calls
better is exported (`hil identify` exits 0, `hil export` takes it). This bench counts the cases where
that promise breaks: **exported, and worse than nominal against the truth** — the RMS of the model's
error against the noise-free true arm over `HELD_OUT` fresh poses, beside the nominal model's
(tracker pose and SMR offset fitted to the same data, `hil.calibration.identification.register`).
Target 0. On good data (tracker-grade noise, enough poses) the same count must stay 0 *and* every
model must be exported: a rule that refuses everything would also meet the target.

Each case is one station: a random realistic truth of a UR5e or a UR10e
(`hil.calibration.synthetic.random_truth`: placement errors, compliance, the SMR's payload, warm-up,
joint errors and lost motion of `hil.arm.joint_physics`), random poses with the upper arm above the
base, each approached from below in every joint (as the campaign engine does), measured with
`hil.calibration.synthetic.measure`. Bad data: `--bad` cases with 10–15 poses (the command refuses
fewer: 27 parameters need 10), 0.5–2 mm flat noise per axis (a flange camera's), every fourth case
with one or two gross outliers (5–20 mm). Good data: `--good` cases with 25–40 poses at the simulated
tracker's noise (`Noise()`). Every case goes through the command itself — the measurements are
written as a CSV and ``hil identify`` runs in this process (`hil.cli.main`), so its defaults (outlier
rejection, the prior, ``--joint-errors auto``, the cross-validated verdict) are what is measured.

Run: OPENBLAS_NUM_THREADS=1 python bench/bad_data.py [--bad 60] [--good 20] [--seed 0] [--verbose]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

from hil.arm.kinematics import Kinematics
from hil.calibration.identification import register
from hil.calibration.measurements import Measurements, write_measurements
from hil.calibration.model_file import load_geometry
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth, true_points
from hil.cli import main as hil_main

#: Fresh poses on which a model's error against the truth is measured.
HELD_OUT = 500
ROBOTS = ("ur5e", "ur10e")


@dataclass(frozen=True)
class Case:
    """One station's data: which arm, how many poses, how noisy, how many gross outliers."""

    kind: str  # "bad" or "good"
    robot: str
    seed: int
    poses: int
    sigma: float | None  # m per axis, flat; None: the simulated tracker's `Noise()`
    outliers: int


@dataclass(frozen=True)
class Outcome:
    """What `hil identify` said of one case, and what the truth says."""

    case: Case
    code: int  # hil identify's exit code: 0 exported, 1 not better than nominal
    truth_calibrated: float  # m, RMS over HELD_OUT fresh poses
    truth_nominal: float
    cv_calibrated: float
    cv_nominal: float
    p_value: float
    groups: tuple[str, ...]

    @property
    def exported(self) -> bool:
        return self.code == 0

    @property
    def worse(self) -> bool:
        return self.truth_calibrated > self.truth_nominal


def cases(kind: str, count: int, seed: int) -> list[Case]:
    """`count` cases of `kind` drawn from `seed` (module docstring)."""
    rng = np.random.default_rng([seed, 0 if kind == "bad" else 1])
    out = []
    for i in range(count):
        robot = ROBOTS[i % 2]
        if kind == "bad":
            out.append(Case(kind, robot, int(rng.integers(2**31)), int(rng.integers(10, 16)),
                            float(rng.uniform(0.5e-3, 2e-3)), int(rng.integers(1, 3)) if i % 4 == 3 else 0))
        else:
            out.append(Case(kind, robot, int(rng.integers(2**31)), int(rng.integers(25, 41)), None, 0))
    return out


def poses(robot: str, count: int, rng: np.random.Generator) -> np.ndarray:
    """Random poses with the upper arm above the base, as a floor arm works."""
    q = random_configurations(robot, count, rng)
    q[:, 1] = rng.uniform(-np.pi, 0.0, count)
    return q


def rms(err: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.sum(err**2, axis=1))))


def run_case(case: Case, folder: Path) -> Outcome:
    """Measure the case's station, run ``hil identify`` on it and judge its model against the truth."""
    rng = np.random.default_rng(case.seed)
    truth = random_truth(case.robot, rng, ideal=False)
    q = poses(case.robot, case.poses, rng)
    up = np.ones(6)  # every pose approached from below in every joint
    noise = Noise() if case.sigma is None else Noise(case.sigma)
    q_read, p = measure(truth, q, noise, rng, directions=up)
    for i in rng.choice(case.poses, case.outliers, replace=False):
        direction = rng.normal(size=3)
        p[i] += rng.uniform(5e-3, 20e-3) * direction / np.linalg.norm(direction)
    csv, model = folder / f"{case.kind}-{case.seed}.csv", folder / f"{case.kind}-{case.seed}.json"
    write_measurements(csv, q_read, p, np.broadcast_to(up, q.shape))
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = hil_main(["identify", "--robot", case.robot, "--measurements", str(csv), "--out", str(model),
                         "--json"])
    if code not in (0, 1):
        raise RuntimeError(f"hil identify exited {code}: {err.getvalue().strip()}")
    geometry, doc = load_geometry(model)
    cv = doc["cross_validation"]
    # the nominal model registered on the poses the fit kept (an outlier it rejected would spoil it)
    kept = np.ones(case.poses, dtype=bool)
    kept[[r["pose"] for r in doc["fit"]["rejected"]]] = False
    nominal = register(Measurements.from_arrays(q_read[kept], p[kept]), case.robot)
    qv = poses(case.robot, HELD_OUT, rng)
    actual = true_points(truth, qv, directions=up)
    choice = doc.get("joint_error_selection") or {}
    calibrated = Kinematics(geometry).points(qv, directions=np.broadcast_to(up, qv.shape))
    return Outcome(case, code, rms(calibrated - actual), rms(Kinematics(nominal).points(qv) - actual),
                   cv["calibrated"]["rms"], cv["nominal"]["rms"], float(cv["p_value_nominal"]),
                   tuple(choice.get("groups", ())))


def table(outcomes: list[Outcome]) -> None:
    """The counts per kind of data (module docstring)."""
    print(f"{'data':5} {'robot':6} {'cases':>5} {'exported':>8} {'refused':>7} {'exp.&worse':>10} "
          f"{'worse(all)':>10} {'truth cal/nom (median)':>22}")
    for kind in ("bad", "good"):
        for robot in (*ROBOTS, "all"):
            rows = [o for o in outcomes if o.case.kind == kind and robot in ("all", o.case.robot)]
            if not rows:
                continue
            exported = sum(o.exported for o in rows)
            ratio = np.median([o.truth_calibrated / o.truth_nominal for o in rows])
            print(f"{kind:5} {robot:6} {len(rows):5d} {exported:8d} {len(rows) - exported:7d} "
                  f"{sum(o.exported and o.worse for o in rows):10d} {sum(o.worse for o in rows):10d} "
                  f"{ratio:22.3f}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bad", type=int, default=60, help="bad-data cases")
    ap.add_argument("--good", type=int, default=20, help="good-data cases")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--verbose", action="store_true", help="one line per case")
    args = ap.parse_args()
    t0 = time.perf_counter()
    outcomes = []
    with tempfile.TemporaryDirectory() as tmp:
        for case in cases("bad", args.bad, args.seed) + cases("good", args.good, args.seed):
            o = run_case(case, Path(tmp))
            outcomes.append(o)
            if args.verbose or (o.exported and o.worse):
                c = o.case
                print(f"{c.kind:4} {c.robot:6} seed {c.seed:10d} {c.poses:2d} poses "
                      f"σ {'tracker' if c.sigma is None else f'{c.sigma * 1e3:.2f} mm'} "
                      f"outliers {c.outliers}: {'exported' if o.exported else 'refused '} "
                      f"truth {o.truth_calibrated * 1e3:.3f} vs nominal {o.truth_nominal * 1e3:.3f} mm, "
                      f"CV {o.cv_calibrated * 1e3:.3f} vs {o.cv_nominal * 1e3:.3f} mm, p {o.p_value:.3g}"
                      f"{' ' + ','.join(o.groups) if o.groups else ''}"
                      f"{'  EXPORTED BUT WORSE' if o.exported and o.worse else ''}", flush=True)
    print(f"\n{args.bad} bad-data and {args.good} good-data cases, seed {args.seed}, "
          f"{time.perf_counter() - t0:.0f} s")
    table(outcomes)
    bad = sum(o.exported and o.worse for o in outcomes)
    good_refused = sum(not o.exported for o in outcomes if o.case.kind == "good")
    return 0 if bad == 0 and good_refused == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
