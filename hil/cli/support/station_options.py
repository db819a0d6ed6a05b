"""The station options of the commands that drive an arm: ``--config station.toml`` or ``--sim``.

Shared by ``hil calibrate``, ``hil verify``, ``hil moveb run`` and ``hil tui``, so each reads the same
options the same way (`hil.jobs.station.StationSource`: ``--truth``/``--speed`` are refused with
``--config``), and the campaign keys their options override.
"""

from __future__ import annotations

import argparse
from typing import Any

from hil.errors import InputError
from hil.jobs.station import StationSource


def add_tracker_protocol(parser: argparse.ArgumentParser) -> None:
    """``--tracker-protocol`` for commands that can run on the simulated station."""
    parser.add_argument("--tracker-protocol", choices=("geocom", "emscon"),
                        help="--sim: talk to the simulated tracker by GeoCOM (serial line, the default) or "
                             "by Leica's emScon TPI over TCP")


def add_arm_choice(parser: argparse.ArgumentParser) -> None:
    """``--ideal``/``--no-ideal``: which random arm ``--sim`` simulates (a ``--truth`` says it itself)."""
    from hil.arm.joint_physics import IDEAL_BY_DEFAULT

    default = "the ideal arm" if IDEAL_BY_DEFAULT else "the realistic arm"
    parser.add_argument("--ideal", action=argparse.BooleanOptionalAction, default=None,
                        help="--sim: --ideal simulates the ideal arm (placement errors, compliance, payload, "
                             "warm-up: a calibrated model reaches hundredths of a millimetre); --no-ideal "
                             "the realistic arm, which adds the joint errors and lost motion of a UR's "
                             "joints (a calibrated model reaches tenths of a millimetre, as real arms "
                             f"do). Default: {default}. Not with --truth, whose own blocks rule")


def config_overrides(args: argparse.Namespace) -> dict[str, Any]:
    """The campaign keys a command's options override (--poses, --validation, --candidates, --accept,
    and calibrate's --stop-early, --stop-margin)."""
    out: dict[str, Any] = {}
    for option, key in (("poses", "campaign__calibration_poses"),
                        ("validation", "campaign__validation_poses"),
                        ("candidates", "campaign__candidates"), ("accept", "campaign__acceptance")):
        value = getattr(args, option, None)
        if value is not None:  # in range: the options' types are rows of hil.files.quantities
            out[key] = value
    if getattr(args, "cycles", 1) < 1:
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
    if getattr(args, "sweep_speed", None) is not None:
        out["campaign__sweep_speed"] = args.sweep_speed
    if getattr(args, "plan_cache", None) is not None:
        out["campaign__plan_cache"] = args.plan_cache
    if getattr(args, "mode", None) is not None:  # hil calibrate: stop-and-go or sweep (wins over the config)
        out["campaign__mode"] = args.mode
    return out


def station_source(args: argparse.Namespace, *, robot: str | None = None) -> StationSource:
    """The station the options name (``--config`` or ``--sim`` with theirs), checked before anything
    starts (`hil.jobs.station.StationSource.of`). `robot`: the robot type to simulate when the command
    settled it from more sources than ``--robot`` (a model file); default ``--robot``."""
    robot = robot if robot is not None else getattr(args, "robot", None)
    return StationSource.of(config=args.config, sim=args.sim, truth=args.truth, speed=args.speed,
                            seed=args.seed, robot=robot,
                            tracker_protocol=getattr(args, "tracker_protocol", None),
                            overrides=config_overrides(args), ideal=getattr(args, "ideal", None))
