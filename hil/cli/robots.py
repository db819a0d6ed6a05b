"""`hil robots` lists a plant's fleet: every robot (by serial), its last calibration, the result, its
age, its station, and which calibration's model is current (`hil.store.fleet`).

Read-only: a missing store, one that is not a hil store or an unknown ``--station`` is bad input (exit
2, one line).
"""

from __future__ import annotations

import argparse
import sys
from typing import TYPE_CHECKING

from hil.cli.support.output import print_json
from hil.cli.support.store_options import add_store_options, clip, mm, open_store, when, where
from hil.jobs.outcome import EXIT_OK

if TYPE_CHECKING:
    from hil.store.fleet import RobotSummary

# 79 columns: the 80x24 terminal. CURRENT is "= last" when the last calibration is the current model,
# else the date of the one that is (its id is in --json and `hil robot SERIAL`).
_ROW = "{:<12} {:<6} {:<10} {:<11} {:>7} {:>5} {:<11} {}"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("robots", help="list the fleet: robots, last calibrations, current models",
                       description="List every robot (by serial) with its last calibration (date, "
                                   "result, validation RMS after calibration, age in days, station) and "
                                   "which calibration's model is current: its newest accepted one not "
                                   "marked bad.")
    add_store_options(p)
    p.add_argument("--station", metavar="NAME",
                   help="only the robots whose last calibration ran at this station")
    p.set_defaults(func=run_robots)


def _result(status: str | None, marked_bad: bool) -> str:
    if status is None:
        return "-"
    return "marked bad" if marked_bad else status


def _current(r: RobotSummary) -> str:
    if r.current is None:
        return "none"
    return "= last" if r.current == r.last else when(r.current_created)


def run_robots(args: argparse.Namespace) -> int:
    from hil.store.fleet import fleet

    with open_store(args) as store:
        rows = fleet(store, station=args.station)
        location = store.location
        shown = where(store)
    if args.json:
        print_json({"database": location, "robots": [r.as_dict() for r in rows]})
        return EXIT_OK
    print(f"database: {shown}", file=sys.stderr)
    if not rows:
        print(f"no robots in {location}" + (f" last calibrated at {args.station}" if args.station else ""))
        return EXIT_OK
    print(_ROW.format("ROBOT", "TYPE", "LAST CALIB", "RESULT", "VAL mm", "AGE", "STATION", "CURRENT"))
    for r in rows:
        age = "-" if r.age_days is None else f"{int(r.age_days)}d"
        print(_ROW.format(clip(r.serial, 12), clip(r.type, 6), when(r.last_created),
                          clip(_result(r.status, r.marked_bad), 11), mm(r.after_rms), age,
                          clip(r.station or "-", 11), _current(r)).rstrip())
    without = sum(1 for r in rows if r.current is None)
    print(f"{len(rows)} robots" + (f", {without} without a usable calibration" if without else "")
          + "; VAL = validation RMS after calibration")
    return EXIT_OK
