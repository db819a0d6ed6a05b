"""`hil report`: rebuild the HTML report of a campaign from its saved result file.

A report is written at the end of every campaign; this command regenerates it later (a lost file, a
newer report layout) from the result JSON alone, so the result file is the only thing an archive must
keep: a calibration's ``hil-result/1`` (``hil calibrate --out``; with ``--verify``, its pose test
too) gives the calibration report, a verification's ``hil-verification/1`` (``hil verify --out``) the
pose test's report, the page ``hil verify --report`` writes.

An arm no campaign drives (any serial arm from its URDF) has only ``hil identify``'s model: ``--model``
renders the same report from it (`hil.report.model_report`), with its calibration and held-out
measurements when given (per-pose figures), else from the model's own cross-validation.
"""

from __future__ import annotations

import argparse
import contextlib
from collections.abc import Iterator
from typing import Any

from hil.cli.support.options import (
    CSV_FILE,
    JSON_FILE,
    RMS_THRESHOLD_HELP,
    add_joint_units,
    rms_threshold,
)
from hil.cli.support.output import wrote
from hil.errors import InputError
from hil.files.outputs import check_output
from hil.jobs.outcome import EXIT_OK

#: `hil.verify.result.FORMAT`, the ``hil verify --out`` document (not imported: the verification's
#: kinematics are not needed to tell it).
VERIFICATION_FORMAT = "hil-verification/1"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("report", help="write the HTML report of a saved calibration or verification result",
                       description="Rebuild the self-contained HTML report of a campaign from its "
                                   "result JSON (hil calibrate --out, or hil verify --out for the ISO 9283 "
                                   "pose test's report). Results without per-pose data give a report "
                                   "without the per-pose plots.")
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--result", metavar="result.json", type=JSON_FILE,
                        help="the campaign's result (hil calibrate --out or hil verify --out)")
    source.add_argument("--model", metavar="model.json", type=JSON_FILE,
                        help="an identification's model instead (hil identify --out): the report of an "
                             "arm no campaign drives, e.g. one from its URDF (the model carries it)")
    p.add_argument("--measurements", metavar="M.csv", type=CSV_FILE,
                   help="with --model: the measurements it was fitted to (per-pose residuals)")
    p.add_argument("--validation", metavar="V.csv", type=CSV_FILE,
                   help="with --model: held-out measurements (default: the model's cross-validation)")
    add_joint_units(p)
    p.add_argument("--max-rms", type=rms_threshold, metavar="METRES",
                   help=f"with --model: acceptance threshold on the validation RMS, {RMS_THRESHOLD_HELP} "
                        "(default: the campaign's automatic verdict)")
    p.add_argument("--out", required=True, metavar="report.html", help="HTML file to write")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hil.cli.support.output_paths import campaign_store

    if args.result is not None:
        for option in ("measurements", "validation", "max_rms"):
            if getattr(args, option) is not None:
                raise InputError(f"--{option.replace('_', '-')}: only with --model (a campaign's result "
                                 "holds its own measurements and verdict)")
    db, where = campaign_store()
    inputs = {name: path for name, path in (("--result", args.result), ("--model", args.model),
                                            ("--measurements", args.measurements),
                                            ("--validation", args.validation)) if path is not None}
    check_output(args.out, field="--out", inputs=inputs, store=db, store_field=where)
    if args.model is not None:
        return _model(args)
    # the report's libraries (matplotlib, the kinematics) load only now, not when the command line is
    # read: a --result that is no file, or an --out that cannot be written, is refused before them
    from hil.calibration.model_file import read_json
    from hil.report import report_data_from_result, write_report
    doc = read_json(args.result)
    if doc.get("format") == VERIFICATION_FORMAT:
        return _verification(doc, args)
    data = report_data_from_result(doc, source=args.result)
    with _malformed(args.result):
        write_report(data, args.out)
    wrote(args.out, "PASS" if data.passed else "FAIL")
    return EXIT_OK


def _model(args: argparse.Namespace) -> int:
    """An identification's model: its report through a result-shaped document
    (`hil.report.model_report`)."""
    from hil.calibration.measurements import read_measurements
    from hil.calibration.model_file import MODEL_FORMAT, load_geometry
    from hil.report import report_data_from_result, write_report
    from hil.report.model_report import result_from_model

    geometry, doc = load_geometry(args.model, formats=(MODEL_FORMAT,))

    def measurements(path: str | None) -> Any:
        return None if path is None else read_measurements(path, args.joint_units, chain=geometry.chain)

    result = result_from_model(doc, args.model, calibration=measurements(args.measurements),
                               validation=measurements(args.validation), accept_rms=args.max_rms)
    data = report_data_from_result(result, source=args.model)
    with _malformed(args.model):
        write_report(data, args.out)
    wrote(args.out, "PASS" if data.passed else "FAIL")
    return EXIT_OK


def _verification(doc: dict[str, Any], args: argparse.Namespace) -> int:
    """A ``hil-verification/1`` result: the pose test's own report, as ``hil verify --report`` writes it."""
    from hil.report.data import check_verification
    from hil.report.verification import write_verification_report

    check_verification(doc, args.result)
    with _malformed(args.result):
        write_verification_report(doc, args.out)
    wrote(args.out, "ISO 9283 pose test")
    return EXIT_OK


@contextlib.contextmanager
def _malformed(source: str) -> Iterator[None]:
    """What the checks before rendering did not catch (a vector that is a string, a block that is a
    list) is bad input naming the file, never a traceback."""
    try:
        yield
    except (KeyError, TypeError, ValueError, AttributeError, IndexError) as exc:
        raise InputError(f"{source}: malformed result ({type(exc).__name__}: {exc})") from None
