"""`hil verify`: the ISO 9283 pose test, uncompensated and compensated in one session.

``hil verify --config station.toml [--model M]`` drives the arm through the test cube's five poses
(``[verify]``: centre and edge in the base frame) for ``--cycles`` cycles (ISO 9283: 30) and measures
each with the tracker; ``--sim`` does it on the simulated station (the cube then in front of the arm,
towards the tracker). With a calibrated model (a ``hil-model/1`` file, or a ``hil calibrate --out``
result) every pose is driven twice a cycle: uncompensated — the controller's own IK of the pose — and
compensated — the joints hil's model solves it to; the commanded positions reach the tracker's frame
by the model's tracker pose. Without one, the uncompensated test only, in a frame fitted to the
measured points with the controller's own model (the result says so). The result gives, per pose
and mode, ISO 9283's position accuracy AP (and AP_x/y/z) and repeatability RP; one SMR measures no
orientation.

The test is stored like a campaign (``hil history`` lists it): re-running the same command after
Ctrl-C or ``kill -9`` continues it, measuring only what is missing; ``--new`` starts afresh,
``--resume`` insists on continuing. ``--out`` writes the result (``hil-verification/1``), ``--report``
an HTML report, both only when the test finishes. Exit codes: 0 done, 2 bad input, 3 hardware fault,
4 aborted, 130 interrupted (128 + the signal number).
"""

from __future__ import annotations

import argparse
import json
from typing import Any

from hil.arm.catalog import ROBOT_NAMES
from hil.cli.support.options import JSON_FILE, SEED, SIM_SPEED, TOML_FILE, VERIFY_CYCLES
from hil.errors import InputError
from hil.files.outputs import atomic_write_text, check_output


def register(sub: argparse._SubParsersAction) -> None:
    from hil.cli.support.station_options import add_arm_choice, add_tracker_protocol

    p = sub.add_parser("verify", help="ISO 9283 pose test, uncompensated and compensated",
                       description=__doc__.split("\n\n")[0],
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--config", metavar="station.toml", type=TOML_FILE,
                     help="station configuration (its [verify] cube)")
    src.add_argument("--sim", action="store_true", help="use the simulated station")
    p.add_argument("--truth", metavar="truth.json", type=JSON_FILE,
                   help="--sim: the hidden truth (default: random)")
    p.add_argument("--speed", type=SIM_SPEED, default=1.0, metavar="F", help="--sim: fast-time factor")
    p.add_argument("--seed", type=SEED, help="--sim: seed of the random truth and noise (default: 1)")
    p.add_argument("--robot", default=None,
                   help=f"--sim: robot type ({', '.join(ROBOT_NAMES)}; default: the model's or --truth's, "
                        "else ur5e); with --config it must match robot.type")
    p.add_argument("--model", metavar="M", type=JSON_FILE,
                   help="hil's calibrated model (model JSON or a calibrate result): adds the compensated "
                        "test; without it, the uncompensated test only")
    p.add_argument("--cycles", type=VERIFY_CYCLES, default=None,
                   help="cycles of P1, P5, P4, P3, P2 (default: verify.cycles, 30)")
    p.add_argument("--db", metavar="PATH",
                   help="campaign database (default: config, $HIL_DB, data dir; with --sim: the simulated "
                        "stations' sim.db in the data dir, never $HIL_DB)")
    again = p.add_mutually_exclusive_group()
    again.add_argument("--resume", action="store_true", help="continue the last unfinished verification")
    again.add_argument("--new", action="store_true",
                       help="start a new verification even if one is unfinished")
    p.add_argument("--json", action="store_true", help="one JSON event per line on stdout")
    add_tracker_protocol(p)
    add_arm_choice(p)
    p.add_argument("--out", metavar="result.json", help="write the result (hil-verification/1)")
    p.add_argument("--report", metavar="report.html", help="write the HTML report")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hil.cli.support.interrupts import interruptible
    from hil.verify.inputs import load_model

    model = load_model(args.model) if args.model else None  # a missing or bad file: exit 2, nothing started
    _check_outputs(args)
    with interruptible():  # Ctrl-C, SIGTERM, SIGHUP: the arm stops, the verification stays resumable
        return _run(args, model)


def _check_outputs(args: argparse.Namespace) -> None:
    """Refuse --out/--report paths that are the store, an input, a directory or each other, before the
    station starts (as ``hil calibrate`` does)."""
    if not (args.out or args.report):
        return
    from hil.cli.support.output_paths import campaign_store

    db, where = campaign_store(args.db, args.config, sim=args.sim)
    inputs = {"--config": args.config, "--truth": args.truth, "--model": args.model}
    if args.out:
        check_output(args.out, field="--out", inputs=inputs, store=db, store_field=where)
    if args.report:
        check_output(args.report, field="--report", inputs=inputs, store=db, store_field=where,
                     outputs={"--out": args.out})


def _simulated_robot(args: argparse.Namespace, model: Any) -> str | None:
    """The robot to simulate: ``--robot``, else with ``--sim`` the model's arm (the one it calibrated)
    unless a ``--truth`` names it; a ``--robot`` the model contradicts is bad input, naming both."""
    robot = args.robot
    if model is not None and robot is not None and robot.lower() != model.geometry.robot:
        raise InputError(f"--robot is {robot}, the model {model.source} is of a {model.geometry.robot}")
    if robot is None and args.sim and model is not None and not args.truth:
        robot = model.geometry.robot
    return robot


def _run(args: argparse.Namespace, model: Any) -> int:
    from hil.cli.support.output import say, wrote
    from hil.cli.support.progress import JsonLines, Progress
    from hil.jobs.station import StationSource
    from hil.jobs.verification import VerificationRequest, run_verification

    source = StationSource.of(config=args.config, sim=args.sim, truth=args.truth, speed=args.speed,
                              seed=args.seed, robot=_simulated_robot(args, model),
                              tracker_protocol=args.tracker_protocol, ideal=args.ideal)
    request = VerificationRequest(source, model, args.cycles, args.db, new=args.new, resume_only=args.resume)
    subscribers: list[Any] = [Progress(), JsonLines()] if args.json else [Progress()]
    out = run_verification(request, subscribers=subscribers, say=say)
    if out.document is None:  # not finished: resumable, so no result (yet)
        return out.exit_code
    if args.out:
        atomic_write_text(args.out, json.dumps(out.document, indent=2, allow_nan=False) + "\n")
        wrote(args.out, "hil-verification/1")
    if args.report and "results" in out.document:
        from hil.report.verification import write_verification_report

        write_verification_report(out.document, args.report)
        wrote(args.report, "HTML report")
    return out.exit_code
