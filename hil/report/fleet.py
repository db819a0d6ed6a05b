"""The fleet report (``hil fleet-report``): a plant's robots in ONE self-contained HTML file.

What a quality engineer asks of the fleet, each answered by a section: which robots there are, when and
where each was last calibrated, with what result, and which calibration it carries now (the fleet table);
how each robot's accuracy went from calibration to calibration (validation RMS after calibration over
time, one line per robot, the uncalibrated arm's RMS as faint markers); how accurate the fleet is now
(a histogram of each robot's current model's RMS); how the stations compare (RMS per station, and how
many calibrations each ran); which robots' geometry moved (parameter changes beyond uncertainty between
consecutive good calibrations: hit or repaired), and which calibrations were marked bad and why.

``since`` restricts what is about the past (the plot over time, the stations, the geometry changes and the
marks) to calibrations from that day on; the fleet table and the distribution are the fleet as it is now.

Like the campaign report (`hil.report.render`), it carries everything inside: plots as PNG ``data:`` URIs,
inline CSS, no script, every outside text (serials, station names, reasons) escaped, well-formed XML. In
the figures, serials and station names are drawn as plain text (``parse_math=False``), never mathtext.
"""

from __future__ import annotations

import datetime as _dt
import os
import statistics
import time
from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from matplotlib import dates as mdates
from matplotlib.lines import Line2D
from matplotlib.ticker import LogFormatterSciNotation, MaxNLocator

from hil import __version__
from hil.files.outputs import atomic_write_text
from hil.report.html import CSS, esc, fmt_mm
from hil.report.html import figure as _html_figure
from hil.report.html import section as _section
from hil.report.html import table as _table
from hil.report.plots import AFTER, BEFORE, _figure, _style, png
from hil.store.fleet import (
    DEFAULT_K,
    Calibration,
    GeometryComparison,
    RobotSummary,
    calibrations,
    fleet,
    geometry_changes,
)

if TYPE_CHECKING:
    from hil.store import Store
    from hil.store.listing import Reader

#: Robots drawn in their own colour and named in the legend; beyond, the lines share a palette unnamed.
MAX_LEGEND = 12
_PALETTE = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
            "#bcbd22", "#17becf", "#393b79", "#637939")

@dataclass(frozen=True)
class FleetData:
    """Everything the fleet report shows, read from the store in one go."""

    location: str  # the store, as messages name it
    since: float | None  # epoch seconds: the past from this day on
    k: float  # "beyond uncertainty": |Δ| > k·sqrt(σa² + σb²)
    robots: list[RobotSummary]  # the fleet now, by serial
    calibrations: list[Calibration]  # since `since`, oldest first
    moved: list[tuple[str, GeometryComparison]]  # (serial, comparison whose later calibration is since)
    now: float


def fleet_data(store: Store | Reader, *, since: float | None = None, k: float = DEFAULT_K,
               now: float | None = None) -> FleetData:
    """Read what the report shows from `store` (a `hil.store.Store`, or a station's file's sqlite3
    reader: `hil.store.sqlite_reader`)."""
    now = time.time() if now is None else now
    return FleetData(store.location, since, k, fleet(store, now=now), calibrations(store, since=since),
                     geometry_changes(store, since=since, k=k), now)


# --- figures ------------------------------------------------------------------------------------------
def _when(t: float) -> _dt.datetime:
    return _dt.datetime.fromtimestamp(t)


def _plain(texts: Sequence[Any]) -> None:
    """Serials and station names as typed, never read as mathtext (``$...$``)."""
    for text in texts:
        text.set_parse_math(False)


class _PlainLog(LogFormatterSciNotation):
    """Log-axis labels as plain decimals (0.03, 0.1, 2), on the ticks matplotlib would label."""

    def __call__(self, x: float, pos: int | None = None) -> str:
        return f"{x:g}" if super().__call__(x, pos) else ""


def _log_mm(ax: Any) -> None:
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(_PlainLog())
    ax.yaxis.set_minor_formatter(_PlainLog(labelOnlyBase=False))
    ax.tick_params(axis="y", which="minor", labelsize=8)


def _dates(ax: Any) -> None:
    locator = mdates.AutoDateLocator(minticks=3, maxticks=8)
    ax.xaxis.set_major_locator(locator)
    ax.xaxis.set_major_formatter(mdates.ConciseDateFormatter(locator))


def _fleet_median(rows: Sequence[Calibration], bins: int = 24) -> tuple[list[_dt.datetime], list[float]]:
    """The median validation RMS after calibration (mm) of the calibrations in each of `bins` equal
    spans of time: the fleet's trend, which a plot of many robots' lines hides."""
    t = np.array([c.created for c in rows])
    rms = np.array([c.after_rms for c in rows], dtype=float) * 1e3
    edges = np.linspace(t.min(), t.max(), bins + 1)
    which = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, bins - 1)
    x, y = [], []
    for b in range(bins):
        inside = which == b
        if inside.any():
            x.append(_when(float(np.median(t[inside]))))
            y.append(float(np.median(rms[inside])))
    return x, y


def accuracy_over_time(rows: Sequence[Calibration]) -> bytes | None:
    """Validation RMS after calibration (mm, log) against date, one line per robot; the RMS before
    calibration as faint markers of the same colour; calibrations marked bad crossed. Beyond
    `MAX_LEGEND` robots the lines are thin and unnamed and the fleet's median over time is drawn over
    them. None without data."""
    by_robot: dict[str, list[Calibration]] = defaultdict(list)
    for c in rows:
        if c.after_rms is not None:
            by_robot[c.serial].append(c)
    if not by_robot:
        return None
    fig = _figure(3.6)
    ax = fig.add_subplot()
    _style(ax)
    named = len(by_robot) <= MAX_LEGEND
    lw, ms, alpha = (1.4, 4.0, 1.0) if named else (0.6, 2.0, 0.35)
    handles = []
    for i, (serial, cals) in enumerate(sorted(by_robot.items())):
        color = _PALETTE[i % len(_PALETTE)]
        x = [_when(c.created) for c in cals]
        line, = ax.plot(x, [c.after_rms * 1e3 for c in cals], "-o", color=color, lw=lw, ms=ms, alpha=alpha,
                        label=serial)
        before = [(xx, c.before_rms * 1e3) for xx, c in zip(x, cals, strict=True) if c.before_rms]
        if before:
            ax.plot(*zip(*before, strict=True), "o", color=color, alpha=0.3 * alpha, ms=ms + 1, mec="none")
        bad = [(xx, c.after_rms * 1e3) for xx, c in zip(x, cals, strict=True) if c.marked_bad]
        if bad:
            ax.plot(*zip(*bad, strict=True), "x", color="black", ms=2 * ms + 1, mew=1.6 if named else 1.0)
        if named:
            handles.append(line)
    if not named:
        x, y = _fleet_median([c for cals in by_robot.values() for c in cals])
        ax.plot(x, y, "-", color="black", lw=2.2, zorder=5)
        handles.append(Line2D([], [], color="black", lw=2.2, label=f"fleet median ({len(by_robot)} robots)"))
    handles += [Line2D([], [], color="#555", marker="o", lw=1.4, ms=4, label="after calibration"),
                Line2D([], [], color="#555", marker="o", lw=0, ms=5, alpha=0.3, mec="none",
                       label="before calibration"),
                Line2D([], [], color="black", marker="x", lw=0, ms=8, mew=1.6, label="marked bad")]
    _log_mm(ax)
    _dates(ax)
    ax.set_ylabel("validation RMS (mm, log scale)", fontsize=9)
    ax.set_xlabel("calibration date", fontsize=9)
    ax.margins(x=0.04)
    legend = ax.legend(handles=handles, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0),
                       frameon=False, title="robot" if named else None, title_fontsize=8)
    _plain(legend.get_texts())
    return png(fig)


def current_distribution(robots: Sequence[RobotSummary]) -> bytes | None:
    """Histogram of each robot's current model's validation RMS (mm), its median dashed. None without
    data."""
    values = np.array([r.current_rms for r in robots if r.current_rms is not None]) * 1e3
    if values.size == 0:
        return None
    fig = _figure(2.6)
    ax = fig.add_subplot()
    _style(ax)
    bins = int(np.clip(np.sqrt(values.size) * 2, 12, 40))
    hi = float(values.max())
    ax.hist(values, bins=bins, range=(0.0, hi * 1.1 if hi > 0 else 1.0), color=AFTER, edgecolor="white",
            linewidth=0.5)
    if values.size <= 50:  # few robots: each one's value as a tick along the axis too
        ax.plot(values, np.zeros_like(values), "|", color="#333", ms=12, mew=1.2, clip_on=False, zorder=5)
    median = float(np.median(values))
    ax.axvline(median, color="#333", ls="--", lw=1)
    ax.set_title(f"{values.size} robot{'' if values.size == 1 else 's'} with a current model; median "
                 f"{median:.3f} mm (dashed)", fontsize=9)
    ax.set_xlabel("validation RMS after calibration of the current model (mm)", fontsize=9)
    ax.set_ylabel("robots", fontsize=9)
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_xlim(left=0)
    return png(fig)


#: The bars of "calibrations per station", bottom up: accepted, finished otherwise, and in progress
#: (running, or interrupted or failed: resumable, not a result).
STATION_BARS = ("accepted", "rejected or aborted", "in progress (resumable)")


def station_counts(rows: Sequence[Calibration], names: Sequence[str]) -> dict[str, np.ndarray]:
    """Per station of `names`, its calibrations counted into `STATION_BARS`."""
    def count(station: str, keep: Any) -> int:
        return sum(1 for c in rows if c.station == station and keep(c))

    keeps = (lambda c: c.status == "accepted", lambda c: c.finished and c.status != "accepted",
             lambda c: not c.finished)
    return {bar: np.array([count(s, keep) for s in names]) for bar, keep in zip(STATION_BARS, keeps,
                                                                                  strict=True)}


def stations_side_by_side(rows: Sequence[Calibration]) -> bytes | None:
    """Per station: a box plot of the validation RMS after calibration (mm, log; every calibration a
    dot) and the number of calibrations it ran, accepted or not. None without data."""
    names = sorted({c.station for c in rows})
    if not names:
        return None
    fig = _figure(3.2)
    left, right = fig.subplots(1, 2, width_ratios=[3, 2])
    _style(left)
    _style(right)
    pos = np.arange(len(names))
    values = [[c.after_rms * 1e3 for c in rows if c.station == s and c.after_rms] for s in names]
    shown = [(p, v) for p, v in zip(pos, values, strict=True) if v]
    if shown:
        box = left.boxplot([v for _, v in shown], positions=[p for p, _ in shown], widths=0.5,
                           patch_artist=True, medianprops={"color": "black"}, showfliers=False)
        for patch in box["boxes"]:
            patch.set_facecolor(AFTER)
            patch.set_alpha(0.35)
        many = max(len(v) for _, v in shown) > 60
        for p, v in shown:
            offsets = np.linspace(-0.15, 0.15, len(v)) if len(v) > 1 else np.zeros(1)
            left.plot(p + offsets, v, "o", color=AFTER, ms=1.5 if many else 3.5, alpha=0.25 if many else 0.8,
                      mec="none", zorder=1)
        _log_mm(left)
    left.set_ylabel("validation RMS after calibration (mm)", fontsize=9)
    left.set_title("accuracy per station", fontsize=9)
    counts = station_counts(rows, names)
    bottom = np.zeros(len(names))
    for bar, color, hatch in zip(STATION_BARS, (AFTER, BEFORE, "white"), (None, None, "///"), strict=True):
        if counts[bar].any() or bar != STATION_BARS[2]:
            right.bar(pos, counts[bar], 0.6, bottom=bottom, color=color, label=bar, hatch=hatch,
                      edgecolor=BEFORE if hatch else None)
        bottom = bottom + counts[bar]
    total = bottom
    right.set_ylabel("calibrations", fontsize=9)
    right.set_title("calibrations per station", fontsize=9)
    right.yaxis.set_major_locator(MaxNLocator(integer=True))
    right.set_ylim(0, max(1, int(total.max())) * 1.6)  # room for the legend's three bars
    right.legend(fontsize=8, frameon=False, loc="upper right")
    rotate = len(names) > 4 or max(len(n) for n in names) > 12
    for ax in (left, right):
        ax.set_xticks(pos)
        labels = ax.set_xticklabels(names, rotation=30 if rotate else 0, ha="right" if rotate else "center",
                                    fontsize=8)
        _plain(labels)
        ax.set_xlim(-0.6, len(names) - 0.4)
    return png(fig)


# --- HTML ---------------------------------------------------------------------------------------------
def _date(t: float | None, fmt: str = "%Y-%m-%d") -> str:
    return "—" if t is None else _dt.datetime.fromtimestamp(t).strftime(fmt)


def _result(r: RobotSummary) -> str:
    """The last (finished) calibration's result, and under it the calibration in progress, if any."""
    going = ""
    if r.in_progress is not None:
        state = r.in_progress_status or "?"
        going = (f'<br /><span class="id">in progress: {esc(state)}'
                 f'{" (resumable)" if state in ("interrupted", "failed") else ""}<br />'
                 f'{esc(_date(r.in_progress_created))} {esc(r.in_progress)}</span>')
    if r.status is None:
        return ('<span class="muted">'
                + ("none finished" if r.in_progress is not None else "never calibrated") + "</span>" + going)
    text = esc(r.status)
    if r.marked_bad:
        return f'<span class="bad">{text}, marked bad</span>' + going
    if r.status == "accepted":
        return f'<span class="ok">{text}</span>' + going
    return (f'<span class="bad">{text}</span>' if r.status == "rejected" else text) + going


def _grid(head: Sequence[str], rows: Sequence[Sequence[str]], right: frozenset[int], cls: str = "") -> str:
    """A table from already-escaped cell HTML, the columns in `right` right-aligned (numbers)."""
    def cells(row: Sequence[str], tag: str) -> str:
        return "".join(f'<{tag} class="r">{c}</{tag}>' if i in right else f"<{tag}>{c}</{tag}>"
                       for i, c in enumerate(row))

    body = "".join(f"<tr>{cells(row, 'td')}</tr>" for row in rows)
    attr = f' class="{cls}"' if cls else ""
    return f"<table{attr}><thead><tr>{cells(head, 'th')}</tr></thead><tbody>{body}</tbody></table>"


def _campaign_cell(campaign: str | None, t: float | None) -> str:
    """A calibration as its date, its campaign id below in small print."""
    if campaign is None:
        return "—"
    return f'{esc(_date(t))}<br /><span class="id">{esc(campaign)}</span>'


def _fleet_table(robots: Sequence[RobotSummary]) -> str:
    if not robots:
        return '<p class="muted">No robot with a known serial number in this store.</p>'
    rows = []
    for r in robots:
        current = ('<span class="bad">none</span>' if r.current is None
                   else "the last calibration" if r.current == r.last
                   else _campaign_cell(r.current, r.current_created))
        rows.append([esc(r.serial), esc(r.type), _campaign_cell(r.last, r.last_created), _result(r),
                     esc(fmt_mm(r.before_rms)), esc(fmt_mm(r.after_rms)),
                     esc("—" if r.age_days is None else f"{r.age_days:.0f} d"), esc(r.station or "—"),
                     current])
    return ('<p class="muted">Each robot\'s last finished calibration (validation on held-out poses: RMS '
            "before calibration, the nominal arm, and after), a calibration in progress under its result "
            "(running, or interrupted and resumable), and the calibration whose model is current: its "
            "newest accepted one not marked bad.</p>"
            + _grid(["robot", "type", "last calibration", "result", "RMS before", "RMS after", "age",
                     "station", "current model"], rows, frozenset({4, 5, 6}), "fleet"))


def _moved(data: FleetData) -> str:
    intro = (f'<p class="muted">Parameters of the robot\'s own geometry (joint origins, flange; se(3) '
             f"log coordinates) that changed between two consecutive good calibrations by more than "
             f"{data.k:g} standard deviations of both (|Δ| &gt; {data.k:g}·√(σa² + σb²)): a robot whose "
             "geometry moved was hit or repaired. The SMR and the tracker pose are the station's, not "
             "the robot's, and are not compared.</p>")
    if not data.moved:
        return intro + '<p class="muted">No robot\'s geometry moved beyond uncertainty.</p>'
    rows = []
    for serial, c in data.moved:
        for ch in c.changes:
            unit = "mrad" if ch.angular else "mm"
            rows.append([esc(serial), f"{esc(_date(c.before_created))} → {esc(_date(c.after_created))}<br />"
                         f'<span class="id">{esc(c.before)} → {esc(c.after)}</span>',
                         esc(ch.name), esc(f"{ch.delta * 1e3:+.4f}"), esc(f"{ch.sigma * 1e3:.4f}"),
                         esc(unit), esc(f"{ch.ratio:.1f}")])
    return intro + _grid(["robot", "between calibrations", "parameter", "Δ", "σ (both)", "unit", "|Δ|/σ"],
                         rows, frozenset({3, 4, 6}))


def _marks(rows: Sequence[Calibration]) -> str:
    marked = [c for c in rows if c.mark is not None]
    if not marked:
        return '<p class="muted">No calibration has been marked.</p>'
    body = []
    for c in marked:
        m = c.mark
        assert m is not None
        body.append([esc(c.id), esc(c.serial), f'<span class="{"bad" if m.bad else "ok"}">'
                     f'{"bad" if m.bad else "good again"}</span>', esc(_date(m.t, "%Y-%m-%d %H:%M")),
                     esc(m.who), esc(m.reason)])
    return ('<p class="muted">The latest mark of each calibration: a calibration marked bad is not used; '
            "its robot's current model is the previous good one.</p>"
            + _table(["calibration", "robot", "mark", "when", "by", "reason"], body))


def _tiles(data: FleetData) -> str:
    current = [r.current_rms for r in data.robots if r.current_rms is not None]
    moved = {serial for serial, _ in data.moved}
    tiles = [("Robots", f"<b>{len(data.robots)}</b>",
              f"{sum(1 for r in data.robots if r.current is not None)} with a current model"),
             ("Calibrations", f"<b>{sum(1 for c in data.calibrations if c.finished)}</b>",
              f"{sum(1 for c in data.calibrations if c.status == 'accepted')} accepted"
              + (f", {going} in progress" if (going := sum(1 for c in data.calibrations if not c.finished))
                 else "")),
             ("Stations", f"<b>{len({c.station for c in data.calibrations})}</b>", "that calibrated"),
             ("Median current RMS", f"<b>{esc(fmt_mm(statistics.median(current)) if current else '—')}</b>",
              "validation, after calibration"),
             ("Geometry moved", f"<b>{len(moved)}</b>", "robots hit or repaired")]
    return '<div class="tiles">' + "".join(
        f'<div class="tile"><div class="label">{label}</div><div class="value">{value}</div>'
        f'<div class="note">{esc(note)}</div></div>' for label, value, note in tiles) + "</div>"


def _figure_or_note(png_bytes: bytes | None, alt: str, caption: str, empty: str) -> str:
    if png_bytes is None:
        return f'<p class="muted">{esc(empty)}</p>'
    return _html_figure(png_bytes, alt, caption)


#: The report's sections, in order: (anchor, title).
_SECTIONS: tuple[tuple[str, str], ...] = (
    ("fleet", "The fleet now"), ("time", "Accuracy over time"), ("distribution", "Accuracy across the fleet"),
    ("stations", "Stations side by side"), ("moved", "Robots whose geometry moved"),
    ("marks", "Calibrations marked"),
)

FLEET_CSS = """
.ok { color: var(--ok); } .bad { color: var(--bad); }
.tiles { grid-template-columns: repeat(auto-fill, minmax(170px, 1fr)); }
th.r, td.r { text-align: right; font-variant-numeric: tabular-nums; }
table.fleet td { white-space: nowrap; }
.id { font-size: 11px; color: var(--muted); }
nav { margin: 14px 0 0; font-size: 13px; }
nav a { color: inherit; }
@media print { nav { display: none; } }
"""


def render_fleet_html(data: FleetData, *, generated: str | None = None) -> str:
    """The whole fleet report as one self-contained HTML (and well-formed XML) document."""
    if generated is None:
        generated = _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")
    period = (f"calibrations since {_date(data.since)}" if data.since is not None else "every calibration")
    titles = dict(_SECTIONS)
    sections = [
        _section("fleet", titles["fleet"], _fleet_table(data.robots)),
        _section("time", titles["time"], _figure_or_note(
            accuracy_over_time(data.calibrations), "validation RMS over time per robot",
            "Validation RMS after calibration at each calibration, one line per robot (log scale); the "
            "faint dots of the same colour are the RMS before calibration (the nominal arm); crossed: "
            "marked bad.", "No validated calibration in this period.")),
        _section("distribution", titles["distribution"], _figure_or_note(
            current_distribution(data.robots), "distribution of the current models' RMS",
            "Each robot's current model: its validation RMS after calibration.",
            "No robot has a current model.")),
        _section("stations", titles["stations"], _figure_or_note(
            stations_side_by_side(data.calibrations), "stations compared",
            "Left: validation RMS after calibration of each calibration a station ran (box: quartiles; "
            "dots: calibrations). Right: how many calibrations each ran: accepted, rejected or aborted, "
            "and in progress (running, or interrupted and resumable: no result yet).",
            "No calibration in this period.")),
        _section("moved", titles["moved"], _moved(data)),
        _section("marks", titles["marks"], _marks(data.calibrations)),
    ]
    header = (f'<header><div class="title"><h1>Fleet calibration report</h1>'
              f'<p class="sub">{esc(data.location)} · {esc(period)}</p></div></header>'
              f'<p class="generated">Generated {esc(generated)} by hil {esc(__version__)}.</p>')
    nav = '<nav class="sub">' + " · ".join(
        f'<a href="#{ident}">{esc(title)}</a>' for ident, title in _SECTIONS) + "</nav>"
    return ("<!DOCTYPE html>\n"
            '<html lang="en"><head><meta charset="utf-8" />'
            '<meta name="viewport" content="width=device-width, initial-scale=1" />'
            f"<title>Fleet calibration report</title><style>{CSS}{FLEET_CSS}</style></head>\n<body>"
            + header + _tiles(data) + nav + "\n".join(sections) + "</body></html>\n")


def write_fleet_report(data: FleetData, path: str | os.PathLike[str], *,
                       generated: str | None = None) -> Path:
    """Render the fleet report and write it atomically; returns the path."""
    atomic_write_text(path, render_fleet_html(data, generated=generated))
    return Path(path)


__all__ = ["FleetData", "accuracy_over_time", "current_distribution", "fleet_data", "render_fleet_html",
           "stations_side_by_side", "write_fleet_report"]
