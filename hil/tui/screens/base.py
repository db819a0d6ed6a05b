"""What every main screen shares: the navigation bar, the footer and a typed handle on the app.

The screens reach the app only through `AppHandle`, the few things they read and ask of it, so they
never import the app module (which imports them).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol, cast

from textual.screen import Screen

if TYPE_CHECKING:
    from hil.tui.session import Session
    from hil.tui.state import RunState


class AppHandle(Protocol):
    """What a screen may use of the app (`hil.tui.app.HilApp` provides it)."""

    session: Session
    run_state: RunState
    now: Callable[[], float]

    def notify(self, message: str, *, severity: Any = ..., **options: Any) -> None: ...

    def start_selection(self, values: dict[str, Any]) -> None: ...

    def open_campaign(self, campaign: str, switch: bool = True) -> None: ...

    def start_history(self) -> None: ...

    def start_export(self, record: Any, kinds: list[str]) -> None: ...


class HilScreen(Screen[None]):
    """A main screen; `refresh_view` redraws it from the app's state (cheap, called on every change)."""

    name_key: str = ""

    @property
    def hil(self) -> AppHandle:
        return cast("AppHandle", self.app)

    def on_screen_resume(self) -> None:
        self.refresh_bindings()  # the footer otherwise keeps the previous screen's (empty) keys
        self.refresh_view()

    def refresh_view(self) -> None:
        """Redraw from the app's state."""
