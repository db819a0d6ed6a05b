"""`hil identify`: calibrated model from a measurements CSV.

Every fit is cross-validated (`hil.calibration.cross_validation`) beside the nominal model and, with
``--controller``, the controller's own model; a fit that cross-validation does not show better than
both is still written (so it can be inspected) with ``better_than_nominal: false``, said in one line on
stderr, and the command exits 1: `hil export` and `hil compensate` then refuse the model unless forced.
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from hil.arm.catalog import ROBOT_NAMES, get_robot
from hil.cli.support.options import (
    CSV_FILE,
    JSON_FILE,
    PAYLOAD_HELP,
    add_joint_units,
    option,
    payload_or_none,
    triplet_or_none,
)
from hil.cli.support.output import mm, print_json, say, wrote
from hil.cli.support.urdf_options import URDF_SCOPE, add_urdf_options, urdf_chain_or_none
from hil.jobs.outcome import EXIT_FAILED, EXIT_OK

if TYPE_CHECKING:
    import numpy as np

    from hil.arm.geometry import Geometry
    from hil.calibration.cross_validation import CrossValidation
    from hil.calibration.identification import FitResult
    from hil.calibration.joint_error_request import JointErrorRequest
    from hil.calibration.measurements import Measurements


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("identify", help="identify a calibrated model from measurements",
                       description="Fit the kinematic parameters of a UR arm to SMR positions measured "
                                   "by a tracker (CSV q1..q6,x,y,z, or another form of docs/design.md: "
                                   "joints in degrees, polar hz,v,d, FIGAROH's x1,y1,z1,phix1,…) and "
                                   "write a hil-model/1 JSON. The fit is cross-validated beside the "
                                   "nominal model (and the controller's own with --controller); exit 1 "
                                   "when it does not predict held-out poses better than them. "
                                   + URDF_SCOPE + " Such an arm's joints are q1..qN (N its joints), "
                                   "beside any position form (orientations and several reflectors "
                                   "too), and its geometry alone is identified.")
    p.add_argument("--robot", help=f"robot type ({', '.join(ROBOT_NAMES)}), or --urdf")
    add_urdf_options(p)
    p.add_argument("--measurements", required=True, metavar="M.csv", type=CSV_FILE,
                   help="measurements CSV")
    p.add_argument("--smr", metavar="X,Y,Z", help="rough SMR offset in the flange frame (m)")
    p.add_argument("--validation", metavar="V.csv", type=CSV_FILE,
                   help="held-out measurements to validate on")
    add_joint_units(p)
    p.add_argument("--no-reject", action="store_true", help="keep every pose (no outlier rejection)")
    p.add_argument("--no-prior", action="store_true",
                   help="plain least squares: no prior toward the nominal geometry (manufacturing "
                        "tolerances); few or noisy poses then chase the noise")
    p.add_argument("--controller", metavar="K.json", type=JSON_FILE,
                   help="the controller's own calibration (a JSON file with a 'controller' block, as "
                        "hil compensate --controller reads), cross-validated beside the fit")
    p.add_argument("--compliance", action="store_true",
                   help="identify the joints' compliance (rad/Nm) with the geometry, for --payload")
    p.add_argument("--payload", metavar="MASS,X,Y,Z", help=PAYLOAD_HELP + " (default: nothing)")
    p.add_argument("--mounting", metavar="R,P,Y",
                   help="base orientation in the world (roll, pitch, yaw in rad; default 0,0,0: floor)")
    p.add_argument("--joint-errors", default="auto", metavar="{none,auto,ORDERS}",
                   help="low-order joint-angle errors to identify: none; auto (the default: the "
                        "harmonics of orders 1-3 and, where the d1..d6 columns show both directions, "
                        "the lost motion that cross-validation supports); or orders for every joint, "
                        "e.g. 1,2 or 1,2,lost")
    p.add_argument("--position-noise", type=option("position noise"), metavar="M",
                   help="σ per axis (m) of a measured position, which weighs positions against "
                        "orientations in a 6-D fit (default 0.002, a camera on a chessboard; "
                        "hil.calibration.pose_identification says why)")
    p.add_argument("--orientation-noise", type=option("orientation noise"), metavar="RAD",
                   help="σ per axis (rad) of a measured orientation in a 6-D fit (default 0.002)")
    p.add_argument("--json", action="store_true", help="print the fit summary as JSON")
    p.add_argument("--out", required=True, metavar="model.json", help="model file to write")
    p.set_defaults(func=run)


def summary(fit: FitResult, cv: CrossValidation | None = None) -> dict:
    """The fit figures a user looks at first."""
    out = {
        "robot": fit.robot_name, "poses": len(fit.used), "used": int(fit.used.sum()),
        "parameters": len(fit.indices), "initial_rms": fit.initial_rms, "rms": fit.rms,
        "max": fit.max_error, "sigma": fit.sigma, "iterations": fit.iterations,
        "condition": fit.condition, "seconds": fit.seconds, "prior": fit.prior is not None,
        "rejected": [{"pose": r.index, "line": r.line, "residual": r.residual} for r in fit.rejected],
        "correlated": [{"a": c.a, "b": c.b, "rho": c.rho} for c in fit.correlated],
        "joint_errors": None if fit.joint_error_choice is None else fit.joint_error_choice.as_dict(),
    }
    if cv is not None:
        out["cross_validation"] = cv.as_dict()
        out["better_than_nominal"] = cv.better_than_nominal
    return out


def _pose_fit(args: argparse.Namespace, meas: Measurements, robot: str, smr: np.ndarray | None,
              request: JointErrorRequest, arm: Geometry | None
              ) -> tuple[FitResult, CrossValidation, list[str]]:
    """The 6-D / several-reflector fit and its cross-validation (`hil.calibration.pose_identification`),
    with the notes on what it leaves out."""
    from hil.calibration import pose_identification as pose
    from hil.calibration.pose_cross_validation import cross_validate_pose
    from hil.errors import InputError

    what = "orientations" if meas.rotation is not None else "several reflectors"
    if args.compliance or request.mode == "orders":
        option = "--compliance" if args.compliance else "--joint-errors"
        raise InputError(f"{option}: {args.measurements} has {what} per pose, and the 6-D fit identifies "
                         "the geometry only; leave out the option or the file's extra columns")
    fit = pose.identify_pose(
        meas, robot, smr, reject_outliers=not args.no_reject, prior=not args.no_prior, arm=None,
        position_noise=pose.POSITION_NOISE if args.position_noise is None else args.position_noise,
        orientation_noise=(pose.ORIENTATION_NOISE if args.orientation_noise is None
                           else args.orientation_noise))
    cv = cross_validate_pose(meas, fit, controller=arm, smr_guess=smr)
    notes = []
    if request.mode != "none":
        notes.append(f"{meas.source}: {what} per pose: the 6-D fit identifies the geometry and the tool; "
                     "joint-error terms are not tried with it")
    return fit, cv, notes


def _urdf_request(args: argparse.Namespace) -> None:
    """Refuse what an arm from its URDF does not have, one line each: its compliance, joint errors and
    the controller's own model are UR-only (`hil.arm.kinematics.refuse_non_ur`)."""
    from hil.errors import InputError

    for flag, given in (("--compliance", args.compliance), ("--payload", args.payload is not None),
                          ("--mounting", args.mounting is not None),
                          ("--controller", args.controller is not None),
                          ("--joint-errors", args.joint_errors not in ("auto", "none"))):
        if given:
            raise InputError(f"{flag}: modelled for Universal Robots arms only, not for an arm from "
                             f"its URDF ({args.urdf}): its geometry alone is identified")


def run(args: argparse.Namespace) -> int:
    from hil.arm.payload import gravity_of_mounting
    from hil.calibration.cross_validation import cross_validate
    from hil.calibration.identification import validate
    from hil.calibration.joint_error_request import parse_request
    from hil.calibration.joint_error_selection import identify_with_joint_errors
    from hil.calibration.measurements import read_measurements, unused_by_position_fit
    from hil.calibration.model_file import model_document, write_json
    from hil.calibration.pose_identification import uses_tool
    from hil.cli.support.output_paths import campaign_store
    from hil.errors import InputError
    from hil.files.outputs import check_output

    db, where = campaign_store()
    check_output(args.out, field="--out", store=db, store_field=where,
                 inputs={"--measurements": args.measurements, "--validation": args.validation,
                         "--controller": args.controller, "--urdf": args.urdf})
    chain = urdf_chain_or_none(args)
    if chain is None and args.robot is None:
        raise InputError("the arm: give --robot (a catalog UR) or --urdf FILE (any serial arm)")
    if chain is not None:
        _urdf_request(args)
        args.joint_errors = "none"
    robot = get_robot(args.robot).name if chain is None else chain
    arm_name = robot if chain is None else chain.name
    smr = triplet_or_none(args.smr, "--smr", "smr offset", norm=True)
    meas = read_measurements(args.measurements, args.joint_units, chain=chain)
    held_out = read_measurements(args.validation, args.joint_units, chain=chain) if args.validation else None
    controller = None
    if args.controller is not None:
        from hil.compensation.controller_source import controller_from_file

        controller = controller_from_file(args.controller, robot)
    payload = payload_or_none(args.payload)
    mounting = triplet_or_none(args.mounting, "--mounting", "mounting angle")
    request = parse_request(args.joint_errors)
    arm = None if controller is None else controller.geometry(robot)
    if uses_tool(meas):
        fit, cv, notes = _pose_fit(args, meas, robot, smr, request, arm)
    else:
        for name in ("position_noise", "orientation_noise"):
            if getattr(args, name) is not None:
                raise InputError(f"--{name.replace('_', '-')}: {args.measurements} has one position per "
                                 "pose and no orientation: there is nothing to weigh it against")
        fit = identify_with_joint_errors(
            meas, robot, smr, request=request, reject_outliers=not args.no_reject,
            compliance=args.compliance, payload=payload if payload is not None and payload.mass > 0 else None,
            gravity=gravity_of_mounting(mounting) if mounting is not None else None,
            prior=not args.no_prior)
        cv = cross_validate(meas, fit, smr_guess=smr, controller=arm)
        notes = unused_by_position_fit(meas)
    validation = validate(fit.geometry, held_out).as_dict() if held_out is not None else None
    write_json(args.out, model_document(fit, validation, cross_validation=cv.as_dict()))
    wrote(args.out, f"hil-model/1, {len(fit.indices)} parameters")
    notes += unused_by_position_fit(held_out) if held_out is not None else []
    for note in notes:
        say(note)
    code = EXIT_OK if cv.better_than_nominal else EXIT_FAILED
    if not cv.better_than_nominal:
        print(f"hil: {args.measurements}: {cv.verdict()}; the model is marked better_than_nominal: "
              "false (hil export and hil compensate refuse it without --force)", file=sys.stderr)
    info = summary(fit, cv)
    if notes:
        info["notes"] = notes
    if validation is not None:
        info["validation"] = validation
    if args.json:
        print_json(info)
        return code
    print(f"{arm_name}: {info['used']}/{info['poses']} poses, {info['parameters']} parameters, "
          f"{fit.iterations} iterations, condition {fit.condition:.1f}, {fit.seconds * 1e3:.0f} ms"
          + ("" if fit.prior is not None else ", no prior"))
    print(f"  after tracker alignment  RMS {mm(fit.initial_rms)}")
    print(f"  calibrated fit           RMS {mm(fit.rms)}  max {mm(fit.max_error)}  "
          f"noise σ {fit.sigma * 1e6:.1f} µm/axis")
    print(f"  held out ({cv.folds}-fold CV)   calibrated RMS {mm(cv.calibrated.rms)}  "
          f"max {mm(cv.calibrated.max)}  nominal RMS {mm(cv.nominal.rms)}"
          + ("" if cv.controller is None else f"  controller RMS {mm(cv.controller.rms)}")
          + ("" if cv.better_than_nominal else "  NOT BETTER"))
    orientation = getattr(cv, "orientation", None)
    if orientation:
        print(f"  held out orientation     calibrated RMS {orientation['calibrated'].rms * 1e3:.3f} mrad  "
              f"nominal RMS {orientation['nominal'].rms * 1e3:.3f} mrad"
              + ("" if orientation.get("controller") is None
                 else f"  controller RMS {orientation['controller'].rms * 1e3:.3f} mrad"))
    if validation is not None:
        print(f"  validation ({validation['count']} poses)  RMS {mm(validation['rms'])}  "
              f"max {mm(validation['max'])}")
    for r in fit.rejected:
        print(f"  rejected pose {r.index} (line {r.line}): residual {mm(r.residual)}")
    if fit.with_compliance:
        for name, v, sd in zip(fit.names, fit.values, fit.std, strict=True):
            if name.startswith("compliance."):
                print(f"  {name:<16} {v:.3e} ± {sd:.1e} rad/Nm")
    choice = fit.joint_error_choice
    if choice is not None:
        kept = ", ".join(choice.groups) or "none"
        print(f"  joint errors ({choice.request}): {kept}; {choice.folds}-fold CV RMS "
              f"{mm(choice.cv_rms_without)} without, {mm(choice.cv_rms)} with")
        for name, v, sd in zip(fit.names, fit.values, fit.std, strict=True):
            if name.startswith(("lost_motion.", *(f"joint{j}.cos" for j in range(1, 7)),
                                *(f"joint{j}.sin" for j in range(1, 7)))):
                print(f"  {name:<16} {v * 1e6:+.1f} ± {sd * 1e6:.1f} µrad")
    for c in fit.correlated[:10]:
        print(f"  correlated: {c.a} ~ {c.b}  ρ = {c.rho:+.3f}")
    return code
