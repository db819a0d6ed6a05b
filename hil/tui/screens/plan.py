"""Plan: how many poses, which index, under which constraints; the selector's answer and where the
chosen poses put the SMR relative to the robot and the tracker (top and side views).

The selector runs on a worker thread (a few seconds for thousands of candidates); the screen shows
an indeterminate progress bar meanwhile. During a run, the plan the campaign actually chose (after
locating the tracker) replaces the preview.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np
from rich.table import Table
from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.widgets import Footer, Input, Label, ProgressBar, Static

from hil.tui.screens.base import HilScreen
from hil.tui.widgets.nav import NavBar
from hil.tui.widgets.plot import PlotView, Series

FIELDS: tuple[tuple[str, str, str], ...] = (
    ("poses", "calibration poses", "campaign.calibration_poses"),
    ("validation", "validation poses", "campaign.validation_poses"),
    ("candidates", "candidates", "campaign.candidates"),
    ("index", "index (O1-O5)", "campaign.index"),
    ("seed", "seed", "campaign.seed"),
)


class PlanScreen(HilScreen):
    """Pose count, index and constraints; the selector's result and a plot of the chosen poses."""

    name_key = "plan"
    AUTO_FOCUS = ""  # nothing: an Input would swallow s and u; tab reaches the fields
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("s", "select", "Select poses"),
        Binding("u", "use", "Use for next run"),
        Binding("escape", "blur", "Leave field", show=False),
    ]

    def __init__(self) -> None:
        super().__init__()
        self.selecting = False
        self.result: dict[str, Any] | None = None  # {"report", "points", "tracker", "assumed", "source"}
        self.error = ""

    def compose(self) -> ComposeResult:
        yield NavBar("plan")
        with Horizontal(id="plan-top"):
            with Vertical(id="plan-form"):
                for key, label, _ in FIELDS:
                    with Horizontal(classes="field"):
                        yield Label(label, classes="field-label")
                        yield Input(id=f"in-{key}", compact=True, select_on_focus=True,
                                    restrict=r"[Oo]?[0-9]*" if key == "index" else r"[0-9]*")
                yield Static(id="constraints")
            with Vertical(id="plan-side"):
                yield ProgressBar(id="plan-progress", total=None, show_eta=False, show_percentage=False)
                yield Static(id="plan-summary")
        with Horizontal(id="plan-plots"):
            yield PlotView("top view  x→ y↑", equal=True, id="top")
            yield PlotView("side view  x→ z↑", equal=True, id="side")
        yield Footer()

    def on_mount(self) -> None:
        self.query_one("#plan-form").border_title = "Plan"
        self.query_one("#plan-side").border_title = "Selection"
        self.load_fields()
        self.refresh_view()

    def load_fields(self) -> None:
        """Fill the fields from the configuration the next run will use."""
        session = self.hil.session
        if session.config is None:
            return
        config = session.run_config()
        for key, _, dotted in FIELDS:
            self.query_one(f"#in-{key}", Input).value = str(config.get(dotted))

    def values(self) -> dict[str, Any] | None:
        """The fields as config values, or None (with a message) when one is not valid."""
        out: dict[str, Any] = {}
        for key, label, dotted in FIELDS:
            text = self.query_one(f"#in-{key}", Input).value.strip()
            if key == "index":
                text = text.upper()
                if text not in ("O1", "O2", "O3", "O4", "O5"):
                    self.hil.notify(f"{label}: choose O1 to O5, got {text!r}", severity="error")
                    return None
                out[dotted] = text
                continue
            if not text.isdigit() or (int(text) < 1 and key != "seed"):
                self.hil.notify(f"{label}: a positive whole number, please", severity="error")
                return None
            out[dotted] = int(text)
        return out

    def action_blur(self) -> None:
        self.set_focus(None)

    def action_select(self) -> None:
        if self.selecting:
            return
        values = self.values()
        if values is None:
            return
        self.selecting, self.error = True, ""
        self.refresh_view()
        self.hil.start_selection(values)

    def action_use(self) -> None:
        values = self.values()
        if values is None:
            return
        if self.hil.session.run_active:
            self.hil.notify("a run is going; the counts apply to the next one", severity="warning")
        self.hil.session.plan_overrides = {k: v for k, v in values.items()}
        self.hil.notify(f"next run: {values['campaign.calibration_poses']} calibration + "
                        f"{values['campaign.validation_poses']} validation poses, "
                        f"{values['campaign.candidates']} candidates, {values['campaign.index']}")

    def show_selection(self, report: dict[str, Any], points: np.ndarray, tracker: tuple[float, ...],
                       assumed: bool, source: str) -> None:
        self.selecting = False
        self.result = {"report": report, "points": np.asarray(points), "tracker": tracker,
                       "assumed": assumed, "source": source}
        self.refresh_view()

    def show_error(self, text: str) -> None:
        self.selecting, self.error = False, text
        self.refresh_view()

    def refresh_view(self) -> None:
        if not self.is_mounted:
            return
        self.query_one(NavBar).refresh()
        self.query_one("#plan-progress").display = self.selecting
        self.query_one("#constraints", Static).update(self._constraints())
        summary = self.query_one("#plan-summary", Static)
        if self.selecting:
            summary.update(Text("selecting poses (tabu search, D-optimal bound)...", style="italic"))
        elif self.error:
            summary.update(Text(self.error, style="bold red"))
        elif self.result is None:
            summary.update(Text("s runs the selector with these settings", style="dim"))
        else:
            summary.update(self._summary())
        self._plots()

    def _constraints(self) -> Text:
        config = self.hil.session.config
        if config is None:
            return Text("station not ready", style="dim")
        lo, hi = config.keep_in["min"], config.keep_in["max"]
        pos = config.tracker["position"]
        return Text.assemble(
            ("keep-in ", "dim"), f"{_box(lo)}..{_box(hi)} m\n",
            ("SMR cone ", "dim"), f"±{config.smr['acceptance_angle']:g}°",
            ("  q2 ", "dim"), "-180..0°\n",
            ("tracker ", "dim"), _box(pos) if pos is not None else "located by bootstrap")

    def _summary(self) -> Table:
        assert self.result is not None
        r = self.result["report"]
        table = Table.grid(padding=(0, 1))
        table.add_column(style="dim", no_wrap=True)
        table.add_column()
        pct = r.get("percent_of_bound")
        table.add_row("source", self.result["source"])
        table.add_row("poses", str(r.get("count", len(r.get("poses", [])))))
        table.add_row("index", f"{r.get('index', '?')} = {_num(r.get('value'))}")
        table.add_row("of bound", Text(f"{pct:.1f} %" if pct is not None else "-",
                                       style="bold green" if pct and pct >= 95 else "bold"))
        table.add_row("method", f"{r.get('method', '')}, {_num(r.get('seconds'))} s")
        travel = (r.get("travel_time") or {}).get("ordered")
        if travel is not None:
            table.add_row("travel", f"{travel:.0f} s (joint space)")
        found = (r.get("candidates") or {}).get("found")
        if found is not None:
            table.add_row("candidates", str(found))
        where = ",".join(f"{v:.2g}" for v in self.result["tracker"])
        table.add_row("tracker", f"({where}) m" + (", assumed" if self.result["assumed"] else ""))
        return table

    def _plots(self) -> None:
        top, side = self.query_one("#top", PlotView), self.query_one("#side", PlotView)
        if self.result is None:
            top.plot([])
            side.plot([])
            return
        p = self.result["points"]
        t = np.asarray(self.result["tracker"], float)
        base = np.zeros(1)
        for view, (a, b) in ((top, (0, 1)), (side, (0, 2))):
            view.plot([
                Series(p[:, a], p[:, b], style="cyan"),
                Series(base, base, style="bold yellow", marker="R"),
                Series(t[a:a + 1], t[b:b + 1], style="bold magenta", marker="T"),
            ])


def _box(v: Any) -> str:
    return "(" + ",".join(f"{x:g}" for x in v) + ")"


def _num(v: Any) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:.4g}"
