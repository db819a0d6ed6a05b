"""`hil validate`: errors of a model on measurements it was not fitted to."""

from __future__ import annotations

import argparse

from hil.calibration.identification import validate
from hil.calibration.measurements import read_measurements
from hil.calibration.model_file import load_geometry
from hil.calibration.pose_validation import validate_tool
from hil.cli.support.options import CSV_FILE, JSON_FILE, RMS_THRESHOLD_HELP, add_joint_units, rms_threshold
from hil.cli.support.output import mm, print_json, say
from hil.jobs.outcome import EXIT_FAILED, EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("validate", help="check a model against held-out measurements",
                       description="Distances between a model's predicted SMR positions and measured "
                                   "ones (CSV q1..q6,x,y,z or another form of docs/design.md); on a "
                                   "6-D or several-reflector file also every reflector the model knows "
                                   "and the orientation error of a model with a tool frame. Exit "
                                   "code 1 when --max-rms is exceeded (by all compared reflectors). "
                                   "A model of an arm from its URDF carries the URDF: its joints are "
                                   "q1..qN.")
    p.add_argument("--model", required=True, metavar="model.json", type=JSON_FILE,
                   help="model to check (hil-model/1, or a hil-truth/1 to see the noise floor)")
    p.add_argument("--measurements", required=True, metavar="V.csv", type=CSV_FILE,
                   help="measurements the model was not fitted to: CSV q1..q6,x,y,z (or another form)")
    add_joint_units(p)
    p.add_argument("--max-rms", type=rms_threshold, metavar="METRES",
                   help=f"acceptance threshold on the RMS, {RMS_THRESHOLD_HELP}")
    p.add_argument("--json", action="store_true", help="print the statistics as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    geometry, _ = load_geometry(args.model)
    meas = read_measurements(args.measurements, args.joint_units, chain=geometry.chain)
    stats = validate(geometry, meas)
    tool = validate_tool(geometry, meas)
    notes = [] if tool is None else tool.notes
    for note in notes:
        say(note)
    judged = stats if tool is None or tool.all_reflectors is None else tool.all_reflectors
    passed = args.max_rms is None or judged.rms <= args.max_rms
    if args.json:
        print_json({**stats.as_dict(), "max_rms": args.max_rms, "passed": passed,
                    **({"tool": tool.as_dict()} if tool is not None else {}),
                    **({"notes": notes} if notes else {})})
    else:
        verdict = "" if args.max_rms is None else ("  PASS" if passed else "  FAIL")
        if tool is None or tool.all_reflectors is None:
            print(f"{stats.count} poses: mean {mm(stats.mean)}  RMS {mm(stats.rms)}  max {mm(stats.max)}"
                  + verdict)
        else:
            for k, s in enumerate(tool.per_reflector, start=1):
                print(f"reflector {k}: {s.count} poses: mean {mm(s.mean)}  RMS {mm(s.rms)}  "
                      f"max {mm(s.max)}")
            a = tool.all_reflectors
            print(f"{tool.reflectors} reflectors: {a.count} points: RMS {mm(a.rms)}  max {mm(a.max)}"
                  + verdict)
        if tool is not None and tool.orientation is not None:
            o = tool.orientation
            print(f"orientation: {o.count} poses: mean {o.mean * 1e3:.3f} mrad  RMS {o.rms * 1e3:.3f} mrad"
                  f"  max {o.max * 1e3:.3f} mrad")
    return EXIT_OK if passed else EXIT_FAILED
