"""`hil compensate`: targets for the controller, so the tool lands where the calibrated model says.

A UR controller moves by its own model (nominal DH + factory deltas); it cannot load hil's. This
rewrites a CSV of tool poses or a URScript program so each target, solved with the calibrated model
and sent in the controller's terms, puts the tool at the pose that was wanted (`hil.compensation`).
"""

from __future__ import annotations

import argparse
import os
import re
import sys

from hil.cli.support.options import JSON_FILE, POSES_OR_PROGRAM, TOML_FILE
from hil.cli.support.output import print_json, wrote
from hil.jobs.outcome import EXIT_OK

#: File name endings read as a URScript program, and as a CSV of poses; anything else is decided by its
#: first line (a CSV header names x,y,z,rx,ry,rz).
#: Suffixes that say the kind; any other (``.txt`` included: Polyscope exports and CSVs both use it)
#: is decided by the content, and a content that is neither kind is refused (`_is_program`).
PROGRAM_SUFFIXES = (".script", ".urscript")
CSV_SUFFIXES = (".csv",)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "compensate", help="rewrite target poses (CSV or URScript) for the controller's own model",
        description="Compensate target poses: each is solved with the calibrated model and written as "
                    "the pose the controller's own model (nominal DH + its factory calibration) maps "
                    "those joints to, so the tool lands where the model says. INPUT is a CSV of tool "
                    "poses (header x,y,z,rx,ry,rz: base frame, metres, UR rotation vector; optional "
                    "q1..q6 columns choose each row's configuration; other columns pass through) or a "
                    "URScript program (every p[...] target of movel/movej/movep/movec/get_inverse_kin, "
                    "and every pose variable those moves go to, is rewritten; set_tcp, offsets in "
                    "pose_trans and everything else stay byte for byte). Moves whose target is computed "
                    "at run time are listed as not compensated. A summary of how far the targets moved "
                    "goes to stderr (or JSON to stdout with --json).")
    p.add_argument("input", metavar="INPUT", type=POSES_OR_PROGRAM,
                   help="targets: a CSV (.csv) or a URScript program (.script, .urscript, .txt); another "
                        "name is read as a CSV when its first line names x,y,z,rx,ry,rz, else as a program")
    p.add_argument("--model", required=True, metavar="model.json", type=JSON_FILE,
                   help="the calibrated model (hil-model/1, a campaign result that embeds one, or a "
                        "simulator truth)")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--controller", metavar="K.json", type=JSON_FILE,
                     help="a JSON file with the controller's 'controller' block (delta_theta, delta_a, "
                          "delta_d, delta_alpha): a truth, a model that carries one, or "
                          '{"robot": ..., "controller": {...}}')
    src.add_argument("--config", metavar="station.toml", type=TOML_FILE,
                     help="read the controller's calibration from the arm at robot.address (primary "
                          "interface, port 30001, within timeouts.connect)")
    p.add_argument("--out", required=True, metavar="OUTPUT",
                   help="file to write: the same CSV or program with the compensated targets")
    p.add_argument("--joints", action="store_true",
                   help="write joint targets instead of poses: a CSV gets q1..q6 columns in place of "
                        "x..rz; in a program, pose literals given to movel/movej/movep/movec become "
                        "joint lists [q1,...] (pose variables stay poses, compensated)")
    p.add_argument("--near", metavar="Q1,..,Q6",
                   help="joints (radians) the first target's configuration is chosen near, when the "
                        "input does not say (CSV q1..q6 columns; a program's Waypoint_n_q or preceding "
                        "movej([...])). Default: 0,-pi/2,pi/2,-pi/2,-pi/2,0 (elbow up, tool down)")
    p.add_argument("--tcp", metavar="X,Y,Z,RX,RY,RZ",
                   help="the TCP in the flange frame (metres, rotation vector in radians) the targets are "
                        "poses of; a program's own set_tcp(p[...]) takes over from its line on. "
                        "Default: the flange (tool0)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON on stdout")
    p.add_argument("--force", action="store_true",
                   help="compensate with a model whose cross-validation did not show it better than the "
                        "nominal or the controller's model (better_than_nominal: false); refused without it")
    p.set_defaults(func=run)


def _is_program(path: str, text: str) -> bool:
    from hil.compensation.targets_csv import looks_like_csv

    if not text.strip():  # nothing to tell the kind by, and nothing to compensate (was exit 0)
        from hil.errors import InputError

        raise InputError(f"{path}: empty file; expected a CSV of poses (x,y,z,rx,ry,rz) or a URScript "
                         "program")
    suffix = os.path.splitext(path)[1].lower()
    if suffix in PROGRAM_SUFFIXES:
        return True
    if suffix in CSV_SUFFIXES:
        return False
    if looks_like_csv(text):
        return False
    first = next((line.strip() for line in text.splitlines() if line.strip()), "")
    fields = [f.strip() for f in first.split(",")]
    if len(fields) >= 2 and all(re.fullmatch(r"[A-Za-z_][A-Za-z0-9_ ]*", f) for f in fields):
        # a header of names, but not the pose columns: a CSV with a typo, not a program (which was
        # "compensated" with no targets, exit 0); neither kind is what the file says
        from hil.compensation.targets_csv import POSE_COLUMNS
        from hil.errors import InputError

        raise InputError(f"{path}: line 1 {first[:60]!r} is a CSV header without the pose columns "
                         f"{','.join(POSE_COLUMNS)}, and the file is no URScript program; expected a CSV "
                         "of poses with that header or a URScript program (.script)")
    return True


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from hil.arm.controller_model import ControllerCalibration
    from hil.calibration.model_file import load_geometry, refuse_worse_than_nominal
    from hil.cli.support.output_paths import campaign_store
    from hil.compensation.controller_source import PRIMARY_PORT, controller_from_arm, controller_from_file
    from hil.compensation.poses import parse_near, parse_tcp, to_vector
    from hil.compensation.solve import Compensator
    from hil.compensation.targets_csv import compensate_csv
    from hil.compensation.urscript import compensate_program
    from hil.errors import InputError
    from hil.files.inputs import check_text_lines, decode_input_text, read_input_bytes
    from hil.files.outputs import atomic_write_text, check_output

    db, where = campaign_store(None, args.config)
    check_output(args.out, field="--out", store=db, store_field=where,
                 inputs={"INPUT": args.input, "--model": args.model, "--controller": args.controller,
                         "--config": args.config})
    if os.path.splitext(args.input)[1].lower() == ".urp":
        raise InputError(f"{args.input}: a Polyscope .urp file is not a script: give the .script Polyscope "
                         "saves beside it")
    geometry, model_doc = load_geometry(args.model)
    forced = refuse_worse_than_nominal(model_doc, args.model, args.force, "compensate with")
    if forced is not None:
        sys.stderr.write(f"hil: warning: {forced}; compensating anyway (--force)\n")
    robot = geometry.robot
    spec = geometry.spec
    near = parse_near(args.near, spec.lower, spec.upper)
    tcp = parse_tcp(args.tcp)
    raw = read_input_bytes(args.input, "a CSV of poses or a URScript program")
    try:
        text = raw.decode("utf-8")  # a byte-order mark stays: the program is copied byte for byte
    except UnicodeDecodeError:
        text = decode_input_text(raw, args.input)  # raises, naming the file and the byte
    check_text_lines(text, args.input, "a CSV of poses or a URScript program")
    program = _is_program(args.input, text)
    if not program:  # a table over the row limit is refused before the controller is asked
        from hil.files.inputs import csv_rows

        csv_rows(text, args.input)

    if args.controller is not None:
        controller: ControllerCalibration = controller_from_file(args.controller, robot)
        source = args.controller
    else:
        from hil.station.config import load_config

        config = load_config(args.config)
        if config.robot["type"] != robot:
            raise InputError(f"{args.config}: robot.type is {config.robot['type']!r}, but the model "
                             f"{args.model} is of a {robot!r}")
        address = config.robot["address"]
        controller = controller_from_arm(address, robot, config.timeouts["connect"])
        source = f"{address}:{PRIMARY_PORT}"

    compensator = Compensator(geometry, controller.geometry(robot), tcp)
    if program:
        out_text, summary = compensate_program(text, args.input, compensator, near, joints=args.joints)
    else:
        out_text, summary = compensate_csv(text.lstrip("\ufeff"), args.input, compensator, near,
                                           joints=args.joints)
    atomic_write_text(args.out, out_text)
    what = "URScript program" if program else "CSV"
    wrote(args.out, f"{what}, {len(summary.moved)} targets compensated"
          + (f", {len(summary.not_compensated)} NOT compensated" if summary.not_compensated else ""))
    if args.json:
        doc = {"format": "hil-compensation/1", "output": args.out, "model": args.model, "robot": robot,
               "controller": source, "controller_calibration": controller.to_dict(),
               "tcp": [float(v) for v in to_vector(tcp)], "near": [float(v) for v in np.asarray(near)],
               **summary.as_dict()}
        print_json(doc)
    else:
        sys.stderr.write(summary.text())
    return EXIT_OK
