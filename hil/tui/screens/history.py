"""History: the campaigns in the store, newest first; enter opens one in Results."""

from __future__ import annotations

import time
from typing import Any, ClassVar

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.widgets import DataTable, Footer, Static

from hil.tui.screens.base import HilScreen
from hil.tui.widgets.nav import NavBar

_STATUS_STYLE = {"accepted": "green", "verified": "green", "rejected": "red", "failed": "red",
                 "aborted": "yellow", "interrupted": "yellow"}


def status_words(summary: Any) -> str:
    """A campaign's status as ``hil history`` says it: a finished verification (ISO 9283 pose test, no
    model) is ``verified``, not ``accepted``."""
    if getattr(summary, "kind", "calibration") == "verification" and summary.status == "accepted":
        return "verified"
    return str(summary.status)


class HistoryScreen(HilScreen):
    """Past campaigns; the table is reloaded from the store (on a worker) each time it is shown."""

    name_key = "history"
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("enter", "open", "Open in Results", priority=True),
        Binding("r", "reload", "Reload"),
    ]

    def __init__(self) -> None:
        super().__init__()
        self.rows: list = []
        self.database = ""

    def compose(self) -> ComposeResult:
        yield NavBar("history")
        table: DataTable[Text] = DataTable(id="campaigns", cursor_type="row", zebra_stripes=True)
        table.add_columns(*(Text(c) for c in ("campaign", "updated", "robot", "status", "poses",
                                             "val [mm]")))
        yield table
        yield Static(id="database")
        yield Footer()

    def on_screen_resume(self) -> None:
        self.action_reload()

    def action_reload(self) -> None:
        self.hil.start_history()

    def action_open(self) -> None:
        table: DataTable[Text] = self.query_one("#campaigns", DataTable)
        if not self.rows or table.cursor_row < 0:
            return
        self.hil.open_campaign(self.rows[table.cursor_row].id)

    def on_data_table_row_selected(self, event: DataTable.RowSelected) -> None:
        self.action_open()

    def show(self, rows: list, database: str) -> None:
        self.rows, self.database = rows, database
        self.refresh_view()

    def refresh_view(self) -> None:
        if not self.is_mounted:
            return
        self.query_one(NavBar).refresh()
        table: DataTable[Text] = self.query_one("#campaigns", DataTable)
        cursor = table.cursor_row
        table.clear()
        for c in self.rows:
            rms = "-" if c.validation_rms is None else f"{c.validation_rms * 1e3:.4f}"
            status = status_words(c)
            table.add_row(Text(c.id), Text(time.strftime("%m-%d %H:%M", time.localtime(c.updated))),
                          Text(c.robot), Text(status, style=_STATUS_STYLE.get(status, "")),
                          Text(f"{c.measured}/{c.planned}"), Text(rms, justify="right"))
        if self.rows:
            table.move_cursor(row=min(max(cursor, 0), len(self.rows) - 1))
        n = len(self.rows)
        text = (f"{n} campaign{'' if n == 1 else 's'} in {self.database}" if self.rows
                else f"no campaigns yet in {self.database or 'the store'}")
        self.query_one("#database", Static).update(Text(text, style="dim"))
