"""`hil calibrate --sim`: a whole calibration of a simulated arm, headless.

For now the simulated station is offline: the hidden truth is measured directly through the
kinematic model with tracker noise (no controller or instrument protocol in between). The campaign
engine against the protocol-level simulators replaces this path when it lands; the command line and
the result file stay the same.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from hil.cli._common import mm, print_json
from hil.errors import InputError
from hil.identification import identify, validate
from hil.measurements import Measurements, atomic_write_text
from hil.model_file import load_truth, model_document, truth_document
from hil.robots import ROBOT_NAMES, get_robot
from hil.synthetic import Noise, measure, random_configurations, random_truth


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("calibrate", help="run a whole calibration (simulated station)",
                       description="Calibrate a simulated arm end to end: measure, identify, validate "
                                   "on held-out poses, report. Exit code 1 if the validation RMS "
                                   "exceeds --accept.")
    p.add_argument("--sim", action="store_true", required=True, help="use the simulated station")
    p.add_argument("--truth", metavar="truth.json", help="hidden truth (default: random, by --seed)")
    p.add_argument("--robot", default="ur5e", help=f"robot type ({', '.join(ROBOT_NAMES)})")
    p.add_argument("--poses", type=int, default=30, help="calibration poses (default 30)")
    p.add_argument("--validation", type=int, default=50, help="held-out poses (default 50)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--accept", type=float, default=1e-4, metavar="METRES",
                   help="acceptance threshold on the validation RMS (default 0.1 mm)")
    p.add_argument("--json", action="store_true", help="print the result JSON on stdout")
    p.add_argument("--out", metavar="result.json", help="write the result (embeds the model)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    if args.validation < 1:
        raise InputError("--validation must be at least 1")
    rng = np.random.default_rng(args.seed)
    if args.truth:
        truth, noise = load_truth(args.truth)
    else:
        truth, noise = random_truth(get_robot(args.robot).name, rng), Noise()
    robot = truth.robot
    q, p = measure(truth, random_configurations(robot, args.poses, rng), noise, rng)
    qv, pv = measure(truth, random_configurations(robot, args.validation, rng), noise, rng)
    fit = identify(Measurements.from_arrays(q, p, "simulated-station"), robot)
    held_out = Measurements.from_arrays(qv, pv, "simulated-validation")
    before = validate(fit.baseline, held_out)
    after = validate(fit.geometry, held_out)
    passed = after.rms <= args.accept
    result = {
        "format": "hil-result/1",
        "station": "offline simulation",
        "robot": robot,
        "passed": passed,
        "accept_rms": args.accept,
        "validation": {"before": before.as_dict(), "after": after.as_dict()},
        "truth": truth_document(truth, noise),
        "model": model_document(fit, after.as_dict()),
    }
    if args.out:
        import json

        atomic_write_text(args.out, json.dumps(result, indent=2) + "\n")
    if args.json:
        print_json(result)
    else:
        out = sys.stdout
        print(f"simulated {robot}: {args.poses} calibration poses, {args.validation} validation poses, "
              f"tracker noise {noise.tracker_sigma * 1e6:.0f} µm", file=out)
        print(f"  fit: {fit.iterations} iterations, RMS {mm(fit.rms)}, "
              f"{len(fit.rejected)} rejected", file=out)
        print(f"  validation before: RMS {mm(before.rms)}  max {mm(before.max)}", file=out)
        print(f"  validation after:  RMS {mm(after.rms)}  max {mm(after.max)}  "
              f"-> {'PASS' if passed else 'FAIL'} (accept {mm(args.accept)})", file=out)
        if args.out:
            print(f"wrote {args.out}", file=out)
    return 0 if passed else 1
