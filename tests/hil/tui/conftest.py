"""Helpers of the terminal app's tests: the screen as plain text, waiting for a condition."""

from __future__ import annotations

import asyncio
import io
import os
import time
from collections.abc import Callable
from pathlib import Path

from rich.console import Console
from textual.app import App

SNAPSHOTS = Path(__file__).parent / "snapshots"


def screen_text(app: App) -> str:
    """What the terminal shows, as text (colours dropped), trailing blanks stripped."""
    width, height = app.size
    console = Console(width=width, height=height, file=io.StringIO(), force_terminal=True,
                      color_system="truecolor", record=True, legacy_windows=False, safe_box=False)
    console.print(app.screen._compositor.render_update(full=True, screen_stack=app._background_screens,
                                                       simplify=True))
    return "\n".join(line.rstrip() for line in console.export_text(styles=False).splitlines()) + "\n"


async def settled_text(pilot, timeout: float = 10.0) -> str:
    """What the terminal shows once the app has finished drawing: two frames alike in a row, with no
    layout, repaint or widget update pending. One `pilot.pause()` processes the messages queued so far,
    but a message's handler may queue more (a table's rows, then its scroll; a panel's text, then the
    layout that wraps it), and on a loaded machine a read taken in between caught the screen
    mid-layout. A screen that never settles is returned as it is at `timeout`, for the caller's
    assertion to show."""
    deadline = time.monotonic() + timeout
    previous: str | None = None
    while True:
        await pilot.pause()
        screen = pilot.app.screen
        text = screen_text(pilot.app)
        pending = screen._layout_required or screen._repaint_required or screen._dirty_widgets
        if (text == previous and not pending) or time.monotonic() > deadline:
            return text
        previous = text


def check_snapshot(app: App, name: str) -> None:
    """Compare the screen with snapshots/<name>.txt (``HIL_SNAPSHOT_UPDATE=1`` rewrites it)."""
    path = SNAPSHOTS / f"{name}.txt"
    text = screen_text(app)
    if os.environ.get("HIL_SNAPSHOT_UPDATE") == "1" or not path.exists():
        path.write_text(text, encoding="utf-8")
        return
    assert text == path.read_text(encoding="utf-8"), f"screen differs from {path}:\n{text}"


async def expect_snapshot(pilot, name: str, timeout: float = 10.0) -> None:
    """`check_snapshot` once the screen has drawn what it was told: on a loaded machine a part of it
    (the footer's keys, say) can come a frame later than the rest. A screen that never matches fails
    with its text."""
    path = SNAPSHOTS / f"{name}.txt"
    deadline = time.monotonic() + timeout
    if path.exists() and os.environ.get("HIL_SNAPSHOT_UPDATE") != "1":
        expected = path.read_text(encoding="utf-8")
        while screen_text(pilot.app) != expected and time.monotonic() < deadline:
            await pilot.pause(0.05)
    check_snapshot(pilot.app, name)


async def wait_for(pilot, condition: Callable[[], object], timeout: float, what: str) -> None:
    """Let the app run until `condition()` holds (fast-time simulation: seconds, not minutes)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out after {timeout} s waiting for {what}\n{screen_text(pilot.app)}")
        await pilot.pause(0.05)
        await asyncio.sleep(0)



async def press_to_close(pilot, key: str, timeout: float = 15.0) -> None:
    """Press a key that closes the app and wait until it has closed.

    The app closes asynchronously (its "stopping..." screen first, the station closed off the UI
    thread); `Pilot.press` would wait for screen messages that an exiting app never processes.
    """
    app = pilot.app
    await pilot.pause()  # the screen that takes the key is ready for it
    app.simulate_key(key)
    deadline = time.monotonic() + timeout
    while app.is_running:  # not pilot.pause: it too waits for the screen's messages
        if time.monotonic() > deadline:
            raise AssertionError(f"the app did not close within {timeout} s of {key}\n{screen_text(app)}")
        await asyncio.sleep(0.05)
