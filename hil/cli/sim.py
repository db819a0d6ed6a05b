"""`hil sim`: run the simulated station (UR controller + a laser tracker sharing one world).

It serves until Ctrl-C and prints one JSON line when ready: the robot's address and ports, the
tracker's GeoCOM pty path and ``socket://`` URL, its emScon TPI ``tcp://`` URL, and the hidden truth
(so a test can compare against it).
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import Any

from hil.errors import InputError


def register(sub: argparse._SubParsersAction) -> None:
    from mocks.ur.cli_entry import add_arguments

    p = sub.add_parser("sim", help="run the simulated station (robot + tracker)",
                       description=__doc__.splitlines()[0])
    add_arguments(p)
    p.add_argument("--baud", type=int, default=None, help="pace the tracker link at this baud rate")
    p.add_argument("--acceptance-angle", type=float, default=30.0, help="SMR half-angle (degrees)")
    p.set_defaults(func=run)


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
        sys.stdout.write(json.dumps(out) + "\n")
        sys.stdout.flush()

    try:
        serve(config, services=[station_spec(args.truth, args.seed, args.acceptance_angle, args.baud)],
              ready=ready)
    except OSError as exc:
        raise InputError(f"--address: cannot serve on {args.address}: {exc}") from None
    return 0
