"""The campaign report as ONE self-contained HTML file.

A report is archived with the robot and opened years later, offline, on whatever machine is at
hand, or printed and signed: so it carries everything inside (plots as base64 PNG ``data:`` URIs,
inline CSS, no script, no font or stylesheet links) and prints cleanly (figures and tables are not
split across pages, colours are kept). Every piece of text that came from outside (station name,
config values, event messages…) is HTML-escaped. The markup is also well-formed XML (void elements
self-closed, only XML's five entities), so it can be checked and post-processed with XML tools.

Built with the standard library (`html.escape` and f-strings; the blocks every page shares are in
`hil.report.html`) — a template engine would be one more dependency for a single page.
"""

from __future__ import annotations

import datetime as _dt
import math
import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from hil import __version__
from hil.calibration.validation_precision import describe_precision
from hil.files.outputs import atomic_write_text
from hil.report.data import ErrorSet, ReportData
from hil.report.html import CSS, esc, fmt_mm, fmt_num
from hil.report.html import figure as _figure
from hil.report.html import finite as _finite
from hil.report.html import kv as _kv
from hil.report.html import section as _section
from hil.report.html import table as _table
from hil.report.plots import drift_plot, errors_per_pose, histograms, per_axis
from hil.report.pose_test import calibration_section  # the pose test of hil calibrate --verify

_ANGLE_SUFFIXES = (".rx", ".ry", ".rz")
#: What "before calibration" is, wherever the report shows it (tables, plots, summary).
BEFORE_MEANS = "nominal arm, only the tracker pose and SMR fitted"
#: What the controller's row is: the model the arm moves with, judged as "before" is.
CONTROLLER_MEANS = "the controller's own model (its factory calibration), tracker pose and SMR fitted for it"


def parameter_unit(name: str) -> tuple[str, float]:
    """Display unit and scale of an identification parameter: rotations in mrad, lengths in mm,
    joint compliances in µrad/Nm (a cobot's strain-wave joint is a few µrad per newton-metre)."""
    if name.startswith("compliance."):
        return ("µrad/Nm", 1e6)
    return ("mrad", 1e3) if name.endswith(_ANGLE_SUFFIXES) else ("mm", 1e3)


def _config_value(v: Any) -> str:
    if v is None:
        return "—"
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return format(v, "g")
    if isinstance(v, list | tuple):
        return ", ".join(_config_value(x) for x in v)
    return str(v)


def _header(d: ReportData, generated: str) -> str:
    verdict = "PASS" if d.passed else "FAIL"
    cmp = "≤" if d.passed else ">"
    robot = " ".join(x for x in (d.robot.type.upper(), d.robot.serial and f"serial {d.robot.serial}") if x)
    when = " → ".join(x for x in (d.started, d.finished) if x) or "—"
    return f"""<header>
<div class="title"><h1>Kinematic calibration report</h1>
<p class="sub">{esc(robot)} · station {esc(d.station or "—")} · campaign {esc(d.campaign or "—")}</p>
<p class="sub">{esc(when)}</p></div>
<div class="verdict {verdict.lower()}"><div class="big">{verdict}</div>
<div>validation RMS {esc(fmt_mm(d.validation_after.rms))} {cmp} acceptance {esc(fmt_mm(d.accept_rms))}</div>
{_verdict_reason(d)}{_precision(d)}{_cross_validation(d)}{_drift_flag(d)}</div></header>
{_stopping(d)}
<p class="generated">Generated {esc(generated)} by hil {esc(__version__)}.</p>"""


def _verdict_reason(d: ReportData) -> str:
    """The verdict's own line (`hil.campaign.acceptance`) when it says more than the RMS line above:
    a model not better than nominal, or the automatic threshold's origin."""
    reason = (d.verdict or {}).get("reason")
    return f'<div class="reason">{esc(str(reason))}</div>\n' if reason else ""


def _cross_validation(d: ReportData) -> str:
    """The verdict box's line with the cross-validated held-out RMS of each model, and a warning when
    the calibrated model is not shown better than the nominal or the controller's."""
    block = d.cross_validation
    if block is None:
        return ""

    def rms(key: str) -> str:
        value = block.get(key)
        return fmt_mm(value.get("rms")) if isinstance(value, dict) else "—"

    text = (f"{block.get('folds')}-fold cross-validation (held-out RMS): calibrated {rms('calibrated')}, "
            f"nominal {rms('nominal')}"
            + (f", controller's model {rms('controller')}" if block.get("controller") else ""))
    if block.get("better_than_nominal") is False:
        return (f'<div><b>NOT BETTER THAN NOMINAL</b>: {esc(text)}; this model may make the arm worse '
                "(exports refuse it without --force)</div>\n")
    return f'<div class="cv">{esc(text)}</div>\n'


def _precision(d: ReportData) -> str:
    """The verdict box's line under the validation RMS: how precise that RMS is, under the design
    that chose the validation poses (none when the result does not say)."""
    text = describe_precision(d.validation_precision)
    return "" if text is None else f'<div class="precision">{esc(text)}</div>\n'


def _drift_flag(d: ReportData) -> str:
    """The verdict box's flag for a campaign whose reference drifted beyond its limit (the verdict
    itself stays the validation's)."""
    if not d.drift_flagged:
        return ""
    block = d.drift or {}
    return (f'<div><b>DRIFT FLAGGED</b>: reference moved {esc(_um(block.get("max")))} '
            f'(limit {esc(_um(block.get("limit")))})</div>')


def _stopping(d: ReportData) -> str:
    """One sentence under the header when the stopping rule was on: whether it stopped acquiring
    calibration poses, after how many, and on what prediction (the verdict is still validation's)."""
    block = d.stopping
    if block is None:
        return ""
    used, left = block.get("poses_used"), block.get("poses_left")
    predicted, target = block.get("predicted_rms"), block.get("target")
    if block.get("stopped"):
        text = (f"Acquisition stopped early: after {used} of {(used or 0) + (left or 0)} calibration poses "
                f"the fit predicted a validation RMS of {fmt_mm(predicted)}, within the stopping target "
                f"of {fmt_mm(target)} ({block.get('margin')} × acceptance); {left} calibration poses "
                "were not visited. Every validation pose was measured.")
    else:
        text = (f"Stopping rule on, not triggered: all {used} calibration poses were measured "
                f"(last prediction {fmt_mm(predicted)}, stopping target {fmt_mm(target)}).")
    return f'<p class="stopping">{esc(text)}</p>'


def _um(v: Any) -> str:
    return f"{v * 1e6:.1f} µm" if _finite(v) else "—"


def _improvement(before: ErrorSet, after: ErrorSet) -> str:
    if _finite(before.rms) and _finite(after.rms) and after.rms > 0:
        return f"{before.rms / after.rms:.0f}× lower RMS"
    return ""


def _summary(d: ReportData) -> str:
    b, a, f = d.validation_before, d.validation_after, d.fit
    tiles = [
        ("Validation RMS", f"{fmt_mm(b.rms)} → <b>{fmt_mm(a.rms)}</b>", _improvement(b, a)),
        ("Validation max", f"{fmt_mm(b.max)} → <b>{fmt_mm(a.max)}</b>", f"{a.count} held-out poses"),
    ]
    c = d.validation_controller
    if c is not None:
        tiles.append(("Controller's own model", f"<b>{fmt_mm(c.rms)}</b> RMS",
                      f"max {fmt_mm(c.max)}: factory calibration, same poses"))
    tiles += [
        ("Fit RMS", f"<b>{fmt_mm(f.rms)}</b>", f"max {fmt_mm(f.max)}, noise σ {fmt_mm(f.sigma, 4)}"),
        ("Poses", f"<b>{f.used}</b> used / {f.poses - f.used} rejected", esc(_fitted_poses(d))),
        ("Iterations", f"<b>{f.iterations}</b>", f"{f.seconds:.2f} s compute" if _finite(f.seconds) else ""),
        ("Condition number", f"<b>{fmt_num(f.condition, '.1f')}</b>",
         "column-normalised Jacobian"),
    ]
    if d.iso9283:
        for key, value in d.iso9283.items():
            tiles.append((f"ISO 9283 {esc(key)}", f"<b>{fmt_mm(value)}</b>", "repeated validation poses"))
    tiles += _verification_tiles(d.verification)
    if d.drift is not None:
        block = d.drift
        warm = block.get("warmup") or {}
        if warm.get("ran"):
            note = (f"warm-up {warm.get('seconds') or 0:.0f} s, "
                    + ("settled" if warm.get("converged") else "did not settle"))
        else:
            note = "no warm-up"
        flag = "FLAGGED: " if d.drift_flagged else ""
        tiles.append(("Reference drift", f"<b>{esc(flag + _um(block.get('max')))}</b>",
                      esc(f"limit {_um(block.get('limit'))}; {note}")))
    if d.observability is not None:
        o = d.observability
        pct = f"{o.percent:.1f} % of bound" if o.percent is not None else "bound unknown"
        tiles.append((f"Observability {esc(o.index)}", f"<b>{fmt_num(o.value)}</b>", pct))
        tour = o.tour or {}
        if _finite(tour.get("robot_time")) and _finite(tour.get("seed_robot_time")):
            tiles.append(("Robot time (predicted)",
                          f"<b>{tour['robot_time']:.0f} s</b> vs {tour['seed_robot_time']:.0f} s",
                          esc(f"time-aware tour vs method 000's {tour.get('seed_poses')} poses"
                              + ("; plan reused" if tour.get("reused") else ""))))
    cells = "".join(f'<div class="tile"><div class="label">{label}</div><div class="value">{value}</div>'
                    f'<div class="note">{note}</div></div>' for label, value, note in tiles)
    return f'<div class="tiles">{cells}</div>'


def _fitted_poses(d: ReportData) -> str:
    """The fit's poses by where they came from (`ReportData.poses`): the bootstrap's points locate the
    tracker and are fitted with the calibration poses."""
    counts = d.poses or {}
    boot, cal = counts.get("bootstrap") or {}, counts.get("calibration") or {}
    if boot.get("measured") is None or cal.get("measured") is None:
        return f"{d.fit.poses} fitted poses"
    if not boot["measured"]:
        return f"{d.fit.poses} fitted: calibration poses"
    return f"{d.fit.poses} fitted: {boot['measured']} bootstrap + {cal['measured']} calibration"


def _pose_rows(d: ReportData) -> list[tuple[str, str]]:
    """The campaign's poses per role, planned and measured (`ReportData.poses`)."""
    words = {"bootstrap": "bootstrap poses (locate the tracker; fitted too)",
             "calibration": "calibration poses", "validation": "validation poses (held out)"}
    rows = []
    for role, counts in (d.poses or {}).items():
        if role == "bootstrap" and not counts.get("planned"):
            continue  # the tracker position was configured: no bootstrap
        rows.append((esc(f"{words.get(role, role)}: measured of planned"),
                     esc(f"{counts.get('measured')} of {counts.get('planned')}")))
    return rows


def _validation(d: ReportData) -> str:
    b, a = d.validation_before, d.validation_after
    models = [(f"before calibration ({BEFORE_MEANS})", b), ("after calibration", a)]
    if d.validation_controller is not None:
        models.append((CONTROLLER_MEANS, d.validation_controller))
    rows = [(label, str(s.count), fmt_mm(s.mean), fmt_mm(s.rms), fmt_mm(s.max)) for label, s in models]
    parts = [_table(["model", "poses", "mean", "RMS", "max"], [[esc(c) for c in r] for r in rows])]
    if d.iso9283:
        parts.append("<h3>ISO 9283</h3>" + _kv((esc(k), esc(fmt_mm(v))) for k, v in d.iso9283.items()))
    lines = d.validation_lines  # the poses' names: campaign pose numbers or input file lines
    if lines is not None and len(lines) != len(a.norms):
        lines = None
    if a.per_pose:
        before = b if b.per_pose and len(b.norms) == len(a.norms) else None
        # no acceptance line here: across the "before" bars (the nominal arm's deviations, millimetres)
        # it read as a judgement of them, and the threshold judges the RMS after calibration only;
        # the histograms draw it on the "after" panel, next to that RMS
        parts.append(_figure(errors_per_pose(before, a, lines=lines, line_kind=d.line_kind),
                             "validation error per pose, before and after calibration",
                             f"3-D error of each held-out pose before calibration (grey: {BEFORE_MEANS}) "
                             "and after (blue). Dashed: RMS."))
        parts.append(_figure(histograms(before, a, accept_rms=d.accept_rms),
                             "histograms of validation errors",
                             "Distribution of the validation errors before and after calibration. Dashed: "
                             "RMS; dotted red, after calibration only: the acceptance threshold on that "
                             "RMS."))
    else:
        parts.append('<p class="muted">Per-pose validation errors were not recorded in this result; '
                     "only the summary figures are shown.</p>")
    if a.vectors is not None and a.per_pose:
        parts.append(_figure(per_axis(a.vectors, lines=lines, line_kind=d.line_kind),
                             "per-axis validation errors after calibration",
                             "Signed x, y, z errors (tracker frame) of each held-out pose after "
                             "calibration, and their spread per axis."))
    elif (d.calibration_after is not None and d.calibration_after.vectors is not None
          and d.calibration_after.per_pose):
        parts.append(_figure(per_axis(d.calibration_after.vectors, xlabel="calibration pose",
                                      lines=d.calibration_lines, line_kind=d.line_kind),
                             "per-axis calibration residuals",
                             "Signed x, y, z residuals (tracker frame) of each calibration pose after "
                             "the fit (per-axis validation errors were not recorded)."))
    return "".join(parts)


def _verification_tiles(doc: Mapping[str, Any] | None) -> list[tuple[str, str, str]]:
    """Summary tiles of the pose test: each mode's worst-pose AP and RP (escaped cells)."""
    results = (doc or {}).get("results")
    if not isinstance(results, Mapping):
        return []
    return [(f"Pose test AP {esc(mode)}", f"<b>{esc(fmt_mm(block.get('AP_max')))}</b>",
             f"RP {esc(fmt_mm(block.get('RP_max')))}; worst pose, ISO 9283")
            for mode, block in results.items() if isinstance(block, Mapping)]


def _drift(d: ReportData) -> str:
    """Warm-up and drift watch: what ran, what the reference did, the plot."""
    block = d.drift or {}
    warm = block.get("warmup") or {}
    rows = []
    if warm.get("ran"):
        why = warm.get("reason") or "still moving beyond the limit at max_time"
        settled = "yes" if warm.get("converged") else f"no — {why}; measured anyway"
        figures = _warmup_figures(warm, block.get("series"))
        every_s = fmt_num(warm.get("interval"), "g")
        rows += [("warm-up", esc(f"{warm.get('seconds') or 0:.0f} s of cycling through the calibration "
                                 f"poses, the reference re-measured every {every_s} s")),
                 (esc(f"warm-up settled (the rule applied: a first-order fit of the reference's whole "
                      f"series says less than {_um(warm.get('limit'))} of drift is still to come, over a "
                      "series spanning three fitted time constants)"),
                  esc(settled + (f": {figures}" if figures else "")))]
    else:
        rows.append(("warm-up", esc("on, but nothing was left to measure in this run" if warm.get("enabled")
                                    else "off (warmup.enabled = false)")))
    for run in warm.get("runs") or []:
        if isinstance(run, Mapping) and len(warm.get("runs") or []) > 1:
            rows.append((esc(f"warm-up of run {run.get('run')}"),
                         esc(f"{run.get('seconds') or 0:.0f} s, "
                             + ("settled" if run.get("converged") else "did not settle"))))
    every = block.get("every")
    rows += [("drift watch", esc(f"the reference re-measured after every {every} poses" if every else "off")),
             ("largest drift while measuring", esc(_um(block.get("max")))),
             ("drift limit", esc(_um(block.get("limit")))),
             ("flagged", esc("YES — the accept/reject verdict above is still the validation's"
                             if d.drift_flagged else "no"))]
    parts = ['<p class="muted">The arm\'s links grow as its joints warm up (about 0.1 mm per metre over the '
             "first tens of minutes), so the campaign warms it up before measuring and re-measures a "
             "reference pose while measuring (ISO 9283 §6.2, §7.6). Reference measurements are never "
             "used in the fit or the validation. Drift is the reference's displacement from its baseline "
             "(its position at the end of the warm-up).</p>", _kv(rows)]
    if any(isinstance(s, Mapping) and s.get("drift") is not None for s in block.get("series") or []):
        parts.append(_figure(drift_plot(block), "reference drift over the campaign",
                             "Displacement of the reference pose from its baseline against station time: "
                             "warm-up (orange), drift watch while measuring (blue), the baseline (star) and "
                             "the drift limit (dotted red); a dotted vertical line marks a resumed run."))
    return "".join(parts)


def _minutes(seconds: Any) -> str:
    return f"{seconds / 60:.1f} min" if _finite(seconds) else "—"


def _warmup_figures(warm: Mapping[str, Any], series: Any) -> str:
    """The figures the warm-up rule judged (`hil.campaign.warmup.ReferenceWatch.settled`): the fitted
    drift still to come against the limit, the series' span against three fitted time constants. A
    result written before the warm-up block carried its ``span``: the span of the last run's warm-up
    measurements in ``series``."""
    remaining, tau, span = warm.get("remaining"), warm.get("time_constant"), warm.get("span")
    if not _finite(span) and isinstance(series, list):
        points = [s for s in series if isinstance(s, Mapping) and s.get("phase") == "warmup"
                  and _finite(s.get("elapsed")) and _finite(s.get("run"))]
        last = max((s["run"] for s in points), default=None)
        times = [s["elapsed"] for s in points if s["run"] == last]
        span = max(times) - min(times) if times else None
    decision = warm.get("decision")
    said = f"; {decision}" if isinstance(decision, str) and decision else ""
    if not _finite(remaining) or not _finite(tau):
        return "no fit: too few reference measurements" + said
    return (f"about {_um(remaining)} of drift still to come (limit {_um(warm.get('limit'))}); the series "
            f"spans {_minutes(span)}, three fitted time constants {_minutes(3 * tau)} (τ = {_minutes(tau)})"
            + said)


def _calibration(d: ReportData) -> str:
    f = d.fit
    before = d.calibration_before
    after = d.calibration_after
    if before is not None and (after is None or len(before.norms) != len(after.norms)):
        before = None
    rows = [*_pose_rows(d), ("poses fitted", esc(_fitted_poses(d))),
            ("poses used (not rejected as outliers)", esc(f.used))]
    if before is not None and before.per_pose:
        rows.append((esc(f"RMS before calibration ({BEFORE_MEANS})"), esc(fmt_mm(before.rms))))
    rows += [
        ("fit RMS / max (after calibration)", esc(f"{fmt_mm(f.rms)} / {fmt_mm(f.max)}")),
        ("estimated noise σ (per axis)", esc(fmt_mm(f.sigma, 4))),
        ("iterations", esc(f.iterations)), ("condition number", esc(fmt_num(f.condition, ".2f"))),
        ("RMS at the start of the fit (tracker aligned in closed form, SMR at its initial guess: the "
         "fit's starting point, not the arm's error)", esc(fmt_mm(f.initial_rms))),
    ]
    parts = [_kv(rows)]
    if after is not None and after.per_pose:
        rejected = None if d.calibration_used is None else ~d.calibration_used
        parts.append(_figure(errors_per_pose(before, after, rejected=rejected, lines=d.calibration_lines,
                                             xlabel="calibration pose", line_kind=d.line_kind),
                             "calibration residual per pose",
                             f"Residual of each calibration pose before calibration (grey: {BEFORE_MEANS}) "
                             "and with the calibrated model (blue); rejected outliers in red."
                             + (" Poses are numbered as in the campaign." if d.line_kind == "pose" else "")))
    return "".join(parts)


def _parameter_rows(params: Iterable[Any]) -> list[list[str]]:
    rows = []
    for p in params:
        unit, scale = parameter_unit(p.name)
        # The SMR offset and tracker pose are absolute placements, not errors: no significance.
        placement_error = p.name.startswith(("joint", "flange", "compliance"))
        ratio = abs(p.value) / p.std if placement_error and _finite(p.std) and p.std > 0 else math.nan
        rows.append([esc(p.name), esc(fmt_num(p.value * scale, ".4f")), esc(fmt_num(p.std * scale, ".4f")),
                     esc(unit), esc(fmt_num(ratio, ".1f"))])
    return rows


def _tracker_placement(pose: Mapping[str, Any]) -> str:
    """The tracker frame in the robot base frame: position in mm, roll/pitch/yaw in degrees."""
    def cells(values: Any, stds: Any, scale: float, unit: str) -> list[list[str]]:
        stds = stds if isinstance(stds, list | tuple) and len(stds) == 3 else (None,) * 3
        return [[esc(fmt_num(v * scale, ".3f")), esc(fmt_num(s * scale if _finite(s) else None, ".4f")),
                 esc(unit)] for v, s in zip(values, stds, strict=True)]

    rows = [[esc(name), *c] for name, c in zip(
        ("x", "y", "z", "roll", "pitch", "yaw"),
        cells(pose["xyz"], pose.get("xyz_std"), 1e3, "mm")
        + cells(pose["rpy"], pose.get("rpy_std"), 180.0 / math.pi, "deg"), strict=True)]
    return ("<h3>Tracker placement</h3>"
            '<p class="muted">Where the tracker is: its frame in the robot base frame, position (mm) and '
            "orientation as roll, pitch, yaw about the fixed x, y, z axes (degrees, URDF convention "
            "R = Rz(yaw)·Ry(pitch)·Rx(roll)).</p>"
            + _table(["tracker", "value", "σ", "unit"], rows, "num"))


def _parameters(d: ReportData) -> str:
    tracker = [p for p in d.parameters if p.name.startswith("tracker.")]
    rest = [p for p in d.parameters if not p.name.startswith("tracker.")]
    note = ('<p class="muted">Deviations from the nominal geometry as 6-D placement errors of each '
            "joint origin and the flange (se(3) log coordinates: translations tx, ty, tz in mm, "
            "rotations rx, ry, rz in mrad), the SMR centre in the flange frame and, when the joints' "
            "compliance was identified, each joint's compliance (µrad/Nm: the link lags its encoder by "
            "it times the gravity torque the joint holds). σ is one standard "
            "deviation; |value|/σ below about 3 means the deviation is not distinguishable from noise "
            "(not shown for the SMR, a placement rather than an error).</p>")
    parts = [note]
    if any(p.name.startswith("compliance.") for p in rest):
        payload = d.model.get("payload") if d.model is not None else None
        load = (f"{payload['mass']:g} kg with its centre of mass at "
                f"{', '.join(f'{v * 1e3:.0f}' for v in payload['com'])} mm in the flange frame"
                if isinstance(payload, Mapping) and "mass" in payload else "no payload")
        missing = [f"j{j}" for j in range(1, 7) if not any(p.name == f"compliance.j{j}" for p in rest)]
        parts.append(f'<p class="muted">Compliance identified for the arm carrying {esc(load)}. '
                     + (f"Not identified ({esc(', '.join(missing))}): those joints hold no gravity torque "
                        "this payload and mounting would reveal; the model keeps them rigid.</p>"
                        if missing else "</p>"))
    parts.append(_table(["parameter", "value", "σ", "unit", "|value|/σ"], _parameter_rows(rest), "num"))
    if d.tracker_pose is not None:
        parts.append(_tracker_placement(d.tracker_pose))
    if tracker:
        parts.append('<p class="muted">The tracker pose as the fit estimates it: se(3) log coordinates '
                     "of the tracker frame in the robot base frame (tx, ty, tz are not its position, nor "
                     "rx, ry, rz its angles; see the tracker placement above).</p>"
                     + _table(["parameter (se(3) log coordinate)", "value", "σ", "unit", "|value|/σ"],
                              _parameter_rows(tracker), "num"))
    return "".join(parts)


def _correlated(d: ReportData) -> str:
    if not d.correlated:
        return '<p class="muted">No pair of parameters is strongly correlated.</p>'
    return _table(["parameter", "parameter", "correlation ρ"],
                  [[esc(c.a), esc(c.b), esc(f"{c.rho:+.4f}")] for c in d.correlated], "num")


def _rejected(d: ReportData) -> str:
    if not d.rejected:
        return '<p class="muted">No pose was rejected as an outlier.</p>'
    test = '<p class="muted">Poses removed by the leave-one-out F test (Bonferroni, α = 1 %)'
    if d.line_kind == "pose":  # a campaign: its poses are named by their pose numbers
        return (test + ".</p>" + _table(
            ["pose", "residual", "p-value"],
            [[esc(r.line), esc(fmt_mm(r.residual)), esc(f"{r.p_value:.2e}")] for r in d.rejected], "num"))
    return (test + "; the line is the row of the measurement file.</p>"
            + _table(["pose", "file line", "residual", "p-value"],
                     [[esc(r.index), esc(r.line), esc(fmt_mm(r.residual)), esc(f"{r.p_value:.2e}")]
                      for r in d.rejected], "num"))


def _observability(d: ReportData) -> str:
    o = d.observability
    if o is None:
        return '<p class="muted">Not recorded for this campaign.</p>'
    pct = o.percent
    rows = [("index", esc(o.index)), ("value", esc(fmt_num(o.value))),
            ("upper bound (D-optimal relaxation)", esc(fmt_num(o.bound)))]
    if pct is not None:
        width = max(0.0, min(100.0, pct))
        rows.append(("% of bound", f'{esc(f"{pct:.1f} %")} <span class="meter"><span '
                                   f'style="width: {width:.1f}%"></span></span>'))
    if o.method:
        rows.append(("selection method", esc(o.method)))
    tour = o.tour or {}
    if _finite(tour.get("robot_time")) and _finite(tour.get("seed_robot_time")):
        rel = tour.get("relative_error")
        rows.append(("time-aware tour", esc(
            f"{tour.get('poses')} poses, {tour['robot_time']:.1f} s of robot time predicted"
            + (f", predicted error {rel:.3f} x method 000's" if _finite(rel) else ""))))
        rows.append(("method 000, reported beside", esc(
            f"{tour.get('seed_poses')} poses in their best tour, {tour['seed_robot_time']:.1f} s")))
    if tour.get("reused") is not None:
        rows.append(("plan cache", "reused: chosen by an earlier campaign asking the same"
                     if tour["reused"] else "chosen now and kept for the next campaign"))
    return _kv(rows)


#: Keys of the campaign's time breakdown that are not phases: the run's wall time, a count, and the
#: part of ``motion`` spent delivering a point's events while the arm travels
#: (`hil.campaign.engine.RunStats.events_in_motion`: already inside ``motion``).
_NOT_PHASES = ("total", "retries", "events_in_motion")
_OTHER = "other (between steps: events, store, I/O)"


def wall_time(times: Mapping[str, Any]) -> tuple[dict[str, float], float, int | None]:
    """The phases (seconds), which sum to the total, the total and the retried pose visits.

    ``total`` is the run's wall time, ``retries`` a count and ``events_in_motion`` a part of
    ``motion``: none is a phase. Time no phase accounts for shows as one more phase (`_OTHER`); a
    total below the phases' sum (or none) is replaced by that sum.
    """
    phases = {str(k): float(v) for k, v in times.items() if k not in _NOT_PHASES and _finite(v)}
    accounted = sum(phases.values())
    given = times.get("total")
    total = float(given) if _finite(given) and given >= accounted else accounted
    if total - accounted > 1e-9 * max(total, 1.0):
        phases[_OTHER] = total - accounted
    retries = times.get("retries")
    return phases, total, int(retries) if _finite(retries) else None


def _campaign(d: ReportData) -> str:
    parts = []
    if d.times:
        phases, total, retries = wall_time(d.times)
        colors = ["#1f6fb4", "#7fb3e0", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#a3acb9", "#d9dde3"]
        color = {k: colors[i % len(colors)] for i, k in enumerate(phases)}
        bar = "".join(f'<span style="width: {100 * v / total:.2f}%; background: {color[k]}" '
                      f'title="{esc(k)}"></span>' for k, v in phases.items() if total > 0)
        rows = [[f'<span class="swatch" style="background: {color[k]}"></span>{esc(k)}',
                 esc(f"{v:.1f} s"), esc(f"{100 * v / total:.1f} %" if total > 0 else "—")]
                for k, v in phases.items()]
        rows.append(["<b>total (wall time of the run)</b>", f"<b>{esc(f'{total:.1f} s')}</b>",
                     "<b>100 %</b>" if total > 0 else ""])
        parts.append("<h3>Wall time</h3>" + f'<div class="stack">{bar}</div>'
                     + _table(["phase", "time", "share"], rows, "num"))
        overlap = d.times.get("events_in_motion")
        if _finite(overlap) and overlap > 0 and "motion" in phases:
            note = (f"motion: {overlap:.1f} s of it delivering events while the arm travelled (each "
                    "point committed to the store during the next move)")
            parts.append(f'<p class="muted">{esc(note)}</p>')
        if retries is not None:
            parts.append(_kv([("pose visits retried after a suspension", esc(retries))]))
    if d.suspensions:
        parts.append("<h3>Suspensions</h3>" + _table(
            ["kind", "message", "waited"],
            [[esc(s.kind), esc(s.message), esc(f"{s.waited:.1f} s" if _finite(s.waited) else "never resumed")]
             for s in d.suspensions]))
    elif d.campaign:  # an identification's report (`hil report --model`) has no campaign to suspend
        parts.append('<h3>Suspensions</h3><p class="muted">None: the campaign ran without interruption.</p>')
    if d.notes:
        parts.append("<h3>Notes</h3><ul>" + "".join(f"<li>{esc(n)}</li>" for n in d.notes) + "</ul>")
    return "".join(parts)


def _config(config: Mapping[str, Any]) -> str:
    if not config:
        return '<p class="muted">Not recorded.</p>'
    rows = []
    for section, values in config.items():
        if isinstance(values, Mapping):
            rows += [(esc(f"{section}.{k}"), esc(_config_value(v))) for k, v in values.items()]
        else:
            rows.append((esc(section), esc(_config_value(values))))
    return _kv(rows)


def _controller(block: Mapping[str, Any], robot: str) -> str:
    """The controller's own DH table (nominal + delta, as its KinematicsInfo has it), with the
    per-joint checksums and the calibration status it reported."""
    from hil.arm.catalog import get_robot
    from hil.errors import InputError

    try:
        dh = get_robot(robot).dh
        nominal = {"theta": [0.0] * 6, "a": list(dh.a), "d": list(dh.d), "alpha": list(dh.alpha)}
    except InputError:
        nominal = {key: [math.nan] * 6 for key in ("theta", "a", "d", "alpha")}

    def delta(key: str, j: int) -> float | None:
        values = block.get(f"delta_{key}")
        value = values[j] if isinstance(values, list) and len(values) == 6 else None
        return float(value) if isinstance(value, int | float) and not isinstance(value, bool) else None

    checksum = block.get("checksum")
    checksum = checksum if isinstance(checksum, list) and len(checksum) == 6 else [None] * 6
    rows = []
    for j in range(6):
        cells = [esc(f"joint {j + 1}")]
        for key, scale, unit in (("theta", 180 / math.pi, "°"), ("a", 1e3, ""), ("d", 1e3, ""),
                                 ("alpha", 180 / math.pi, "°")):
            base, value = nominal[key][j], delta(key, j)  # metres and radians; deltas in mm and mrad
            cells += [esc(fmt_num(base * scale, ".4f") + (unit if _finite(base) else "")),
                      esc(fmt_num(None if value is None else value * 1e3, ".4f"))]
        cells.append(esc("—" if checksum[j] is None else checksum[j]))
        rows.append(cells)
    status = block.get("calibration_status")
    return ('<p class="muted">The model the controller moves with, reports <code>actual_TCP_pose</code> in '
            "and solves inverse kinematics with: the nominal DH table plus the deltas of its factory "
            "calibration, as its KinematicsInfo reported them at connect (θ and α nominal in degrees, "
            "a and d nominal in mm; deltas δθ, δα in mrad and δa, δd in mm). Its error on the held-out "
            "poses is in the validation table above.</p>"
            + _table(["joint", "θ", "δθ", "a", "δa", "d", "δd", "α", "δα", "checksum"], rows, "num")
            + _kv([("calibration status", esc("—" if status is None else status))]))


def _provenance(d: ReportData) -> str:
    robot = [("model", esc(d.robot.type or "—")), ("serial number", esc(d.robot.serial or "—")),
             ("controller software", esc(d.robot.software or "—"))]
    urdf = (d.model or {}).get("urdf")
    if isinstance(urdf, Mapping):  # an arm from its URDF: which file and which chain of it
        joints = urdf.get("joints") if isinstance(urdf.get("joints"), list) else []
        robot += [("URDF", esc(str(urdf.get("file") or "—"))),
                  ("chain", esc(f"{urdf.get('base') or '—'} → {urdf.get('tip') or '—'}, "
                                f"{len(joints)} joints: {', '.join(str(j) for j in joints)}"))]
    software = [(esc(k), esc(v)) for k, v in d.software.items()]
    hashes = [(esc(k), f"<code>{esc(v)}</code>") for k, v in d.hashes.items()]
    return ("<h3>Robot</h3>" + _kv(robot)
            + "<h3>Software</h3>" + (_kv(software) if software else '<p class="muted">Not recorded.</p>')
            + "<h3>Data hashes (sha256)</h3>"
            + (_kv(hashes) if hashes else '<p class="muted">Not recorded.</p>'))




def render_html(data: ReportData, *, generated: str | None = None) -> str:
    """The whole report as one self-contained HTML (and well-formed XML) document.

    `generated` is the timestamp printed in the report (default: now, UTC); tests pass a fixed one.
    """
    if generated is None:
        generated = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    title = f"Calibration {data.robot.type} {data.robot.serial} {data.campaign}".strip()
    sections = [
        _section("validation", "Validation on held-out poses", _validation(data)),
        *([_section("verification", "ISO 9283 pose test of the calibrated model",
                    calibration_section(data.verification))] if data.verification is not None else []),
        *([_section("drift", "Warm-up and drift", _drift(data))] if data.drift is not None else []),
        _section("calibration", "Calibration fit", _calibration(data)),
        _section("parameters", "Identified parameters", _parameters(data)),
        _section("correlated", "Correlated parameters", _correlated(data)),
        _section("rejected", "Rejected poses", _rejected(data)),
        _section("observability", "Observability of the pose set", _observability(data)),
        *([_section("controller", "The controller's own kinematic model",
                    _controller(data.controller, str((data.model or {}).get("robot") or data.robot.type)))]
          if data.controller is not None else []),
        _section("campaign", "Campaign", _campaign(data)),
        _section("config", "Station configuration", _config(data.config)),
        _section("provenance", "Robot, software and data", _provenance(data)),
    ]
    return ("<!DOCTYPE html>\n"
            '<html lang="en"><head><meta charset="utf-8" />'
            '<meta name="viewport" content="width=device-width, initial-scale=1" />'
            f"<title>{esc(title)}</title><style>{CSS}</style></head>\n<body>"
            + _header(data, generated) + _summary(data) + "\n".join(sections)
            + "</body></html>\n")


def write_report(data: ReportData, path: str | os.PathLike[str], *, generated: str | None = None) -> Path:
    """Render the report and write it atomically (a reader never sees half a file); returns the path."""
    atomic_write_text(path, render_html(data, generated=generated))
    return Path(path)
