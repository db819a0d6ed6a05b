"""`hil calibrate`: a whole calibration campaign, headless (end-of-line cells, CI).

``hil calibrate --config station.toml`` runs against the configured robot and tracker;
``hil calibrate --sim [--truth truth.json] [--speed F]`` starts the simulated station (UR controller
and GeoCOM tracker, driven through the real ur_rtde and serial clients) and calibrates it.

Re-running the same command continues the last unfinished campaign of the same station, robot (by
serial number) and configuration — after ``kill -9`` included — measuring only what is missing;
``--new`` starts afresh, ``--resume`` insists on continuing. A campaign is continued when only how the
station is reached changed (a tracker URL, the robot's address, a timeout: see
`hil.store.schema.MEASUREMENT_IGNORED`). A campaign another live process is running, or an arm another
campaign is driving, is refused (exit 2, naming that process) before anything moves; a campaign whose
process died (kill -9, a power cut) is taken over and continued (`hil.store.leases`).

Before measuring, the arm is warmed up (``[warmup]``: cycling the planned poses until a reference pose
stops moving; ``--no-warmup`` skips it for an arm that is already warm) and, while measuring, the
reference is re-measured every ``drift.every`` poses; a drift beyond ``drift.limit`` flags the campaign
(a warning line, the result's ``drift`` block, the report) without changing its verdict or exit code.

Progress goes to stderr (a bar with ETA on a terminal, plain lines otherwise); ``--json`` prints one
event per line on stdout; ``--out`` writes the final result (``hil-result/1``, the calibrated model
under ``model``) and ``--report`` a self-contained HTML report — both only when the campaign
finishes (accepted, rejected, aborted): an interrupted or failed run, which is resumable, leaves an
earlier file at that path as it was.

Ctrl-C (SIGINT), SIGTERM and a closed terminal (SIGHUP) interrupt the run: the arm is stopped at
once, the campaign is recorded as ``interrupted`` and stays resumable (re-running the same command
continues it, nothing measured twice), and the exit is clean. Exit codes: 0 accepted, 1 finished
above the acceptance threshold, 2 bad input, 3 hardware fault, 4 aborted, 130 interrupted
(128 + the signal number: 130 Ctrl-C, 143 SIGTERM, 129 SIGHUP).
"""

from __future__ import annotations

import argparse
import json
from typing import Any

from hil.arm.catalog import ROBOT_NAMES
from hil.cli.support.options import (
    CANDIDATES,
    CYCLES,
    JSON_FILE,
    POSE_COUNT,
    RMS_THRESHOLD_HELP,
    SEED,
    SIM_SPEED,
    TOML_FILE,
    VERIFY_CYCLES,
    option,
    rms_threshold,
)
from hil.cli.support.output import say, wrote
from hil.cli.support.progress import JsonLines, Progress
from hil.cli.support.station_options import add_arm_choice, add_tracker_protocol, station_source
from hil.errors import InputError
from hil.files.outputs import atomic_write_text, check_output

#: ``--stop-margin``: a fraction of the acceptance threshold, as ``campaign.stop_margin``.
STOP_MARGIN = option("fraction")
#: --time-budget: robot seconds (campaign.time_budget's range, without its 0 = "no budget")
TIME_BUDGET = option("time budget")
#: --search-time: seconds (campaign.search_time's range)
SEARCH_TIME = option("search time")
#: --sweep-speed: metres a second at the tool (campaign.sweep_speed's range)
SWEEP_SPEED = option("sweep tool speed")
#: --selection: campaign.selection's values (hil.station.config.SELECTIONS)
SELECTIONS = ("tabu", "time-aware")
#: --mode: campaign.mode's values (hil.station.config.MODES)
MODES = ("stop-and-go", "sweep")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("calibrate", help="run a whole calibration campaign",
                       description=__doc__.split("\n\n")[0],
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--config", metavar="station.toml", type=TOML_FILE, help="station configuration")
    src.add_argument("--sim", action="store_true", help="use the simulated station")
    p.add_argument("--truth", metavar="truth.json", type=JSON_FILE,
                   help="--sim: the hidden truth (default: random)")
    p.add_argument("--speed", type=SIM_SPEED, default=1.0, metavar="F", help="--sim: fast-time factor")
    p.add_argument("--seed", type=SEED, help="--sim: seed of the random truth and noise (default: 1)")
    p.add_argument("--robot", default=None,
                   help=f"--sim: robot type ({', '.join(ROBOT_NAMES)}; default: --truth's, else ur5e); "
                        "with --config it must match robot.type")
    p.add_argument("--poses", type=POSE_COUNT, help="calibration poses (overrides the config)")
    p.add_argument("--validation", type=POSE_COUNT, help="validation poses (overrides the config)")
    p.add_argument("--candidates", type=CANDIDATES, help="selector candidates (overrides the config)")
    p.add_argument("--accept", type=rms_threshold, metavar="METRES",
                   help=f"validation RMS threshold, {RMS_THRESHOLD_HELP}; overrides the config")
    p.add_argument("--cycles", type=CYCLES, default=1,
                   help="visits of each validation pose (>1 adds ISO 9283 AP/RP)")
    p.add_argument("--stop-early", action="store_true",
                   help="stop visiting calibration poses once the fit so far predicts the acceptance with "
                        "margin (validation poses are all still measured); overrides campaign.stop_early")
    p.add_argument("--stop-margin", type=STOP_MARGIN, metavar="F",
                   help="with the stopping rule: stop once the predicted validation RMS is at most F x the "
                        "acceptance, 0 < F <= 1 (default: campaign.stop_margin, 0.7)")
    p.add_argument("--selection", choices=SELECTIONS,
                   help="pose selection: tabu (the most informative --poses poses, then their tour) or "
                        "time-aware (poses and tour together: the same accuracy in the least robot time); "
                        "overrides campaign.selection")
    p.add_argument("--mode", choices=MODES,
                   help="stop-and-go (measure each pose standing still) or sweep (follow a path through "
                        "the poses while emScon and the joints stream; emScon only); overrides "
                        "campaign.mode")
    p.add_argument("--sweep-speed", type=SWEEP_SPEED, metavar="M/S",
                   help="sweep: tool speed, each joint within it over the reach and accelerations within "
                        "the deflection model's quasi-static limit; overrides campaign.sweep_speed")
    p.add_argument("--time-budget", type=TIME_BUDGET, metavar="SECONDS",
                   help="time-aware: the most accurate tour within this much robot time; overrides "
                        "campaign.time_budget")
    p.add_argument("--search-time", type=SEARCH_TIME, metavar="SECONDS",
                   help="time-aware: seconds the search improves the tour before the first move; "
                        "overrides campaign.search_time")
    p.add_argument("--plan-cache", metavar="DIR",
                   help="keep the chosen poses in DIR and reuse them in every later campaign asking the "
                        "same (an end-of-line cell: chosen once per station layout); overrides "
                        "campaign.plan_cache")
    p.add_argument("--no-warmup", action="store_true",
                   help="measure without warming the arm up first (it has been running already); "
                        "overrides warmup.enabled, the drift watch stays as configured")
    p.add_argument("--db", metavar="PATH",
                   help="campaign database (default: config, $HIL_DB, data dir; with --sim: the simulated "
                        "stations' sim.db in the data dir, never $HIL_DB)")
    again = p.add_mutually_exclusive_group()
    again.add_argument("--resume", action="store_true", help="continue the last unfinished campaign")
    again.add_argument("--new", action="store_true", help="start a new campaign even if one is unfinished")
    p.add_argument("--json", action="store_true", help="one JSON event per line on stdout")
    add_tracker_protocol(p)
    add_arm_choice(p)
    p.add_argument("--out", metavar="result.json", help="write the result (embeds the model)")
    p.add_argument("--report", metavar="report.html", help="write the HTML report")
    p.add_argument("--verify", action="store_true",
                   help="after an accepted calibration, run the ISO 9283 pose test (hil verify) with the new "
                        "model on the same devices; its result goes into the result under 'verification'")
    p.add_argument("--verify-cycles", type=VERIFY_CYCLES, default=None, metavar="N",
                   help="--verify: cycles of the pose test (default: verify.cycles, 30)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hil.cli.support.interrupts import interruptible

    _check_poses(args)
    _check_outputs(args)
    if args.verify_cycles is not None and not args.verify:
        raise InputError("--verify-cycles goes with --verify")
    _check_stop_margin(args)
    _check_time_budget(args)
    _check_sweep_speed(args)
    _check_plan_cache(args)
    with interruptible():  # Ctrl-C, SIGTERM, SIGHUP: the arm stops, the campaign stays resumable
        return _run(args)


def _check_poses(args: argparse.Namespace) -> None:
    """Refuse a --poses the fit cannot identify from, before the station starts or the arm moves
    (`hil.jobs.calibration.check_pose_count`)."""
    from hil.jobs.calibration import check_pose_count

    check_pose_count(args.poses, args.config, args.robot)


def _check_stop_margin(args: argparse.Namespace) -> None:
    """--stop-margin without the stopping rule on (--stop-early, or the configuration's
    campaign.stop_early) would be silently ignored: refused before the station starts."""
    if args.stop_margin is None or args.stop_early:
        return
    from hil.station.config import load_config

    if not (args.config and load_config(args.config).campaign["stop_early"]):
        raise InputError("--stop-margin goes with --stop-early (or campaign.stop_early = true in --config)")


def _check_time_budget(args: argparse.Namespace) -> None:
    """--time-budget or --search-time without the time-aware selection (--selection time-aware, or the
    configuration's campaign.selection) would be silently ignored: refused before the station starts."""
    given = [o for o, v in (("--time-budget", args.time_budget), ("--search-time", args.search_time))
             if v is not None]
    if not given or args.selection == "time-aware":
        return
    from hil.station.config import load_config

    configured = args.config and load_config(args.config).campaign["selection"] == "time-aware"
    if args.selection is None and configured:
        return
    raise InputError(f"{given[0]} goes with --selection time-aware (or campaign.selection = "
                     "\"time-aware\" in --config)")


def _check_sweep_speed(args: argparse.Namespace) -> None:
    """--sweep-speed without the sweep mode (--mode sweep, or the configuration's campaign.mode) would be
    silently ignored: refused before the station starts."""
    if args.sweep_speed is None or args.mode == "sweep":
        return
    from hil.station.config import load_config

    if args.mode is None and args.config and load_config(args.config).campaign["mode"] == "sweep":
        return
    raise InputError("--sweep-speed goes with --mode sweep (or campaign.mode = \"sweep\" in --config)")


def _check_plan_cache(args: argparse.Namespace) -> None:
    """A plan cache directory that cannot be made is refused before the station starts."""
    path = args.plan_cache
    if path is None and args.config:
        from hil.station.config import load_config

        path = load_config(args.config).campaign["plan_cache"]
    if path:
        from hil.campaign.plan_cache import cache_directory

        cache_directory(path)


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse --out/--report paths that are the store, an input, a directory or each other, before
    the station starts: the result is written by a rename, which would replace that file."""
    if not (args.out or args.report):
        return
    from hil.cli.support.output_paths import campaign_store

    db, where = campaign_store(args.db, args.config, sim=args.sim)
    inputs = {"--config": args.config, "--truth": args.truth}
    if args.out:
        check_output(args.out, field="--out", inputs=inputs, store=db, store_field=where)
    if args.report:
        check_output(args.report, field="--report", inputs=inputs, store=db, store_field=where,
                     outputs={"--out": args.out})


def _subscribers(args: argparse.Namespace) -> list[Any]:
    """Progress on stderr, and with ``--json`` one event per line on stdout."""
    return [Progress(), JsonLines()] if args.json else [Progress()]


def _run(args: argparse.Namespace) -> int:
    from hil.jobs.calibration import CalibrationRequest, calibrate
    from hil.jobs.verification import VerifyOptions

    verify = (VerifyOptions(args.verify_cycles, args.out, lambda: _subscribers(args)) if args.verify
              else None)
    request = CalibrationRequest(station_source(args), db=args.db, no_warmup=args.no_warmup,
                                 validation_cycles=args.cycles,
                                 resume="only" if args.resume else "new" if args.new else "find",
                                 verify=verify)
    out = calibrate(request, subscribers=_subscribers(args), say=say)
    if not out.finished or out.document is None:  # interrupted or failed: resumable, so no result (yet)
        return out.exit_code  # an earlier result at --out / --report stays as it was
    if not out.recorded:  # finished, but its result could not be recorded: said
        return out.exit_code
    if args.out:
        atomic_write_text(args.out, json.dumps(out.document, indent=2, allow_nan=False) + "\n")
        wrote(args.out, "hil-result/1")
    if args.report and out.run is not None and out.run.result is not None:
        from hil.report import write_report

        write_report(out.report_data(), args.report)
        wrote(args.report, "HTML report")
    return out.exit_code
