"""`hil fk`: positions a model predicts for joint configurations."""

from __future__ import annotations

import argparse

from hil.arm.kinematics import Kinematics
from hil.calibration.measurements import read_joints
from hil.calibration.model_file import load_geometry
from hil.files.outputs import atomic_write_text, format_csv


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fk", help="forward kinematics of a model",
                       description="Write x,y,z (metres) of the SMR or flange for each row of a joints "
                                   "CSV (q1..q6, radians).")
    p.add_argument("--model", required=True, metavar="model.json", help="hil-model/1 or hil-truth/1")
    p.add_argument("--joints", required=True, metavar="Q.csv")
    p.add_argument("--frame", choices=("tracker", "base"), default="tracker")
    p.add_argument("--point", choices=("smr", "flange"), default="smr")
    p.add_argument("--out", required=True, metavar="P.csv")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    geometry, _ = load_geometry(args.model)
    q, _ = read_joints(args.joints)
    points = Kinematics(geometry).points(q, frame=args.frame, point=args.point)
    atomic_write_text(args.out, format_csv(("x", "y", "z"), points))
    return 0
