"""The terminal app: one factory (`create_app`) for ``hil tui`` and for the tests.

The app owns the screens and the presentation state; the `Session` owns the station, the store and
the engine and works only on worker threads. Messages go one way (session → app, see
`hil.tui.messages`), requests the other (app → session, always through `run_worker(thread=True)`), so
the UI thread never waits on a device, the store or the selector.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from typing import Any, ClassVar

from rich.text import Text
from textual import on
from textual.app import App, ScreenStackError, SystemCommand
from textual.binding import Binding, BindingType
from textual.screen import ModalScreen, Screen
from textual.widgets import Input
from textual.worker import Worker, WorkerState

from hil.campaign.events import PlanReady, RunStarted
from hil.errors import EXIT_ABORTED, EXIT_FAILED, EXIT_FAULT, EXIT_INTERRUPTED, EXIT_OK
from hil.tui.messages import (
    CampaignLoaded,
    EarlierPoints,
    EngineEvent,
    Exported,
    HistoryLoaded,
    Notice,
    ResumeQuestion,
    RunEnded,
    SelectionDone,
    SelectionFailed,
    StationChanged,
)
from hil.tui.screens.base import HilScreen
from hil.tui.screens.dialogs import Confirm, HelpScreen, ResumeDialog, Stopping
from hil.tui.screens.history import HistoryScreen
from hil.tui.screens.pose_plan import PlanScreen
from hil.tui.screens.results import ResultsScreen
from hil.tui.screens.run import RunScreen
from hil.tui.screens.station import StationScreen
from hil.tui.session import CLOSE_WAIT, STOP_WAIT, Session, TuiOptions
from hil.tui.state import RunState
from hil.tui.widgets.nav import SCREENS
from hil.tui.words import plain

__all__ = ["HilApp", "TuiOptions", "create_app"]

POLL_SECONDS = 2.0  # station status refresh while idle
#: The app's exit code by the run's final status: as ``hil calibrate``'s. A quit mid-run leaves the
#: campaign interrupted (resumable), the code of an interruption, not of an abort (final).
EXIT_CODES = {"accepted": EXIT_OK, "rejected": EXIT_FAILED, "aborted": EXIT_ABORTED,
              "interrupted": EXIT_INTERRUPTED}
#: The simulated station's faults in the command palette (--sim): (fault, title, its arguments, what it
#: does, in the operator's words); the Help screen lists them too.
SIMULATOR_FAULTS: tuple[tuple[str, str, dict[str, Any], str], ...] = (
    ("protective_stop", "Simulator: protective stop", {}, "the arm stops as if it hit something"),
    ("clear", "Simulator: clear the protective stop", {}, "unlocks it, as the teach pendant would"),
    ("block_beam", "Simulator: block the tracker beam", {"on": True},
     "something comes between the tracker and the SMR"),
    ("block_beam", "Simulator: unblock the tracker beam", {"on": False},
     "the line of sight is clear again; the tracker locks back on"),
    ("emergency_stop", "Simulator: emergency stop", {}, "presses the emergency stop button"),
    ("release_emergency_stop", "Simulator: release the emergency stop", {}, "twists the button out"),
    ("power_on", "Simulator: power the arm on", {}, "as on the teach pendant, after an emergency stop"),
    ("brake_release", "Simulator: release the brakes", {}, "as on the teach pendant, after power on"),
)
#: How long the closing after a quit mid-run takes, as measured in tmux at 80x24 against the simulated
#: station (``hil tui --sim --speed 20``): 7 to 11 s from "yes" to the shell prompt, quitting while
#: measuring or selecting, on a 2-core PC under load averages of 20 to 47 (other sessions' test
#: suites; the same quits took 10.5 to 19 s before the unmount wait and the interpreter's teardown
#: were cut). The arm's stop is sent first; then the run records the campaign and closes the robot
#: link (1 s of it ur_rtde's two disconnects, 0.5 s each) and the tracker; then the store and the
#: simulator. On an idle machine it is shorter; the bound is the time-outs'.
CLOSING_TYPICALLY = "a few seconds"


def closing_time(bound: float) -> str:
    """What the Stopping dialog promises: the typical closing time and the time-outs' bound."""
    return f"the app closes in {CLOSING_TYPICALLY} (at most {bound:.0f} s)"


#: The run's phases that compute without moving the arm (and cannot be cut short): a quit does not wait.
COMPUTING = frozenset({"select", "identify", "validate"})


class HilApp(App[int]):
    """Calibration campaigns from a terminal; see the module docstring and the Help screen (``?``)."""

    CSS_PATH = "hil.tcss"
    TITLE = "hil"
    ENABLE_COMMAND_PALETTE = True
    BINDINGS: ClassVar[list[BindingType]] = [
        *(Binding(key, f"show('{name}')", title, show=False) for key, name, title in SCREENS),
        Binding("question_mark", "help", "Help"),
        Binding("q", "quit_app", "Quit"),
        Binding("ctrl+c", "quit_app", "Quit", show=False, priority=True),  # not Textual's "use ctrl+q"
    ]

    def __init__(self, options: TuiOptions, *, now: Callable[[], float] = time.time) -> None:
        super().__init__()
        self.options = options
        self.now = now  # the wall clock of elapsed waits (fixed in snapshot tests)
        self.session = Session(options, self.post_message)
        self.run_state = RunState()
        self.exit_code = 0
        self._stop_dialog: Stopping | None = None  # shown from the quit's "yes" until the app exits
        self._closing_station = False  # the station is being closed: the app exits when it is
        self._latest_asked = False  # Results asked the store for its latest campaign (at start-up)
        self.views: dict[str, HilScreen] = {
            "station": StationScreen(), "plan": PlanScreen(), "run": RunScreen(),
            "results": ResultsScreen(), "history": HistoryScreen()}

    # --- start and stop ------------------------------------------------------------------------------
    def on_mount(self) -> None:
        for name, screen in self.views.items():
            self.install_screen(screen, name)
        self.push_screen("station")
        if self.options.start_station:
            self.session.start()
        self.set_interval(POLL_SECONDS, self._poll)
        self.set_interval(1.0, self._tick)

    def on_unmount(self) -> None:
        # Every way out goes through action_quit_app, which has done this already (with a visible
        # "stopping..."); this is the last resort when the app ends otherwise. A run the quit gave
        # up (busy computing, its campaign marked interrupted) is not waited for again: that wait
        # once held the closed app for STOP_WAIT seconds after the screen was restored.
        if self.session.run_active and not self.session.run_given_up:
            self.session.interrupt()
            if not self.session.wait_for_run(STOP_WAIT):
                self.session.abandon_run()
        self.session.shutdown()

    def _top(self) -> Screen[Any] | None:
        """The screen on top, or None once the app is closing: its screens are gone while the run's
        messages (posted from other threads) can still arrive. Reading `screen` then raised
        ScreenStackError from a message handler, which ended a test that had timed out (the station
        starting slowly under load) with that error instead of the time-out."""
        try:
            return self.screen
        except ScreenStackError:
            return None

    def _poll(self) -> None:
        if self.session.devices is not None and not self.session.run_active:
            self._work(self.session.poll, "poll", exclusive=True)

    def _tick(self) -> None:
        screen = self._top()
        if self.run_state.active and isinstance(screen, RunScreen):
            screen.tick()

    def _work(self, fn: Callable[..., Any], group: str, *args: Any, exclusive: bool = False) -> Worker[Any]:
        """Run `fn` on a worker thread; its errors are shown, never raised into the UI."""
        return self.run_worker(lambda: fn(*args), thread=True, group=group, exclusive=exclusive,
                               exit_on_error=False, name=group)

    def on_worker_state_changed(self, event: Worker.StateChanged) -> None:
        if event.state == WorkerState.ERROR and event.worker.error is not None:
            self.notify(f"{event.worker.name}: {plain(event.worker.error)}", severity="error", timeout=10)

    # --- navigation ----------------------------------------------------------------------------------
    def action_show(self, name: str) -> None:
        screen = self._top()
        if screen is None or isinstance(screen, ModalScreen):
            return
        if screen is not self.views[name]:
            self.switch_screen(name)

    def action_help(self) -> None:
        if not isinstance(self._top(), HelpScreen | None):
            self.push_screen(HelpScreen(simulator=self.options.sim))

    def nav_status(self) -> Text:
        """The right-hand side of the navigation bar."""
        run, st = self.run_state, self.session.station
        if run.active:
            state = "SUSPENDED" if run.suspended else run.state
            style = "bold red" if run.suspended else "bold yellow" if state == "paused" else "bold green"
            return Text.assemble((state, style), f" {run.measured}/{run.planned}")
        style = {"connected": "green", "failed": "red"}.get(st.phase, "yellow")
        return Text(st.phase, style=style)

    def _refresh(self, *names: str) -> None:
        for name in names or tuple(self.views):
            self.views[name].redraw()

    # --- quitting ------------------------------------------------------------------------------------
    def action_quit(self) -> None:  # ctrl+q and the command palette's "Quit"
        self.action_quit_app()

    def action_help_quit(self) -> None:  # Textual's ctrl+c
        self.action_quit_app()

    def action_quit_app(self) -> None:
        """Every way out (q, ctrl+c, ctrl+q, the palette): one question mid-run, then the arm stops at
        once, the campaign is left interrupted (resumable) and the app closes, saying so meanwhile."""
        if self._stop_dialog is not None or any(isinstance(s, Confirm) and s.kind == "quit"
                                             for s in self.screen_stack):
            return
        if not self.session.run_active:
            self._stop_screen("closing the station...")
            self._close_station()
            return

        def answer(yes: bool | None) -> None:
            if yes and self.session.run_active:
                self._stop_run_and_quit()
            elif yes:
                self._stop_screen("closing the station...")
                self._close_station()

        self.push_screen(Confirm("A campaign is running. Quit?\nThe arm stops now; every measured point is "
                                 "kept and the next start resumes the campaign.", yes="Quit",
                                 no="Keep running", kind="quit"), answer)

    def _stop_screen(self, stage: str) -> None:
        if self._stop_dialog is None:
            self._stop_dialog = Stopping(stage)
            self.push_screen(self._stop_dialog)
        else:
            self._stop_dialog.stage(stage)

    def _stop_run_and_quit(self) -> None:
        """The arm first (`Session.interrupt`: the engine sends its stop at once), then the closing."""
        self._stop_screen("stopping the arm; the campaign stays resumable...")

        def stop() -> None:
            self.session.interrupt()
            self.call_from_thread(self._arm_stopped)

        self._work(stop, "stop")

    def _arm_stopped(self) -> None:
        """The stop is sent. A run that is measuring ends itself within `STOP_WAIT` (recording the
        campaign interrupted); one in a computation (selection, identification) moves nothing and
        cannot be cut short, so it is not waited for: the campaign is marked interrupted here."""
        if self._closing_station:
            return
        computing = self.run_state.phase in COMPUTING
        wait = 0.0 if computing else STOP_WAIT
        self._stop_screen(f"the arm is stopped. Saving the campaign as interrupted (resumable) and "
                          f"closing the station: {closing_time(wait + CLOSE_WAIT)}.")
        if computing:
            self._give_up_on_run()
        else:
            self.set_timer(wait, self._give_up_on_run)

    def _give_up_on_run(self) -> None:
        """The run did not end in time (busy computing): mark its campaign interrupted and close."""
        if self._closing_station or not self.session.run_active:
            return
        self._stop_screen("the run is busy computing: saving the campaign as interrupted...")

        def give_up() -> None:
            self.session.abandon_run()
            self.call_from_thread(self._close_station)

        self.exit_code = EXIT_INTERRUPTED
        self._work(give_up, "stop")

    def _close_station(self) -> None:
        """Close the devices, the store and the simulator off the UI thread, then exit."""
        if self._closing_station:
            return
        self._closing_station = True
        if self._stop_dialog is not None:
            saved = ("the arm is stopped and the campaign saved as interrupted (resumable); "
                     if self.session.quitting else "")
            self._stop_dialog.stage(f"{saved}closing the station: {closing_time(CLOSE_WAIT)}...")

        def close() -> None:
            self.session.shutdown()
            self.call_from_thread(self.exit, self.exit_code)

        self._work(close, "close")

    # --- station -------------------------------------------------------------------------------------
    def action_toggle_connection(self) -> None:
        st = self.session.station
        if st.phase in ("connecting", "starting"):
            return
        self._work(self.session.disconnect if st.connected else self.session.connect, "connect",
                   exclusive=True)

    def action_measure_now(self) -> None:
        self._work(self.session.measure_now, "measure", exclusive=True)

    def action_poll(self) -> None:
        self._work(self.session.poll, "poll", exclusive=True)

    def on_station_changed(self, _: StationChanged) -> None:
        self._refresh("station", "plan")  # the Plan panel's constraints come with the station's config
        top = self._top()
        for widget in top.query("NavBar") if top is not None else ():
            widget.refresh()
        plan = self.views["plan"]
        if isinstance(plan, PlanScreen) and plan.is_mounted and not plan.query_one("#in-poses", Input).value:
            plan.load_fields()
        if not self._latest_asked and self.session.store is not None:  # the store is open: Results
            self._latest_asked = True  # shows its latest campaign until a run or History shows another
            self._work(self.session.load_latest, "load")

    # --- plan ----------------------------------------------------------------------------------------
    def start_selection(self, values: dict[str, Any]) -> None:
        self._work(self.session.select, "select", values["campaign.calibration_poses"],
                   values["campaign.validation_poses"], values["campaign.candidates"],
                   values["campaign.index"], values["campaign.seed"], exclusive=True)

    def on_selection_done(self, message: SelectionDone) -> None:
        plan = self.views["plan"]
        assert isinstance(plan, PlanScreen)
        plan.show_selection(message.report, message.points, message.tracker, message.assumed_tracker,
                            "preview (s)")

    def on_selection_failed(self, message: SelectionFailed) -> None:
        plan = self.views["plan"]
        assert isinstance(plan, PlanScreen)
        plan.show_error(message.text)

    def _show_run_plan(self, event: PlanReady) -> None:
        """The plan the campaign chose, on the Plan screen (computed off the UI thread: FK of the poses)."""
        import numpy as np

        from hil.arm.geometry import Geometry
        from hil.arm.kinematics import Kinematics

        config = self.session.run_config()
        info = dict((event.selection or {}).get("calibration") or {})
        poses = [p["q"] for p in event.poses if p["role"] == "calibration"]
        if not poses:
            return
        tracker = event.tracker or {"xyz": [0.0, 0.0, 0.0], "rpy": [0.0, 0.0, 0.0]}
        nominal = Geometry.nominal(config.robot["type"], config.smr["offset"]).to_dict()
        geometry = Geometry.from_dict({**nominal, "tracker": tracker})
        points = Kinematics(geometry).points(np.array(poses), frame="base")
        info.update(count=len(poses), poses=poses)
        self.call_from_thread(self._plan_from_run, info, points, tuple(tracker["xyz"]))

    def _plan_from_run(self, info: dict[str, Any], points: Any, tracker: tuple[float, ...]) -> None:
        plan = self.views["plan"]
        assert isinstance(plan, PlanScreen)
        plan.show_selection(info, points, tracker, False, f"campaign {self.run_state.campaign}")

    # --- run -----------------------------------------------------------------------------------------
    def action_start_run(self) -> None:
        if self.session.run_active:
            self.notify("a run is already going", severity="warning")
            return
        if self.session.store is None:
            self.notify("the station is not ready yet", severity="warning")
            return
        self.notify("starting: connecting and checking for an unfinished campaign...")
        self._work(self.session.prepare_run, "run")

    def on_resume_question(self, message: ResumeQuestion) -> None:
        def answer(choice: str | None) -> None:
            if choice == "resume":
                self.session.start_run(message.campaign)
            elif choice == "new":
                self.session.start_run(None)

        self.push_screen(ResumeDialog(message.campaign, message.measured, message.planned,
                                      message.bootstrap), answer)

    def action_pause(self) -> None:
        if not self.session.run_active or self.session.engine is None:
            self.notify("no run to pause", severity="warning")
            return
        paused = self.session.pause()
        self.notify("pausing after the current step" if paused else "resuming")

    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """Skip / wait longer only while the run waits on a suspension (skip: one that can skip)."""
        s = self.run_state.suspended
        if action == "skip_pose":
            return s is not None and s.on_timeout == "skip"
        if action == "wait_longer":
            return s is not None
        return True

    def action_skip_pose(self) -> None:
        """Give up the pose the run is waiting on (a lost beam), now rather than at the time-out."""
        s = self.run_state.suspended
        if s is None or s.on_timeout != "skip":
            self.notify("no pose to skip: the run is not waiting on a lost beam", severity="warning")
            return
        self.session.skip_pose()
        self.notify("skipping this pose")

    def action_wait_longer(self) -> None:
        s = self.run_state.suspended
        if s is None:
            self.notify("the run is not waiting on anything", severity="warning")
            return
        self.session.wait_longer()

    def action_abort(self) -> None:
        if not self.session.run_active:
            self.notify("no run to abort", severity="warning")
            return

        def answer(yes: bool | None) -> None:
            if yes:
                self.session.abort()
                self.notify("aborting: the arm stops after the current step", severity="warning")

        self.push_screen(Confirm("Abort the campaign? It ends as 'aborted' and cannot be resumed.\n"
                                 "(To stop now and continue later, quit with q instead.)",
                                 yes="Abort", no="Keep running"), answer)

    def on_engine_event(self, message: EngineEvent) -> None:
        event = message.event
        suspended = self.run_state.suspended
        self.run_state.apply(event)
        if (suspended is None) != (self.run_state.suspended is None):
            self.views["run"].refresh_bindings()  # skip / wait longer come and go with a suspension
        top = self._top()
        if isinstance(event, RunStarted) and not isinstance(top, ModalScreen):
            self.action_show("run")
        if isinstance(event, PlanReady):
            self._work(self._show_run_plan, "plan-fk", event)
        run = self.views["run"]
        if top is run:
            run.redraw()
        elif top is not None:
            for widget in top.query("NavBar"):
                widget.refresh()

    def on_earlier_points(self, message: EarlierPoints) -> None:
        """A resumed run's points from before: in the Run table and plot, and its counts."""
        self.run_state.restore(message.campaign, message.points)
        run = self.views["run"]
        if self._top() is run:
            run.redraw()

    def on_run_ended(self, message: RunEnded) -> None:
        self.exit_code = EXIT_CODES.get(message.status, EXIT_FAULT)
        self.run_state.end(message.status, message.detail)
        self.views["run"].refresh_bindings()
        if message.quitting or self._stop_dialog is not None:
            self._stop_screen("closing the station...")
            self._close_station()
            return
        severity = "information" if message.status == "accepted" else "warning"
        if self.session.station.fault:
            severity = "error"
        self.notify(f"campaign {message.campaign}: {message.status}"
                    + (f" ({message.detail})" if message.detail else ""), severity=severity, timeout=8)
        self._refresh("run", "station")
        if message.campaign:
            self.open_campaign(message.campaign, switch=message.status in ("accepted", "rejected"))

    # --- results and history -------------------------------------------------------------------------
    def open_campaign(self, campaign: str, switch: bool = True) -> None:
        self._switch_to_results = switch
        self._work(self.session.load_campaign, "load", campaign, exclusive=True)

    def on_campaign_loaded(self, message: CampaignLoaded) -> None:
        results = self.views["results"]
        assert isinstance(results, ResultsScreen)
        if message.latest and results.record is not None:
            return  # a run or History was quicker: theirs stays
        results.show(message.record)
        if not message.latest and getattr(self, "_switch_to_results", True):
            self.action_show("results")

    def start_history(self) -> None:
        self._work(self.session.load_history, "history", exclusive=True)

    def on_history_loaded(self, message: HistoryLoaded) -> None:
        history = self.views["history"]
        assert isinstance(history, HistoryScreen)
        history.show(message.rows, message.database)

    def start_export(self, record: Any, kinds: list[str]) -> None:
        self._work(self.session.export, "export", record, kinds)

    def on_exported(self, message: Exported) -> None:
        results = self.views["results"]
        assert isinstance(results, ResultsScreen)
        results.exported(message.paths, message.error)
        if message.error:
            self.notify(f"export: {message.error}", severity="error", timeout=8)
        elif message.paths:
            self.notify(f"wrote {len(message.paths)} file(s) (paths on the Results screen)", timeout=4)

    @on(Notice)
    def _notice(self, message: Notice) -> None:
        severity = message.severity if message.severity in ("warning", "error") else "information"
        self.notify(message.text, severity=severity,  # type: ignore[arg-type]
                    timeout=10 if severity == "error" else 4)

    def _inject(self, fault: str, args: dict[str, Any]) -> None:
        self._work(lambda: self.session.inject(fault, **args), "sim")

    # --- command palette -----------------------------------------------------------------------------
    def get_system_commands(self, screen: Screen[Any]) -> Iterable[SystemCommand]:
        for key, name, title in SCREENS:
            yield SystemCommand(f"Go to {title}", f"the {title} screen (key {key})",
                                lambda name=name: self.action_show(name))
        yield SystemCommand("Connect / disconnect", "the robot and the tracker (Station, c)",
                            self.action_toggle_connection)
        yield SystemCommand("Measure now", "one SMR point with the tracker (Station, m)",
                            self.action_measure_now)
        yield SystemCommand("Start campaign", "run (or resume) a calibration campaign (Run, g)",
                            self.action_start_run)
        yield SystemCommand("Pause / resume run", "between steps (Run, p)", self.action_pause)
        yield SystemCommand("Abort run", "ends the campaign as aborted (Run, a)", self.action_abort)
        yield SystemCommand("Help", "every key (?)", self.action_help)
        if self.options.sim:
            for fault, title, args, what in SIMULATOR_FAULTS:
                yield SystemCommand(title, what, lambda f=fault, a=args: self._inject(f, a))
        yield from super().get_system_commands(screen)


def create_app(options: TuiOptions | None = None, **kwargs: Any) -> HilApp:
    """The app for ``hil tui`` and for the tests (`TuiOptions` fields as keywords, or `options`)."""
    now = kwargs.pop("now", time.time)
    return HilApp(options or TuiOptions(**kwargs), now=now)
