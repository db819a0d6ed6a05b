"""`hil sim`: run the simulated station (UR controller + a laser tracker sharing one world).

It serves until Ctrl-C and says when it is ready: the robot's address and ports, the tracker's GeoCOM
pty path and ``socket://`` URL and its emScon TPI ``tcp://`` URL. On a terminal that is a few readable
lines; with ``--json``, or when stdout is not a terminal (a script reading it), one JSON line that
also holds the hidden truth (so a test can compare against it).
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from hil.cli.support.options import JSON_FILE, SEED, SIM_SPEED, option
from hil.cli.support.output import wants_json
from hil.errors import InputError
from hil.jobs.outcome import EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    from mocks.ur.cli_entry import add_arguments

    p = sub.add_parser("sim", help="run the simulated station (robot + tracker)",
                       description=__doc__.splitlines()[0])
    add_arguments(p)
    for action in p._actions:  # the robot simulator's options that come without a word of help
        if not action.help and action.dest in _MISSING_HELP:
            action.help = _MISSING_HELP[action.dest]
        if action.dest == "robot":  # unset unless given: the truth's robot then, not a silent UR5e
            action.default = None
            action.help = "robot model (default: the --truth's, else ur5e; with --truth both must agree)"
        if action.dest == "serial":  # unset unless given: the simulated arm's own (mocks.station)
            action.default = None
            action.help = ("serial number the simulated controller reports (default: the simulated arm's "
                           "own, from --robot, --seed and --truth; the same arm always has the same)")
        if action.dest == "truth":  # a FIFO or a folder: one line before the station starts
            action.type = JSON_FILE
        if action.dest in _RANGES:  # checked by argparse: one line and exit 2, before anything serves
            action.type = _RANGES[action.dest]
    # RS-232 rates, as tracker.baudrate in the station configuration
    p.add_argument("--baud", type=option("baud rate"), default=None,
                   help="pace the tracker link at this baud rate")
    p.add_argument("--acceptance-angle", type=option("acceptance angle"),
                   default=30.0,
                   help="SMR acceptance half-angle (degrees): beyond it the tracker loses the beam")
    from hil.cli.support.station_options import add_arm_choice

    add_arm_choice(p)
    p.add_argument("--json", action="store_true",
                   help="print the ready line as JSON even on a terminal (it always is when piped)")
    p.set_defaults(func=run)


def _loopback(text: str) -> str:
    """argparse ``type`` of ``--address``: an IPv4 loopback address (127.0.0.256 failed only at bind)."""
    import ipaddress

    try:
        ok = ipaddress.IPv4Address(text).is_loopback
    except ValueError:
        ok = False
    if not ok:
        raise argparse.ArgumentTypeError(f"must be a loopback address 127.x.y.z, got {text!r}")
    return text


# The robot simulator's numeric options (mocks.ur.cli_entry declares them as bare int/float).
_RANGES = {
    "address": _loopback,
    "speed": SIM_SPEED,
    "control_port": option("tcp port"),  # a TCP port; 0 lets the system choose (99999 was exit 70)
    "speed_slider": option("fraction or none"),  # the pendant's speed slider, a fraction
    # std of actual_q: UR's encoders resolve ~1e-5 rad; a milliradian is already a worn joint
    "encoder_noise": option("encoder noise"),
    "seed": SEED,
}


_MISSING_HELP = {
    "seed": "random seed of the hidden truth (when no --truth), the tracker's noise and the start pose",
}


def _summary(out: dict[str, Any]) -> str:
    robot, tracker = out["robot"], out["tracker"]
    serial = f", serial {robot['serial']}" if robot.get("serial") else ""
    return "\n".join([
        f"robot    {robot['address']}  (RTDE {robot['rtde_port']}, dashboard {robot['dashboard_port']}, "
        f"script {robot['script_port']}, faults {robot['control_port']}){serial}",
        f"tracker  GeoCOM {tracker['url']}  (pty {tracker['pty']})",
        f"tracker  emScon {tracker['emscon_url']}",
        "serving until Ctrl-C (--json prints this and the hidden truth as JSON)",
    ]) + "\n"


def run(args: argparse.Namespace) -> int:
    from hil.station.robot_type import Claim, agreed_robot, option_claim
    from mocks.station import station_spec
    from mocks.ur.cli_entry import config_from_args
    from mocks.ur.process import serve

    claims = option_claim(args.robot)
    if args.truth:
        from hil.calibration.model_file import load_truth

        geometry, _ = load_truth(args.truth)  # bad truth files fail here, with the key named, before serving
        claims.append(Claim(geometry.robot, f"the truth {args.truth} is for {geometry.robot}"))
    # the controller simulates (and reports) the arm the truth describes: a disagreement is refused
    args.robot = agreed_robot(claims, default="ur5e")
    if args.truth and args.ideal is not None:
        raise InputError(f"--{'' if args.ideal else 'no-'}ideal chooses a random arm: the truth {args.truth} "
                         "says itself whether its arm has joint errors and lost motion")
    from hil.arm.joint_physics import IDEAL_BY_DEFAULT

    ideal = IDEAL_BY_DEFAULT if args.ideal is None else args.ideal
    if args.serial is None:  # each simulated arm its own robot, as `hil calibrate --sim`'s (mocks.station)
        from mocks.station import simulated_serial

        args.serial = simulated_serial(args.robot, args.seed, args.truth, ideal=ideal)
    try:
        config = config_from_args(args)
    except ValueError as exc:
        raise InputError(str(exc)) from None

    def ready(info: dict[str, Any]) -> None:
        station = info["services"][0]
        out = {"robot": {**{k: info[k] for k in ("address", "rtde_port", "dashboard_port", "script_port",
                                                 "control_port")}, "serial": args.serial},
               "tracker": {"url": station["tracker_url"], "pty": station["tracker_pty"],
                           "emscon_url": station["tracker_emscon_url"]},
               "truth": station["truth"]}
        sys.stdout.write(json.dumps(out) + "\n" if wants_json(args) else _summary(out))
        sys.stdout.flush()

    try:
        serve(config, services=[station_spec(args.truth, args.seed, args.acceptance_angle, args.baud,
                                             ideal=ideal)],
              ready=ready)
    except OSError as exc:
        raise InputError(f"--address: cannot serve on {args.address}: {exc}") from None
    return EXIT_OK
