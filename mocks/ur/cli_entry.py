"""``hil sim`` (robot part): run a simulated UR controller in this process until Ctrl-C / SIGTERM.

For the lead to wire into the CLI dispatcher: ``register(subparsers)`` adds the ``sim`` subcommand and
sets ``func=run``; ``run(args) -> int`` serves. ``add_arguments(parser)`` and ``config_from_args(args)``
are separate so a combined station command (robot + tracker) can reuse them and pass extra services.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from typing import Any

from hil.calibration.synthetic import ENCODER_SIGMA
from mocks.ur.controller import SimConfig
from mocks.ur.process import serve

FAULTS = ("protective_stop", "emergency_stop", "stall", "stop_program", "power_off")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The robot simulator's options."""
    p.add_argument("--robot", default="ur5e", help="robot model (default ur5e)")
    p.add_argument("--address", default="127.0.0.2",
                   help="loopback address to serve on (127.x.y.z; default 127.0.0.2)")
    p.add_argument("--speed", type=float, default=1.0, help="simulated seconds per real second")
    p.add_argument("--truth", help="truth JSON of the simulated world (used by the station's world model)")
    p.add_argument("--control-port", type=int, default=30999, help="JSON-lines fault channel port (0: any)")
    p.add_argument("--polyscope", default=None,
                   help="controller software version to report (default 5.15.0.12345; 3.15.8.106339 for CB3)")
    p.add_argument("--serial", default="20235500001")
    p.add_argument("--local-control", action="store_true", help="start in local control (not remote)")
    p.add_argument("--speed-slider", type=float, default=1.0, help="speed slider fraction 0..1")
    p.add_argument("--encoder-noise", type=float, default=ENCODER_SIGMA,
                   help=f"rad, std of actual_q (default {ENCODER_SIGMA:g}, a UR joint's)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--fault", action="append", default=[], choices=FAULTS,
                   help="fault active from the start (repeatable)")


def config_from_args(args: argparse.Namespace) -> SimConfig:
    """A SimConfig from parsed options (raises ValueError with a one-line message on bad values)."""
    parts = args.polyscope.split(".") if args.polyscope else None
    if parts is not None and (len(parts) != 4 or not all(x.isdigit() for x in parts)):
        raise ValueError(f"--polyscope: expected four numbers like 5.15.0.12345, got {args.polyscope!r}")
    if not args.address.startswith("127."):
        raise ValueError(f"--address: only loopback addresses (127.x.y.z) are allowed, got {args.address!r}")
    if not 0.0 <= args.speed_slider <= 1.0:
        raise ValueError("--speed-slider: must be within [0, 1]")
    if not args.speed > 0:
        raise ValueError("--speed: must be > 0")
    faults: list[dict[str, Any]] = [{"name": f} for f in args.fault]
    return SimConfig(address=args.address, robot=args.robot, speed=args.speed,
                     version=tuple(int(x) for x in parts) if parts else None,  # type: ignore[arg-type]
                     serial=args.serial, control_port=args.control_port,
                     remote_control=not args.local_control, speed_slider=args.speed_slider,
                     encoder_noise=args.encoder_noise, seed=args.seed, faults=faults)


def run(args: argparse.Namespace, services: Sequence[Any] = ()) -> int:
    """Serve until interrupted; prints one JSON line with the robot address and ports when ready."""
    config = config_from_args(args)

    def ready(info: dict[str, Any]) -> None:
        sys.stdout.write(json.dumps({"robot": info}) + "\n")
        sys.stdout.flush()

    serve(config, services=services, ready=ready)
    return 0


def register(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``sim`` to an argparse subparsers object."""
    p = subparsers.add_parser("sim", help="run the simulated robot controller",
                              description=__doc__.splitlines()[0])
    add_arguments(p)
    p.set_defaults(func=run)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Standalone use: ``python -m mocks.ur.cli_entry [options]``."""
    parser = argparse.ArgumentParser(prog="ur-sim")
    add_arguments(parser)
    args = parser.parse_args(argv)
    try:
        return run(args)
    except ValueError as exc:
        sys.stderr.write(f"ur-sim: error: {exc}\n")
        return 2
    except OSError as exc:
        sys.stderr.write(f"ur-sim: error: cannot serve on {args.address}: {exc}\n")
        return 2


if __name__ == "__main__":
    sys.exit(main())
