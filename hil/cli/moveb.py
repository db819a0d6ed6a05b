"""`hil moveb`: error-controlled smooth trajectories (seed 001).

``hil moveb plan PROGRAM [--continuity G2|G3] --out samples.csv`` plans the program and writes dense
samples (``s,x,y,z,i,j,k,u,v,w,curvature``: mm, unit tool Z and X axes, 1/mm) and prints a JSON
summary. ``hil moveb run PROGRAM --config station.toml`` (or ``--sim``) streams the timed trajectory
through the robot's servo loop, samples the tracker continuously and prints the path accuracy.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from hil.cli._common import print_json
from hil.errors import InputError
from hil.robots import ROBOT_NAMES


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("moveb", help="smooth error-controlled trajectories (plan, run)",
                       description=__doc__.split("\n\n")[0])
    moveb = p.add_subparsers(dest="moveb_command", metavar="ACTION")
    plan = moveb.add_parser("plan", help="plan a MOVEB program and write dense samples")
    plan.add_argument("program", metavar="PROGRAM")
    plan.add_argument("--continuity", choices=("G2", "G3"), default="G2")
    plan.add_argument("--out", required=True, metavar="samples.csv")
    plan.add_argument("--step", type=float, default=0.5, metavar="MM",
                      help="sample spacing on straight parts (every bridge gets 64 samples too)")
    plan.add_argument("--rate", type=float, default=500.0, metavar="HZ",
                      help="controller rate for the cycle time in the summary (500 e-series, 125 CB3)")
    _limit_options(plan)
    plan.set_defaults(func=run_plan)

    run = moveb.add_parser("run", help="run a MOVEB program on the robot and measure it")
    run.add_argument("program", metavar="PROGRAM")
    src = run.add_mutually_exclusive_group(required=True)
    src.add_argument("--config", metavar="station.toml", help="station configuration")
    src.add_argument("--sim", action="store_true", help="use the simulated station")
    run.add_argument("--model", metavar="model.json",
                     help="calibrated model (hil-model/1, a campaign result that embeds one, or a truth): "
                          "IK and the tracker pose")
    run.add_argument("--ik", choices=("model", "nominal"), default="model",
                     help="with --model: solve the joints on the model (default), or on the nominal arm "
                          "and measure in the model's frame (how far off the uncalibrated arm is)")
    run.add_argument("--continuity", choices=("G2", "G3"), default="G2")
    run.add_argument("--frame", choices=("base", "current"), default="base",
                     help="program frame: the robot base, or anchored at the arm's current TCP pose")
    _limit_options(run)
    run.add_argument("--joint-speed", type=float, default=1.0, metavar="F",
                     help="allowed fraction of the datasheet joint speeds (0 < F <= 1); the feed slows "
                          "down where the path would need more")
    run.add_argument("--joint-acceleration", type=float, default=None, metavar="RAD/S2",
                     help="largest joint acceleration at the controller samples (every joint; UR "
                          "publishes none, so none by default: the peak is reported either way)")
    run.add_argument("--tracker-rate", type=float, default=100.0, metavar="HZ")
    run.add_argument("--min-coverage", type=float, default=0.9, metavar="F",
                     help="share of the path the tracker must measure; below it the run is reported "
                          "'incomplete' (exit code 1)")
    run.add_argument("--truth", metavar="truth.json", help="--sim: the hidden truth (default: random)")
    run.add_argument("--speed", type=float, default=1.0, metavar="F", help="--sim: fast-time factor")
    run.add_argument("--seed", type=int, default=1, help="--sim: seed of the random truth and noise")
    run.add_argument("--robot", default="ur5e", help=f"--sim: robot type ({', '.join(ROBOT_NAMES)})")
    run.add_argument("--out", metavar="result.json", help="write the path-accuracy result")
    run.add_argument("--plot", metavar="run.png",
                     help="write a figure: commanded and measured path, deviation along the path")
    run.set_defaults(func=run_run)
    p.set_defaults(func=lambda args: (p.print_help(sys.stderr), 2)[1])


def _limit_options(p: argparse.ArgumentParser) -> None:
    """The Cartesian limits of the feed profile (tool point)."""
    p.add_argument("--velocity", type=float, default=100.0, metavar="MM/S")
    p.add_argument("--acceleration", type=float, default=1000.0, metavar="MM/S2")
    p.add_argument("--jerk", type=float, default=10000.0, metavar="MM/S3")
    p.add_argument("--normal-acceleration", type=float, default=1000.0, metavar="MM/S2")


def run_plan(args: argparse.Namespace) -> int:
    from hil.moveb.plan import plan_program, summary, write_samples
    from hil.moveb.program import load_program

    if not args.step > 0:
        raise InputError(f"--step must be positive, got {args.step}")
    if Path(args.out).is_dir():
        raise InputError(f"{args.out}: is a directory")
    from hil.moveb.timing import Limits

    if not args.rate > 0:
        raise InputError(f"--rate must be positive, got {args.rate}")
    limits = Limits(args.velocity, args.acceleration, args.jerk, args.normal_acceleration)
    plan = plan_program(load_program(args.program), args.continuity)
    write_samples(args.out, plan.dense(args.step))
    law, _samples = plan.timed(limits, args.rate)
    # the Cartesian limits only: joint speeds depend on where the arm runs it (`hil moveb run`)
    print_json(dict(summary(plan), cycle_time_s=law.cycle_time, rate_hz=args.rate,
                    limits={"velocity": limits.velocity, "acceleration": limits.acceleration,
                            "jerk": limits.jerk, "normal_acceleration": limits.normal_acceleration}))
    return 0


def run_run(args: argparse.Namespace) -> int:
    from hil.moveb.run import run_from_cli

    for path in (args.out, args.plot):
        if path and Path(path).is_dir():
            raise InputError(f"{path}: is a directory")

    doc = run_from_cli(args)
    if args.out:
        from hil.measurements import atomic_write_text

        atomic_write_text(args.out, json.dumps(doc, indent=2, allow_nan=False) + "\n")
    print_json(doc)
    return int(doc.get("exit_code", 0))
