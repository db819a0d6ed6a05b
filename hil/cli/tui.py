"""`hil tui`: the shop-floor terminal app (Textual) for calibration campaigns.

``hil tui --sim [--speed F]`` starts the simulated station inside the app; ``hil tui --config
station.toml`` talks to a real one. The app runs the same campaigns as ``hil calibrate`` on the same
engine and store: a campaign interrupted in one can be resumed from the other. Keys: ``?`` in the app.
"""

from __future__ import annotations

import argparse

from hil.arm.catalog import ROBOT_NAMES
from hil.cli.support.options import (
    CANDIDATES,
    JSON_FILE,
    POSE_COUNT,
    RMS_THRESHOLD_HELP,
    SEED,
    SIM_SPEED,
    TOML_FILE,
    rms_threshold,
)
from hil.cli.support.station_options import add_arm_choice, add_tracker_protocol


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("tui", help="the operator's terminal app (keyboard only, 80x24 and larger)",
                       description=__doc__.split("\n\n")[0],
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--config", metavar="station.toml", type=TOML_FILE, help="station configuration")
    src.add_argument("--sim", action="store_true", help="use the simulated station")
    p.add_argument("--speed", type=SIM_SPEED, default=1.0, metavar="F", help="--sim: fast-time factor")
    p.add_argument("--seed", type=SEED, help="--sim: seed of the random truth and noise (default: 1)")
    p.add_argument("--robot", default=None,
                   help=f"--sim: robot type ({', '.join(ROBOT_NAMES)}; default: --truth's, else ur5e); "
                        "with --config it must match robot.type")
    p.add_argument("--truth", metavar="truth.json", type=JSON_FILE,
                   help="--sim: the hidden truth (default: random)")
    p.add_argument("--poses", type=POSE_COUNT, help="calibration poses (overrides the config)")
    p.add_argument("--validation", type=POSE_COUNT, help="validation poses (overrides the config)")
    p.add_argument("--candidates", type=CANDIDATES, help="selector candidates (overrides the config)")
    p.add_argument("--accept", type=rms_threshold, metavar="METRES",
                   help=f"validation RMS threshold, {RMS_THRESHOLD_HELP}; overrides the config")
    p.add_argument("--no-warmup", action="store_true",
                   help="measure without warming the arm up first (a quick look, or an arm that has been "
                        "running), as hil calibrate --no-warmup; the Plan screen's w toggles it")
    p.add_argument("--db", metavar="PATH",
                   help="campaign database (default: config, $HIL_DB, data dir; with --sim: the simulated "
                        "stations' sim.db in the data dir, never $HIL_DB)")
    p.add_argument("--out-dir", default=".", metavar="DIR", help="where exports go (default: here)")
    add_tracker_protocol(p)
    add_arm_choice(p)
    p.set_defaults(func=run, cycles=1)


def options_from(args: argparse.Namespace) -> object:
    """`TuiOptions` from the command line; bad input raises InputError before the app starts."""
    from hil.cli.support.output import say
    from hil.cli.support.station_options import station_source
    from hil.files.outputs import check_output_dir
    from hil.jobs.calibration import check_pose_count
    from hil.jobs.station import store_location
    from hil.station.robot_type import Claim, agreed_robot, option_claim
    from hil.tui.session import TuiOptions

    check_output_dir(args.out_dir, field="--out-dir")  # a file, or a missing parent: refused up front
    # as `hil calibrate`: too few --poses is refused before the app starts, not later
    check_pose_count(args.poses, args.config, args.robot)
    source = station_source(args)  # before the app opens (or creates) a store
    if source.config is not None:
        return TuiOptions(config=source.config, db=args.db, out_dir=args.out_dir, overrides=source.overrides,
                          no_warmup=args.no_warmup)
    claims = option_claim(args.robot)
    if args.truth:
        from hil.calibration.model_file import load_truth

        geometry, _ = load_truth(args.truth)  # a bad truth fails here, naming the key
        claims.append(Claim(geometry.robot, f"the truth {args.truth} is for {geometry.robot}"))
    robot = agreed_robot(claims, default="ur5e")  # --robot and the truth must agree, before the app starts
    # a simulated station's campaigns go to the simulated stations' store unless --db names one (said
    # on stderr before the app takes the screen), never to $HIL_DB's or the default: the plant's
    db = str(store_location(args.db, source, None, say))
    return TuiOptions(sim=True, speed=args.speed, seed=1 if args.seed is None else args.seed, robot=robot,
                      truth=args.truth, tracker_protocol=args.tracker_protocol or "geocom", db=db,
                      ideal=args.ideal,
                      out_dir=args.out_dir, overrides=source.overrides, no_warmup=args.no_warmup)


def check_store(db: str | None, config: object | None) -> None:
    """Refuse, before the app opens, a store the app could not use (a folder, a damaged file, another
    program's database, a newer hil's): on a full-screen app the error would otherwise appear only
    after the operator connected the arm. An existing store is opened and closed again; a missing one
    is left for the app to create."""
    from hil.jobs.station import open_existing_store
    from hil.store import resolve_location

    store = open_existing_store(resolve_location(db, config), config)  # a server: reachable, not newer
    if store is not None:
        store.close()


def require_terminal() -> None:
    """Refuse, in one line, to start the app without a terminal: with its input or output redirected
    (a cron job, a pipe, an SSH command without -t) a full-screen app has no keyboard to be answered
    from and would wait for ever, holding the station. Headless runs are `hil calibrate`'s."""
    import sys

    missing = [name for name, stream in (("standard input", sys.stdin), ("standard output", sys.stdout))
               if stream is None or not stream.isatty()]
    if missing:
        from hil.errors import InputError

        raise InputError(f"hil tui needs a terminal, and its {' and '.join(missing)} "
                         f"{'is' if len(missing) == 1 else 'are'} not one: run it in a terminal (ssh -t), "
                         "or use hil calibrate, the headless command")


def run(args: argparse.Namespace) -> int:
    """Run the app; once it has closed (arm stopped, campaign recorded, devices, store and simulator
    closed, terminal restored) the ``hil`` program ends at once (`end_process`), not after the
    interpreter's seconds of teardown; called in-process (`hil.cli.main` with arguments) it returns."""
    from hil.cli.support.process_end import end_process
    from hil.tui.app import create_app

    if getattr(args, "as_program", False):
        require_terminal()
    options = options_from(args)
    check_store(getattr(options, "db", None), getattr(options, "config", None))
    app = create_app(options)  # type: ignore[arg-type]
    code = int(app.run() or 0)
    if getattr(args, "as_program", False):
        end_process(code)
    return code
