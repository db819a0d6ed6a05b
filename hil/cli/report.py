"""`hil report`: rebuild the HTML report of a campaign from its saved result file.

A report is written at the end of every campaign; this command regenerates it later (a lost file, a
newer report layout) from the ``hil-result/1`` JSON alone, so the result file is the only thing an
archive must keep.
"""

from __future__ import annotations

import argparse

from hil.calibration.model_file import read_json
from hil.cli._common import wrote
from hil.files.outputs import check_output
from hil.report import report_data_from_result, write_report


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("report", help="write the HTML report of a saved calibration result",
                       description="Rebuild the self-contained HTML report of a campaign from its "
                                   "result JSON (hil calibrate --out). Results without per-pose data "
                                   "give a report without the per-pose plots.")
    p.add_argument("--result", required=True, metavar="result.json",
                   help="the campaign's result (hil calibrate --out)")
    p.add_argument("--out", required=True, metavar="report.html", help="HTML file to write")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from hil.cli.output_paths import campaign_store

    db, where = campaign_store()
    check_output(args.out, field="--out", inputs={"--result": args.result}, store=db, store_field=where)
    data = report_data_from_result(read_json(args.result), source=args.result)
    write_report(data, args.out)
    wrote(args.out, "PASS" if data.passed else "FAIL")
    return 0
