"""What every main screen shares: the navigation bar, the footer, a typed handle on the app, and
in a terminal smaller than `MIN_SIZE`, a notice saying so instead of a cut-off screen.

The screens reach the app only through `AppHandle`, the few things they read and ask of it, so they
never import the app module (which imports them).
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol, cast

from textual.css.query import NoMatches
from textual.geometry import Size
from textual.screen import Screen
from textual.widgets import Static

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


#: The smallest terminal the screens are laid out for (columns, rows).
MIN_SIZE = (80, 24)


def too_small(size: Size) -> str | None:
    """The notice for a terminal smaller than `MIN_SIZE`, or None."""
    width, height = MIN_SIZE
    if size.width >= width and size.height >= height:
        return None
    return (f"This terminal is {size.width}×{size.height}; hil needs at least {width}×{height}.\n"
            "Enlarge the window (or use a smaller font). q quits.")


class HilScreen(Screen[None]):
    """A main screen; `refresh_view` redraws it from the app's state (cheap, called on every change)."""

    name_key: str = ""

    @property
    def hil(self) -> AppHandle:
        return cast("AppHandle", self.app)

    def on_screen_resume(self) -> None:
        self.refresh_bindings()  # the footer otherwise keeps the previous screen's (empty) keys
        self.fit_terminal(self.app.size)
        self.redraw()

    def redraw(self) -> None:
        """`refresh_view` from outside the screen's own handlers: a state change (or the screen
        becoming current) can come while the screen is mounted but its widgets are not yet; the
        screen then draws itself when they are (its on_mount), so nothing is lost by waiting."""
        with contextlib.suppress(NoMatches):
            self.refresh_view()

    def on_resize(self, event: Any) -> None:
        self.fit_terminal(event.size)

    def fit_terminal(self, size: Size) -> None:
        """Below `MIN_SIZE`, hide the screen behind a notice of the size it needs (class -too-small)."""
        notice = too_small(size)
        if notice is not None:
            found = self.query("#too-small")
            if found:
                found.first(Static).update(notice)
            else:
                self.mount(Static(notice, id="too-small"))
        self.set_class(notice is not None, "-too-small")

    def refresh_view(self) -> None:
        """Redraw from the app's state."""
