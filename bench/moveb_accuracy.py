"""Benchmark: how much a calibration improves the path a MOVEB program really follows (simulator).

    python bench/moveb_accuracy.py [--seed 5] [--program hil/moveb/examples/square.moveb]

On the simulated station (a random "true" arm, hidden from hil; the real ur_rtde and the GeoCOM
tracker driver against their protocol simulators) the same program runs three times:

* **nominal**: IK on the catalogue model. The tracker pose is then unknown, so the measured path is
  rigidly fitted to the commanded one (the figures favour it: a rigid misplacement is not seen);
* **nominal IK, calibrated frame**: the same nominal IK, measured in the calibrated model's base frame
  (its tracker pose and SMR): the uncalibrated arm's absolute path error;
* **calibrated**: IK on the model `hil calibrate --sim` identified for the same arm (same seed);
* **truth**: IK on the simulator's own truth, the best any calibration could do.

Reported per run (ISO 9283-style path accuracy, mm): max and RMS distance of the measured points
to the commanded path, and the largest corner deviation (distance from a programmed corner point to
the measured path; "planned" is the same for the commanded path, which the bridges keep within E);
with a model both in the model's base frame and after the same rigid fit as the nominal run.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def hil(*args: str) -> dict:
    """Run the CLI; its JSON output (moveb run), or {} (calibrate prints a summary, the file is read)."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    res = subprocess.run([sys.executable, "-m", "hil", *args], capture_output=True, text=True, env=env,
                         cwd=ROOT, timeout=1800)
    if res.returncode != 0:
        raise SystemExit(f"hil {' '.join(args)} failed ({res.returncode}): {res.stderr.strip()[-500:]}")
    return json.loads(res.stdout[res.stdout.index("{"):]) if "{" in res.stdout else {}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--program", default=str(ROOT / "hil" / "moveb" / "examples" / "square.moveb"))
    ap.add_argument("--velocity", default="100")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        result = Path(tmp) / "result.json"
        hil("calibrate", "--sim", "--speed", "20", "--seed", str(args.seed), "--out", str(result),
            "--db", str(Path(tmp) / "hil.db"))
        doc = json.loads(result.read_text())
        truth = Path(tmp) / "truth.json"
        truth.write_text(json.dumps(doc["truth"]))
        print(f"calibration: validation RMS {doc['validation']['after']['rms'] * 1e6:.1f} µm "
              f"({time.perf_counter() - t0:.0f} s)")
        rows = []
        runs = (("nominal", None, "model"), ("nominal IK, calibrated frame", result, "nominal"),
                ("calibrated", result, "model"), ("truth", truth, "model"))
        for name, model, ik in runs:
            t0 = time.perf_counter()
            extra = ["--model", str(model), "--ik", ik] if model else []
            run = hil("moveb", "run", args.program, "--sim", "--seed", str(args.seed), "--frame", "current",
                      "--velocity", args.velocity, *extra)
            rows.append((name, run, time.perf_counter() - t0))
    print(f"\nprogram {Path(args.program).name}, seed {args.seed}, {args.velocity} mm/s\n")
    print("| model | frame | max dev. (mm) | RMS dev. (mm) | max corner dev. (mm) | planned (mm) | "
          "cycle (s) | peak joint speed (% of max) | peak joint acc. (rad/s²) | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, run, wall in rows:
        speed = max(run["joint_speeds"]["peak_fraction"]) * 100
        accel = max(run["joint_speeds"]["peak_acceleration_rad_s2"])
        views = [("fitted" if run["registered"] else "model", run["path_accuracy"])]
        if run.get("path_accuracy_registered"):
            views.append(("fitted", run["path_accuracy_registered"]))
        for frame, acc in views:
            corner = max((c for c in acc["corner_deviation_measured_mm"] if c is not None),
                         default=float("nan"))  # null: a corner the tracker did not see
            planned = max(acc["corner_deviation_commanded_mm"], default=float("nan"))
            print(f"| {name} | {frame} | {acc['max_deviation_mm']:.4f} | {acc['rms_deviation_mm']:.4f} | "
                  f"{corner:.4f} | {planned:.4f} | {run['cycle_time_s']:.2f} | {speed:.1f} | {accel:.2f} | "
                  f"{wall:.0f} |")


if __name__ == "__main__":
    main()
