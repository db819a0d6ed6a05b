"""`hil fk`: positions (and, for a model of a measured tool, orientations) a model predicts for joint
configurations.

A model fitted to 6-D measurements carries the measured frame's orientation on the flange (``tool_rpy``)
and one fitted to several reflectors every reflector's centre (``reflectors``); `hil fk` then writes
what that instrument would read: every reflector's position and the frame's orientation, the latter as
a rotation vector (axis × angle, rad, R = exp([r]ₓ), angle in [0, π]) and as URDF roll, pitch, yaw
(rad, R = Rz(yaw)·Ry(pitch)·Rx(roll), the model file's own convention). A single-SMR model writes
x, y, z as it always did.
"""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from hil.cli.support.options import CSV_FILE, JSON_FILE, PAYLOAD_HELP, add_joint_units, payload_or_none
from hil.cli.support.output import print_json, wrote
from hil.jobs.outcome import EXIT_OK

#: The two spellings of an orientation `hil fk` writes, said in its CSV's columns and its JSON.
ROTATION_VECTOR = "rotation vector: axis x angle (rad), R = exp([r]x), angle in [0, pi]"
RPY = "URDF roll, pitch, yaw (rad): R = Rz(yaw) Ry(pitch) Rx(roll)"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fk", help="forward kinematics of a model",
                       description="Write x,y,z (metres) of the SMR or flange for each row of a joints "
                                   "CSV (q1..q6 in radians, q1_deg..q6_deg in degrees, or the URDF's "
                                   "joint names; q1..qN for a model of an arm from its URDF, which "
                                   "the model file carries). A model of a measured tool (a 6-D fit's "
                                   "tool_rpy, several reflectors) also gets every reflector (x2,y2,z2, "
                                   "...) and the measured frame's orientation: rx,ry,rz (rotation "
                                   "vector, rad) and roll,pitch,yaw (URDF: R = Rz(yaw) Ry(pitch) "
                                   "Rx(roll), rad).")
    p.add_argument("--model", required=True, metavar="model.json", type=JSON_FILE,
                   help="hil-model/1 or hil-truth/1")
    p.add_argument("--joints", required=True, metavar="Q.csv", type=CSV_FILE,
                   help="joint configurations: CSV with columns q1..q6 (radians) or another joint form")
    add_joint_units(p)
    p.add_argument("--frame", choices=("tracker", "base"), default="tracker",
                   help="frame of the positions (and orientations) written: the tracker's (as it would "
                        "measure them) or the robot base's")
    p.add_argument("--point", choices=("smr", "flange"), default="smr",
                   help="which point: the SMR centre (with a measured tool: every reflector and the "
                        "measured frame) or the flange centre (tool0)")
    p.add_argument("--payload", metavar="MASS,X,Y,Z",
                   help=PAYLOAD_HELP + "; default: the payload the model was calibrated with (a compliant "
                        "model predicts the sag for it)")
    p.add_argument("--out", required=True, metavar="P.csv",
                   help="CSV to write (x,y,z in metres; a measured tool's further columns as above)")
    p.add_argument("--json", action="store_true",
                   help="also print the poses as JSON on stdout (positions, reflectors, orientations "
                        "with their conventions)")
    p.set_defaults(func=run)


def tool_table(geometry: Any, q: np.ndarray, frame: str) -> tuple[list[str], np.ndarray, dict[str, Any]]:
    """The columns, rows and JSON document of what a measured tool's model predicts at `q`: each
    reflector's position, then (with ``tool_rpy``) the measured frame's rotation vector and rpy."""
    import pinocchio as pin

    from hil.arm.tool_frame import predict

    p, R = predict(geometry, q, frame=frame)
    reflectors = p.shape[1]
    header = ["x", "y", "z"] + [f"{a}{k}" for k in range(2, reflectors + 1) for a in "xyz"]
    columns = [p.reshape(len(p), -1)]
    oriented = geometry.tool_rotation is not None
    rotvec = rpy = None
    if oriented:
        rotvec = np.array([pin.log3(r) for r in R]).reshape(-1, 3)
        rpy = np.array([pin.rpy.matrixToRpy(r) for r in R]).reshape(-1, 3)
        header += ["rx", "ry", "rz", "roll", "pitch", "yaw"]
        columns += [rotvec, rpy]
    poses = []
    for n in range(len(p)):
        pose: dict[str, Any] = {"position": p[n, 0].tolist(), "reflectors": p[n].tolist()}
        if oriented:
            assert rotvec is not None and rpy is not None
            pose["rotation_vector"] = rotvec[n].tolist()
            pose["rpy"] = rpy[n].tolist()
        poses.append(pose)
    doc = {"frame": frame, "point": "smr", "units": {"position": "m", "rotation": "rad"},
           "reflectors": reflectors,
           "orientation": ({"rotation_vector": ROTATION_VECTOR, "rpy": RPY} if oriented else None),
           "poses": poses}
    return header, np.hstack(columns), doc


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
    q, _ = read_joints(args.joints, args.joint_units, chain=geometry.chain)
    tool = args.point == "smr" and (geometry.tool_rotation is not None or geometry.reflectors is not None)
    if tool:
        header, rows, doc = tool_table(geometry, q, args.frame)
        parts = [f"{len(rows)} poses: {doc['reflectors']} reflector(s)"]
        if doc["orientation"] is not None:
            parts.append("the measured frame's orientation as a rotation vector (rx,ry,rz) and URDF "
                         "roll,pitch,yaw (R = Rz(yaw) Ry(pitch) Rx(roll)), rad")
        what = ", ".join(parts) + f", in the {args.frame} frame"
    else:
        points = Kinematics(geometry).points(q, frame=args.frame, point=args.point)
        header, rows = ["x", "y", "z"], points
        doc = {"frame": args.frame, "point": args.point, "units": {"position": "m"}, "reflectors": 1,
               "orientation": None, "poses": [{"position": p.tolist()} for p in points]}
        what = f"{len(points)} positions, {args.point} in the {args.frame} frame"
    atomic_write_text(args.out, format_csv(header, rows))
    wrote(args.out, what)
    if args.json:
        print_json({"format": "hil-fk/1", **doc})
    return EXIT_OK
