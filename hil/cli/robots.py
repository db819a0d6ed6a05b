"""`hil robots` lists a plant's fleet: every robot (by serial), its last (finished) calibration, the
result, its age, its station, which calibration's model is current, and under its row a calibration
in progress (running, or interrupted and resumable) (`hil.store.fleet`).

Read-only: a missing store, one that is not a hil store or an unknown ``--station`` is bad input (exit
2, one line).
"""

from __future__ import annotations

import argparse
import shutil
import sys
from typing import TYPE_CHECKING

from hil.cli.support.output import print_json
from hil.cli.support.store_options import add_store_options, clip, mm, open_store, when, where
from hil.jobs.outcome import EXIT_OK

if TYPE_CHECKING:
    from hil.store.fleet import RobotSummary

# CURRENT is "= last" when the last calibration is the current model, else the date of the one that is
# (its id is in --json and `hil robot SERIAL`). Each column is as wide as its widest cell; only on a
# terminal too narrow for that are the text columns cut to these widths (79 columns: the 80x24
# terminal), an ellipsis marking the cut. A pipe or a file gets every cell whole.
_HEAD = ("ROBOT", "TYPE", "LAST CALIB", "RESULT", "VAL mm", "AGE", "STATION", "CURRENT")
_NARROW = (12, 6, 10, 11, 7, 5, 11, 10)
_RIGHT = frozenset({4, 5})


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


def _in_progress(r: RobotSummary) -> str | None:
    """The robot's calibration in progress, said under its row: a running one, or a resumable one."""
    if r.in_progress is None:
        return None
    state = r.in_progress_status or "?"
    words = f"{state} (resumable)" if state in ("interrupted", "failed") else state
    return (f"  in progress: {r.in_progress} {words}, started {when(r.in_progress_created)}"
            + (f" at {r.in_progress_station}" if r.in_progress_station else ""))


def _table(rows: list[tuple[str, ...]], width: int | None) -> list[str]:
    """`rows` under `_HEAD`, each column as wide as its widest cell; cut to `_NARROW` only when the
    table would not fit `width` columns (None: no limit, a pipe or a file)."""
    widths = [max(len(h), *(len(r[i]) for r in rows)) for i, h in enumerate(_HEAD)]
    if width is not None and sum(widths) + len(widths) - 1 > width:
        widths = [min(w, n) for w, n in zip(widths, _NARROW, strict=True)]
        rows = [tuple(clip(c, w) for c, w in zip(r, widths, strict=True)) for r in rows]

    def line(cells: tuple[str, ...]) -> str:
        return " ".join(c.rjust(w) if i in _RIGHT else c.ljust(w)
                        for i, (c, w) in enumerate(zip(cells, widths, strict=True))).rstrip()

    return [line(_HEAD), *(line(r) for r in rows)]


def _terminal_width() -> int | None:
    """Columns of the terminal stdout is, None when it is a pipe or a file."""
    return shutil.get_terminal_size().columns if sys.stdout.isatty() else None


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
    cells = [(r.serial, r.type, when(r.last_created), _result(r.status, r.marked_bad), mm(r.after_rms),
              "-" if r.age_days is None else f"{int(r.age_days)}d", r.station or "-", _current(r))
             for r in rows]
    width = _terminal_width()
    head, *lines = _table(cells, width)
    print(head)
    for r, line in zip(rows, lines, strict=True):
        print(line)
        going = _in_progress(r)
        if going is not None:
            print(going if width is None else clip(going, width - 1))
    without = sum(1 for r in rows if r.current is None)
    going = sum(1 for r in rows if r.in_progress is not None)
    print(f"{len(rows)} robot{'' if len(rows) == 1 else 's'}"
          + (f", {without} without a usable calibration" if without else "")
          + (f", {going} with a calibration in progress" if going else "")
          + "; VAL = validation RMS after calibration")
    return EXIT_OK
