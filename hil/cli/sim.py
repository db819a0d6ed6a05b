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

from hil.cli._common import wants_json
from hil.errors import InputError


def register(sub: argparse._SubParsersAction) -> None:
    from mocks.ur.cli_entry import add_arguments

    p = sub.add_parser("sim", help="run the simulated station (robot + tracker)",
                       description=__doc__.splitlines()[0])
    add_arguments(p)
    for action in p._actions:  # the robot simulator's options that come without a word of help
        if not action.help and action.dest in _MISSING_HELP:
            action.help = _MISSING_HELP[action.dest]
    p.add_argument("--baud", type=int, default=None, help="pace the tracker link at this baud rate")
    p.add_argument("--acceptance-angle", type=float, default=30.0,
                   help="SMR acceptance half-angle (degrees): beyond it the tracker loses the beam")
    p.add_argument("--json", action="store_true",
                   help="print the ready line as JSON even on a terminal (it always is when piped)")
    p.set_defaults(func=run)


_MISSING_HELP = {
    "serial": "serial number the simulated controller reports",
    "seed": "random seed of the hidden truth (when no --truth), the tracker's noise and the start pose",
}


def _summary(out: dict[str, Any]) -> str:
    robot, tracker = out["robot"], out["tracker"]
    return "\n".join([
        f"robot    {robot['address']}  (RTDE {robot['rtde_port']}, dashboard {robot['dashboard_port']}, "
        f"script {robot['script_port']}, faults {robot['control_port']})",
        f"tracker  GeoCOM {tracker['url']}  (pty {tracker['pty']})",
        f"tracker  emScon {tracker['emscon_url']}",
        "serving until Ctrl-C (--json prints this and the hidden truth as JSON)",
    ]) + "\n"


def run(args: argparse.Namespace) -> int:
    from mocks.station import station_spec
    from mocks.ur.cli_entry import config_from_args
    from mocks.ur.process import serve

    if args.truth:
        from hil.calibration.model_file import load_truth

        load_truth(args.truth)  # bad truth files fail here, with the key named, before serving
    try:
        config = config_from_args(args)
    except ValueError as exc:
        raise InputError(str(exc)) from None

    def ready(info: dict[str, Any]) -> None:
        station = info["services"][0]
        out = {"robot": {k: info[k] for k in ("address", "rtde_port", "dashboard_port", "script_port",
                                              "control_port")},
               "tracker": {"url": station["tracker_url"], "pty": station["tracker_pty"],
                           "emscon_url": station["tracker_emscon_url"]},
               "truth": station["truth"]}
        sys.stdout.write(json.dumps(out) + "\n" if wants_json(args) else _summary(out))
        sys.stdout.flush()

    try:
        serve(config, services=[station_spec(args.truth, args.seed, args.acceptance_angle, args.baud)],
              ready=ready)
    except OSError as exc:
        raise InputError(f"--address: cannot serve on {args.address}: {exc}") from None
    return 0
