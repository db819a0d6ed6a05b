"""What every main screen shares: the navigation bar, the footer and a typed handle on the app."""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

from textual.screen import Screen

if TYPE_CHECKING:
    from hil.tui.app import HilApp


class HilScreen(Screen[None]):
    """A main screen; `refresh_view` redraws it from the app's state (cheap, called on every change)."""

    name_key: str = ""

    @property
    def hil(self) -> HilApp:
        return cast("HilApp", self.app)

    def on_screen_resume(self) -> None:
        self.refresh_bindings()  # the footer otherwise keeps the previous screen's (empty) keys
        self.refresh_view()

    def refresh_view(self) -> None:
        """Redraw from the app's state."""
