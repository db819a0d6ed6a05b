"""The app's link to the station, the store and the engine. Every method that blocks runs on a worker
thread; results reach the UI only as messages (`hil.tui.messages`), posted thread-safely.

It takes the station and runs campaigns the way ``hil calibrate`` does, through the same functions
(`hil.jobs.station.take_station`, `hil.jobs.calibration.run_calibration`): the same lock, devices,
controller check, store claim, resume rules, critical subscribers and result document, so a campaign
run from the terminal app is the same campaign as a headless one. The differences are the operator's:

* the robot and tracker stay connected between runs (the Station screen reads their status and can
  measure the SMR); a run takes the open devices over and the session reconnects afterwards;
* quitting mid-run (`interrupt`) stops the arm at once and ends the run as ``interrupted`` rather
  than ``aborted``: ``aborted`` is final in the store, ``interrupted`` is resumable, so the next start
  (from the app or ``hil calibrate``) continues it. An emergency stop ends the run the same way: the
  campaign waits for the operator to recover the arm and resume it;
* the run works on a daemon thread of its own (`start_run`), not on one of Textual's workers, which
  the process waits for on exit: a quit never waits for a run stuck in a long computation — the app
  marks the campaign interrupted itself (`abandon_run`) and closes, at once during a computation,
  after `STOP_WAIT` seconds if a measuring run has not ended by then.

The simulated station's process is started and stopped by one long-lived thread (`_host_main`), which
keeps it for the app's lifetime; the simulator watches its parent's pid and exits when this process
is gone, however it ends (`mocks.ur.process`), so it is never left behind.
"""

from __future__ import annotations

import contextlib
import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from textual.message import Message

from drivers.robot.model import RobotIdentity
from hil.campaign.engine import Engine
from hil.campaign.events import Event, PointMeasured, RunFinished, RunStarted
from hil.errors import InputError
from hil.jobs.calibration import StoreGate
from hil.jobs.station import SimulatedSpec, StationSource, TakenStation, station_setup, take_station
from hil.jobs.words import outage_words
from hil.station.config import StationConfig
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
from hil.tui.state import StationState
from hil.tui.words import ESTOP_STEPS, plain, technical

log = logging.getLogger(__name__)

INTERRUPTED = "interrupted"  # not in hil.store.FINISHED: resumable
QUIT_REASON = "quit from the terminal app mid-run; resumable"
STOP_WAIT = 8.0  # seconds a quit waits for a measuring run to stop before marking the campaign itself
CLOSE_WAIT = 15.0  # seconds closing the station may take at most (devices, store, simulator)

#: Export actions of the Results screen: key -> (file suffix, hil.calibration.exports format or "html").
EXPORTS: dict[str, tuple[str, str]] = {
    "model": ("-model.json", "json"),
    "urdf": (".urdf", "urdf"),
    "ros": ("-kinematics.yaml", "ros-kinematics"),
    "report": ("-report.html", "html"),
}


@dataclass
class TuiOptions:
    """How ``hil tui`` was started (also what the tests pass to `hil.tui.app.create_app`)."""

    config: StationConfig | None = None  # --config, already loaded and checked
    sim: bool = False
    speed: float = 1.0
    seed: int = 1
    robot: str = "ur5e"
    truth: str | None = None
    tracker_protocol: str = "geocom"  # --sim: which of the simulated tracker's protocols to talk
    ideal: bool | None = None  # --sim without a truth: the ideal arm (None: the simulator's default)
    db: str | None = None
    out_dir: str = "."
    overrides: dict[str, Any] = field(default_factory=dict)  # "campaign.seed" or "campaign__seed" keys
    no_warmup: bool = False  # --no-warmup: as ``hil calibrate --no-warmup`` (the Plan screen's w toggles it)
    connect: bool = True  # connect to the robot and tracker at start
    start_station: bool = True  # False: no station at all (snapshot tests feed the screens by hand)


def station_source(options: TuiOptions) -> StationSource:
    """Where the app's station comes from (`hil.jobs.station`): the configuration, or the simulator."""
    overrides = _dotted(options.overrides)
    if not options.sim:  # --config (checked by `hil.cli.tui`; the tests' stations have none)
        return StationSource(config=options.config, overrides=overrides)
    return StationSource(sim=SimulatedSpec(options.robot, options.truth, options.speed, options.seed,
                                           options.tracker_protocol, options.ideal), overrides=overrides)


def _error(exc: BaseException) -> str:
    """The error in the operator's words; its class and text go to the log."""
    log.info("%s", technical(exc))
    return plain(exc)


def _is_verification(record: Any) -> bool:
    """Whether a stored campaign is an ISO 9283 pose test (``hil verify``), whose report is its own."""
    from hil.store.records import VERIFICATION

    return getattr(record.summary, "kind", "") == VERIFICATION


def _dotted(overrides: dict[str, Any]) -> dict[str, Any]:
    return {k.replace(".", "__"): v for k, v in overrides.items()}


class Session:
    """Station, store and runs of one app (see the module docstring)."""

    def __init__(self, options: TuiOptions, post: Callable[[Message], Any]) -> None:
        self.options = options
        self._post = post
        self.station = StationState(simulated=options.sim)
        self.config: StationConfig | None = None
        self.identity: dict[str, Any] | None = None
        self.truth: dict[str, Any] | None = None
        self.sim: Any = None
        self.store: Any = None
        self.devices: Any = None
        self.engine: Engine | None = None
        self.plan_overrides: dict[str, Any] = {}  # campaign.* keys set on the Plan screen
        # measure without warming the arm up (``--no-warmup``, the Plan screen's w): as the CLI's, it
        # overrides warmup.enabled for the next run and is not part of what identifies the campaign
        self.no_warmup = options.no_warmup
        self.run_active = False
        self.run_campaign: str = ""  # the campaign of the run going on (once it has one)
        self.paused = False
        self.quitting = False
        self._run_thread: threading.Thread | None = None
        self._gate = StoreGate()  # the run's store writes vs. `abandon_run`
        self._device_lock = threading.Lock()
        self._stop = threading.Event()
        self.ready = threading.Event()
        self._host: threading.Thread | None = None
        self._held: contextlib.ExitStack | None = None  # the station taken (`_take`), while we have it
        self._taken: TakenStation | None = None

    # --- plumbing ----------------------------------------------------------------------------------
    def post(self, message: Message) -> None:
        try:
            self._post(message)
        except Exception:  # the app is gone (shutting down): nothing left to show it on
            log.debug("dropped %r", message, exc_info=True)

    def changed(self) -> None:
        self.post(StationChanged())

    def notice(self, text: str, severity: str = "information") -> None:
        self.post(Notice(text, severity))

    def _say(self, text: str, severity: str = "information") -> None:
        """A job's words (`hil.jobs.words.Say`) as a notice."""
        self.notice(text, severity)

    # --- the station's lifetime ----------------------------------------------------------------------
    def start(self) -> None:
        """Start the station (simulator and store) on its own long-lived thread."""
        self._host = threading.Thread(target=self._host_main, name="hil-station", daemon=True)
        self._host.start()

    def _host_main(self) -> None:
        st = self.station
        st.detail = (f"speed {self.options.speed:g}x, seed {self.options.seed}" if self.options.sim
                     else "")
        self.changed()
        try:
            with station_setup(station_source(self.options)) as setup:
                from hil.store import Store

                config = setup.config
                self.config, self.identity, self.truth, self.sim = (config, setup.identity, setup.truth,
                                                                    setup.simulator)
                self.store = Store.open(self.options.db, config=config)
                self.store.on_outage = outage_words(self._say)
                st.name = config.station["name"]
                st.robot_address, st.tracker_url = config.robot["address"], config.tracker["url"]
                st.phase = "disconnected"
                self.ready.set()
                self.changed()
                if self.options.connect:
                    self.connect()
                self._stop.wait()
                self._close_devices()
                self.store.close()
        except Exception as exc:  # a station that cannot start is shown, not raised
            st.phase, st.error = "failed", f"the station did not start: {_error(exc)}"
            self.notice(st.error, "error")
            self.changed()
        finally:
            self.ready.set()

    def shutdown(self, timeout: float = CLOSE_WAIT) -> None:
        """Close the devices, the store and the simulator (waits for the station thread)."""
        self._stop.set()
        if self._host is not None:
            self._host.join(timeout)

    # --- devices -------------------------------------------------------------------------------------
    def _take(self, config: StationConfig) -> Any:
        """Take the station (`hil.jobs.station.take_station`: the arm's address lock, the devices, the
        controller's word on the robot type) and hold it until `_release`: while this app has the arm
        connected or runs on it, no other process of this host connects to it."""
        stack = contextlib.ExitStack()
        taken = stack.enter_context(take_station(config, what="hil tui"))
        self._held, self._taken = stack, taken
        return taken

    def _release(self) -> None:
        """Let go of the station taken by `_take` (its devices closed, the lock released)."""
        stack, self._held, self._taken = self._held, None, None
        if stack is not None:
            stack.close()

    def connect(self) -> None:
        """Open the robot and the tracker and read their status.

        A controller that reports another robot than the configured ``robot.type`` is refused here
        (`hil.station.robot_type.check_controller`): shown on the Station screen and disconnected, so
        the operator sees it at connect rather than when a run starts (which would refuse it too)."""
        from hil.station.robot_type import ControllerMismatch

        st = self.station
        if self.config is None:
            self.notice("the station is not ready yet", "warning")
            return
        with self._device_lock:
            if self.devices is not None or self.run_active:
                return
            st.phase, st.error = "connecting", ""
            self.changed()
            try:
                devices = self._take(self.config).devices
            except Exception as exc:
                # a controller of another robot: the configured kinematics would drive another arm, so
                # the station let go of it again
                refused = isinstance(exc, ControllerMismatch)
                what = "cannot use this robot" if refused else "cannot connect"
                st.phase, st.error = "disconnected", f"{what}: {_error(exc)}"
                if not refused:  # every driver error, and a bad tracker URL, is the operator's to see
                    self._safety_fault(exc)
                self.notice(st.error, "error")
                self.changed()
                return
            info, ident = devices.robot.info, devices.tracker.identity
            self.devices = devices
            st.robot = ({"model": info.model, "serial": info.serial, "software": info.software_version}
                        if info is not None else {})
            st.tracker = ({"name": ident.name, "serial": str(ident.serial_number),
                           "firmware": ".".join(map(str, ident.firmware)), "interface": ident.interface}
                          if ident is not None else {})
            st.phase = "connected"
            self._read_status()
        self.check_unfinished()
        self.changed()

    def _safety_fault(self, exc: BaseException | None) -> None:
        """The safety reading and the fault the operator must clear by hand, from a robot error."""
        from drivers.robot import errors as robot_errors

        st = self.station
        if isinstance(exc, robot_errors.EmergencyStop):
            st.safety, st.fault, st.steps = "EMERGENCY STOP", "EMERGENCY STOP", ESTOP_STEPS
        elif isinstance(exc, robot_errors.ProtectiveStop):
            st.safety = "PROTECTIVE STOP"
        elif exc is None:
            st.fault, st.steps = "", ()

    def check_unfinished(self) -> None:
        """Look for a resumable campaign of this station, robot and configuration (Station and Run
        screens say so at start-up and after a run, not only once g is pressed)."""
        st, store = self.station, self.store
        if store is None or self.identity is None or self.run_active:
            return
        devices = self.devices
        info = getattr(devices.robot, "info", None) if devices is not None else None
        try:
            campaign = store.find_resumable(self.run_identity(), robot_serial=info.serial if info else None)
            summary = store.campaign(campaign).summary if campaign else None
        except Exception as exc:
            log.info("looking for an unfinished campaign: %s", technical(exc))
            return
        st.unfinished = ((campaign, summary.measured, summary.planned, summary.bootstrap_measured)
                         if campaign and summary else None)

    def disconnect(self) -> None:
        with self._device_lock:
            if self.run_active:
                self.notice("a run is using the station; pause or abort it first", "warning")
                return
            self._close_devices()
            self.station.phase, self.station.safety, self.station.lock = "disconnected", "-", "-"
        self.changed()

    def _close_devices(self) -> None:
        devices, self.devices = self.devices, None
        if self._held is not None:
            self._release()  # closes the devices it opened, then releases the lock
        elif devices is not None:  # handed to the session as they are (tests)
            devices.close()

    def _read_status(self) -> None:
        """Safety status of the robot and lock status of the tracker (device lock held)."""
        from drivers.robot import errors as robot_errors
        from drivers.tracker.errors import TrackerError

        st, devices = self.station, self.devices
        if devices is None:
            return
        try:
            try:
                devices.robot.check_status()
            except robot_errors.ProgramStopped:
                # after a protective stop is unlocked the control script is gone: reload it, as the
                # run's own suspender does (refused while the controller is still not ready)
                devices.robot.reconnect()
                devices.robot.check_status()
            st.safety = "normal"
            self._safety_fault(None)
        except robot_errors.ProtectiveStop:
            st.safety = "PROTECTIVE STOP"
        except robot_errors.EmergencyStop as exc:
            self._safety_fault(exc)
        except robot_errors.ProgramStopped:
            st.safety = "program stopped"
        except robot_errors.SpeedSliderReduced as exc:
            st.safety = f"normal ({exc})"
        except robot_errors.RobotError as exc:
            st.safety = f"unknown ({_error(exc)})"
        try:
            st.lock = devices.tracker.lock_status()
        except TrackerError as exc:
            st.lock = f"unknown ({_error(exc)})"

    def poll(self) -> None:
        """Refresh the status readings, unless a run or another device action is using the devices."""
        if self.run_active or self.devices is None or not self._device_lock.acquire(blocking=False):
            return
        try:
            before = (self.station.safety, self.station.lock)
            self._read_status()
            changed = before != (self.station.safety, self.station.lock)
        finally:
            self._device_lock.release()
        if changed:
            self.changed()

    def measure_now(self) -> None:
        """Measure the SMR once, as the run would (samples and stability from the config)."""
        st = self.station
        with self._device_lock:
            if self.devices is None or self.config is None or self.run_active:
                self.notice("connect to the station first (c)" if not self.run_active
                            else "a run is using the tracker", "warning")
                return
            try:
                point = self.devices.tracker.measure_point(self.config.campaign["samples"])
            except Exception as exc:
                st.last_point = f"failed: {_error(exc)}"
                self.notice(f"measure now: {_error(exc)}", "error")
            else:
                x, y, z = (1e3 * v for v in point.xyz)
                spread = 1e6 * max(point.spread)
                st.last_point = (f"x {x:.3f}  y {y:.3f}  z {z:.3f} mm  (spread {spread:.1f} µm, "
                                 f"{point.samples} samples)")
                self.notice(f"SMR at {st.last_point}")
            self._read_status()
        self.changed()

    # --- runs ----------------------------------------------------------------------------------------
    def run_config(self) -> StationConfig:
        """The configuration the next run uses: the station's, with the Plan screen's changes and
        without the warm-up when it is skipped (`no_warmup`)."""
        assert self.config is not None
        overrides = _dotted(self.plan_overrides)
        if self.no_warmup:
            overrides["warmup__enabled"] = False
        return self.config.with_overrides(**overrides) if overrides else self.config

    def warmup_on(self) -> bool:
        """Whether the next run warms the arm up first (configured on, and not skipped)."""
        return self.config is not None and bool(self.run_config().warmup["enabled"])

    def run_identity(self) -> dict[str, Any]:
        """The configuration that identifies this run in the store (the Plan screen's changes included)."""
        assert self.identity is not None
        if not self.plan_overrides:
            return self.identity
        data = {section: dict(values) for section, values in self.identity.items()}
        for key, value in self.plan_overrides.items():
            section, name = key.split(".")
            data[section][name] = value
        return data

    def prepare_run(self) -> None:
        """Before a run: connect if needed, then ask about an unfinished campaign, or start."""
        if self.run_active:
            self.notice("a run is already going", "warning")
            return
        if self.store is None:
            self.notice("the station is not ready yet", "warning")
            return
        if self.devices is None:
            self.connect()
            if self.devices is None:
                return
        from hil.store import LeaseRefused

        serial = self.devices.robot.info.serial if self.devices.robot.info else None
        try:
            campaign = self.store.find_resumable(self.run_identity(), robot_serial=serial)
            # another process runs that campaign, or drives this arm: say who, offer nothing
            self.store.check_claim(campaign, serial or "")
            if campaign is not None:
                summary = self.store.campaign(campaign).summary
                self.post(ResumeQuestion(campaign, summary.measured, summary.planned,
                                         summary.bootstrap_measured))
                return
        except LeaseRefused as exc:
            self.notice(str(exc), "warning")
            return
        except Exception as exc:
            self.notice(f"store: {_error(exc)}", "error")
            return
        self.start_run(None)

    def start_run(self, resume_campaign: str | None) -> None:
        """`run` on a daemon thread of its own (see the module docstring); returns at once."""
        if self.run_active or (self._run_thread is not None and self._run_thread.is_alive()):
            self.notice("a run is already going", "warning")
            return

        def main() -> None:
            try:
                self.run(resume_campaign)
            except BaseException:  # never a traceback over the operator's screen
                log.exception("the run thread failed")

        self._run_thread = threading.Thread(target=main, name="hil-run", daemon=True)
        self._run_thread.start()

    def run(self, resume_campaign: str | None) -> None:
        """One campaign, as ``hil calibrate`` runs it (a new one, or `resume_campaign` continued), on the
        station this app holds (`hil.jobs.calibration.run_calibration`)."""
        from hil.jobs.calibration import CalibrationRequest, run_calibration
        from hil.jobs.station import StationSetup

        if self.run_active or self.config is None or self.store is None:
            return
        self.run_active, self._gate = True, StoreGate()
        st, store, gate = self.station, self.store, self._gate
        self.run_campaign = ""  # none of ours until claimed: a refused claim must not touch the campaign

        def claimed(campaign: str) -> None:
            self.run_campaign = campaign
            st.unfinished = None

        def to_station(event: Event) -> None:  # the Station screen's readings, from the run's events
            if st.apply(event):
                self.changed()

        error: BaseException | None = None
        taken: TakenStation | None = None
        devices: Any = None
        try:
            config = self.run_config()
            with self._device_lock:
                devices, self.devices = self.devices, None
            if devices is None:
                devices = self._take(config).devices
            st.phase = "in run"
            self.changed()
            assert self.identity is not None
            request = CalibrationRequest(station_source(self.options), identity=self.run_identity(),
                                         campaign=resume_campaign, resume="new", no_warmup=self.no_warmup)
            setup = StationSetup(config, self.identity, self.truth, self.sim)
            taken = self._taken
            if taken is None or taken.devices is not devices:  # devices handed to the session (tests)
                robot = RobotIdentity.of(config.robot["type"], devices.robot.info)
                taken = TakenStation(config, devices, robot)
            taken.store = store
            to_screens = (to_station, self._to_screens)
            out = run_calibration(request, setup, taken, subscribers=to_screens, say=self._say,
                                  engine_ready=self._engine_ready, gate=gate, status_of=self._final,
                                  on_claimed=claimed)
            status, detail = out.status, out.detail
            if out.run is not None and out.run.error is not None:
                error = out.run.error
        except Exception as exc:  # bad input found before motion, a store failure, a connect failure
            status, detail, error = "failed", _error(exc), exc
            if self.quitting:
                status = INTERRUPTED
            else:
                self.notice(f"the run stopped: {detail}", "error")
            if self.run_campaign:
                with contextlib.suppress(Exception):
                    gate.write(lambda: store.set_status(self.run_campaign, status, detail=detail))
        finally:  # the run's devices and the station's lock; connect() takes them again
            if self._held is not None:
                self._release()  # closes the devices unless the run did, and releases the lock
            elif devices is not None and not (taken is not None and taken.devices_closed):
                devices.close()  # handed to the session as they are (tests)
            self.engine = None
            self.run_active = False
            st.phase, st.safety, st.lock = "disconnected", "-", "-"
            self.changed()
        self._safety_fault(error)
        self.post(RunEnded(self.run_campaign, status, detail, self.quitting))
        if not self.quitting and not self._stop.is_set():
            self.connect()
            if self.devices is None:
                self.check_unfinished()
                self.changed()

    def _to_screens(self, event: Event) -> None:
        """A run's event to the screens; a resumed run's start brings the points measured before it
        (`EarlierPoints`), so the Run screen shows what the campaign already has."""
        self.post(EngineEvent(event))
        if isinstance(event, RunStarted) and event.resumed:
            self.post(EarlierPoints(event.campaign, self._earlier_points(event.campaign)))

    def _earlier_points(self, campaign: str) -> list[PointMeasured]:
        """The campaign's stored points, the latest of each pose — what the resume keeps
        (`hil.campaign.runner.resume_state` reads the same) — in measuring order, as the events the
        run would have shown; none if the store cannot say (the run goes on, its table without them)."""
        try:
            measured = self.store.measured_poses(campaign).values()
            targets = {p.index: p.target for p in self.store.campaign(campaign).poses}
        except Exception as exc:
            log.info("the points of %s: %s", campaign, technical(exc))
            return []
        return [PointMeasured(campaign=campaign, index=m.index, role=m.role, q=list(m.q), p=list(m.p),
                              p_spread=list(m.p_spread or ()), samples=m.samples, deviation=m.deviation,
                              q_spread=list(m.q_spread or ()), target=list(targets.get(m.index) or m.q),
                              t=m.t)
                for m in sorted(measured, key=lambda m: m.id)]

    def _final(self, outcome: Any, events: list[Event]) -> tuple[str, str]:
        """The campaign's status in the store and its plain-words detail.

        An emergency stop, and whatever a quit ends the run with, leave it ``interrupted``
        (resumable): nothing is wrong with the campaign, the operator carries on after recovering.
        """
        from drivers.robot.errors import EmergencyStop

        error = outcome.error
        if error is None:
            finished = next((e for e in reversed(events) if isinstance(e, RunFinished)), None)
            return outcome.status, finished.detail if finished is not None else ""
        detail = _error(error)
        if isinstance(error, EmergencyStop):
            return INTERRUPTED, f"{detail}; recover the arm, then resume the campaign"
        if self.quitting and outcome.status in ("aborted", "failed", INTERRUPTED):
            return INTERRUPTED, QUIT_REASON
        return outcome.status, detail

    def _engine_ready(self, engine: Engine) -> None:
        self.engine, self.paused = engine, False
        if self.quitting:
            engine.request_interrupt(QUIT_REASON)

    def interrupt(self) -> None:
        """Every way out of the app mid-run: stop the arm now and end the run as interrupted."""
        self.quitting = True
        engine = self.engine
        if engine is not None:
            engine.request_interrupt(QUIT_REASON)

    @property
    def run_given_up(self) -> bool:
        """Whether `abandon_run` gave the run up: its campaign is marked and its writes are dropped,
        so nothing is left to wait for, however long its thread still computes."""
        return self._gate.abandoned

    def wait_for_run(self, timeout: float) -> bool:
        """Wait (bounded) for the run thread to end; True if no run is left."""
        thread = self._run_thread
        if thread is not None:
            thread.join(timeout)
        return not self.run_active

    def abandon_run(self) -> str:
        """The run did not stop in time (a long computation): mark its campaign interrupted here and
        let the run write nothing more; returns the campaign (or "")."""
        campaign, store = self.run_campaign, self.store

        def mark() -> None:
            if campaign and store is not None:
                try:
                    store.set_status(campaign, INTERRUPTED, detail=QUIT_REASON)
                except Exception as exc:
                    log.info("marking %s interrupted: %s", campaign, technical(exc))

        if not self.run_active or not self._gate.abandon(mark):
            return ""
        return campaign

    def pause(self) -> bool:
        """Pause (True) or resume (False) the run; takes effect between steps."""
        engine = self.engine
        if engine is None:
            return False
        if self.paused:
            self.paused = False
            engine.request_resume()
            return False
        self.paused = True
        engine.request_pause()
        return True

    def abort(self) -> None:
        """End the run as aborted (final), after the current step."""
        if self.engine is not None:
            self.engine.request_abort()

    def skip_pose(self) -> None:
        """Give up the suspended pose now (a lost beam that does not come back)."""
        if self.engine is not None:
            self.engine.request_skip()

    def wait_longer(self) -> None:
        """Keep waiting for the suspension to clear: its time limit moves by its length again."""
        if self.engine is not None:
            self.engine.request_extend()

    # --- planning ------------------------------------------------------------------------------------
    def select(self, count: int, validation: int, candidates: int, index: str, seed: int) -> None:
        """Run the campaign's own pose chooser for a preview of the plan (Plan screen)."""
        from hil.arm.geometry import Geometry, look_at_tracker
        from hil.arm.kinematics import Kinematics
        from hil.calibration.selection import DEFAULT_TRACKER_FOR_JACOBIAN
        from hil.campaign.calibration_plan import CALIBRATION, SelectionRequest
        from hil.campaign.chooser import campaign_chooser

        if self.config is None:
            self.post(SelectionFailed("the station is not ready yet"))
            return
        try:
            config = self.config.with_overrides(
                campaign__calibration_poses=count, campaign__validation_poses=validation,
                campaign__candidates=candidates, campaign__index=index, campaign__seed=seed)
            position = config.tracker["position"]
            assumed = position is None
            where = tuple(float(v) for v in (DEFAULT_TRACKER_FOR_JACOBIAN if assumed else position))
            model = Geometry.nominal(config.robot["type"], config.smr["offset"], look_at_tracker(where))
            choice = campaign_chooser(config)(SelectionRequest(
                CALIBRATION, count, model=model,
                keep_in=(np.array(config.keep_in["min"]), np.array(config.keep_in["max"])),
                acceptance_angle=config.smr["acceptance_angle"], index=index, candidates=candidates,
                seed=seed, exclude=np.zeros((0, 6))))
            points = Kinematics(model).points(choice.poses, frame="base")
        except Exception as exc:  # an impossible request (InputError) or a selector failure
            self.post(SelectionFailed(str(exc) if isinstance(exc, InputError) else _error(exc)))
            return
        report = dict(choice.info, poses=choice.poses.tolist(), count=len(choice.poses))
        self.post(SelectionDone(report, points, where, assumed))

    # --- the store -----------------------------------------------------------------------------------
    def load_history(self, limit: int = 200) -> None:
        if self.store is None:
            return
        try:
            self.post(HistoryLoaded(self.store.campaigns(limit), self.store.location))
        except Exception as exc:
            self.notice(f"history: {_error(exc)}", "error")

    def load_latest(self) -> None:
        """The store's latest campaign, for the Results screen at start-up (none: nothing posted)."""
        if self.store is None:
            return
        try:
            rows = self.store.campaigns(1)
            if rows:
                self.post(CampaignLoaded(self.store.campaign(rows[0].id), latest=True))
        except Exception as exc:
            self.notice(f"the latest campaign: {_error(exc)}", "error")

    def load_campaign(self, campaign: str) -> None:
        if self.store is None:
            return
        try:
            self.post(CampaignLoaded(self.store.campaign(campaign)))
        except Exception as exc:
            self.notice(f"campaign {campaign}: {_error(exc)}", "error")

    def export(self, record: Any, kinds: list[str]) -> None:
        """Write the campaign's model, URDF, ROS kinematics YAML and/or HTML report to the output dir."""
        from hil.arm.geometry import Geometry
        from hil.calibration.exports import export
        from hil.calibration.model_file import refuse_worse_than_nominal
        from hil.files.outputs import atomic_write_text
        from hil.report import report_data_from_result, write_report

        out = Path(self.options.out_dir)
        written: list[str] = []
        try:
            out.mkdir(parents=True, exist_ok=True)
            for kind in kinds:
                suffix, fmt = EXPORTS[kind]
                path = out / f"{record.id}{suffix}"
                if fmt == "html" and _is_verification(record):  # the pose test's own page, as `hil
                    from hil.report.data import check_verification  # verify --report` writes it
                    from hil.report.verification import write_verification_report

                    check_verification(record.result or {}, f"campaign {record.id}")
                    write_verification_report(record.result, path)
                elif fmt == "html":
                    if not record.result or "model" not in record.result:
                        raise InputError(f"campaign {record.id} has no finished result to report")
                    write_report(report_data_from_result(record.result, source=f"campaign {record.id}"),
                                 path)
                else:
                    if record.model is None:
                        raise InputError(f"campaign {record.id} has no calibrated model "
                                         f"(status {record.summary.status})")
                    source = f"campaign {record.id}"
                    doc = record.model.doc
                    # a model cross-validation did not show better than nominal: the CLI's --force only
                    refuse_worse_than_nominal(doc, source, False, "export",
                                              "hil export --force exports it anyway")
                    atomic_write_text(path, export(doc, Geometry.from_dict(doc, source=source), fmt,
                                                   source=source))
                written.append(str(path))
        except Exception as exc:
            self.post(Exported(written, str(exc) if isinstance(exc, InputError) else _error(exc)))
            return
        self.post(Exported(written))

    # --- the simulator -------------------------------------------------------------------------------
    def inject(self, fault: str, **args: Any) -> None:
        """A fault in the simulated station (command palette; tests)."""
        if self.sim is None:
            self.notice("fault injection needs the simulated station (--sim)", "warning")
            return
        try:
            self.sim.inject(fault, **args)
            self.notice(f"simulator: {fault}")
        except Exception as exc:
            self.notice(f"simulator: {fault}: {_error(exc)}", "error")
