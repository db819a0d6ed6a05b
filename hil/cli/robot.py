"""`hil robot SERIAL` shows one robot's calibration history: accuracy before and after each calibration,
its parameter changes beyond uncertainty between consecutive good calibrations (a robot whose geometry
moved was hit or repaired), which model is current; it marks a calibration bad (or good again) and
exports the current model (`hil.store.fleet`).

Bad input is one line and exit 2, with nothing written: an unknown serial or campaign, a campaign of
another robot, a mark without a reason, an export path that is an input or the store.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from hil.cli.support.export_formats import FORMATS
from hil.cli.support.options import option
from hil.cli.support.output import print_json
from hil.cli.support.store_options import add_store_options, clip, mm, open_store, when, where
from hil.errors import InputError
from hil.jobs.outcome import EXIT_OK

if TYPE_CHECKING:
    from hil.store import Store
    from hil.store.fleet import Calibration, GeometryComparison, RobotHistory
    from hil.store.sqlite_reader import SqliteReader

# File suffixes that say which export format is meant when --format is not given (as `hil show`).
_SUFFIX_FORMATS = {".urdf": "urdf", ".xml": "urdf", ".yaml": "ros-kinematics", ".yml": "ros-kinematics",
                   ".json": "json"}

# 79 columns: a marker (* current model, x marked bad), the campaign, where and when, its status, the
# validation RMS before and after calibration and the max after (mm).
_ROW = "{:1} {:<20} {:<10} {:<10} {:<11} {:>6} {:>6} {:>6}"
_KEY = "  {:<20} {}"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("robot", help="one robot's history; mark a calibration bad or good",
                       description="One robot's calibrations (validation RMS before and after each), "
                                   "parameter changes beyond uncertainty between consecutive good "
                                   "calibrations, and which model is current (its newest accepted "
                                   "calibration not marked bad). ID is a campaign id, a unique prefix of "
                                   "one, or 'last' (this robot's newest).")
    p.add_argument("serial", metavar="SERIAL", help="the robot's serial number (see hil robots)")
    add_store_options(p)
    marks = p.add_mutually_exclusive_group()
    marks.add_argument("--mark-bad", metavar="ID",
                       help="mark this calibration bad: its model is no longer used (needs --reason)")
    marks.add_argument("--mark-good", metavar="ID",
                       help="mark this calibration good again (needs --reason)")
    p.add_argument("--reason", metavar="TEXT", help="why the calibration is marked bad or good")
    p.add_argument("--export-model", metavar="FILE", help="write the robot's current model")
    p.add_argument("--format", choices=FORMATS,
                   help="export format (default: from FILE's suffix, else json)")
    p.add_argument("--sigmas", type=option("sigmas"), default=3.5, metavar="K",
                   help="a parameter changed when |Δ| > K·sqrt(σa² + σb²) "
                        "(default 3.5, `hil.store.fleet.DEFAULT_K`)")
    p.set_defaults(func=run_robot)


def _marking(args: argparse.Namespace) -> str | None:
    """The campaign --mark-bad or --mark-good names, None without either."""
    return args.mark_bad if args.mark_bad is not None else args.mark_good


def _check(args: argparse.Namespace) -> None:
    """Bad combinations of options, before the store is opened."""
    marking = _marking(args)
    option = "--mark-bad" if args.mark_bad is not None else "--mark-good"
    if args.reason is not None and marking is None:
        raise InputError("--reason: only with --mark-bad or --mark-good")
    if marking is not None and not marking.strip():
        raise InputError(f"{option}: empty campaign id (give an id, a unique prefix of one, or 'last')")
    if marking is not None and not (args.reason or "").strip():
        raise InputError(f"{option}: needs --reason TEXT saying why (it is kept with the mark)")
    if args.format and not args.export_model:
        raise InputError("--format: only with --export-model")
    if args.export_model is not None:
        from hil.cli.support.output_paths import campaign_store
        from hil.files.outputs import check_output

        db, field = campaign_store(args.db, args.config)
        check_output(args.export_model, field="--export-model", inputs={"--config": args.config},
                     store=db, store_field=field)


def _resolve(store: Store, history: RobotHistory, text: str) -> str:
    """The campaign `text` names among this robot's: 'last' is its newest, else an id or a unique
    prefix; a campaign of another robot, or none, is bad input."""
    mine = [c.id for c in history.calibrations]
    serial = history.robot.serial
    if text in ("last", "latest"):
        if not mine:
            raise InputError(f"robot {serial} has no calibrations yet")
        return mine[-1]
    matches = [cid for cid in mine if cid == text] or [cid for cid in mine if cid.startswith(text)]
    if len(matches) == 1:
        return matches[0]
    if len(matches) > 1:
        raise InputError(f"{text!r} matches several calibrations of robot {serial} "
                         f"({', '.join(matches[:5])}{', ...' if len(matches) > 5 else ''})")
    cid = store.resolve_id(text)  # UnknownCampaignError (exit 2) if no campaign at all
    other = store.campaign(cid).robot.serial
    raise InputError(f"campaign {cid} is not robot {serial}'s: it calibrated "
                     + (f"robot {other}" if other else "a robot whose serial was not read"))


def _export_format(args: argparse.Namespace) -> str:
    if args.format:
        return str(args.format)
    return _SUFFIX_FORMATS.get(Path(args.export_model).suffix.lower(), "json")


def _export(args: argparse.Namespace, store: Store | SqliteReader, history: RobotHistory) -> str:
    from hil.arm.geometry import Geometry  # pinocchio: only when exporting
    from hil.calibration.exports import export
    from hil.files.outputs import atomic_write_text
    from hil.store.fleet import current_model

    current = current_model(store, history.robot.serial)
    if current is None:
        raise InputError(f"robot {history.robot.serial}: has no current model (no accepted calibration "
                         "that is not marked bad)")
    cid, doc = current
    source = f"campaign {cid}"
    geometry = Geometry.from_dict(doc, source=source)
    atomic_write_text(args.export_model, export(doc, geometry, _export_format(args), source=source))
    return cid


def _factory(controller: dict[str, Any] | None) -> list[str]:
    """The controller's factory calibration: the largest delta of each DH column."""
    if controller is None:
        return ["not read"]
    bits = []
    for key, name, unit in (("delta_theta", "θ", "mrad"), ("delta_a", "a", "mm"), ("delta_d", "d", "mm"),
                            ("delta_alpha", "α", "mrad")):
        values = controller.get(key)
        if isinstance(values, list) and values and all(isinstance(v, int | float) for v in values):
            bits.append(f"{name} {max(abs(v) for v in values) * 1e3:.3f} {unit}")
    if not bits:
        return ["read from the controller: " + (", ".join(sorted(controller)) or "empty")]
    return ["read from the controller, largest deltas:", ", ".join(bits)]


def _change_text(change: Any) -> str:
    unit, scale = ("mrad", 1e3) if change.angular else ("mm", 1e3)
    return (f"{change.name} {change.delta * scale:+.3f} {unit} "
            f"(±{change.sigma * scale:.3f}, {change.ratio:.0f}σ)")


def _comparison_lines(c: GeometryComparison) -> list[str]:
    head = f"  {c.before} -> {c.after}  "
    if not c.changes:
        return [head + f"no change ({c.compared} parameters)"]
    return [head + "MOVED"] + [f"      {_change_text(ch)}" for ch in c.changes]


def _marker(c: Calibration, current: str | None) -> str:
    return "*" if c.id == current else "x" if c.marked_bad else ""


def _text(history: RobotHistory) -> list[str]:
    r = history.robot
    extra = ", ".join(x for x in (r.model, f"software {r.software}" if r.software else "") if x)
    n = len(history.calibrations)
    lines = [f"robot {r.serial}: {r.type}" + (f" ({extra})" if extra else ""),
             _KEY.format("first seen", f"{when(r.first_seen)}, {n} calibration{'s' if n != 1 else ''}")]
    factory = _factory(r.controller)
    lines += [_KEY.format("factory calibration" if i == 0 else "", text) for i, text in enumerate(factory)]
    current = history.calibration(history.current) if history.current else None
    if current is not None:
        lines.append(_KEY.format("current model", f"campaign {current.id} ({when(current.created)}, "
                                                  f"{clip(current.station, 12)})"))
    else:
        lines.append(_KEY.format("current model", "none (no accepted calibration not marked bad)"))
    if not history.calibrations:
        return lines
    lines += ["", _ROW.format("", "CAMPAIGN", "DATE", "STATION", "STATUS", "BEFORE", "AFTER", "MAX")]
    for c in history.calibrations:
        lines.append(_ROW.format(_marker(c, history.current), c.id, when(c.created), clip(c.station, 10),
                                 clip(c.status, 11), mm(c.before_rms), mm(c.after_rms), mm(c.after_max)))
    lines.append("  mm, validation on held-out poses: RMS before and after calibration, max after")
    lines.append("  * current model, x marked bad")
    marked = [c for c in history.calibrations if c.mark is not None]
    if marked:
        lines += ["", "marks (the latest of each calibration):"]
        for c in marked:
            m = c.mark
            assert m is not None
            lines.append(f"  {c.id} {'bad' if m.bad else 'good'} {when(m.t, '%Y-%m-%d %H:%M')} by {m.who}: "
                         + " ".join(m.reason.split()))
    if history.verifications:
        lines += ["", "verifications (ISO 9283 pose test, worst pose of P1-P5, mm):",
                  f"  {'CAMPAIGN':<22}{'DATE':<18}{'STATUS':<12}{'AP UNCOMP':>10}{'AP COMP':>9}{'RP':>7}"]
        for v in history.verifications:
            rp = max(v.rp_max.values()) if v.rp_max else None
            lines.append(f"  {v.id:<22}{when(v.created):<18}{clip(v.status, 11):<12}"
                         f"{mm(v.ap_max.get('uncompensated')):>10}{mm(v.ap_max.get('compensated')):>9}"
                         f"{mm(rp):>7}")
    k = history.comparisons[0].k if history.comparisons else None
    lines += ["", "geometry between good calibrations"
              + (f" (moved: |Δ| > {k:g}·sqrt(σa² + σb²)):" if k is not None else ":")]
    if not history.comparisons:
        lines.append("  fewer than two good calibrations: nothing to compare")
    for c in history.comparisons:
        lines += _comparison_lines(c)
    return lines


def run_robot(args: argparse.Namespace) -> int:
    from hil.store.fleet import mark, robot_history

    _check(args)
    marking = _marking(args)
    marked = exported = None
    with open_store(args, readonly=marking is None) as store:
        history = robot_history(store, args.serial, k=args.sigmas)
        if marking is not None:
            cid = _resolve(store, history, marking.strip())
            marked = mark(store, cid, bad=args.mark_bad is not None, reason=args.reason)
            history = robot_history(store, args.serial, k=args.sigmas)
        if args.export_model:
            exported = _export(args, store, history)
        shown, location = where(store), store.location
    if marked is not None:
        print(f"marked campaign {marked.campaign} {'bad' if marked.bad else 'good'}: "
              + (f"the current model is now campaign {history.current}'s" if history.current
                 else "the robot has no current model now"), file=sys.stderr)
    if args.json:
        doc: dict[str, Any] = {"database": location, **history.as_dict(),
                               "moved": [c.as_dict() for c in history.moved]}
        if marked is not None:
            doc["marked"] = marked.as_dict()
        print_json(doc)
    else:
        print(f"database: {shown}", file=sys.stderr)
        for line in _text(history):
            print(line)
    if exported is not None:
        print(f"wrote {os.fspath(args.export_model)} (current model: campaign {exported})", file=sys.stderr)
    return EXIT_OK

