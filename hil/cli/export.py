"""`hil export`: a model as URDF, ROS kinematics YAML or JSON.

``--which controller`` exports instead the controller's own model that the campaign ran with (the
model's ``controller`` block: its factory calibration, read from the controller at connect) as the
ROS kinematics YAML UR's ur_calibration would write for it, so both models can be loaded side by side.
"""

from __future__ import annotations

import argparse

from hil.calibration.exports import FORMATS
from hil.cli.support.options import JSON_FILE
from hil.cli.support.output import wrote
from hil.errors import InputError
from hil.jobs.outcome import EXIT_OK

#: Whose model to export: hil's calibrated one, or the controller's own (its factory calibration).
WHICH: tuple[str, ...] = ("hil", "controller")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="export a model (URDF, ROS kinematics YAML, JSON)",
                       description="Write a calibrated model in a format other tools load. A model of "
                                   "an arm from its URDF (hil identify --urdf) exports as json; "
                                   "ros-kinematics holds a UR's six joints and is refused for it.")
    p.add_argument("--model", required=True, metavar="model.json", type=JSON_FILE,
                   help="calibrated model to export (hil-model/1, from hil identify)")
    p.add_argument("--format", required=True, choices=FORMATS,
                   help="urdf: a URDF of the calibrated arm; ros-kinematics: ur_description's "
                        "kinematics_params YAML; json: the model itself")
    p.add_argument("--which", choices=WHICH, default="hil",
                   help="hil: the calibrated model (default); controller: the controller's own model "
                        "the campaign ran with (its factory calibration), --format ros-kinematics only")
    p.add_argument("--out", required=True, metavar="FILE", help="file to write")
    p.add_argument("--force", action="store_true",
                   help="export a model whose cross-validation did not show it better than the nominal "
                        "or the controller's model (better_than_nominal: false); refused without it")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hil.calibration.exports import export
    from hil.calibration.model_file import MODEL_FORMAT, load_geometry, refuse_worse_than_nominal
    from hil.cli.support.output_paths import campaign_store
    from hil.files.outputs import atomic_write_text, check_output

    db, where = campaign_store()
    check_output(args.out, field="--out", inputs={"--model": args.model}, store=db, store_field=where)
    geometry, doc = load_geometry(args.model, (MODEL_FORMAT,))
    if args.which == "hil":  # the controller's own model is the arm's as it is: no fit to judge
        forced = refuse_worse_than_nominal(doc, args.model, args.force, "export")
        if forced is not None:
            import sys

            print(f"hil: warning: {forced}; exported anyway (--force)", file=sys.stderr)
    if args.which == "controller":
        text = _controller_yaml(args, doc)
    else:
        text = export(doc, geometry, args.format, source=args.model)
    atomic_write_text(args.out, text)
    wrote(args.out, args.format if args.which == "hil" else f"{args.format} of the controller's model")
    return EXIT_OK


def _controller_yaml(args: argparse.Namespace, doc: dict) -> str:
    """The controller's model of `doc` as ur_calibration's YAML; what it cannot hold said on stderr too."""
    import sys

    from hil.calibration.controller_export import controller_ros_kinematics, flange_not_held
    from hil.calibration.model_file import model_controller

    if args.format != "ros-kinematics":
        raise InputError(f"--which controller: only --format ros-kinematics, not {args.format!r} (the "
                         "controller's model is exported as UR's ur_calibration writes it)")
    calibration = model_controller(doc, args.model)
    if calibration is None:
        raise InputError(f"{args.model}: no field 'controller': the campaign did not read the "
                         "controller's own model (a hil model from a campaign on a controller that "
                         "reports its KinematicsInfo has one)")
    missing = flange_not_held(calibration)
    if missing is not None:
        print(f"hil: warning: {missing}", file=sys.stderr)
    digest = (doc.get("input") or {}).get("sha256") if isinstance(doc.get("input"), dict) else None
    return controller_ros_kinematics(calibration, str(doc["robot"]),
                                     f"exported by hil from {args.model} (model of data sha256 "
                                     f"{digest or 'unknown'})")
