"""`hil moveb`: smooth tool paths that keep within the program's error bounds, planned and measured.

``hil moveb plan PROGRAM [--continuity G2|G3] --out samples.csv`` plans the program and writes dense
samples (``s,x,y,z,i,j,k,u,v,w,curvature``: mm, unit tool Z and X axes, 1/mm) and prints a summary.
``hil moveb run PROGRAM --config station.toml`` (or ``--sim``) streams the timed trajectory through the
robot's servo loop, samples the tracker continuously and prints the path accuracy.

Both print a readable summary on a terminal, and JSON with ``--json`` or when stdout is not a terminal
(a pipe or a file: what scripts have always read).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from hil.arm.catalog import ROBOT_NAMES
from hil.cli.support.options import JSON_FILE, MOVEB_FILE, SEED, SIM_SPEED, TOML_FILE, option
from hil.cli.support.output import print_json, say, wants_json, wrote
from hil.cli.support.station_options import add_arm_choice, add_tracker_protocol
from hil.files.outputs import check_output
from hil.jobs.moveb import FRAMES, MovebRequest, run_moveb
from hil.jobs.outcome import EXIT_BAD_INPUT, EXIT_FAULT, EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("moveb", help="smooth error-controlled trajectories (plan, run)",
                       description=__doc__.split("\n\n")[0])
    moveb = p.add_subparsers(dest="moveb_command", metavar="ACTION")
    plan = moveb.add_parser("plan", help="plan a MOVEB program and write dense samples")
    plan.add_argument("program", metavar="PROGRAM", type=MOVEB_FILE,
                      help="MOVEB program (hil/moveb/examples/ has two)")
    plan.add_argument("--continuity", choices=("G2", "G3"), default="G2", help=_CONTINUITY)
    plan.add_argument("--out", required=True, metavar="samples.csv",
                      help="CSV of dense samples to write (s,x,y,z,i,j,k,u,v,w,curvature)")
    plan.add_argument("--step", type=STEP_MM, default=0.5, metavar="MM",
                      help="sample spacing on straight parts (every bridge gets 64 samples too)")
    plan.add_argument("--rate", type=CONTROLLER_RATE, default=500.0, metavar="HZ",
                      help="controller rate for the cycle time in the summary (500 e-series, 125 CB3)")
    _limit_options(plan)
    _json_option(plan)
    plan.set_defaults(func=run_plan)

    run = moveb.add_parser("run",
                           help="run a MOVEB program on the robot and measure it")
    run.add_argument("program", metavar="PROGRAM", type=MOVEB_FILE,
                     help="MOVEB program (hil/moveb/examples/ has two)")
    src = run.add_mutually_exclusive_group(required=True)
    src.add_argument("--config", metavar="station.toml", type=TOML_FILE, help="station configuration")
    src.add_argument("--sim", action="store_true", help="use the simulated station")
    add_tracker_protocol(run)
    add_arm_choice(run)
    run.add_argument("--model", metavar="model.json", type=JSON_FILE,
                     help="calibrated model (hil-model/1, a campaign result that embeds one, or a truth): "
                          "IK and the tracker pose")
    run.add_argument("--ik", choices=("model", "nominal"), default="model",
                     help="with --model: solve the joints on the model (default), or on the nominal arm "
                          "and measure in the model's frame (how far off the uncalibrated arm is)")
    run.add_argument("--continuity", choices=("G2", "G3"), default="G2", help=_CONTINUITY)
    run.add_argument("--frame", choices=FRAMES, default=None,
                     help="where the program runs: 'base' as written, in the robot base frame; 'current' "
                          "anchored at the arm's current TCP pose (jog the SMR to face the tracker first); "
                          "'tracker' centred in front of the robot towards the tracker, the tool facing it "
                          "(needs --sim or --model, which know where the tracker stands). Default: 'tracker' "
                          "with --sim (its tracker stands at a random place), else 'base'")
    _limit_options(run)
    run.add_argument("--joint-speed", type=option("fraction"), default=1.0, metavar="F",
                     help="allowed fraction of the datasheet joint speeds (0 < F <= 1); the feed slows "
                          "down where the path would need more")
    # ur_rtde's limit on a joint acceleration (UR_JOINT_ACCELERATION_MAX), as for robot.acceleration
    run.add_argument("--joint-acceleration", type=option("joint acceleration"), default=None,
                     metavar="RAD/S2",
                     help="largest joint acceleration at the controller samples (every joint; UR "
                          "publishes none, so none by default: the peak is reported either way)")
    # Leica's trackers stream at most 1000 points a second (AT960 real-time feature pack)
    run.add_argument("--tracker-rate", type=option("tracker rate"), default=100.0,
                     metavar="HZ",
                     help="rate at which the tracker is sampled during the motion")
    run.add_argument("--min-coverage", type=option("fraction"), default=0.9, metavar="F",
                     help="share of the path the tracker must measure; below it the run is reported "
                          "'incomplete' (exit code 1)")
    run.add_argument("--truth", metavar="truth.json", type=JSON_FILE,
                     help="--sim: the hidden truth (default: random)")
    run.add_argument("--speed", type=SIM_SPEED, default=1.0, metavar="F", help="--sim: fast-time factor")
    run.add_argument("--seed", type=SEED, help="--sim: seed of the random truth and noise (default: 1)")
    run.add_argument("--robot", default=None,
                     help=f"--sim: robot type ({', '.join(ROBOT_NAMES)}; default: --truth's, "
                          "--model's, else ur5e); with --config it must match robot.type")
    run.add_argument("--out", metavar="result.json", help="write the path-accuracy result")
    run.add_argument("--plot", metavar="run.png",
                     help="write a figure: commanded and measured path, deviation along the path")
    _json_option(run)
    run.set_defaults(func=run_run)
    p.set_defaults(func=lambda args: (p.print_help(sys.stderr), EXIT_BAD_INPUT)[1])



#: Sample spacing of ``moveb plan`` (mm): finer than 10 µm is below any UR arm's repeatability (UR5e:
#: ±0.03 mm, ISO 9283) and a metre of path would need 10^5+ samples; 1e-9 asked numpy for 2.9 TiB.
STEP_MM = option("path step")

#: Controller rate for the cycle time of ``moveb plan`` (Hz): UR controllers run at 125 Hz (CB3) or
#: 500 Hz (e-Series); the timing law makes one sample per cycle, so 1e308 Hz could not be allocated.
CONTROLLER_RATE = option("controller rate")
_CONTINUITY = ("smoothness at the corners: G2 (continuous curvature) or G3 (continuous change of "
               "curvature too: smoother, slightly longer bridges)")


def _limit_options(p: argparse.ArgumentParser) -> None:
    """The Cartesian limits of the feed profile (tool point)."""
    # Ranges: ur_rtde's moveL takes at most 3 m/s and 150 m/s² at the tool (UR_TOOL_VELOCITY_MAX,
    # UR_TOOL_ACCELERATION_MAX); UR publishes no jerk limit, so 1e8 mm/s³ (full tool acceleration in
    # 1.5 ms, three e-Series cycles). The lower ends keep the samples the timing law makes at the
    # controller rate in memory: 1 mm/s walks a metre in 17 minutes (500 Hz: half a million samples),
    # and 1e-30 asked for more samples than numpy can index.
    p.add_argument("--velocity", type=option("tool speed"), default=100.0, metavar="MM/S",
                   help="largest tool speed along the path")
    p.add_argument("--acceleration", type=option("tool acceleration"), default=1000.0, metavar="MM/S2",
                   help="largest tool acceleration along the path")
    p.add_argument("--jerk", type=option("tool jerk"), default=10000.0, metavar="MM/S3",
                   help="largest jerk along the path")
    p.add_argument("--normal-acceleration", type=option("tool acceleration"), default=1000.0,
                   metavar="MM/S2",
                   help="largest acceleration across the path (v²·curvature): slows the feed at corners")


def _json_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true",
                   help="print JSON even on a terminal (it always is when stdout is piped or redirected)")


def run_plan(args: argparse.Namespace) -> int:
    from hil.cli.support.output_paths import campaign_store
    from hil.moveb.path_plan import plan_program, summary, write_samples
    from hil.moveb.program import load_program

    db, where = campaign_store()
    check_output(args.out, field="--out", inputs={"PROGRAM": args.program}, store=db, store_field=where)
    from hil.moveb.timing import Limits

    limits = Limits(args.velocity, args.acceleration, args.jerk, args.normal_acceleration)
    plan = plan_program(load_program(args.program), args.continuity)
    dense = plan.dense(args.step)
    law, _samples = plan.timed(limits, args.rate)  # before writing: a failure leaves no samples file
    write_samples(args.out, dense)
    wrote(args.out, f"{len(dense.s)} samples")
    # the Cartesian limits only: joint speeds depend on where the arm runs it (`hil moveb run`)
    doc = dict(summary(plan), cycle_time_s=law.cycle_time, rate_hz=args.rate,
               limits={"velocity": limits.velocity, "acceleration": limits.acceleration,
                       "jerk": limits.jerk, "normal_acceleration": limits.normal_acceleration})
    if wants_json(args):
        print_json(doc)
    else:
        sys.stdout.write(_plan_text(doc))
    return EXIT_OK


def _plan_text(doc: dict[str, Any]) -> str:
    """`hil moveb plan`'s summary for a person."""
    lim = doc["limits"]
    lines = [f"{doc['points']} points, {doc['length_mm']:.1f} mm of path, {doc['continuity']}, "
             f"{doc['bridges']} corners bridged (planned in {doc['planning_ms']:.0f} ms)",
             f"cycle time {doc['cycle_time_s']:.3f} s at {doc['rate_hz']:g} Hz under the Cartesian limits "
             f"(velocity {lim['velocity']:g} mm/s, acceleration {lim['acceleration']:g} mm/s², "
             f"jerk {lim['jerk']:g} mm/s³, normal acceleration {lim['normal_acceleration']:g} mm/s²)"]
    for g in doc["groups"]:
        lines.append(f"  lines {g['lines'][0]}-{g['lines'][1]}: {g['points']} points, corner deviation D "
                     f"{g['D']:g} mm, point error E {g['E']:g} mm: largest point error "
                     f"{g['max_point_error']:.4f} mm")
    return "\n".join(lines) + "\n"


def _run_text(doc: dict[str, Any]) -> str:
    """`hil moveb run`'s result for a person."""
    lines = [f"{doc.get('program') or 'moveb run'}: {doc.get('status')}"]
    if doc.get("error"):
        lines.append(f"  {doc['error']}")
    if doc.get("frame"):
        lines.append(f"  program frame   {doc['frame']}")
    smr = doc.get("smr")
    if smr:
        x, y, z = smr["offset_mm"]
        lines.append(f"  SMR offset      ({x:.1f}, {y:.1f}, {z:.1f}) mm, {smr['source']}")
    if doc.get("cycle_time_s") is not None:
        lines.append(f"  cycle time      {doc['cycle_time_s']:.3f} s")
    if doc.get("coverage") is not None:
        lines.append(f"  measured        {doc['coverage']:.0%} of the path "
                     f"({doc.get('lost_samples', 0)} samples lost)")
    for title, key in (("path deviation", "path_accuracy"), ("rigidly fitted", "path_accuracy_registered")):
        acc = doc.get(key)
        if acc:
            note = " (rigidly fitted: no model)" if key == "path_accuracy" and doc.get("registered") else ""
            lines.append(f"  {title:<15} max {acc['max_deviation_mm']:.3f} mm, "
                         f"RMS {acc['rms_deviation_mm']:.3f} mm{note}")
    servo = doc.get("servo")
    if servo:
        lines.append(f"  servo stream    {servo['deadline_misses']} of {servo['samples']} targets late, "
                     f"longest gap {servo['max_gap_s'] * 1e3:.0f} ms")
    peak = (doc.get("joint_speeds") or {}).get("peak_fraction")
    if peak:
        lines.append("  joint speeds    peak " + ", ".join(f"{v:.0%}" for v in peak) + " of the allowed")
    return "\n".join(lines) + "\n"


def run_run(args: argparse.Namespace) -> int:
    from hil.cli.support.output_paths import campaign_store

    inputs = {"PROGRAM": args.program, "--model": args.model, "--truth": args.truth, "--config": args.config}
    db, where = campaign_store(None, args.config) if args.out or args.plot else (None, "")
    if args.out:
        check_output(args.out, field="--out", inputs=inputs, store=db, store_field=where)
    if args.plot:
        check_output(args.plot, field="--plot", inputs=inputs, store=db, store_field=where,
                     outputs={"--out": args.out})

    out = run_moveb(_request(args), say=say)
    doc = out.document or {}
    if out.exit_code == EXIT_FAULT:  # stdout may be a pipe nobody reads: the fault goes to stderr too
        print(f"hil: hardware fault: {doc.get('error')}", file=sys.stderr)
    if args.plot and out.run is not None:
        _plot(args.plot, args.program, out.run)
        wrote(args.plot, "figure: commanded and measured path, deviation along it")
    if args.out:
        from hil.files.outputs import atomic_write_text

        atomic_write_text(args.out, json.dumps(doc, indent=2, allow_nan=False) + "\n")
        wrote(args.out, "hil-moveb-run/1")
    if wants_json(args):
        print_json(doc)
    else:
        sys.stdout.write(_run_text(doc))
    return out.exit_code


def _request(args: argparse.Namespace) -> MovebRequest:
    """``hil moveb run``'s options as the job's request."""
    return MovebRequest(
        args.program, config=args.config, sim=args.sim, truth=args.truth, speed=args.speed, seed=args.seed,
        robot=args.robot, tracker_protocol=args.tracker_protocol, ideal=args.ideal, model=args.model,
        ik=args.ik,
        continuity=args.continuity, frame=args.frame, velocity=args.velocity, acceleration=args.acceleration,
        jerk=args.jerk, normal_acceleration=args.normal_acceleration, joint_speed=args.joint_speed,
        joint_acceleration=args.joint_acceleration, tracker_rate=args.tracker_rate,
        min_coverage=args.min_coverage)


def _plot(path: str, program: str, result: Any) -> None:
    """``--plot``: the commanded and measured path and the deviation along it."""
    from hil.moveb.accuracy import distance_to_path
    from hil.moveb.plot import write_run_figure

    frame = "rigidly fitted (no model)" if result.registered else "model base frame"
    write_run_figure(path, result.path, result.path_s, result.measured,
                     distance_to_path(result.measured, result.path), result.corners,
                     f"{Path(program).name}: max {result.accuracy['max_deviation_mm']:.3f} mm, "
                     f"RMS {result.accuracy['rms_deviation_mm']:.3f} mm ({frame}; "
                     f"{result.accuracy['coverage']:.0%} of the path measured)")
