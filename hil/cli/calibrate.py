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
import contextlib
import json
import sys
import time
from pathlib import Path
from typing import Any

from hil.arm.catalog import ROBOT_NAMES
from hil.campaign.events import Event, EventBus
from hil.cli._common import (
    CANDIDATES,
    CYCLES,
    POSE_COUNT,
    RMS_THRESHOLD_HELP,
    SEED,
    SIM_SPEED,
    VERIFY_CYCLES,
    finite_float,
    rms_threshold,
)
from hil.cli.progress import JsonLines, Progress
from hil.cli.station_args import add_tracker_protocol, station_from_args
from hil.errors import InputError
from hil.files.outputs import atomic_write_text, check_output

#: ``--stop-margin``: a fraction of the acceptance threshold, as ``campaign.stop_margin``.
STOP_MARGIN = finite_float(0, 1, lo_open=True)
#: --time-budget: robot seconds (campaign.time_budget's range, without its 0 = "no budget")
TIME_BUDGET = finite_float(0, 86_400, "s", lo_open=True)
#: --search-time: seconds (campaign.search_time's range)
SEARCH_TIME = finite_float(0, 3600, "s", lo_open=True)
#: --selection: campaign.selection's values (hil.station.config.SELECTIONS)
SELECTIONS = ("tabu", "time-aware")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("calibrate", help="run a whole calibration campaign",
                       description=__doc__.split("\n\n")[0],
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--config", metavar="station.toml", help="station configuration")
    src.add_argument("--sim", action="store_true", help="use the simulated station")
    p.add_argument("--truth", metavar="truth.json", help="--sim: the hidden truth (default: random)")
    p.add_argument("--speed", type=SIM_SPEED, default=1.0, metavar="F", help="--sim: fast-time factor")
    p.add_argument("--seed", type=SEED, default=1, help="--sim: seed of the random truth and noise")
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
    p.add_argument("--db", metavar="PATH", help="campaign database (default: config, $HIL_DB, data dir)")
    again = p.add_mutually_exclusive_group()
    again.add_argument("--resume", action="store_true", help="continue the last unfinished campaign")
    again.add_argument("--new", action="store_true", help="start a new campaign even if one is unfinished")
    p.add_argument("--json", action="store_true", help="one JSON event per line on stdout")
    add_tracker_protocol(p)
    p.add_argument("--out", metavar="result.json", help="write the result (embeds the model)")
    p.add_argument("--report", metavar="report.html", help="write the HTML report")
    p.add_argument("--verify", action="store_true",
                   help="after an accepted calibration, run the ISO 9283 pose test (hil verify) with the new "
                        "model on the same devices; its result goes into the result under 'verification'")
    p.add_argument("--verify-cycles", type=VERIFY_CYCLES, default=None, metavar="N",
                   help="--verify: cycles of the pose test (default: verify.cycles, 30)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hil.cli.interrupts import interruptible

    _check_poses(args)
    _check_outputs(args)
    if args.verify_cycles is not None and not args.verify:
        raise InputError("--verify-cycles goes with --verify")
    _check_stop_margin(args)
    _check_time_budget(args)
    _check_plan_cache(args)
    with interruptible():  # Ctrl-C, SIGTERM, SIGHUP: the arm stops, the campaign stays resumable
        return _run(args)


def _check_poses(args: argparse.Namespace) -> None:
    """Refuse a --poses the fit cannot identify from, before the station starts or the arm moves:
    found later, it would fail only after the bootstrap (tracker location) had moved the arm. The
    configuration's own count is checked when it is read (`hil.station.config`)."""
    if args.poses is None or args.poses <= 0:  # not given, or refused as not positive
        return
    from hil.station.config import load_config, minimum_calibration_poses

    config = load_config(args.config) if args.config else None
    robot = args.robot or (config.robot["type"] if config is not None else "ur5e")
    # with the compliance (on unless the station turns it off) its identifiable joints count too
    compliance = bool(config.campaign["compliance"]) if config is not None else True
    need, n = minimum_calibration_poses(robot, compliance, config.payload if config else None,
                                        config.gravity if config else None)
    if args.poses < need:
        raise InputError(f"--poses {args.poses}: too few calibration poses: identifying the {n} parameters "
                         f"of a {robot} from 3 coordinates per pose needs at least {need}")


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
    from hil.cli.output_paths import campaign_store

    db, where = campaign_store(args.db, args.config)
    inputs = {"--config": args.config, "--truth": args.truth}
    if args.out:
        check_output(args.out, field="--out", inputs=inputs, store=db, store_field=where)
    if args.report:
        check_output(args.report, field="--report", inputs=inputs, store=db, store_field=where,
                     outputs={"--out": args.out})


def _say_outage(reason: str | None) -> None:
    """A lost database link: the run waits (the arm stands at its pose) until it is back."""
    if reason is None:
        print("hil: database link back; the run continues", file=sys.stderr, flush=True)
    else:
        print(f"hil: {reason}; the arm waits at its pose", file=sys.stderr, flush=True)


def _run(args: argparse.Namespace) -> int:
    from hil.campaign.chooser import campaign_chooser
    from hil.campaign.engine import RealClock
    from hil.campaign.runner import claim_run, plan_saver, run_campaign, store_recorder
    from hil.report.result import report_data, result_document
    from hil.station.devices import HARDWARE_ERRORS, open_devices
    from hil.station.robot_type import check_controller
    from hil.store import FINISHED, Store, StoreError, address_lock, resolve_location

    with station_from_args(args) as (config, identity, truth):
        if args.no_warmup:  # not part of what identifies the campaign (`hil.store.hashing`)
            config = config.with_overrides(warmup__enabled=False)
        cube = _verify_cube(args, config)  # --verify: the [verify] cube, refused before anything connects
        # An existing store is opened (so a damaged or newer one is refused) before the arm is touched;
        # a new one is created only once the controller has confirmed the configured robot, so a
        # refused station leaves no file behind.
        path = resolve_location(args.db, config)  # a file, or a PostgreSQL server (opened now: reachable?)
        store: Store | None = (Store.open(path, config=config) if not isinstance(path, Path) or path.exists()
                               else None)
        choose = campaign_chooser(config)
        guards = contextlib.ExitStack()  # the arm's address lock, then the campaign's lease
        devices, verified = None, 0  # verified: the exit code the verification asks for (0: done)
        try:
            # no second process of this host connects to the arm (see hil.store.leases)
            guards.enter_context(address_lock(config.robot["address"], what="hil calibrate"))
            try:
                devices = open_devices(config)
            except HARDWARE_ERRORS as exc:
                print(f"hil: hardware fault: cannot connect: {type(exc).__name__}: {exc}",
                      file=sys.stderr)
                return 3
            info = devices.robot.info
            try:  # the controller's word on the robot type, before anything is recorded or moved
                check_controller(config, info)
                if store is None:
                    store = Store.open(path, config=config)
            except BaseException:
                devices.close()
                raise
            robot = {"type": config.robot["type"], "serial": info.serial if info else "",
                     "model": info.model if info else "", "software": info.software_version if info else ""}
            try:
                if args.resume and store.find_resumable(identity, robot_serial=robot["serial"]) is None:
                    raise InputError("--resume: no unfinished campaign of this station, robot and "
                                     "configuration")
                # this process owns the campaign and the arm before the first motion, or exits 2
                lease, resume = claim_run(store, identity, robot, find=not args.new)
            except BaseException:
                devices.close()
                raise
            campaign = guards.enter_context(lease).campaign
            store.on_outage = _say_outage
            events: list[Event] = []
            bus = EventBus()
            bus.subscribe(store_recorder(store), critical=True)  # a failed write names itself
            bus.subscribe(plan_saver(store, campaign), critical=True)
            bus.subscribe(events.append)
            bus.subscribe(Progress())
            if args.json:
                bus.subscribe(JsonLines())
            started = time.time()
            outcome = run_campaign(config, choose, bus=bus, campaign=campaign,
                                   resume=resume, devices=devices, clock=RealClock(args.speed),
                                   validation_cycles=args.cycles, lease=lease,
                                   close_devices=not args.verify)  # --verify: the same devices go on
            result = result_document(outcome, config, events, started, truth)
            if outcome.unrecorded is not None:  # the store refused RunFinished: no progress line said why
                print(f"hil: fault: campaign {campaign} {outcome.status}: {outcome.error}; what was "
                      "recorded before stays: re-run the same command to continue it", file=sys.stderr)
            try:
                store.set_status(campaign, outcome.status, result=result)
            except StoreError as exc:  # a full disk: a fault (exit 3), not "not accepted" (exit 1)
                if outcome.unrecorded is None:
                    print(f"hil: fault: campaign {campaign} ended {outcome.status}, but could not record "
                          f"its result in {store.location}: {exc.__cause__ or exc}", file=sys.stderr)
                return 3
            if args.verify:
                result["verification"], verified = _verify_after(args, outcome, store, devices, config,
                                                                 identity, robot, truth, cube, lease)
                try:
                    store.set_status(campaign, outcome.status, result=result)
                except StoreError as exc:
                    print(f"hil: fault: could not record the verification with campaign {campaign} in "
                          f"{store.location}: {exc.__cause__ or exc}", file=sys.stderr)
                    return 3
        finally:
            if args.verify and devices is not None:  # run_campaign left them open for the verification
                devices.close()
            guards.close()  # never raises: a lease the store cannot delete lapses (Lease.release)
            if store is not None:
                store.close()
    if outcome.status not in FINISHED:  # interrupted or failed: resumable, so no result (yet)
        if outcome.status == "interrupted":
            print(f"hil: campaign {campaign} is resumable: re-run the same command to continue it",
                  file=sys.stderr)
        return outcome.exit_code  # an earlier result at --out / --report stays as it was
    from hil.cli._common import wrote

    if args.out:
        atomic_write_text(args.out, json.dumps(result, indent=2, allow_nan=False) + "\n")
        wrote(args.out, "hil-result/1")
    if args.report and outcome.result is not None:
        from hil.report import write_report

        write_report(report_data(outcome, config, events, started, result.get("verification")), args.report)
        wrote(args.report, "HTML report")
    return verified if outcome.exit_code == 0 and verified else outcome.exit_code


def _verify_cube(args: argparse.Namespace, config: Any) -> Any:
    """--verify: the ``[verify]`` cube (None: the simulated station's default), checked against the
    arm's reach and the keep-in box before anything connects."""
    if not args.verify:
        return None
    from hil.verify.design import check_cube
    from hil.verify.session import cube_where, requested_cube

    cube = requested_cube(config, sim=args.sim)
    if cube is not None:
        check_cube(config.robot["type"], cube, config.smr["offset"],
                   (config.keep_in["min"], config.keep_in["max"]), cube_where(config))
    return cube


def _verify_after(args: argparse.Namespace, outcome: Any, store: Any, devices: Any, config: Any,
                  identity: Any, robot: Any, truth: Any, cube: Any, lease: Any) -> tuple[dict[str, Any], int]:
    """--verify: the ISO 9283 pose test with the model just accepted, on the same devices (`hil.verify`).

    Returns the result's ``verification`` block and the exit code it asks for (0: done; the test's own
    code when it did not finish: 3 fault, 130 interrupted — resumable by ``hil verify --model`` with the
    calibration's result; 2 when no configuration serves the cube). Nothing runs unless the calibration
    was accepted. The calibration's lease is given up first: the verification is a campaign of its own
    and takes the arm's lease itself. The calibration's result is already stored, so whatever happens
    here it stays.
    """
    if outcome.status != "accepted" or outcome.result is None or outcome.unrecorded is not None:
        return {"status": "not run", "reason": f"the calibration ended {outcome.status}"}, 0
    from hil.arm.geometry import Geometry
    from hil.campaign.engine import RealClock
    from hil.verify.session import ModelInput, verify

    lease.release()
    doc = outcome.result.model
    model = ModelInput.of(doc, Geometry.from_dict(doc, source="the calibrated model"),
                          f"campaign {outcome.campaign}")
    subscribers: list[Any] = [Progress()]
    if args.json:
        subscribers.append(JsonLines())
    print("hil: verifying the calibrated model (ISO 9283 pose test)", file=sys.stderr)
    try:
        done = verify(store, devices, config, identity, robot, model=model, cube=cube,
                      cycles=args.verify_cycles or config.verify["cycles"], clock=RealClock(args.speed),
                      subscribers=subscribers, truth=truth)
    except InputError as exc:  # no configuration serves the cube: the calibration stands, said so
        print(f"hil: error: --verify: {exc}", file=sys.stderr)
        return {"status": "not run", "reason": str(exc)}, 2
    if done.outcome.status == "interrupted":
        print(f"hil: verification {done.campaign} is resumable: run hil verify on this station with "
              f"--model {args.out or 'the calibration result'} to continue it", file=sys.stderr)
    return done.document, done.exit_code
