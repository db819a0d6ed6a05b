"""Run: progress with ETA, the current step, every pose as it is measured, the live error plot, and
the banner that tells the operator what to do when a suspender has paused the run."""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.css.query import NoMatches
from textual.widgets import DataTable, Footer, ProgressBar, Static
from textual.widgets.data_table import ColumnKey

from hil.tui.screens.base import HilScreen
from hil.tui.screens.pose_plan import FIELDS, count_problem
from hil.tui.screens.station import fault_text, unfinished_text
from hil.tui.state import PoseRow, RunState
from hil.tui.widgets.nav import NavBar
from hil.tui.widgets.plot import PlotView, Series
from hil.tui.words import kind_words

#: The table's columns, most telling first; at 80 columns every one is in view, whole. The joint targets
#: (six angles, the widest and least read) are on the line below the table, for the pose under the
#: cursor (`pose_line`): the current one unless the operator moves the cursor (up/down).
#: (label, key, width): fixed widths, so the table is whole from its first frame. Textual sizes an
#: automatic column when the table's message queue falls idle, and under a flood of engine events
#: on a loaded machine that came late: the operator saw "measur" under "status" until it did. Each
#: width holds the column's longest text: an index up to 999, "measuring", a deviation of a metre
#: ("1000.000"), a joint error of a turn, and three coordinates out to a tracker's 40 m range
#: ("-40000.0", Leica AT960 datasheet). A longer cell widens its column at once (`_fit_width`).
COLUMNS = (("#", "idx", 3), ("role", "role", 4), ("status", "status", 9), ("dev [mm]", "dev", 8),
           ("Δq [mdeg]", "dq", 9), ("measured [mm]", "p", 26))
_ROLE = {"bootstrap": "boot", "calibration": "cal", "validation": "val"}
_STATUS = {"moving": ("moving", "yellow"), "reached": ("measuring", "yellow"), "skipped": ("skipped", "red"),
           "measured": ("measured", "")}
#: A deviation this many times the run's median (of at least `OUTLIER_AFTER` points) is shown red: a
#: point unlike the others (a slipped SMR, a disturbed reading) rather than the arm's error.
OUTLIER_FACTOR = 3.0
OUTLIER_AFTER = 5


def deviation_style(deviation: float | None, outlier: float | None) -> str:
    """Red above `outlier` (`OUTLIER_FACTOR` × the run's median deviation: a point unlike the
    campaign's others), else uncoloured.

    A deviation from the nominal model is the arm's error before calibration — millimetres on a
    healthy arm, the very thing calibration removes — not an accuracy figure: judging it against
    the campaign's acceptance threshold (which is on the validation RMS *after* calibration) once
    coloured every healthy point "above acceptance". Only the campaign's own spread says whether
    one point is odd.
    """
    if deviation is None or outlier is None or deviation <= outlier:
        return ""
    return "bold red"


def outlier_level(deviations: list[float]) -> float | None:
    """The deviation above which a point is an outlier (None until `OUTLIER_AFTER` points)."""
    if len(deviations) < OUTLIER_AFTER:
        return None
    return OUTLIER_FACTOR * float(np.median(deviations))


def run_outlier_level(run: RunState) -> float | None:
    """`outlier_level` of the run's poses, the bootstrap's points left out: they are registered on
    themselves around one start pose (hundredths of a millimetre from nominal) and set against the
    poses' millimetres their median marked every calibration pose red — the arm's plain error
    shown as an outlier."""
    return outlier_level([r.deviation for (role, _), r in run.rows.items()
                          if role != "bootstrap" and r.deviation is not None])


def clock(seconds: float | None) -> str:
    """m:ss (or h:mm:ss) for a duration."""
    if seconds is None or not math.isfinite(seconds):
        return "--:--"
    s = round(max(0.0, seconds))
    h, m = divmod(s, 3600)
    return f"{h}:{m // 60:02d}:{m % 60:02d}" if h else f"{m // 60}:{m % 60:02d}"


def row_cells(row: PoseRow, outlier: float | None = None) -> tuple[Text, ...]:
    """The cells of one pose, in `COLUMNS` order (deviations coloured by `deviation_style`)."""
    status, style = _STATUS.get(row.status, (row.status, ""))
    dq = "-"
    if row.q is not None and row.target:
        dq = f"{1e3 * math.degrees(float(np.max(np.abs(np.subtract(row.q, row.target))))):.1f}"
    p = " ".join(f"{1e3 * v:.1f}" for v in row.p) if row.p is not None else "-"
    dev = f"{1e3 * row.deviation:.3f}" if row.deviation is not None else "-"
    return (Text(str(row.index), justify="right"), Text(_ROLE.get(row.role, row.role)),
            Text(status, style=style),
            Text(dev, style=deviation_style(row.deviation, outlier), justify="right"),
            Text(dq, justify="right"), Text(p))


def pose_line(row: PoseRow | None) -> Text:
    """The pose under the table's cursor: its joint targets, whole, and why it was skipped."""
    if row is None:
        return Text()
    role = _ROLE.get(row.role, row.role)
    text = Text.assemble((f"pose {row.index} {role}", "bold"), "  ")
    if row.target:
        text.append("target q [deg] ", "dim")
        text.append(" ".join(f"{math.degrees(v):.1f}" for v in row.target))
    if row.status == "skipped" and row.reason:
        text.append(("  " if row.target else "") + f"skipped: {row.reason}", "red")
    return text


def pose_counts(run: RunState) -> tuple[int, int, int, int]:
    """(measured, planned, skipped, bootstrap points) of the run: the calibration and validation poses,
    the count the progress bar of ``hil calibrate`` and the history show too; the bootstrap's points
    (they locate the tracker) apart."""
    planned = run.planned
    if run.plan is not None:  # the plan itself (a resumed campaign keeps its own)
        planned = sum(1 for p in run.plan.poses if p["role"] != "bootstrap")
    skipped = sum(1 for (role, _), r in run.rows.items() if role != "bootstrap" and r.status == "skipped")
    boot = sum(1 for (role, _), r in run.rows.items() if role == "bootstrap" and r.status == "measured")
    return run.measured, planned, skipped, boot


class RunScreen(HilScreen):
    """The live campaign."""

    name_key = "run"
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("g", "start_run", "Start"),
        Binding("p", "app.pause", "Pause/resume"),
        Binding("a", "app.abort", "Abort"),
        Binding("s", "app.skip_pose", "Skip"),  # short: the footer holds them all at 80 columns
        Binding("w", "app.wait_longer", "Wait"),
    ]

    def __init__(self) -> None:
        super().__init__()
        self._shown: dict[str, tuple[tuple[str, str], ...]] = {}  # row key -> cells (text, style) as shown
        self._followed = -1  # the row the cursor was put on to follow the current pose

    def compose(self) -> ComposeResult:
        yield NavBar("run")
        yield Static(id="banner")
        yield Static(id="run-status")
        yield ProgressBar(id="run-progress", total=1, show_eta=False)
        yield Static(id="run-step")
        drift = Static(id="run-drift")  # warm-up and drift watch: shown once there is something to say
        drift.display = False
        yield drift
        sweep = Static(id="run-sweep")  # a sweep's segments and its streams' health, once it sweeps
        sweep.display = False
        yield sweep
        table: DataTable[Text] = DataTable(id="poses", cursor_type="row", zebra_stripes=True)
        for label, key, width in COLUMNS:
            table.add_column(Text(label), key=key, width=width)  # Text: "[mm]" is not markup
        yield table
        yield Static(id="pose-line")
        yield PlotView("deviation from nominal [mm]", y_floor=0.0, x_label="point", integer_x=True,
                       id="errors")
        yield Footer()

    def on_mount(self) -> None:
        self.query_one("#errors", PlotView).empty_text = "appears after the 4th point (registration)"
        self.refresh_view()

    def refresh_view(self) -> None:
        if not self.is_mounted:
            return
        run = self.hil.run_state
        self.query_one(NavBar).refresh()
        self._banner(run)
        self._status(run)
        self._table(run)
        self._errors(run)

    async def action_start_run(self) -> None:
        """Start a campaign, unless its counts cannot calibrate (said before the arm moves)."""
        config = self.hil.session.config
        if config is not None and not self.hil.session.run_active:
            run = self.hil.session.run_config()
            problem = count_problem({dotted: run.get(dotted) for _, _, dotted in FIELDS}, run.robot["type"])
            if problem is not None:
                self.hil.notify(f"{problem} (Plan screen, 2)", severity="error", timeout=10)
                return
        await self.app.run_action("app.start_run")

    def _errors(self, run: RunState) -> None:
        """The deviations from the nominal model in measuring order, and the outliers (as the table).

        No acceptance line: the acceptance threshold judges the validation RMS after calibration, not
        how far the uncalibrated arm is from nominal (millimetres, which calibration removes)."""
        d = 1e3 * np.asarray(run.deviations, float)
        x = np.arange(1, len(d) + 1, dtype=float)
        series = [Series(x, d, style="yellow", line=True, label="deviation")]
        level = run_outlier_level(run)
        if level is not None and np.any(d > 1e3 * level):
            out = d > 1e3 * level
            series.append(Series(x[out], d[out], style="bold red", marker="•",
                                 label=f"> {OUTLIER_FACTOR:g}× median"))
        self.query_one("#errors", PlotView).plot(series)

    def tick(self) -> None:
        """Once a second: the elapsed wait in the banner and the ETA.

        The app's timer can fire between the screen being pushed (mounted) and its widgets being
        composed; that tick has nothing to update yet, and the next one will (seen on a loaded machine:
        the query for the banner found nothing and the app stopped).
        """
        if not self.is_mounted:
            return
        try:
            self._banner(self.hil.run_state)
            self._status(self.hil.run_state)
        except NoMatches:
            return

    def _banner(self, run: RunState) -> None:
        banner = self.query_one("#banner", Static)
        s = run.suspended
        st = self.hil.session.station
        fault = st.fault if not run.active else ""
        banner.display = s is not None or bool(fault)
        if s is None:
            if fault:
                banner.update(fault_text(fault, st.steps))
            return
        now = self.hil.now()
        line = Text.assemble((f" {kind_words(s.kind).upper()} ", "bold reverse"),
                             f"  waiting {clock(now - s.t)}")
        if run.suspend_deadline is not None and s.on_timeout == "skip":
            line.append(f"; skips the pose in {clock(run.suspend_deadline - now)}", "bold")
            line.append(" (s skip now, w wait longer)")
        elif run.suspend_deadline is not None:
            line.append(f"; the run stops in {clock(run.suspend_deadline - now)}")
            line.append("  (w wait longer)")
        else:
            line.append("  (resumes by itself once cleared)")
        banner.update(Text.assemble(line, "\n", (s.message, "bold")))

    def _drift(self, run: RunState) -> None:
        """The warm-up's and the drift watch's latest line (red once the campaign is flagged)."""
        line = self.query_one("#run-drift", Static)
        line.display = bool(run.reference_line)
        line.update(Text(run.reference_line, style="bold red" if run.drift_flagged else "cyan"))

    def _sweep(self, run: RunState) -> None:
        """A sweep campaign's latest line: the segment recorded and its streams' health, then the
        clock map the join found (`hil.campaign.sweep_lines`); yellow while the beam broke."""
        line = self.query_one("#run-sweep", Static)
        line.display = bool(run.sweep_line)
        line.update(Text(run.sweep_line, style="yellow" if "beam break" in run.sweep_line else "cyan"))

    def _status(self, run: RunState) -> None:
        self._drift(run)
        self._sweep(run)
        status = self.query_one("#run-status", Static)
        bar = self.query_one("#run-progress", ProgressBar)
        step = self.query_one("#run-step", Static)
        if not run.campaign:
            unfinished = self.hil.session.station.unfinished
            status.update(unfinished_text(unfinished, line=True) if unfinished else
                          Text("no run yet: g starts a campaign with the Plan screen's counts", style="dim"))
            bar.update(total=1, progress=0)
            step.update("")
            return
        measured, planned, skipped, boot = pose_counts(run)
        bar.update(total=max(1, planned), progress=min(measured + skipped, planned))
        state = run.finished.status if run.finished else run.state
        text = Text.assemble((run.campaign, "bold"), "  ", (state.upper(), _state_style(state)),
                             f"  {measured}/{planned} poses")
        if skipped:
            text.append(f", {skipped} skipped", "red")
        if boot:
            text.append(f" (+{boot} bootstrap)", "dim")
        if run.active and not run.finished:
            text.append(f"  ETA {clock(run.eta())}")
        status.update(text)
        if run.finished is not None:
            detail = run.finished.detail if run.ended else "closing the run..."
            step.update(Text(f"finished: {detail}" if detail else "finished",
                             style=_state_style(run.finished.status)))
            return
        current = _current(run)
        phase = f"{run.phase}: {run.detail}" if run.detail else run.phase
        if current is not None and run.phase in ("measure", "bootstrap"):
            verb = "moving to" if current.status == "moving" else "measuring"
            phase = f"{run.phase}: {verb} pose {current.index} ({current.role})"
        elif run.phase == "measure":  # between poses (a pause, the reference pose): the count now,
            # not the one the phase started with
            phase = f"measure: {measured} of {planned} poses measured"
        step.update(Text(phase or "starting...", style="italic"))

    def _table(self, run: RunState) -> None:
        table: DataTable[Text] = self.query_one("#poses", DataTable)
        keys = {f"{role}:{index}" for role, index in run.rows}
        if any(key not in keys for key in self._shown):  # a new run: start over
            table.clear()
            self._shown = {}
        # the cursor follows the current pose unless the operator moved it elsewhere
        follow = table.cursor_row >= table.row_count - 1 or table.cursor_row == self._followed
        outlier = run_outlier_level(run)
        for (role, index), row in run.rows.items():
            key = f"{role}:{index}"
            cells = row_cells(row, outlier)
            plain = tuple((c.plain, str(c.style)) for c in cells)  # a colour may change alone
            if self._shown.get(key) == plain:
                continue
            _fit_width(table, cells)
            if key in self._shown:
                for (_, column, _), cell in zip(COLUMNS, cells, strict=True):
                    table.update_cell(key, column, cell)
            else:
                table.add_row(*cells, key=key)
            self._shown[key] = plain
        current = _current(run)
        if run.suspended is not None or follow:  # a suspended pose is always brought into view
            row_index = (table.get_row_index(f"{current.role}:{current.index}") if current is not None
                         else table.row_count - 1)
            if row_index >= 0:
                self._followed = row_index
                table.move_cursor(row=row_index, animate=False)
                # again once laid out: a banner that appears with the suspension shrinks the table
                self.call_after_refresh(table.move_cursor, row=row_index, animate=False)
        self._pose_line(run)

    def _pose_line(self, run: RunState) -> None:
        table: DataTable[Text] = self.query_one("#poses", DataTable)
        row = None
        if table.row_count and 0 <= table.cursor_row < table.row_count:
            key = table.coordinate_to_cell_key((table.cursor_row, 0)).row_key.value
            role, _, index = str(key).partition(":")
            row = run.rows.get((role, int(index)))
        self.query_one("#pose-line", Static).update(pose_line(row))

    def on_data_table_row_highlighted(self, event: DataTable.RowHighlighted) -> None:
        """The operator moved the cursor: the pose line shows that pose."""
        if self.is_mounted:
            self._pose_line(self.hil.run_state)


def _fit_width(table: DataTable[Text], cells: tuple[Text, ...]) -> None:
    """Widen a column whose cell is longer than its width now, rather than cut the number."""
    for (_, key, _), cell in zip(COLUMNS, cells, strict=True):
        column = table.columns[ColumnKey(key)]
        if cell.cell_len > column.width:
            column.width = cell.cell_len
            table.refresh(layout=True)


def _current(run: RunState) -> PoseRow | None:
    """The pose the run is on (moving to it or measuring it), if any."""
    return next((r for r in reversed(run.rows.values()) if r.status in ("moving", "reached")), None)


def _state_style(state: str) -> str:
    return {"running": "bold green", "paused": "bold yellow", "suspended": "bold red",
            "accepted": "bold green", "rejected": "bold red", "failed": "bold red",
            "aborted": "bold yellow", "interrupted": "bold yellow"}.get(state, "bold")
