"""Modal dialogs: help, a yes/no question (quit or abort mid-run), resume-or-new, "stopping..."."""

from __future__ import annotations

import time
from typing import ClassVar

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.screen import ModalScreen
from textual.widgets import Button, Static

from hil.tui.words import progress_words

HELP = """\
[b]Screens[/b]   1 Station  2 Plan  3 Run  4 Results  5 History
[b]Anywhere[/b]  ? help  q quit (ctrl+c too)  ctrl+p commands  tab next field
[b]Station[/b]   c connect/disconnect  m measure SMR now  r refresh
[b]Plan[/b]      s select poses  u use for next run  esc leave field
          w warm-up on/off for the next run (off: as --no-warmup)
[b]Run[/b]       g start or resume  p pause/resume  a abort
          s skip the pose (beam lost)  w wait longer
[b]Results[/b]   m model  u URDF  y ROS YAML  h HTML report  x all
[b]History[/b]   enter open in Results  r reload

"""

HELP += ("A run pauses by itself when the beam is lost, on a protective stop or when a link drops, "
         "says what to do, and goes on once the cause is cleared; a lost beam skips its pose after a "
         "countdown. Quitting mid-run stops the arm at once and keeps the campaign resumable, as an "
         "emergency stop does: the next start (here or hil calibrate) continues it.")


#: With --sim, the faults the command palette injects into the simulated station.
SIMULATOR_HELP = ("[b]Simulator[/b] (ctrl+p) block the tracker beam, unblock it; protective stop,\n"
                  "          clear it; emergency stop, release it; power on; release brakes\n\n")


class HelpScreen(ModalScreen[None]):
    """Every key of the app on one page (and the simulator's faults, with --sim)."""

    BINDINGS: ClassVar[list[BindingType]] = [Binding("escape,question_mark,q", "dismiss", "Close")]

    def __init__(self, simulator: bool = False) -> None:
        super().__init__()
        self.simulator = simulator

    def compose(self) -> ComposeResult:
        text = HELP
        if self.simulator:
            head, _, tail = HELP.partition("\n\n")
            text = f"{head}\n{SIMULATOR_HELP}{tail}"
        with Vertical(id="dialog", classes="help"):
            yield Static(text, id="help-text")
            yield Static("[dim]esc or ? closes[/dim]")


class Confirm(ModalScreen[bool]):
    """A yes/no question; y / n / esc answer it."""

    BINDINGS: ClassVar[list[BindingType]] = [Binding("y", "answer(True)", "Yes"),
                                             Binding("n,escape", "answer(False)", "No")]

    def __init__(self, question: str, yes: str = "Yes", no: str = "No", kind: str = "") -> None:
        super().__init__()
        self.question, self.yes, self.no, self.kind = question, yes, no, kind

    def compose(self) -> ComposeResult:
        with Vertical(id="dialog"):
            yield Static(self.question, id="question")
            with Horizontal(classes="buttons"):
                yield Button(f"{self.yes} (y)", id="yes", variant="error", compact=True)
                yield Button(f"{self.no} (n)", id="no", compact=True)

    def action_answer(self, value: bool) -> None:
        self.dismiss(value)

    def on_button_pressed(self, event: Button.Pressed) -> None:
        self.dismiss(event.button.id == "yes")


class ResumeDialog(ModalScreen[str]):
    """An unfinished campaign exists: resume it (r), start a new one (n) or cancel (esc)."""

    BINDINGS: ClassVar[list[BindingType]] = [Binding("r", "answer('resume')", "Resume"),
                                             Binding("n", "answer('new')", "New"),
                                             Binding("escape", "answer('cancel')", "Cancel")]

    def __init__(self, campaign: str, measured: int, planned: int, bootstrap: int = 0) -> None:
        super().__init__()
        self.campaign, self.measured, self.planned, self.bootstrap = campaign, measured, planned, bootstrap

    def compose(self) -> ComposeResult:
        with Vertical(id="dialog"):
            yield Static(f"Campaign [b]{self.campaign}[/b] of this station, robot and configuration "
                         f"is unfinished ({progress_words(self.measured, self.planned, self.bootstrap)}).\n"
                         "Resume it, measuring only what is missing, or start a new campaign?",
                         id="question")
            with Horizontal(classes="buttons"):
                yield Button("Resume (r)", id="resume", variant="primary", compact=True)
                yield Button("New (n)", id="new", compact=True)
                yield Button("Cancel (esc)", id="cancel", compact=True)

    def action_answer(self, value: str) -> None:
        self.dismiss(value)

    def on_button_pressed(self, event: Button.Pressed) -> None:
        self.dismiss(str(event.button.id))


class Stopping(ModalScreen[None]):
    """Shown from a quit's "yes" until the app exits: what it is doing, and for how long so far."""

    def __init__(self, stage: str) -> None:
        super().__init__()
        self._stage, self._t0 = stage, time.monotonic()

    def compose(self) -> ComposeResult:
        with Vertical(id="dialog"):
            yield Static(id="stopping")

    def on_mount(self) -> None:
        self._show()
        self.set_interval(0.5, self._show)

    def stage(self, text: str) -> None:
        self._stage = text
        if self.is_mounted:
            self._show()

    def _show(self) -> None:
        waited = time.monotonic() - self._t0
        self.query_one("#stopping", Static).update(Text.assemble(
            ("Stopping... ", "bold"), f"{waited:.0f} s\n{self._stage}\nThe app closes by itself."))
