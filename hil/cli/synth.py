"""`hil synth`: a synthetic arm with hidden errors and its simulated measurements."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from hil.arm.catalog import ROBOT_NAMES
from hil.arm.joint_physics import IDEAL_BY_DEFAULT, standstill_sigma
from hil.calibration.measurements import write_measurements
from hil.calibration.model_file import load_truth, truth_document, write_json
from hil.calibration.synthetic import Noise, measure, random_configurations, random_truth
from hil.cli.support.options import JSON_FILE, SEED, option
from hil.cli.support.output import say, wrote
from hil.cli.support.urdf_options import URDF_SCOPE, add_urdf_options, urdf_chain_or_none
from hil.jobs.outcome import EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("synth", help="write a synthetic truth and simulated measurements",
                       description="Make a random realistic arm (or load --truth), measure it at random "
                                   "poses with tracker and encoder noise and write truth.json, "
                                   "measurements.csv and validation.csv into --out-dir. The random arm "
                                   "has compliant joints carrying an SMR payload and warms up as it "
                                   "runs (the poses are measured cold); --rigid makes it without. "
                                   "It also has the joint errors and lost motion of a UR's joints "
                                   "(every pose approached from below in every joint, as hil's campaign "
                                   "approaches them), which keep a calibrated model at tenths of a "
                                   "millimetre as on a real arm; --ideal leaves them out. "
                                   + URDF_SCOPE + " Such an arm's random truth has geometric errors "
                                   "only (its compliance, joint errors and warm-up are not modelled) "
                                   "and its measurements are q1..qN,x,y,z.")
    p.add_argument("--robot", help=f"robot type ({', '.join(ROBOT_NAMES)}; default ur5e, or the truth's)")
    add_urdf_options(p)
    p.add_argument("--truth", metavar="truth.json", type=JSON_FILE,
                   help="use this hil-truth/1 instead of a random one")
    # rows of a CSV: 100 000 are ~10 MB; 1e9 asked numpy for 45 GiB (exit 70)
    p.add_argument("--poses", type=option("synthetic poses"), default=30,
                   help="calibration poses (measurements.csv)")
    p.add_argument("--validation", type=option("synthetic poses or none"), default=100,
                   help="validation poses (validation.csv)")
    # a laser tracker's noise is micrometres (AT960: 15 µm + 6 µm/m MPE): 1 mm is already a poor
    # instrument, and 1 (m) is a value in millimetres
    p.add_argument("--noise", type=option("tracker noise"), default=None, metavar="METRES",
                   help="a flat tracker noise per axis instead of the default, the tracker's "
                        "distance-dependent error (hil.calibration.tracker_noise; AT960), or the truth's")
    p.add_argument("--rigid", action="store_true",
                   help="a random arm without compliance, payload and warm-up (geometry errors only)")
    p.add_argument("--ideal", action=argparse.BooleanOptionalAction, default=None,
                   help="--ideal: the random arm without joint errors and lost motion (a calibrated model "
                        "reaches hundredths of a millimetre); --no-ideal: with them (tenths, as real "
                        "arms). Default: the simulator's (--help's description says which). "
                        "Not with --truth, whose own blocks rule")
    p.add_argument("--seed", type=SEED, default=1,
                   help="random seed of the truth, the poses and the noise; equal seeds give equal files")
    p.add_argument("--out-dir", required=True, metavar="DIR", help="directory to write the three files to")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hil.cli.support.output_paths import campaign_store
    from hil.errors import InputError
    from hil.files.outputs import check_output_dir

    db, where = campaign_store()
    check_output_dir(args.out_dir, field="--out-dir", inputs={"--truth": args.truth, "--urdf": args.urdf},
                     store=db,
                     store_field=where, names=("truth.json", "measurements.csv", "validation.csv"))
    if args.rigid and args.truth:
        raise InputError("--rigid makes a random arm: it cannot be combined with --truth")
    if args.ideal is not None and args.truth:
        raise InputError(f"--{'' if args.ideal else 'no-'}ideal makes a random arm: it cannot be combined "
                         "with --truth, whose own blocks say what the arm has")
    rng = np.random.default_rng(args.seed)
    from hil.station.robot_type import Claim, agreed_robot, option_claim

    chain = urdf_chain_or_none(args)
    if chain is not None and args.truth:
        raise InputError("--urdf makes a random arm from a URDF: it cannot be combined with --truth, "
                         "which carries its own URDF")
    if chain is not None and args.ideal is False:
        raise InputError("--no-ideal: joint errors and lost motion are modelled for Universal Robots "
                         f"arms only, not for an arm from its URDF ({args.urdf})")
    claims = option_claim(args.robot)
    if chain is not None:
        truth, noise = random_truth(chain, rng, rigid=True), Noise()
        if not args.rigid:
            say(f"{args.urdf}: the random {chain.name} has geometric errors only (compliance, joint errors "
                "and warm-up are modelled for Universal Robots arms only)")
    elif args.truth:
        truth, noise = load_truth(args.truth)
        if truth.chain is not None and claims:
            raise InputError(f"--robot names a catalog UR, but the truth {args.truth} is of "
                             f"{truth.robot} from its URDF")
        # --robot beside --truth must name the truth's arm: silently using either hides a mistake
        if truth.chain is None:
            agreed_robot([*claims, Claim(truth.robot, f"the truth {args.truth} is for {truth.robot}")])
    else:
        ideal = IDEAL_BY_DEFAULT if args.ideal is None else args.ideal
        robot = agreed_robot(claims, default="ur5e")
        # the realistic arm's repeatability goes with its truth, for a simulated station that runs it
        # (`hil calibrate --sim --truth`); the measurements here take the joints as they stand
        stops = 0.0 if args.rigid or ideal else standstill_sigma(robot)
        truth, noise = random_truth(robot, rng, rigid=args.rigid, ideal=ideal), Noise(standstill_sigma=stops)
    if args.noise is not None:
        noise = Noise(args.noise, noise.encoder_sigma, standstill_sigma=noise.standstill_sigma)
    out = Path(args.out_dir)
    # every pose approached from below in every joint, as a campaign does (a UR's lost motion needs it)
    up = np.ones(6) if truth.chain is None else None
    q, p = measure(truth, random_configurations(truth.identity, args.poses, rng), noise, rng, directions=up)
    qv, pv = measure(truth, random_configurations(truth.identity, args.validation, rng), noise, rng,
                     directions=up)
    write_json(out / "truth.json", truth_document(truth, noise))
    write_measurements(out / "measurements.csv", q, p)
    write_measurements(out / "validation.csv", qv, pv)
    wrote(out / "truth.json", "the hidden truth")
    wrote(out / "measurements.csv", f"{args.poses} poses")
    wrote(out / "validation.csv", f"{args.validation} poses")
    return EXIT_OK
