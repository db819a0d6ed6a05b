"""A calibration campaign as a job: a typed request in, an outcome with its exit code out.

``hil calibrate`` and the terminal app's Run screen both run a campaign through `run_calibration` on
a station taken by `hil.jobs.station.take_station`, so a campaign run from the terminal app is the
same campaign as a headless one — the same claim on the store (a lease, resume rules), the same
critical subscribers (every point committed before the next move; the plan before the first pose),
the same result document. The front-ends differ only in what they pass: their own subscribers
(progress lines or screen updates), how they hear the job's words (`Say`), and the app's policy for an
emergency stop or a quit (`status_of`, `gate`).

`calibrate` is the whole headless job (``hil calibrate``): station from its source, store, arm,
campaign, then ``--verify``'s pose test on the same devices.
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Literal

from hil.campaign.events import Event, EventBus
from hil.errors import InputError
from hil.jobs.outcome import EXIT_FAULT, EXIT_OK, JobOutcome
from hil.jobs.station import (
    StationSetup,
    StationSource,
    TakenStation,
    open_existing_store,
    simulator_words,
    station_setup,
    store_location,
    take_station,
)
from hil.jobs.words import Say, outage_words, quiet

if TYPE_CHECKING:
    from hil.campaign.engine import Engine
    from hil.campaign.runner import RunOutcome
    from hil.jobs.verification import VerifyAfter, VerifyOptions

#: How a campaign is found: "find" continues the unfinished one of this station, robot and
#: configuration (else a new one); "new" always starts afresh; "only" refuses unless one exists.
Resume = Literal["find", "new", "only"]


@dataclass(frozen=True)
class CalibrationRequest:
    """What to calibrate and how: the front-end's options, checked, in one place.

    ``hil calibrate`` fills it from its arguments; the terminal app from its start-up options, its
    Plan screen (`identity`, with the keys it changed) and the operator's choice (`campaign`).
    """

    source: StationSource  # the station: a configuration, or the simulated one
    db: str | None = None  # the store (None: a simulated station's own; else $HIL_DB, config, default)
    no_warmup: bool = False  # the arm has been running: measure without warming it up
    validation_cycles: int = 1  # visits of each validation pose (>1 adds ISO 9283 AP/RP)
    resume: Resume = "find"
    campaign: str | None = None  # continue exactly this campaign (the operator chose it)
    identity: Mapping[str, Any] | None = None  # what finds the campaign again (None: the station's)
    verify: VerifyOptions | None = None  # ``--verify``: the pose test after an accepted calibration

    @property
    def speed(self) -> float:
        """The station clock's speed (a simulated station's fast time)."""
        return self.source.speed


class StoreGate:
    """Lets a front-end give a run up: once `abandon`ed, the run writes nothing more to the store.

    The terminal app uses it when a quit outwaits a run stuck in a long computation: it marks the
    campaign interrupted itself, and whatever the run still tries to record is dropped.
    """

    def __init__(self) -> None:
        import threading

        self._lock = threading.Lock()
        self.abandoned = False

    def write(self, action: Callable[[], Any]) -> None:
        with self._lock:
            if not self.abandoned:
                action()

    def abandon(self, action: Callable[[], Any]) -> bool:
        """Run `action` (the giving-up write) and close the gate; False if it was closed already."""
        with self._lock:
            if self.abandoned:
                return False
            self.abandoned = True
            action()
            return True


@dataclass
class CalibrationOutcome(JobOutcome):
    """A calibration job's end: the job's outcome plus what its report is made from."""

    run: RunOutcome | None = None
    config: Any = None
    events: list[Event] = field(default_factory=list)
    started: float = 0.0
    detail: str = ""  # the status in words (the app's Results screen)
    recorded: bool = True  # False: the store refused the result (a fault, exit 3, said)

    @property
    def finished(self) -> bool:
        """Accepted, rejected or aborted: the result exists (an interrupted or failed run is resumable)."""
        from hil.store import FINISHED

        return self.status in FINISHED

    def report_data(self) -> Any:
        """The HTML report's data (`hil.report.write_report`); only for a run that produced a result."""
        from hil.report.result import report_data

        verification = (self.document or {}).get("verification")
        return report_data(self.run, self.config, self.events, self.started, verification)


def check_pose_count(poses: int | None, config_path: str | None, robot: str | None) -> None:
    """Refuse a calibration pose count the fit cannot identify from, before the station starts or the
    arm moves: found later, it would fail only after the bootstrap (tracker location) had moved the
    arm. The configuration's own count is checked when it is read (`hil.station.config`)."""
    if poses is None or poses <= 0:  # not given, or refused as not positive
        return
    from hil.station.config import load_config, minimum_calibration_poses

    config = load_config(config_path) if config_path else None
    robot = robot or (config.robot["type"] if config is not None else "ur5e")
    # with the compliance (on unless the station turns it off) its identifiable joints count too
    compliance = bool(config.campaign["compliance"]) if config is not None else True
    need, n = minimum_calibration_poses(robot, compliance, config.payload if config else None,
                                        config.gravity if config else None)
    if poses < need:
        raise InputError(f"--poses {poses}: too few calibration poses: identifying the {n} parameters "
                         f"of a {robot} from 3 coordinates per pose needs at least {need}")


def claim(store: Any, request: CalibrationRequest, identity: Mapping[str, Any], robot: Any
          ) -> tuple[Any, Any]:
    """The campaign's lease and resume state (`hil.campaign.runner.claim_run`) as the request asks."""
    from hil.campaign.runner import claim_run

    if request.campaign is not None:
        return claim_run(store, identity, robot, campaign=request.campaign)
    if request.resume == "only" and store.find_resumable(identity, robot_serial=robot.serial) is None:
        raise InputError("--resume: no unfinished campaign of this station, robot and configuration")
    return claim_run(store, identity, robot, find=request.resume != "new")


def run_calibration(request: CalibrationRequest, setup: StationSetup, taken: TakenStation, *,
                    verify: VerifyAfter | None = None,
                    subscribers: Sequence[Callable[[Event], None]] = (), say: Say = quiet,
                    engine_ready: Callable[[Engine], None] | None = None, gate: StoreGate | None = None,
                    status_of: Callable[[RunOutcome, list[Event]], tuple[str, str]] | None = None,
                    on_claimed: Callable[[str], None] | None = None) -> CalibrationOutcome:
    """One campaign of `request` on the station `setup` describes and `taken` holds (its devices and
    store): claimed, run, its result stored; then `verify`'s pose test (``--verify``), if given.

    `subscribers` hear every event after the store's critical ones. `status_of` turns the run's end
    into the stored status and its words (default: the run's own). `gate` lets the caller give the run
    up (`StoreGate`). `on_claimed` hears the campaign id once this process owns it. Bad input found
    before motion raises InputError; a store that refuses the result is a fault (exit 3), said.
    """
    from hil.campaign.chooser import campaign_chooser
    from hil.campaign.runner import plan_saver, run_campaign, store_recorder
    from hil.report.result import result_document
    from hil.store import StoreError

    store, config, gate = taken.store, setup.config, gate or StoreGate()
    assert store is not None, "a calibration needs the store"
    identity = request.identity if request.identity is not None else setup.identity
    lease, resume = claim(store, request, identity, taken.robot)  # before the first motion, or bad input
    with lease:
        campaign = lease.campaign
        if on_claimed is not None:
            on_claimed(campaign)
        record = store_recorder(store)
        events: list[Event] = []
        bus = EventBus()
        # critical: a failed write names itself and ends the run
        bus.subscribe(lambda event: gate.write(lambda: record(event)), critical=True)
        bus.subscribe(plan_saver(store, campaign), critical=True)
        bus.subscribe(events.append)
        for subscriber in subscribers:
            bus.subscribe(subscriber)
        started = time.time()
        # closed as the run ends, before RunFinished (the operator may quit on it); --verify: the same
        # devices go on, and the station closes them after
        close = verify is None
        try:
            with setup.clock(request.speed) as clock:
                run = run_campaign(config, campaign_chooser(config), bus=bus, campaign=campaign,
                                   resume=resume, devices=taken.devices, clock=clock,
                                   validation_cycles=request.validation_cycles, lease=lease,
                                   engine_ready=engine_ready, close_devices=close)
        finally:
            taken.devices_closed = taken.devices_closed or close
        status, detail = status_of(run, events) if status_of is not None else (run.status, "")
        result = result_document(run, config, events, started, setup.truth)
        result["status"] = status
        out = CalibrationOutcome(run.exit_code, status, campaign, result, run=run, config=config,
                                 events=events, started=started, detail=detail)
        if run.unrecorded is not None:  # the store refused RunFinished: no progress line said why
            say(f"fault: campaign {campaign} {run.status}: {run.error}; what was recorded before stays: "
                "re-run the same command to continue it", "error")
        try:
            gate.write(lambda: store.set_status(campaign, status, detail=detail or None, result=result))
        except StoreError as exc:  # a full disk: a fault (exit 3), not "not accepted" (exit 1)
            if run.unrecorded is None:
                say(f"fault: campaign {campaign} ended {status}, but could not record its result in "
                    f"{store.location}: {exc.__cause__ or exc}", "error")
            out.exit_code, out.recorded = EXIT_FAULT, False
            return out
        if verify is None:
            return out
        from hil.jobs.verification import verify_after

        lease.release()  # the verification is a campaign of its own and takes the arm's lease itself
        result["verification"], verified = verify_after(verify, run, taken, identity, setup.truth, say=say,
                                                          setup=setup)
        try:
            gate.write(lambda: store.set_status(campaign, status, detail=detail or None, result=result))
        except StoreError as exc:
            say(f"fault: could not record the verification with campaign {campaign} in {store.location}: "
                f"{exc.__cause__ or exc}", "error")
            out.exit_code, out.recorded = EXIT_FAULT, False
            return out
        if out.exit_code == EXIT_OK and verified:
            out.exit_code = verified
        return out


def _say_simulator(setup: StationSetup, say: Say) -> None:
    """After a fault on a simulated station: did the simulator go silent (`simulator_words`)?"""
    words = simulator_words(setup.simulator)
    if words:
        say(words, "information")


def _check_store_file(location: Any, resume: Resume = "find") -> None:
    """An SQLite store that exists is opened and closed again, so that a file that is not a hil
    database (or a damaged or a newer one) is refused before a simulated station's seconds of start-up
    rather than after them; a server's location waits for the configuration that may name it. With
    ``--resume`` (`resume` "only"), a store with nothing unfinished, or whose unfinished campaigns'
    rows are damaged, is refused then too: no station could change that."""
    from pathlib import Path

    if not isinstance(location, Path):
        return
    store = open_existing_store(location, None)
    if store is None:
        if resume == "only":
            raise InputError(f"--resume: {location} holds no campaign yet (no such file)")
        return
    try:
        if resume == "only" and not store.unfinished_campaigns():
            raise InputError(f"--resume: {location} holds no unfinished campaign")
    finally:
        store.close()


def calibrate(request: CalibrationRequest, *, subscribers: Sequence[Callable[[Event], None]] = (),
              say: Say = quiet) -> CalibrationOutcome:
    """``hil calibrate``: the whole headless job (module docstring): the station set up from the
    request's source, the store, the arm taken, the campaign, and ``--verify``'s pose test. Bad input
    raises InputError before anything moves; a device that cannot be reached is a fault (exit 3), said."""
    from hil.station.devices import HARDWARE_ERRORS

    if request.db or request.source.sim is not None:  # needs no config: checked before a simulated
        _check_store_file(store_location(request.db, request.source, None), request.resume)  # seconds
    with station_setup(request.source) as setup:
        if request.no_warmup:  # not part of what identifies the campaign (`hil.store.hashing`)
            setup = StationSetup(setup.config.with_overrides(warmup__enabled=False), setup.identity,
                                 setup.truth, setup.simulator)
        after = None
        if request.verify is not None:  # the [verify] cube, refused before anything connects
            from hil.jobs.verification import VerifyAfter

            after = VerifyAfter.of(setup.config, request.verify, request.speed,
                                   sim=request.source.sim is not None)
        # a file, or a PostgreSQL server (opened now: reachable?)
        location = store_location(request.db, request.source, setup.config, say)
        with contextlib.ExitStack() as stack:
            try:
                taken = stack.enter_context(take_station(setup.config, what="hil calibrate", store=location))
            except HARDWARE_ERRORS as exc:
                say(f"hardware fault: cannot connect: {type(exc).__name__}: {exc}", "error")
                _say_simulator(setup, say)
                return CalibrationOutcome(EXIT_FAULT, "failed")
            assert taken.store is not None
            taken.store.on_outage = outage_words(say)
            out = run_calibration(request, setup, taken, verify=after, subscribers=subscribers, say=say)
        if out.exit_code == EXIT_FAULT:
            _say_simulator(setup, say)
    if out.status == "interrupted" and out.recorded:  # resumable, and recorded so
        say(f"campaign {out.campaign} is resumable: re-run the same command to continue it", "information")
    return out
