"""The station a command runs on, from its options: ``--config station.toml`` or ``--sim``.

Shared by ``hil calibrate``, ``hil moveb run`` and ``hil tui``, so each reads the same options the same
way (and ``--truth``/``--speed`` are refused with ``--config``).
"""

from __future__ import annotations

import argparse
import contextlib
from collections.abc import Iterator
from typing import Any

from hil.errors import InputError
from hil.station.config import StationConfig, check_runnable, load_config
from hil.station.robot_type import agreed_robot, config_claim, option_claim


def add_tracker_protocol(parser: argparse.ArgumentParser) -> None:
    """``--tracker-protocol`` for commands that can run on the simulated station."""
    parser.add_argument("--tracker-protocol", choices=("geocom", "emscon"),
                        help="--sim: talk to the simulated tracker by GeoCOM (serial line, the default) or "
                             "by Leica's emScon TPI over TCP")


def config_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """The campaign keys a command's options override (--poses, --validation, --candidates, --accept,
    and calibrate's --stop-early, --stop-margin)."""
    out: dict[str, Any] = {}
    for option, key in (("poses", "campaign__calibration_poses"),
                        ("validation", "campaign__validation_poses"),
                        ("candidates", "campaign__candidates"), ("accept", "campaign__acceptance")):
        value = getattr(args, option)
        if value is not None:
            if not value > 0:
                raise InputError(f"--{option} must be positive, got {value}")
            out[key] = value
    if args.cycles < 1:
        raise InputError(f"--cycles must be at least 1, got {args.cycles}")
    if getattr(args, "stop_early", False):  # hil calibrate: the stopping rule (hil.campaign.stopping)
        out["campaign__stop_early"] = True
    if getattr(args, "stop_margin", None) is not None:
        out["campaign__stop_margin"] = args.stop_margin
    if getattr(args, "selection", None) is not None:  # hil calibrate: tabu or time-aware
        out["campaign__selection"] = args.selection
    if getattr(args, "time_budget", None) is not None:
        out["campaign__time_budget"] = args.time_budget
    if getattr(args, "search_time", None) is not None:
        out["campaign__search_time"] = args.search_time
    if getattr(args, "plan_cache", None) is not None:
        out["campaign__plan_cache"] = args.plan_cache
    return out


@contextlib.contextmanager
def station_from_args(
        args: argparse.Namespace) -> Iterator[tuple[StationConfig, dict[str, Any], dict | None]]:
    """(config to run, config that identifies the run in the store, hidden truth or None).

    ``--robot`` (None when not given) must agree with the configuration's ``robot.type`` or the truth's
    ``robot``: a disagreement is bad input, never settled silently in favour of one of them.
    """
    protocol = getattr(args, "tracker_protocol", None)
    said = option_claim(getattr(args, "robot", None))  # an unknown --robot is refused first, named
    if args.config:
        if args.truth or args.speed != 1.0 or protocol:
            raise InputError("--truth, --speed and --tracker-protocol go with --sim, not --config "
                             "(the configuration's tracker.protocol says which tracker it has)")
        config = check_runnable(load_config(args.config))  # before a store is opened or created
        config = config.with_overrides(**config_overrides(args)) if config_overrides(args) else config
        agreed_robot([config_claim(config), *said])  # said twice: both must name the same arm
        yield config, config.as_dict(), None
        return
    if not args.speed > 0:
        raise InputError(f"--speed must be positive, got {args.speed}")
    from hil.station.simulated import simulated_station

    with simulated_station(args.robot, args.truth, args.speed, args.seed, protocol or "geocom",
                           **config_overrides(args)) as (
            config, identity, truth, _sim):
        yield config, identity, truth
