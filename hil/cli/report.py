"""`hil report`: rebuild the HTML report of a campaign from its saved result file.

A report is written at the end of every campaign; this command regenerates it later (a lost file, a
newer report layout) from the result JSON alone, so the result file is the only thing an archive must
keep: a calibration's ``hil-result/1`` (``hil calibrate --out``; with ``--verify``, its pose test
too) gives the calibration report, a verification's ``hil-verification/1`` (``hil verify --out``) the
pose test's report, the page ``hil verify --report`` writes.
"""

from __future__ import annotations

import argparse
import contextlib
from collections.abc import Iterator
from typing import Any

from hil.cli.support.options import JSON_FILE
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
    p.add_argument("--result", required=True, metavar="result.json", type=JSON_FILE,
                   help="the campaign's result (hil calibrate --out or hil verify --out)")
    p.add_argument("--out", required=True, metavar="report.html", help="HTML file to write")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hil.cli.support.output_paths import campaign_store

    db, where = campaign_store()
    check_output(args.out, field="--out", inputs={"--result": args.result}, store=db, store_field=where)
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
