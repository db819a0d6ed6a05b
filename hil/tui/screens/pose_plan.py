"""Plan: how many poses, which index, under which constraints; the selector's answer and where the
chosen poses put the SMR relative to the robot and the tracker (top and side views).

The selector runs on a worker thread (a few seconds for thousands of candidates); the screen shows
an indeterminate progress bar meanwhile. During a run, the plan the campaign actually chose (after
locating the tracker) replaces the preview; the summary says which of the two is shown, and whether the
run will choose the previewed poses (only with the tracker's position configured and the same settings).

The counts are checked before the selector or a run starts (`count_problem`): the fit needs
`minimum_poses` of its identifiable parameters (27 for a UR), whatever the tracker and SMR guess.
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
from textual.events import Key
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


def count_problem(values: dict[str, Any], robot: str) -> str | None:
    """What is wrong with the counts (`FIELDS`' config keys) in the Plan screen's words, or None.

    The selector and the fit refuse fewer than `minimum_poses` of the identifiable parameters
    (27 for every UR); checked here so that a run never locates the tracker only to fail at selection.
    """
    from hil.arm.kinematics import identifiable_parameters
    from selector.design import minimum_poses

    n = len(identifiable_parameters(robot))
    need = minimum_poses(n)
    cal, val = values["campaign.calibration_poses"], values["campaign.validation_poses"]
    candidates = values["campaign.candidates"]
    if cal < need:
        return (f"calibration poses: at least {need}, not {cal} — the fit identifies {n} parameters "
                f"from 3 coordinates per pose and keeps 3 to spare")
    for label, count in (("calibration poses", cal), ("validation poses", val)):
        if count > candidates:
            return f"{label}: {count} is more than the {candidates} candidates they are chosen from"
    return None


class FieldInput(Input):
    """A one-line field that takes only the characters it can hold, so the screen's keys (s, u, ?, q)
    still work, and show in the footer, while it has the focus."""

    BINDINGS: ClassVar[list[BindingType]] = [Binding("escape", "leave", "Leave field")]

    def __init__(self, accepts: str, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.accepts = accepts

    def check_consume_key(self, key: str, character: str | None) -> bool:
        return character is not None and character in self.accepts

    async def _on_key(self, event: Key) -> None:
        if event.is_printable and event.character not in self.accepts:
            event.prevent_default()  # not typed: it goes on to the screen's and the app's bindings

    def action_leave(self) -> None:
        self.screen.set_focus(None)


class PlanScreen(HilScreen):
    """Pose count, index and constraints; the selector's result and a plot of the chosen poses."""

    name_key = "plan"
    AUTO_FOCUS = ""  # nothing: an Input would swallow s and u; tab reaches the fields
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("s", "select", "Select poses"),
        Binding("u", "use", "Use for next run"),
        # not in the footer (it would cut "q Quit" at 80 columns): the panel's warm-up line and ? show it
        Binding("w", "toggle_warmup", "Warm-up on/off", show=False),
    ]

    def __init__(self) -> None:
        super().__init__()
        self.selecting = False
        self.result: dict[str, Any] | None = None  # {"report", "points", "tracker", "assumed", "source",
        #                                             "preview", "values"}
        self.error = ""  # the selector's failure
        self.problem = ""  # what is wrong with the fields (`values`)
        self._asked: dict[str, Any] | None = None  # the values of the selection under way

    def compose(self) -> ComposeResult:
        yield NavBar("plan")
        with Horizontal(id="plan-top"):
            with Vertical(id="plan-form"):
                for key, label, _ in FIELDS:
                    with Horizontal(classes="field"):
                        yield Label(label, classes="field-label")
                        yield FieldInput("Oo0123456789" if key == "index" else "0123456789",
                                         id=f"in-{key}", compact=True, select_on_focus=True,
                                         restrict=r"[Oo]?[0-9]*" if key == "index" else r"[0-9]*")
                yield Static(id="constraints")
            with Vertical(id="plan-side"):
                yield ProgressBar(id="plan-progress", total=None, show_eta=False, show_percentage=False)
                yield Static(id="plan-summary")
        with Horizontal(id="plan-plots"):
            yield PlotView("top view [m]", equal=True, x_label="x→", y_label="y↑", id="top")
            yield PlotView("side view [m]", equal=True, x_label="x→", y_label="z↑", id="side")
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
        """The fields as config values, or None (with a message, also in the summary) when one is not
        valid or the counts cannot calibrate (`count_problem`)."""
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
        config = self.hil.session.config
        problem = count_problem(out, config.robot["type"]) if config is not None else None
        self.problem = problem or ""
        self.refresh_view()
        if problem is not None:
            self.hil.notify(problem, severity="error")
            return None
        return out

    def action_select(self) -> None:
        if self.selecting:
            return
        values = self.values()
        if values is None:
            return
        self.selecting, self.error, self._asked = True, "", values
        self.refresh_view()
        self.hil.start_selection(values)

    def action_use(self) -> None:
        values = self.values()
        if values is None:
            return
        if self.hil.session.run_active:
            self.hil.notify("a run is going; the counts apply to the next one", severity="warning")
        self.hil.session.plan_overrides = {k: v for k, v in values.items()}
        self.refresh_view()  # the summary says whether the run will choose the previewed poses
        self.hil.notify(f"next run: {values['campaign.calibration_poses']} calibration + "
                        f"{values['campaign.validation_poses']} validation poses, "
                        f"{values['campaign.candidates']} candidates, {values['campaign.index']}")

    def action_toggle_warmup(self) -> None:
        """Skip the warm-up in the next run, or warm up again: ``hil calibrate --no-warmup``'s meaning
        (a quick look, or an arm that has been running already); it applies to a resumed campaign
        too, which otherwise warms up again (the arm may have cooled)."""
        session = self.hil.session
        if session.config is None:
            self.hil.notify("the station is not ready yet", severity="warning")
            return
        if not session.no_warmup and not session.warmup_on():
            self.hil.notify("the configuration has no warm-up (warmup.enabled = false)", severity="warning")
            return
        session.no_warmup = not session.no_warmup
        self.refresh_view()
        self.hil.notify("next run: no warm-up, it measures at once (as --no-warmup)" if session.no_warmup
                        else "next run: warms the arm up first, as configured")

    def show_selection(self, report: dict[str, Any], points: np.ndarray, tracker: tuple[float, ...],
                       assumed: bool, source: str) -> None:
        self.selecting = False
        preview = source.startswith("preview")  # else a run's plan: the poses it measures
        self.result = {"report": report, "points": np.asarray(points), "tracker": tracker,
                       "assumed": assumed, "source": source, "preview": preview, "values": self._asked}
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
        elif self.problem or self.error:
            summary.update(Text(self.problem or self.error, style="bold red"))
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
            ("tracker ", "dim"), _box(pos) if pos is not None else "located by bootstrap", "\n",
            ("warm-up ", "dim"), self._warmup())

    def _warmup(self) -> Text:
        """Whether the next run warms the arm up, and the key that changes it."""
        session = self.hil.session
        if session.no_warmup:
            return Text.assemble(("off", "bold yellow"), ("  (w: warm up)", "dim"))
        if not session.warmup_on():
            return Text("off in the configuration", style="dim")
        return Text.assemble("on", ("  (w: skip it)", "dim"))

    def _next_run(self) -> dict[str, Any] | None:
        """The Plan fields' settings the next run will use."""
        if self.hil.session.config is None:
            return None
        config = self.hil.session.run_config()
        return {dotted: config.get(dotted) for _, _, dotted in FIELDS}

    def _source(self) -> Text:
        """Where the poses shown come from, and whether the run measures them."""
        assert self.result is not None
        res = self.result
        if not res["preview"]:  # the plan of a run
            return Text(f"{res['source']}: the poses it measures")
        if res["assumed"]:
            return Text("preview: the run locates the tracker, then selects again", style="yellow")
        if res["values"] == self._next_run():
            return Text("preview: the poses the next run measures", style="green")
        return Text("preview: the next run has other settings (u uses these)", style="yellow")

    def _parameters(self, report: dict[str, Any]) -> Text | None:
        """How many parameters the selection served, next to the fit's count, and why they differ."""
        from hil.arm.kinematics import identifiable_parameters

        config = self.hil.session.config
        chosen = report.get("parameters")
        if config is None or chosen is None:
            return None
        fit = len(identifiable_parameters(config.robot["type"]))
        if chosen >= fit:
            return Text(f"{chosen}, as the fit")
        x, y, _ = config.smr["offset"]
        why = ("SMR guess on the flange axis" if abs(x) < 1e-9 and abs(y) < 1e-9  # smr.offset x = y = 0
               else "some are not observable")
        return Text(f"{chosen} of the fit's {fit}: {why}")

    def _summary(self) -> Table:
        assert self.result is not None
        r = self.result["report"]
        table = Table.grid(padding=(0, 1))
        table.add_column(style="dim", no_wrap=True)
        table.add_column()
        table.add_row("source", self._source())
        count = r.get("count", len(r.get("poses", [])))
        found = (r.get("candidates") or {}).get("found")
        table.add_row("poses", f"{count} of {found} candidates" if found is not None else str(count))
        pct = r.get("percent_of_bound")
        index = Text(f"{r.get('index', '?')} = {_num(r.get('value'))}")
        if pct is not None:
            index.append(", ")
            index.append(f"{pct:.1f} %", "bold green" if pct >= 95 else "bold")
            index.append(" of bound")
        table.add_row("index", index)
        search = f"{r.get('method', '')} {_num(r.get('seconds'))} s"
        travel = (r.get("travel_time") or {}).get("ordered")
        if travel is not None:
            search += f", travel {travel:.0f} s"
        table.add_row("search", search)
        parameters = self._parameters(r)
        if parameters is not None:
            table.add_row("parameters", parameters)
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
                Series(p[:, a], p[:, b], style="cyan", marker="•", label="pose"),
                Series(base, base, style="bold yellow", marker="R", label="base"),
                Series(t[a:a + 1], t[b:b + 1], style="bold magenta", marker="T", label="tracker",
                       optional=True),
            ])


def _box(v: Any) -> str:
    return "(" + ",".join(f"{x:g}" for x in v) + ")"


def _num(v: Any) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:.4g}"
