"""Run: progress with ETA, the current step, every pose as it is measured, the live error plot, and
the banner that tells the operator what to do when a suspender has paused the run."""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np
from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.widgets import DataTable, Footer, ProgressBar, Static

from hil.tui.screens.base import HilScreen
from hil.tui.state import PoseRow, RunState
from hil.tui.widgets.nav import NavBar
from hil.tui.widgets.plot import PlotView, Series

COLUMNS = (("#", "idx"), ("role", "role"), ("target q [deg]", "target"), ("Δq [mdeg]", "dq"),
           ("measured [mm]", "p"), ("dev [mm]", "dev"))
_ROLE = {"bootstrap": "boot", "calibration": "cal", "validation": "val"}
_STATUS_STYLE = {"moving": "yellow", "reached": "yellow", "skipped": "red", "measured": ""}


def clock(seconds: float | None) -> str:
    """m:ss (or h:mm:ss) for a duration."""
    if seconds is None or not math.isfinite(seconds):
        return "--:--"
    s = round(max(0.0, seconds))
    h, m = divmod(s, 3600)
    return f"{h}:{m // 60:02d}:{m % 60:02d}" if h else f"{m // 60}:{m % 60:02d}"


def row_cells(row: PoseRow) -> tuple[Text, ...]:
    style = _STATUS_STYLE.get(row.status, "")
    target = " ".join(f"{math.degrees(v):4.0f}" for v in row.target) if row.target else "-"
    dq = "-"
    if row.q is not None and row.target:
        dq = f"{1e3 * math.degrees(float(np.max(np.abs(np.subtract(row.q, row.target))))):.1f}"
    if row.status == "skipped":
        p = "skipped"
    elif row.p is not None:
        p = " ".join(f"{1e3 * v:.1f}" for v in row.p)
    else:
        p = row.status + "..."
    dev = f"{1e3 * row.deviation:.3f}" if row.deviation is not None else "-"
    return (Text(str(row.index), style=style), Text(_ROLE.get(row.role, row.role), style=style),
            Text(target, style=style), Text(dq, style=style), Text(p, style=style),
            Text(dev, style=style, justify="right"))


class RunScreen(HilScreen):
    """The live campaign."""

    name_key = "run"
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("g", "app.start_run", "Start"),
        Binding("p", "app.pause", "Pause/resume"),
        Binding("a", "app.abort", "Abort"),
    ]

    def __init__(self) -> None:
        super().__init__()
        self._shown: dict[str, tuple[str, ...]] = {}  # row key -> cells as shown

    def compose(self) -> ComposeResult:
        yield NavBar("run")
        yield Static(id="banner")
        yield Static(id="run-status")
        yield ProgressBar(id="run-progress", total=1, show_eta=False)
        yield Static(id="run-step")
        table: DataTable[Text] = DataTable(id="poses", cursor_type="row", zebra_stripes=True)
        for label, key in COLUMNS:
            table.add_column(Text(label), key=key)  # Text: "[deg]" is not markup
        yield table
        yield PlotView("deviation from nominal [mm] per pose", y_floor=0.0, id="errors")
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
        errors = self.query_one("#errors", PlotView)
        d = 1e3 * np.asarray(run.deviations, float)
        errors.plot([Series(np.arange(1, len(d) + 1, dtype=float), d, style="red", line=True)])

    def tick(self) -> None:
        """Once a second: the elapsed wait in the banner and the ETA."""
        if self.is_mounted:
            self._banner(self.hil.run_state)
            self._status(self.hil.run_state)

    def _banner(self, run: RunState) -> None:
        banner = self.query_one("#banner", Static)
        s = run.suspended
        banner.display = s is not None
        if s is None:
            return
        waited = self.hil.now() - s.t
        banner.update(Text.assemble(
            (f" {s.kind.replace('_', ' ').upper()} ", "bold reverse"),
            f"  waiting {clock(waited)}  (resumes by itself once cleared)\n",
            (s.message, "bold")))

    def _status(self, run: RunState) -> None:
        status = self.query_one("#run-status", Static)
        bar = self.query_one("#run-progress", ProgressBar)
        step = self.query_one("#run-step", Static)
        if not run.campaign:
            status.update(Text("no run yet: g starts a campaign with the Plan screen's counts", style="dim"))
            bar.update(total=1, progress=0)
            step.update("")
            return
        done = run.measured + run.skipped
        bar.update(total=max(1, run.planned), progress=min(done, run.planned))
        state = run.finished.status if run.finished else run.state
        text = Text.assemble((run.campaign, "bold"), "  ", (state.upper(), _state_style(state)),
                             f"  {run.measured}/{run.planned} poses")
        if run.skipped:
            text.append(f", {run.skipped} skipped", "red")
        if run.active and not run.finished:
            text.append(f"  ETA {clock(run.eta())}")
        status.update(text)
        if run.finished is not None:
            step.update(Text(f"finished: {run.finished.detail}", style=_state_style(run.finished.status)))
            return
        current = next((r for r in reversed(run.rows.values()) if r.status in ("moving", "reached")), None)
        phase = f"{run.phase}: {run.detail}" if run.detail else run.phase
        if current is not None and run.phase in ("measure", "bootstrap"):
            verb = "moving to" if current.status == "moving" else "measuring"
            phase = f"{run.phase}: {verb} pose {current.index} ({current.role})"
        step.update(Text(phase or "starting...", style="italic"))

    def _table(self, run: RunState) -> None:
        table: DataTable[Text] = self.query_one("#poses", DataTable)
        keys = {f"{role}:{index}" for role, index in run.rows}
        if any(key not in keys for key in self._shown):  # a new run: start over
            table.clear()
            self._shown = {}
        at_end = table.cursor_row >= table.row_count - 1
        for (role, index), row in run.rows.items():
            key = f"{role}:{index}"
            cells = row_cells(row)
            plain = tuple(c.plain for c in cells)
            if self._shown.get(key) == plain:
                continue
            if key in self._shown:
                for (_, column), cell in zip(COLUMNS, cells, strict=True):
                    table.update_cell(key, column, cell, update_width=True)
            else:
                table.add_row(*cells, key=key)
            self._shown[key] = plain
        if at_end and table.row_count:
            table.move_cursor(row=table.row_count - 1)


def _state_style(state: str) -> str:
    return {"running": "bold green", "paused": "bold yellow", "suspended": "bold red",
            "accepted": "bold green", "rejected": "bold red", "failed": "bold red",
            "aborted": "bold yellow", "interrupted": "bold yellow"}.get(state, "bold")
