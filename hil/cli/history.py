"""`hil history` lists the campaigns in the store; `hil show ID` prints one and exports its results.

Both read the database the campaign engine writes (``--db``, else ``HIL_DB``, else the config's
``store.path``, else the user's data directory). They never create a database: a missing file, a
file that is not a hil store, or an unknown campaign id is bad input (exit 2, one line).
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from collections import Counter
from typing import TYPE_CHECKING, Any

from hil.cli.support.export_formats import FORMATS, format_of
from hil.cli.support.options import TOML_FILE, option
from hil.cli.support.output import mm, print_json
from hil.errors import InputError
from hil.jobs.outcome import EXIT_OK
from hil.store.records import INTERRUPTED, ROLES

if TYPE_CHECKING:  # the Store (SQLAlchemy) is imported when a command opens it, not for its --help
    from hil.store import CampaignRecord, CampaignSummary, Store
    from hil.store.sqlite_reader import SqliteReader


def _add_db_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--db", metavar="LOCATION", help="the store: an SQLite file or a postgresql:// URL "
                                                    "(default: $HIL_DB, the config's store.url or "
                                                    "store.path, or the user's data directory)")
    p.add_argument("--config", metavar="station.toml", type=TOML_FILE,
                   help="take the database location from it")
    p.add_argument("--json", action="store_true", help="print JSON on stdout")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("history", help="list calibration campaigns",
                       description="List the campaigns in the store, newest first.")
    _add_db_options(p)
    p.add_argument("--limit", type=option("listed rows"), default=20, metavar="N",
                   help="at most N campaigns (default 20)")  # beyond SQLite's integers: exit 70 before
    p.add_argument("--station", metavar="NAME", help="only this station's campaigns")
    p.set_defaults(func=run_history)

    s = sub.add_parser("show", help="print one campaign; export its model or measurements",
                       description="Print a campaign (configuration, poses, model fit, validation, "
                                   "events). ID is a campaign id, a unique prefix of one, or 'last'.")
    s.add_argument("id", metavar="ID",
                   help="campaign id (from hil history), a unique prefix of one, or 'last'")
    _add_db_options(s)
    s.add_argument("--export-model", metavar="FILE", help="write the campaign's calibrated model")
    s.add_argument("--format", choices=FORMATS,
                   help="export format (default: from FILE's suffix, else json)")
    s.add_argument("--export-measurements", metavar="FILE",
                   help="write the measurements CSV (q1..q6,x,y,z) of --role poses")
    s.add_argument("--role", choices=ROLES, default="calibration",
                   help="poses for --export-measurements (default calibration)")
    s.set_defaults(func=run_show)


def _open(args: argparse.Namespace) -> Store | SqliteReader:
    """The store, read-only (read-only media too); a station's SQLite file through sqlite3 alone
    (`hil.cli.support.store_options.open_location`)."""
    from hil.cli.support.store_options import open_location

    config = None
    if args.config:
        from hil.station.config import load_config

        config = load_config(args.config)
    return open_location(args.db, config)


def _when(t: float | None, fmt: str = "%Y-%m-%d %H:%M") -> str:
    return "-" if t is None else time.strftime(fmt, time.localtime(t))


def _mm(value: float | None) -> str:
    return "-" if value is None else mm(value)


# 78 columns: fits the 80x24 terminal. The id already says when (and in which year) the campaign was
# created, so the table shows the last activity instead, without the year: the status needs the room.
_ROW = "{:<20} {:<11} {:<10} {:<5} {:<11} {:>7} {:>8}"

# Below the table when it lists an interrupted campaign: what that status means.
_INTERRUPTED_NOTE = (f"{INTERRUPTED} (resumable): re-run the same `hil calibrate` command to continue "
                     "it")


def _status(c: CampaignSummary) -> str:
    """The status as `hil show` prints it: an interrupted campaign says it can be resumed."""
    return f"{c.status} (resumable)" if c.status == INTERRUPTED else c.status


def _history_line(c: CampaignSummary) -> str:
    rms = "-" if c.validation_rms is None else f"{c.validation_rms * 1e3:.3f}"
    # a finished verification (ISO 9283 test, no model) reads "verified", not "accepted"
    status = "verified" if c.kind == "verification" and c.status == "accepted" else c.status
    return _ROW.format(c.id, _when(c.updated, "%m-%d %H:%M"), c.station[:10], c.robot[:5],
                       status[:11], f"{c.measured}/{c.planned}", rms)


def run_history(args: argparse.Namespace) -> int:
    if args.limit < 1:
        raise InputError(f"--limit: must be at least 1, got {args.limit}")
    with _open(args) as store:
        rows = store.campaigns(args.limit, station=args.station)
        where = store.location
    if args.json:
        print_json({"database": where, "campaigns": [r.as_dict() for r in rows]})
        return EXIT_OK
    shown = os.path.abspath(store.path) if store.path is not None else where
    print(f"database: {shown}", file=sys.stderr)  # which store (stdout: the table)
    if not rows:
        print(f"no campaigns in {where}")
        return EXIT_OK
    print(_ROW.format("ID", "UPDATED", "STATION", "ROBOT", "STATUS", "POSES", "VAL [mm]"))
    for r in rows:
        print(_history_line(r))
    if any(r.status == INTERRUPTED for r in rows):
        print(_INTERRUPTED_NOTE)
    return EXIT_OK


def _export(args: argparse.Namespace, store: Store | SqliteReader, rec: CampaignRecord) -> list[str]:
    """Write what ``--export-model`` and ``--export-measurements`` ask for: their libraries (numpy,
    pinocchio) are imported only then, so that showing a campaign does not pay for them."""
    written: list[str] = []
    if not (args.export_model or args.export_measurements):
        return written
    from hil.arm.geometry import Geometry
    from hil.calibration.exports import export
    from hil.calibration.measurements import write_measurements
    from hil.files.outputs import atomic_write_text

    if args.export_model:
        if rec.model is None:
            raise InputError(f"campaign {rec.id}: has no calibrated model yet (status {rec.summary.status})")
        source = f"campaign {rec.id}"
        geometry = Geometry.from_dict(rec.model.doc, source=source)
        fmt = format_of(args.export_model, args.format)
        atomic_write_text(args.export_model, export(rec.model.doc, geometry, fmt, source=source))
        written.append(args.export_model)
    if args.export_measurements:
        q, p = store.arrays(rec.id, args.role)
        if len(q) == 0:
            raise InputError(f"campaign {rec.id}: has no {args.role} measurements")
        write_measurements(args.export_measurements, q, p)
        written.append(args.export_measurements)
    return written


def _show_text(rec: CampaignRecord) -> list[str]:
    s = rec.summary
    roles = Counter(p.role for p in rec.poses)
    pending = sum(1 for p in rec.poses if p.status == "planned")
    robot = rec.robot
    ident = f"serial {robot.serial}" if robot.serial else "serial unknown"
    extra = ", ".join(x for x in (robot.model, f"software {robot.software}" if robot.software else "")
                      if x)
    lines = [
        f"campaign {s.id}: {_status(s)}" + (f" — {rec.detail}" if rec.detail else ""),
        f"  station     {s.station}",
        f"  robot       {s.robot}, {ident}" + (f" ({extra})" if extra else ""),
        f"  created     {_when(s.created)}  (updated {_when(s.updated)}, hil {rec.software or '?'})",
        f"  config      sha256 {rec.config_hash[:12]}",
    ]
    if rec.plan:
        shown = {k: rec.plan[k] for k in ("method", "index", "value", "bound") if k in rec.plan}
        if shown:
            lines.append("  plan        " + ", ".join(f"{k} {v}" for k, v in shown.items()))
    lines.append("  poses       " + (", ".join(f"{roles[r]} {r}" for r in ROLES if roles[r]) or "none")
                 + f"; {s.measured} measured, {s.skipped} skipped, {pending} pending")
    lines.append(f"  points      {len(rec.measurements)} recorded")
    model = rec.model
    if model is not None:
        fit: dict[str, Any] = model.doc.get("fit") or {}
        params = model.doc.get("parameters")
        bits = [f"RMS {_mm(fit.get('rms'))}", f"max {_mm(fit.get('max'))}"]
        if isinstance(params, list):
            bits.append(f"{len(params)} parameters")
        if fit.get("iterations") is not None:
            bits.append(f"{fit['iterations']} iterations")
        if isinstance(fit.get("rejected"), list):
            bits.append(f"{len(fit['rejected'])} rejected")
        lines.append("  model fit   " + ", ".join(bits)
                     + (f" ({len(rec.models)} models, latest shown)" if len(rec.models) > 1 else ""))
    else:
        lines.append("  model       none yet")
    v = rec.validation
    if v is not None:
        lines.append(f"  validation  RMS {_mm(v.before.get('rms'))} before -> {_mm(v.after.get('rms'))} "
                     f"after (max {_mm(v.after.get('max'))}, {v.after.get('count', '?')} poses): "
                     + ("passed" if v.passed else "NOT passed"))
    else:
        lines.append("  validation  none yet")
    if rec.event_counts:
        lines.append(f"  events      {sum(rec.event_counts.values())}: "
                     + ", ".join(f"{k} {n}" for k, n in rec.event_counts.items()))
    return lines


def _check_exports(args: argparse.Namespace) -> None:
    """Refuse export paths that are the store, the config, a directory or each other, before the store
    is opened: a rename onto the database would replace it with the export."""
    if not (args.export_model or args.export_measurements):
        return
    from hil.cli.support.output_paths import campaign_store
    from hil.files.outputs import check_output

    db, where = campaign_store(args.db, args.config)
    inputs = {"--config": args.config}
    if args.export_model:
        check_output(args.export_model, field="--export-model", inputs=inputs, store=db, store_field=where)
    if args.export_measurements:
        check_output(args.export_measurements, field="--export-measurements", inputs=inputs, store=db,
                     store_field=where, outputs={"--export-model": args.export_model})


def run_show(args: argparse.Namespace) -> int:
    if args.format and not args.export_model:
        raise InputError("--format: only with --export-model")
    _check_exports(args)
    with _open(args) as store:
        rec = store.campaign(store.resolve_id(args.id))
        written = _export(args, store, rec)
    if args.json:
        print_json(rec.as_dict() | {"database": store.location})
    else:
        for line in _show_text(rec):
            print(line)
    for path in written:
        print(f"wrote {os.fspath(path)}", file=sys.stderr)
    return EXIT_OK
