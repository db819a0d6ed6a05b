"""`hil select`: choose the measurement poses of a calibration, JSON out.

    hil select --robot ur5e --count 30 [--candidates 20000] [--index O1] [--method tabu|exchange|random]
               [--seed S] [--tracker X,Y,Z] [--smr X,Y,Z] [--out poses.json] [constraint options]
    hil select --robot ur5e --count 30 --method time-aware [--budget SECONDS] [--speed V]
               [--acceleration A] [--dwell S] ...

``--method time-aware`` chooses poses and their order together for the most accuracy per second of
robot time (`hil.calibration.timed_selection`): without ``--budget`` it reaches the predicted accuracy
of method 000's ``--count`` poses in the least time (the pose count is free), with ``--budget`` it finds
the most accurate tour that fits; ``predicted`` and ``seed_method`` in the JSON compare the two.

The JSON (``hil-poses/1``) has robot, index, value, bound (O1's D-optimal bound), percent_of_bound,
method, seconds (the selection itself), poses (6-lists in radians, in visiting order), the travel time
ordered vs unordered, the candidate statistics and every constraint setting used. Without --out it goes
to stdout. Progress (what it is doing, candidates found, search progress, the bound) goes to stderr;
``--no-bound`` skips the bound (often most of the time): ``bound`` and ``percent_of_bound`` are then null.
Bad input is one line on stderr and exit code 2, and nothing is written.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

from hil.cli.support.options import CANDIDATES, POSE_COUNT, SEED, option
from hil.cli.support.output import wrote
from hil.cli.support.urdf_options import URDF_SCOPE, add_urdf_options, urdf_chain_or_none
from hil.errors import InputError
from hil.files.quantities import check_vector, quantity
from hil.jobs.outcome import EXIT_OK
from selector.names import CONSTRAINT_NAMES, INDEX_NAMES, METHODS, SCALINGS

DEFAULT_SMR = "0,0,0.045"

#: `--method` value of the time-aware selection (`hil.calibration.timed_selection`).
TIME_AWARE = "time-aware"

#: Farthest tracker range (m) a --range may give: Leica's AT403 measures to 80 m (160 m diameter), the
#: longest of the laser trackers hil drives.
MAX_TRACKER_RANGE = quantity("tracker position").high  # the table's row (hil.files.quantities)


def register(sub: Any) -> None:
    """Add the ``select`` subcommand to the dispatcher's subparsers."""
    p = sub.add_parser("select", help="choose optimal measurement poses (JSON out)",
                       description=__doc__.split("\n\n")[0] + " " + URDF_SCOPE + " For such an arm "
                       "self-collision is checked on the URDF's collision geometry, and the UR "
                       "singularity margins, compliance, joint errors and --method time-aware do not apply.")
    p.add_argument("--robot", help="robot type, e.g. ur5e; or --urdf")
    add_urdf_options(p)
    p.add_argument("--count", required=True, type=POSE_COUNT, help="number of poses to choose")
    p.add_argument("--candidates", type=CANDIDATES, default=20_000,
                   help="random feasible configurations to choose from")
    p.add_argument("--index", default="O1",
                   help=f"what to maximise: observability index {', '.join(INDEX_NAMES)}")
    p.add_argument("--method", default="tabu",
                   help=f"search method: {', '.join(METHODS)} (the last two are baselines to compare with), "
                        f"or {TIME_AWARE} (poses and order together, for robot time)")
    # ur_rtde's moveJ takes at most 3.14 rad/s and 40 rad/s² (hil.station.config, robot.speed)
    p.add_argument("--speed", type=option("joint speed"), default=0.5,
                   help="time-aware: joint speed of the moves (rad/s, the station's robot.speed)")
    p.add_argument("--acceleration", type=option("joint acceleration"), default=1.0,
                   help="time-aware: joint acceleration of the moves (rad/s², robot.acceleration)")
    p.add_argument("--dwell", type=option("dwell"), default=None,
                   help="time-aware: robot seconds per pose besides moving (settle, read, measure; "
                        "default 0.85)")
    p.add_argument("--budget", type=option("time budget"), default=None,
                   help="time-aware: the most accurate tour within this many seconds of robot time")
    p.add_argument("--time-limit", type=option("search time"), default=5.0,
                   help="time-aware: seconds of search after the first tour")
    p.add_argument("--seed", type=SEED, default=0, help="random seed; equal seeds give equal output")
    p.add_argument("--tracker", help="tracker position X,Y,Z in the robot base frame (m); without it the "
                                     "range, acceptance and line-of-sight constraints are off")
    p.add_argument("--smr", default=DEFAULT_SMR,
                   help="SMR centre in the flange frame X,Y,Z (m)")
    p.add_argument("--scaling", default="expected", help=f"column scaling for O2–O5: {', '.join(SCALINGS)}")
    p.add_argument("--keep-in", help="SMR keep-in box XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX (m, base frame)")
    # lengths in the base frame within the keep-in box's ±5 m (hil.files.quantities); angles as
    # the selector's constraints take them: an SMR is seen within a half-angle below 90°, a margin from a
    # singularity is below 90°; the shoulder margin is well inside the arm's reach (at most 1.75 m)
    p.add_argument("--floor", type=option("mounting surface height"), default=0.0,
                   help="height of the mounting surface (m)")
    p.add_argument("--range", dest="tracker_range",
                   help=f"tracker distance MIN,MAX (m), within 0-{MAX_TRACKER_RANGE:g} (default: 0.8,20)")
    p.add_argument("--half-angle", type=option("acceptance angle"),
                   default=30.0, help="SMR acceptance half-angle (deg)")
    p.add_argument("--wrist-margin", type=option("margin angle"), default=10.0,
                   help="min |q5| from 0/π (deg)")
    p.add_argument("--elbow-margin", type=option("margin angle"), default=10.0,
                   help="min |q3| from 0/π (deg)")
    p.add_argument("--shoulder-margin", type=option("clearance"), default=0.05,
                   help="min distance of the wrist point from the shoulder singularity (m)")
    p.add_argument("--disable", action="append", default=[],
                   help=f"switch constraints off (comma list; repeatable): {', '.join(CONSTRAINT_NAMES)}")
    p.add_argument("--start", help="current joint configuration q1..q6 (rad): the route starts there")
    p.add_argument("--compliance", action="store_true",
                   help="choose poses that identify the joints' compliance too (for --payload)")
    p.add_argument("--payload", metavar="MASS,X,Y,Z",
                   help="what the arm carries (kg; centre of mass in the flange frame, m); default nothing")
    p.add_argument("--prune", action="store_true",
                   help="drop poses that add nothing to the result: may return fewer than --count")
    p.add_argument("--no-bound", dest="bound", action="store_false",
                   help="skip the D-optimal bound (often most of the run time): bound and "
                        "percent_of_bound are then null")
    p.add_argument("--quiet", action="store_true", help="no progress on stderr")
    p.add_argument("--out", help="output JSON file (default: stdout)")
    p.set_defaults(func=run)


def _numbers(text: str | None, n: int, name: str) -> tuple[float, ...] | None:
    if text is None:
        return None
    parts = [s.strip() for s in str(text).split(",")]
    try:
        values = tuple(float(s) for s in parts)
    except ValueError:
        raise InputError(f"{name}: expected {n} comma-separated numbers, got {text!r}") from None
    if len(values) != n or not all(math.isfinite(v) for v in values):
        raise InputError(f"{name}: expected {n} finite comma-separated numbers, got {text!r}")
    return values


def _finite(value: float, name: str) -> float:
    if not math.isfinite(value):
        raise InputError(f"{name}: must be a finite number")
    return value


def run(args: argparse.Namespace) -> int:
    """Validate everything, select, then write the JSON (nothing is written on bad input)."""
    import numpy as np

    from hil.arm.geometry import parse_triplet  # pinocchio: not for `hil select --help`
    from hil.calibration.selection import parse_constraints, select_poses
    from hil.files.outputs import atomic_write_text, check_output
    from selector.tabu import TabuSettings

    if args.out is not None:
        from hil.cli.support.output_paths import campaign_store

        db, where = campaign_store()
        check_output(args.out, field="--out", store=db, store_field=where)
    # stdout (full, closed) is checked before any subcommand runs: hil.cli.support.output
    if args.candidates < 1:
        raise InputError(f"--candidates must be at least 1, got {args.candidates}")
    chain = urdf_chain_or_none(args)
    if chain is None and args.robot is None:
        raise InputError("the arm: give --robot (a catalog UR) or --urdf FILE (any serial arm)")
    if chain is not None:
        for flag, given in (("--method time-aware", args.method == TIME_AWARE),
                            ("--compliance", args.compliance), ("--payload", args.payload is not None)):
            if given:
                raise InputError(f"{flag} is modelled for Universal Robots arms only, not for {chain.name} "
                                 f"(from its URDF {args.urdf})")
    # 1e308 never found a pose; 10 m "from the flange" is a value in millimetres
    tracker = None if args.tracker is None else check_vector(
        parse_triplet(args.tracker, "--tracker").tolist(), "tracker distance from the base", "--tracker",
        norm=True)
    smr = np.array(check_vector(parse_triplet(args.smr, "--smr").tolist(), "smr offset", "--smr", norm=True))
    disabled = [s.strip() for item in args.disable for s in item.split(",") if s.strip()]
    settings: dict[str, Any] = {
        "floor": _finite(args.floor, "--floor"),
        "half_angle_deg": _finite(args.half_angle, "--half-angle"),
        "wrist_margin_deg": _finite(args.wrist_margin, "--wrist-margin"),
        "elbow_margin_deg": _finite(args.elbow_margin, "--elbow-margin"),
        "shoulder_margin": _finite(args.shoulder_margin, "--shoulder-margin"),
    }
    box = _numbers(args.keep_in, 6, "--keep-in")
    if box is not None:
        check_vector(box, "keep-in corner", "--keep-in")
        if any(a >= b for a, b in zip(box[:3], box[3:], strict=True)):
            raise InputError(f"--keep-in: XMIN,YMIN,ZMIN must be below XMAX,YMAX,ZMAX, got {args.keep_in}")
        settings["keep_in_lower"], settings["keep_in_upper"] = box[:3], box[3:]
    rng = _numbers(args.tracker_range, 2, "--range")
    if rng is not None:
        if not 0 <= rng[0] < rng[1] <= MAX_TRACKER_RANGE:
            raise InputError(f"--range: needs 0 <= MIN < MAX <= {MAX_TRACKER_RANGE:g} m, "
                             f"got {args.tracker_range}")
        settings["tracker_range"] = rng
    start = _numbers(args.start, 6 if chain is None else chain.dof, "--start")
    if start is not None:  # outside the joint limits the route search never ended (1e300, 20 rad)
        from hil.arm.chain import chain_of

        limits = chain_of(chain if chain is not None else args.robot)
        outside = [f"q{j + 1} = {v:g} is outside [{limits.lower[j]:.4g}, {limits.upper[j]:.4g}]"
                   for j, v in enumerate(start) if not limits.lower[j] <= v <= limits.upper[j]]
        if outside:
            raise InputError(f"--start: {'; '.join(outside)}, the {limits.title}'s joint limits")
    constraints = parse_constraints(tracker=tracker, disabled=disabled, **settings)
    from hil.cli.support.options import payload_or_none

    payload = payload_or_none(args.payload)
    status = StatusLine(None if args.quiet else sys.stderr)
    timed = args.method == TIME_AWARE
    if not timed:
        for name in ("budget", "dwell"):
            if getattr(args, name) is not None:
                raise InputError(f"--{name}: only with --method {TIME_AWARE}")
    elif args.prune:  # the time-aware search already keeps only the poses its target needs
        raise InputError(f"--prune: not with --method {TIME_AWARE} (it chooses the pose count itself)")
    try:
        if timed:
            from hil.calibration.timed_selection import select_timed
            from selector.motion_time import Dwell

            dwell = Dwell() if args.dwell is None else Dwell(settle=0.0, measure=args.dwell, overhead=0.0)
            report = select_timed(
                args.robot, args.count, speed=args.speed, acceleration=args.acceleration, dwell=dwell,
                budget=args.budget, start=None if start is None else np.array(start),
                candidates=args.candidates, index=args.index, seed=args.seed, smr=smr,
                constraints=constraints, scaling=args.scaling, compliance=args.compliance,
                payload=payload if payload is not None and payload.mass > 0 else None,
                time_limit=args.time_limit, progress=status)
        else:
            report = select_poses(chain if chain is not None else args.robot, args.count,
                                  candidates=args.candidates, index=args.index,
                                  method=args.method, seed=args.seed, smr=smr, constraints=constraints,
                                  scaling=args.scaling, start=None if start is None else np.array(start),
                                  settings=TabuSettings(prune=True) if args.prune else None,
                                  bound=args.bound, progress=status, compliance=args.compliance,
                                  payload=payload if payload is not None and payload.mass > 0 else None,
                                  urdf_path=args.urdf)
    except BaseException:
        status.close(keep=False)  # the error is then the one line below the finished phases
        raise
    status.close(keep=True)
    text = json.dumps(report, indent=2) + "\n"
    if args.out:
        atomic_write_text(args.out, text)
        wrote(args.out, f"{report['count']} poses")
    else:
        sys.stdout.write(text)
    return EXIT_OK


class StatusLine:
    """Progress on a terminal: one line per phase, redrawn while the phase runs; nothing elsewhere
    (a log or a script keeps seeing only errors, one line each)."""

    def __init__(self, stream: Any | None) -> None:
        self.stream = stream if stream is not None and stream.isatty() else None
        self.phase = ""
        self.text = ""

    def __call__(self, phase: str, text: str) -> None:
        if self.stream is None:
            return
        if self.text and phase != self.phase:
            self.stream.write("\n")  # the finished phase keeps its last line
        self.phase, self.text = phase, text
        self.stream.write(f"\r\x1b[K{phase}: {text}"[:160])
        self.stream.flush()

    def close(self, keep: bool) -> None:
        """End the display: keep the last line (the run finished) or erase it (it failed)."""
        if self.stream is not None and self.text:
            self.stream.write("\n" if keep else "\r\x1b[K")
            self.stream.flush()
            self.text = ""
