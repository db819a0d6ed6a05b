"""Station: is the robot connected and in a state to move, is the tracker locked on the SMR?"""

from __future__ import annotations

from typing import ClassVar

from rich.table import Table
from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal
from textual.widgets import Footer, Static

from hil.tui.screens.base import HilScreen
from hil.tui.widgets.nav import NavBar
from hil.tui.words import progress_words

_PHASE_STYLE = {"connected": "bold green", "in run": "bold cyan", "connecting": "yellow",
                "starting": "yellow", "failed": "bold red", "disconnected": "bold"}


def _kv(rows: list[tuple[str, str, str]]) -> Table:
    table = Table.grid(padding=(0, 1))
    table.add_column(style="dim", no_wrap=True, min_width=8)
    table.add_column(overflow="fold")  # wrapped, never cut (a long tracker URL, a robot's fault)
    for key, value, style in rows:
        table.add_row(key, Text(value or "-", style=style))
    return table


class StationScreen(HilScreen):
    """Connection state of the robot and the tracker; connect, disconnect, measure the SMR now."""

    name_key = "station"
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("c", "app.toggle_connection", "Connect/disconnect"),
        Binding("m", "app.measure_now", "Measure now"),
        Binding("r", "app.poll", "Refresh"),
    ]

    def compose(self) -> ComposeResult:
        yield NavBar("station")
        yield Static(id="station-line")
        with Horizontal(id="devices"):
            yield Static(id="robot", classes="panel")
            yield Static(id="tracker", classes="panel")
        yield Static(id="last-point", classes="panel")
        yield Static(id="station-error")
        yield Static(id="station-note")
        yield Footer()

    def on_mount(self) -> None:
        self.query_one("#robot").border_title = "Robot"
        self.query_one("#tracker").border_title = "Tracker"
        self.query_one("#last-point").border_title = "Measure now (m)"
        self.refresh_view()

    def refresh_view(self) -> None:
        if not self.is_mounted:
            return
        st = self.hil.session.station
        line = Text()
        line.append(st.name or "station", "bold")
        if st.simulated:
            line.append(f"  simulated ({st.detail})" if st.detail else "  simulated", "italic")
        line.append("   ")
        line.append(st.phase.upper(), _PHASE_STYLE.get(st.phase, ""))
        self.query_one("#station-line", Static).update(line)
        safety_style = "green" if st.safety.startswith("normal") else "bold red" if st.safety != "-" else ""
        robot = st.robot
        self.query_one("#robot", Static).update(_kv([
            ("address", st.robot_address, ""),
            ("model", robot.get("model", ""), ""),
            ("serial", robot.get("serial", ""), ""),
            ("software", robot.get("software", ""), ""),
            ("safety", st.safety, safety_style),
        ]))
        tracker = st.tracker
        lock_style = "green" if st.lock == "locked in" else "bold red" if st.lock != "-" else ""
        self.query_one("#tracker", Static).update(_kv([
            ("link", st.tracker_url, ""),
            ("name", tracker.get("name", ""), ""),
            ("serial", tracker.get("serial", ""), ""),
            ("firmware", _firmware(tracker), ""),
            ("lock", st.lock, lock_style),
        ]))
        self.query_one("#last-point", Static).update(
            Text(st.last_point or "not measured yet", style="" if st.last_point else "dim"))
        self.query_one("#station-error", Static).update(fault_text(st.fault, st.steps, st.error))
        self.query_one("#station-note", Static).update(unfinished_text(st.unfinished))
        self.query_one(NavBar).refresh()


def fault_text(fault: str, steps: tuple[str, ...], error: str = "") -> Text:
    """A fault the operator must clear by hand and the steps that clear it, then the last error."""
    text = Text()
    if fault:
        text.append(f" {fault} ", "bold reverse red")
        text.append("  the arm is stopped. To go on:\n", "bold red")
        for k, step in enumerate(steps, 1):
            text.append(f"  {k}. {step}\n")
    if error:
        text.append(error, "bold red")
    return text


def unfinished_text(unfinished: tuple[str, int, int, int] | None, line: bool = False) -> Text:
    """The resumable campaign of this station, and how to resume it (`line`: on one line)."""
    if unfinished is None:
        return Text()
    campaign, measured, planned, bootstrap = unfinished
    if line:
        done = f"{measured}/{planned}" if planned else f"{bootstrap} bootstrap" if bootstrap else "0"
        return Text.assemble(("unfinished ", "bold yellow"), (campaign, "bold"),
                             f" ({done} measured): ", ("g resumes it", "bold"))
    return Text.assemble(("Unfinished campaign ", "bold yellow"), (campaign, "bold"),
                         f": {progress_words(measured, planned, bootstrap)}.\n",
                         ("g on the Run screen (3) resumes it", "bold"), ", or starts a new one.")


def _firmware(tracker: dict) -> str:
    """Firmware, and the interface the tracker is spoken to by ("3.6.0 (emScon TPI 3.6.0)")."""
    interface = tracker.get("interface")
    return f"{tracker.get('firmware', '')} ({interface})" if interface else tracker.get("firmware", "")
