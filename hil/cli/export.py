"""`hil export`: a model as URDF, ROS kinematics YAML or JSON."""

from __future__ import annotations

import argparse

from hil.calibration.exports import FORMATS
from hil.cli._common import wrote


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="export a model (URDF, ROS kinematics YAML, JSON)",
                       description="Write a calibrated model in a format other tools load.")
    p.add_argument("--model", required=True, metavar="model.json",
                   help="calibrated model to export (hil-model/1, from hil identify)")
    p.add_argument("--format", required=True, choices=FORMATS,
                   help="urdf: a URDF of the calibrated arm; ros-kinematics: ur_description's "
                        "kinematics_params YAML; json: the model itself")
    p.add_argument("--out", required=True, metavar="FILE", help="file to write")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hil.calibration.exports import export
    from hil.calibration.model_file import MODEL_FORMAT, load_geometry
    from hil.cli.output_paths import campaign_store
    from hil.files.outputs import atomic_write_text, check_output

    db, where = campaign_store()
    check_output(args.out, field="--out", inputs={"--model": args.model}, store=db, store_field=where)
    geometry, doc = load_geometry(args.model, (MODEL_FORMAT,))
    atomic_write_text(args.out, export(doc, geometry, args.format, source=args.model))
    wrote(args.out, args.format)
    return 0
