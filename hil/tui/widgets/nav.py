"""The one-line navigation bar at the top of every screen: where you are, how to go elsewhere, and
what the station and the run are doing (so a suspended run is visible from every screen)."""

from __future__ import annotations

from rich.text import Text
from textual.widget import Widget

SCREENS: tuple[tuple[str, str, str], ...] = (
    ("1", "station", "Station"),
    ("2", "plan", "Plan"),
    ("3", "run", "Run"),
    ("4", "results", "Results"),
    ("5", "history", "History"),
)


class NavBar(Widget):
    """Screen keys (the current one highlighted) and a short status on the right."""

    DEFAULT_CSS = "NavBar { height: 1; dock: top; background: $panel; }"

    def __init__(self, current: str) -> None:
        super().__init__()
        self.current = current

    def render(self) -> Text:
        out = Text(" hil ", style="bold reverse")
        for key, name, title in SCREENS:
            style = "bold reverse" if name == self.current else ""
            out.append(" ")
            out.append(f"{key} {title}", style=style or "")
        status_fn = getattr(self.app, "nav_status", None)
        status = status_fn() if callable(status_fn) else Text()
        room = self.content_size.width - out.cell_len - 1
        if room > 3 and status.cell_len:
            status.truncate(room, overflow="ellipsis")
            out.append(" " * max(1, room - status.cell_len + 1))
            out.append_text(status)
        return out
