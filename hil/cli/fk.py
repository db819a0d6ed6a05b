"""`hil fk`: positions a model predicts for joint configurations."""

from __future__ import annotations

import argparse

from hil.cli.support.options import PAYLOAD_HELP, add_joint_units, payload_or_none
from hil.cli.support.output import wrote
from hil.jobs.outcome import EXIT_OK


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fk", help="forward kinematics of a model",
                       description="Write x,y,z (metres) of the SMR or flange for each row of a joints "
                                   "CSV (q1..q6 in radians, q1_deg..q6_deg in degrees, or the URDF's "
                                   "joint names).")
    p.add_argument("--model", required=True, metavar="model.json", help="hil-model/1 or hil-truth/1")
    p.add_argument("--joints", required=True, metavar="Q.csv",
                   help="joint configurations: CSV with columns q1..q6 (radians) or another joint form")
    add_joint_units(p)
    p.add_argument("--frame", choices=("tracker", "base"), default="tracker",
                   help="frame of the positions written: the tracker's (as it would measure them) or "
                        "the robot base's")
    p.add_argument("--point", choices=("smr", "flange"), default="smr",
                   help="which point: the SMR centre or the flange centre (tool0)")
    p.add_argument("--payload", metavar="MASS[,X,Y,Z]",
                   help=PAYLOAD_HELP + "; default: the payload the model was calibrated with (a compliant "
                        "model predicts the sag for it)")
    p.add_argument("--out", required=True, metavar="P.csv", help="CSV to write (x,y,z in metres)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hil.arm.kinematics import Kinematics
    from hil.calibration.measurements import read_joints
    from hil.calibration.model_file import load_geometry
    from hil.cli.support.output_paths import campaign_store
    from hil.files.outputs import atomic_write_text, check_output, format_csv

    db, where = campaign_store()
    check_output(args.out, field="--out", inputs={"--model": args.model, "--joints": args.joints},
                 store=db, store_field=where)
    geometry, _ = load_geometry(args.model)
    payload = payload_or_none(args.payload)
    if payload is not None:
        geometry = geometry.with_payload(payload if payload.mass > 0 else None)
    q, _ = read_joints(args.joints, args.joint_units)
    points = Kinematics(geometry).points(q, frame=args.frame, point=args.point)
    atomic_write_text(args.out, format_csv(("x", "y", "z"), points))
    wrote(args.out, f"{len(points)} positions, {args.point} in the {args.frame} frame")
    return EXIT_OK
