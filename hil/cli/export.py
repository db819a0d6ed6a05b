"""`hil export`: a model as URDF, ROS kinematics YAML or JSON."""

from __future__ import annotations

import argparse

from hil.calibration.exports import FORMATS, export
from hil.calibration.model_file import MODEL_FORMAT, load_geometry
from hil.files.outputs import atomic_write_text


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="export a model (URDF, ROS kinematics YAML, JSON)",
                       description="Write a calibrated model in a format other tools load.")
    p.add_argument("--model", required=True, metavar="model.json")
    p.add_argument("--format", required=True, choices=FORMATS)
    p.add_argument("--out", required=True, metavar="FILE")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    geometry, doc = load_geometry(args.model, (MODEL_FORMAT,))
    atomic_write_text(args.out, export(doc, geometry, args.format, source=args.model))
    return 0
