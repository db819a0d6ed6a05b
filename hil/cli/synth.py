"""`hil synth`: a synthetic arm with hidden errors and its simulated measurements."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from hil.arm.catalog import ROBOT_NAMES, get_robot
from hil.calibration.measurements import write_measurements
from hil.calibration.model_file import load_truth, truth_document, write_json
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.cli._common import wrote


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("synth", help="write a synthetic truth and simulated measurements",
                       description="Make a random realistic arm (or load --truth), measure it at random "
                                   "poses with tracker noise and write truth.json, measurements.csv "
                                   "and validation.csv into --out-dir.")
    p.add_argument("--robot", default="ur5e", help=f"robot type ({', '.join(ROBOT_NAMES)})")
    p.add_argument("--truth", metavar="truth.json", help="use this hil-truth/1 instead of a random one")
    p.add_argument("--poses", type=int, default=30, help="calibration poses (measurements.csv)")
    p.add_argument("--validation", type=int, default=100, help="validation poses (validation.csv)")
    p.add_argument("--noise", type=float, default=None, metavar="METRES",
                   help="tracker noise per axis (default 20e-6, or the truth's)")
    p.add_argument("--seed", type=int, default=1,
                   help="random seed of the truth, the poses and the noise; equal seeds give equal files")
    p.add_argument("--out-dir", required=True, metavar="DIR", help="directory to write the three files to")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hil.errors import InputError

    if args.poses < 1 or args.validation < 0:
        raise InputError("--poses must be at least 1 and --validation at least 0")
    if args.noise is not None and not (np.isfinite(args.noise) and args.noise >= 0):
        raise InputError("--noise must be a non-negative number of metres")
    rng = np.random.default_rng(args.seed)
    if args.truth:
        truth, noise = load_truth(args.truth)
    else:
        truth, noise = random_truth(get_robot(args.robot).name, rng), Noise()
    if args.noise is not None:
        noise = Noise(args.noise, noise.encoder_sigma)
    out = Path(args.out_dir)
    q, p = measure(truth, random_configurations(truth.robot, args.poses, rng), noise, rng)
    qv, pv = measure(truth, random_configurations(truth.robot, args.validation, rng), noise, rng)
    write_json(out / "truth.json", truth_document(truth, noise))
    write_measurements(out / "measurements.csv", q, p)
    write_measurements(out / "validation.csv", qv, pv)
    wrote(out / "truth.json", "the hidden truth")
    wrote(out / "measurements.csv", f"{args.poses} poses")
    wrote(out / "validation.csv", f"{args.validation} poses")
    return 0
