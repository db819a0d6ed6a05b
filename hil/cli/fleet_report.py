"""`hil fleet-report --out fleet.html` writes the plant's fleet report: one self-contained HTML file
with the fleet table, accuracy over time per robot, the distribution across the fleet, the stations
side by side and the robots whose geometry moved (`hil.report.fleet`).

Read-only on the store. Bad input (a missing store, an output path that is an input, the store or a
folder, a malformed ``--since``) is one line and exit 2, with nothing written.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import sys

from hil.cli.support.options import option
from hil.cli.support.store_options import add_store_options, open_store
from hil.jobs.outcome import EXIT_OK


def _day(text: str) -> float:
    """argparse ``type`` of ``--since``: a YYYY-MM-DD date, as the epoch time of its local midnight."""
    try:
        day = _dt.date.fromisoformat(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a date YYYY-MM-DD, got {text!r}") from None
    return _dt.datetime(day.year, day.month, day.day).timestamp()


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("fleet-report", help="write the fleet's HTML report (accuracy over time, stations)",
                       description="Write one self-contained HTML file about the fleet: each robot's "
                                   "last calibration and current model, accuracy over time per robot, "
                                   "the distribution across the fleet, the stations side by side, the "
                                   "robots whose geometry moved and the calibrations marked bad.")
    p.add_argument("--out", metavar="FILE", required=True, help="the HTML file to write")
    add_store_options(p, json=False)
    p.add_argument("--since", metavar="YYYY-MM-DD", type=_day,
                   help="only calibrations from this day on in the plots over time, the stations, the "
                        "geometry changes and the marks (the fleet table is always the fleet now)")
    p.add_argument("--sigmas", type=option("sigmas"), default=3.5, metavar="K",
                   help="a parameter changed when |Δ| > K·sqrt(σa² + σb²) "
                        "(default 3.5, `hil.store.fleet.DEFAULT_K`)")
    p.set_defaults(func=run_fleet_report)


def run_fleet_report(args: argparse.Namespace) -> int:
    from hil.cli.support.output_paths import campaign_store
    from hil.files.outputs import check_output

    db, field = campaign_store(args.db, args.config)
    check_output(args.out, field="--out", inputs={"--config": args.config}, store=db, store_field=field)
    from hil.report.fleet import fleet_data, write_fleet_report  # matplotlib: only when writing

    with open_store(args) as store:
        data = fleet_data(store, since=args.since, k=args.sigmas)
    write_fleet_report(data, args.out)
    print(f"wrote {args.out} ({len(data.robots)} robots, {len(data.calibrations)} calibrations)",
          file=sys.stderr)
    return EXIT_OK
