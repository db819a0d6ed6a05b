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

_PHASE_STYLE = {"connected": "bold green", "in run": "bold cyan", "connecting": "yellow",
                "starting": "yellow", "failed": "bold red", "disconnected": "bold"}


def _kv(rows: list[tuple[str, str, str]]) -> Table:
    table = Table.grid(padding=(0, 1))
    table.add_column(style="dim", no_wrap=True, min_width=8)
    table.add_column(no_wrap=True, overflow="ellipsis")
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
        self.query_one("#station-error", Static).update(Text(st.error, style="bold red"))
        self.query_one(NavBar).refresh()


def _firmware(tracker: dict) -> str:
    """Firmware, and the interface the tracker is spoken to by ("3.6.0 (emScon TPI 3.6.0)")."""
    interface = tracker.get("interface")
    return f"{tracker.get('firmware', '')} ({interface})" if interface else tracker.get("firmware", "")
