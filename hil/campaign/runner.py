"""Running one campaign end to end: devices, engine, plan, events in and result out.

Shared by every job that runs a plan on the arm (`hil.jobs`) so all behave the same: on the station's
open devices it emits `RunStarted`, runs the plan on the engine with the station's suspenders, and
always emits `RunFinished` (accepted, rejected, aborted, interrupted or failed) and, unless told not
to, closes the devices — whatever happened in between. A `KeyboardInterrupt` (the CLI's `RunInterrupted` for
SIGINT, SIGTERM, SIGHUP) is an interruption, not an abort: status ``interrupted``, which the store
keeps resumable, so re-running the same command continues the campaign as after ``kill -9``.
"""

from __future__ import annotations

import logging
import secrets
import signal
import sqlite3
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from drivers.robot.model import RobotIdentity
from hil import __version__
from hil.arm.catalog import RobotSpec, get_robot
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.calibration.identification import register
from hil.calibration.measurements import Measurements
from hil.campaign.calibration_plan import (
    BOOTSTRAP,
    CampaignResult,
    ChoosePoses,
    ResumeState,
    calibration_plan,
)
from hil.campaign.controller import controller_calibration, controller_record
from hil.campaign.engine import Clock, Engine, RealClock, RunAborted, RunInterrupted
from hil.campaign.events import (
    AcquisitionStopped,
    BootstrapPlanned,
    ControllerModel,
    Event,
    EventBus,
    PlanReady,
    PointMeasured,
    ReferenceMeasured,
    RunFinished,
    RunStarted,
    SweepPlanned,
)
from hil.campaign.ids import new_campaign_id
from hil.campaign.steps import PoseRecord, SegmentRecord
from hil.campaign.stopping import stopped_words
from hil.campaign.suspenders import suspenders
from hil.errors import EXIT_ABORTED, EXIT_FAILED, EXIT_FAULT, EXIT_OK, HilError, InputError
from hil.station.config import StationConfig
from hil.station.devices import Devices
from hil.station.robot_type import check_controller

log = logging.getLogger(__name__)


@dataclass
class RunOutcome:
    """How a run ended, for exit codes and the result file."""

    status: str  # accepted, rejected, aborted, interrupted, failed
    campaign: str
    result: Any = None  # the plan's return value: a CampaignResult, a verification's result
    error: BaseException | None = None
    robot_info: dict[str, Any] = field(default_factory=dict)
    tracker_info: dict[str, Any] = field(default_factory=dict)
    timing: dict[str, float] = field(default_factory=dict)
    # the store could not record how the run ended (RunFinished): the caller must say so itself
    unrecorded: BaseException | None = None

    @property
    def exit_code(self) -> int:
        """0 accepted, 1 rejected, 3 hardware fault, 4 aborted, 128 + the signal number interrupted
        (130 for Ctrl-C, the shell's convention); bad input raises before a run."""
        if self.status == "accepted":
            return EXIT_OK
        if self.status == "rejected":
            return EXIT_FAILED
        if self.status == "aborted":
            return EXIT_ABORTED
        if self.status == "interrupted":
            return 128 + int(getattr(self.error, "signum", signal.SIGINT))
        return EXIT_FAULT


def keep_in_model(spec: RobotSpec, smr: Any, controller: dict[str, Any] | None) -> Geometry:
    """The arm the engine checks every planned move against the keep-in box with: the controller's
    own model when it reported one, since the controller's driver checks each commanded move with the
    controller's forward kinematics (`drivers.robot.ur`), and a path that the nominal arm keeps inside
    the box by less than the factory deltas' millimetres is refused there mid-campaign; else nominal."""
    if controller is None:
        return Geometry.nominal(spec, smr)
    return controller_calibration(controller).geometry(spec, smr)


def _nominal_deviation(config: StationConfig, earlier: Iterable[PoseRecord] = ()
                       ) -> Callable[[PoseRecord], float | None]:
    """Distance of each new point from the nominal arm's prediction, shown live to the operator.

    The nominal arm is registered (tracker pose and SMR offset fitted) on the points measured so far,
    so the figure is the arm's kinematic error, not the error of a rough SMR guess. Needs 4 points.
    `earlier`: a resumed campaign's points, so its next point is registered on all the campaign has,
    as it would have been without the interruption (not on none: no figure, then a rough one).
    """
    robot = config.robot["type"]
    smr = np.array(config.smr["offset"])
    seen: list[PoseRecord] = list(earlier)

    def deviation(record: PoseRecord) -> float | None:
        seen.append(record)
        if len(seen) < 4:
            return None
        meas = Measurements(np.array([r.q for r in seen]), np.array([r.p for r in seen]),
                            np.arange(len(seen)), "live", "")
        model = register(meas, robot, smr)
        return float(np.linalg.norm(Kinematics(model).points(record.q)[0] - record.p))

    return deviation


def run_campaign(config: StationConfig, choose: ChoosePoses, *, bus: EventBus | None = None,
                 campaign: str | None = None, resume: ResumeState | None = None,
                 clock: Clock | None = None, devices: Devices,
                 engine_ready: Callable[[Engine], None] | None = None,
                 validation_cycles: int = 1, lease: Any = None, close_devices: bool = True) -> RunOutcome:
    """Run one calibration campaign on the station's open `devices`; never raises for hardware.

    Bad input (config, unsafe targets found before motion) still raises InputError. `engine_ready`
    receives the engine before it starts, so a UI can pause or abort it from another thread.
    `lease` is the campaign's (`claim_run`): should its heartbeat find it taken over, the arm stops
    and the run ends as interrupted, as another process now owns the campaign. `close_devices`
    False leaves the given devices open for a run that follows on the same arm (``--verify``).
    """
    # One count everywhere (Run screen, progress bar, history): calibration + validation poses, the
    # plan's; the bootstrap's points locate the tracker and are not among them.
    camp = config.campaign
    planned = (len(resume.poses) if resume is not None and resume.poses else
               camp["calibration_poses"] + camp["validation_poses"] * validation_cycles)
    measured = sum(1 for role, _ in resume.records if role != BOOTSTRAP) if resume else 0

    def judge(result: CampaignResult) -> tuple[str, str]:
        # the verdict is the validation's; a drift beyond its limit flags the campaign, said beside it
        drift = result.drift or {}
        flag = (f"; drift flagged: the reference moved {drift['max'] * 1e6:.1f} µm "
                f"(limit {drift['limit'] * 1e6:.1f} µm)" if drift.get("flagged") else "")
        reason = (result.verdict.reason if result.verdict is not None else
                  f"validation RMS {result.after.rms * 1e3:.4f} mm")
        status = "accepted" if result.passed else "rejected"
        return status, f"{reason}{flag}{stopped_words(result.stopping)}"

    session = secrets.token_hex(6)  # this run's: a sweep's segments name the run that recorded them
    return run_plan(
        config, lambda run: calibration_plan(config, choose, run.campaign, resume, validation_cycles,
                                             run.controller,
                                             keep_in_check=keep_in_model(get_robot(config.robot["type"]),
                                                                         config.smr["offset"],
                                                                         run.controller),
                                             session=session),
        judge=judge, poses=planned, measured=measured, resumed=resume is not None, bus=bus,
        campaign=campaign, clock=clock, devices=devices, engine_ready=engine_ready, lease=lease,
        deviation=_nominal_deviation(config, resume.records.values() if resume else ()),
        close_devices=close_devices)


@dataclass(frozen=True)
class RunContext:
    """What a plan is built from once the devices are open: the campaign, the controller's word."""

    campaign: str
    # the controller's own kinematic model (`controller_record` of its KinematicsInfo), None: unknown
    controller: dict[str, Any] | None
    home: np.ndarray | None  # the joints the arm stood at when the run started (None: no reading)


def run_plan(config: StationConfig, plan: Callable[[RunContext], Any], *,
             judge: Callable[[Any], tuple[str, str]], poses: int, measured: int = 0, resumed: bool = False,
             bus: EventBus | None = None, campaign: str | None = None, clock: Clock | None = None,
             devices: Devices, engine_ready: Callable[[Engine], None] | None = None,
             lease: Any = None, deviation: Callable[[PoseRecord], float | None] | None = None,
             close_devices: bool = True) -> RunOutcome:
    """Run one plan of steps on the station's devices: the calibration campaign's and the ISO 9283
    verification's (`hil.verify`) one way — on the station's open devices (taken by
    `hil.jobs.station.take_station`, or a test's), the controller checked, the
    engine with the station's suspenders and keep-in box, `RunStarted` … `RunFinished` always emitted,
    the devices closed (unless `close_devices` is False) whatever happened; never raises for hardware.

    `plan(context)` builds the plan's generator; `judge(result)` turns the plan's return value into
    the final status and detail; `poses`/`measured`/`resumed` go into `RunStarted`.
    """
    bus = bus or EventBus()
    campaign = campaign or new_campaign_id()
    outcome = RunOutcome("failed", campaign)
    spec = get_robot(config.robot["type"])
    info = getattr(devices.robot, "info", None)
    outcome.robot_info = ({"model": info.model, "serial": info.serial, "software": info.software_version}
                          if info is not None else {})
    # the controller's own kinematic model (its KinematicsInfo), kept and compared with hil's
    controller = controller_record(spec.name, getattr(info, "kinematics", None))
    if controller is not None:
        outcome.robot_info["controller"] = controller
    ident = getattr(devices.tracker, "identity", None)
    outcome.tracker_info = ({"name": ident.name, "serial": ident.serial_number,
                             "firmware": ".".join(map(str, ident.firmware)), "interface": ident.interface}
                            if ident is not None else {})
    engine: Engine | None = None
    try:  # from here on the devices are closed and RunFinished emitted, even on Ctrl-C
        # the controller's word on the robot type, before the plan uses the configured kinematics
        check_controller(config, info)
        try:
            home = np.asarray(devices.robot.read_joints(1).q, dtype=float)  # where the operator left it
        except Exception:  # no reading: the first move's path is then not checked from here
            home = None
        engine = Engine(
            devices.robot, devices.tracker, campaign, spec, bus=bus, home=home,
            suspenders=suspenders(devices, relock_timeout=config.timeouts["relock"]),
            clock=clock or RealClock(), suspend_timeout=config.timeouts["suspend"],
            keep_in=(np.array(config.keep_in["min"]), np.array(config.keep_in["max"])),
            check_model=keep_in_model(spec, config.smr["offset"], controller), deviation=deviation)
        if lease is not None:
            lease.on_lost = engine.request_interrupt
        if engine_ready is not None:
            engine_ready(engine)
        bus.emit(RunStarted(campaign=campaign, robot=spec.name, station=config.station["name"],
                            poses=poses, resumed=resumed, measured=measured))
        if controller is not None:
            bus.emit(ControllerModel(campaign=campaign, model=controller))
        result = engine.run(plan(RunContext(campaign, controller, home)))
        outcome.result = result
        outcome.status, detail = judge(result)
    except RunAborted as exc:
        outcome.status, outcome.error, detail = "aborted", exc, str(exc) or "aborted"
    except KeyboardInterrupt as exc:
        outcome.status, outcome.error = "interrupted", exc
        detail = str(exc) if isinstance(exc, RunInterrupted) else "interrupted"
    except InputError as exc:  # an unsafe target found before moving: bad input, not a fault
        bus.emit(RunFinished(campaign=campaign, status="failed", detail=str(exc)))
        raise
    except Exception as exc:  # hardware faults, suspensions that never cleared, failed fits
        outcome.status, outcome.error, detail = "failed", exc, f"{type(exc).__name__}: {exc}"
    finally:
        if engine is not None:
            outcome.timing = engine.stats.as_dict()
        if close_devices:
            devices.close()
    try:
        bus.emit(RunFinished(campaign=campaign, status=outcome.status, detail=detail,
                             result={"software": __version__}))
    except Exception as exc:  # the store could not record the end (a full disk): a fault, said so
        log.debug("could not record the end of campaign %s: %s", campaign, exc)
        if outcome.status != "failed":  # else the first failure (often the same disk) is the news
            outcome.status, outcome.error = "failed", exc
        outcome.unrecorded = exc
    return outcome


def claim_run(store: Any, identity: Mapping[str, Any], robot: RobotIdentity | Mapping[str, str], *,
              campaign: str | None = None, find: bool = False) -> tuple[Any, ResumeState | None]:
    """Own the campaign to run before anything moves; returns (its lease, its resume state or None).

    `campaign`: continue that one (the operator chose it); else with `find` the newest resumable
    campaign of `identity` and the robot, or a new one; else a new one. The store's lease (see
    `hil.store.leases`) is taken for the campaign and the robot's serial at once, so a second process
    finding the same campaign — or driving the same arm for another campaign — is refused (the
    store's LeaseRefused, bad input: the message names the process that has it) and nothing is
    written. The resume state is read only once the lease is held: what is resumed is what the
    previous owner left, not a snapshot taken while it still measured. Release the lease (``with``)
    when the run has ended and its result is stored.
    """
    serial = RobotIdentity.coerce(robot).serial
    for _ in range(3):
        cid = campaign or (store.find_resumable(identity, robot_serial=serial) if find else None)
        if cid is None:
            return store.claim_new(identity, robot), None
        try:
            lease = store.claim(cid, serial)
        except InputError:
            if campaign is None and store.find_resumable(identity, robot_serial=serial) != cid:
                continue  # it finished between finding and claiming: look again
            raise
        try:
            return lease, resume_state(store, cid)
        except BaseException:
            lease.release()
            raise
    raise InputError("the campaigns of this station keep finishing and starting; try again")


def plan_saver(store: Any, campaign: str) -> Callable[[Any], None]:
    """Critical subscriber: the selected poses reach the store before the first of them is visited."""

    def save(event: Any) -> None:
        if isinstance(event, PlanReady) and event.campaign == campaign:
            summary: dict[str, Any] = {"tracker": event.tracker, "selection": event.selection}
            if event.reference is not None:  # the warm-up/drift reference pose: a resume keeps it
                summary["reference"] = event.reference
        elif isinstance(event, BootstrapPlanned) and event.campaign == campaign:
            # the "bootstrap" key tells `resume_state` these poses are the whole bootstrap plan
            summary = {"tracker": None, "selection": {}, "bootstrap": {"start": event.start}}
        else:
            return
        try:
            store.save_plan(campaign, [(p["index"], p["role"], p["q"]) for p in event.poses],
                            plan=summary)
        except Exception as exc:
            raise _record_failed(store, f"the plan of campaign {campaign}", exc) from exc

    return save


class RecordFailed(HilError):
    """The store could not record an event of the run (a full disk, a failing drive): the run stops
    as a fault, the arm stopped; what was committed before stays, so the campaign can resume."""


def store_recorder(store: Any) -> Callable[[Event], None]:
    """The store's critical subscriber, its failures named for the operator: which write failed,
    in which database, and why ("could not record the measurement of pose 12 in k.db: database or
    disk is full") rather than the store's own wording of the event type."""

    def record(event: Event) -> None:
        try:
            store.record_event(event)
        except Exception as exc:
            what = (f"the measurement of pose {event.index}" if isinstance(event, PointMeasured)
                    else f"{event.name} of campaign {event.campaign}")
            raise _record_failed(store, what, exc) from exc

    return record


def _record_failed(store: Any, what: str, exc: BaseException) -> RecordFailed:
    """"could not record WHAT in DB: why", the database's own words (SQLite's, the OS's) for why."""
    cause = exc.__cause__ if isinstance(exc.__cause__, sqlite3.Error | OSError) else exc
    where = getattr(store, "location", None) or getattr(store, "path", store)
    return RecordFailed(f"could not record {what} in {where}: {cause}")


def resume_state(store: Any, campaign: str) -> ResumeState:
    """What an interrupted campaign already has: its plan, tracker estimate and measured poses, its
    reference pose and reference measurements (warm-up and drift watch: the log's ReferenceMeasured),
    and the stopping rule's decision (the log's AcquisitionStopped)."""
    record = store.campaign(campaign)
    plan = record.plan or {}
    tracker = None
    if plan.get("tracker"):
        tracker = Geometry.from_dict({**Geometry.nominal(record.robot.type or "ur5e").to_dict(),
                                      "tracker": plan["tracker"]}, source=f"campaign {campaign}").tracker
    targets = {p.index: p for p in record.poses}
    planned = [(p.index, p.role, np.array(p.target)) for p in record.poses if p.role != "bootstrap"]
    # a stored bootstrap plan (`plan_saver`): resumed at its own targets; without one (a run of an
    # older hil) the poses in the table are only those it had started, not the whole bootstrap
    bootstrap = ([(p.index, np.array(p.target)) for p in record.poses if p.role == BOOTSTRAP]
                 if "bootstrap" in plan else None)
    records = {}
    for index, m in store.measured_poses(campaign).items():
        pose = targets.get(index)
        target = np.array(pose.target) if pose is not None else np.array(m.q)
        records[(m.role, index)] = PoseRecord(
            index=index, role=m.role, target=target, q=np.array(m.q),
            q_spread=np.array(m.q_spread if m.q_spread is not None else np.zeros(6)), p=np.array(m.p),
            p_spread=np.array(m.p_spread if m.p_spread is not None else np.zeros(3)), samples=m.samples)
    reference = plan.get("reference")
    references = [e for e in store.events(campaign, types=("ReferenceMeasured",))
                  if isinstance(e, ReferenceMeasured)]
    resumed = planned if tracker is not None and planned else None
    # the stopping rule's decision: the remaining calibration poses stay unvisited (the last stop)
    stops = [e for e in store.events(campaign, types=("AcquisitionStopped",))
             if isinstance(e, AcquisitionStopped)]
    tours = [e for e in store.events(campaign, types=("SweepPlanned",)) if isinstance(e, SweepPlanned)]
    return ResumeState(poses=resumed, tracker=tracker, sweep=sweep_state(store, campaign),
                       sweep_tour=list(tours[0].segments) if tours and resumed else None,
                       records=records, selection=plan.get("selection") or {}, bootstrap=bootstrap,
                       reference=np.array(reference, dtype=float) if reference and resumed else None,
                       references=references,
                       stopping=dict(stops[-1].figures) if stops and resumed else None)


def sweep_state(store: Any, campaign: str) -> dict[int, SegmentRecord]:
    """A sweep campaign's segments recorded whole: each segment's last `SweepSegmentDone` names the
    take whose chunks are read back (`hil.campaign.sweep_plan.record_from_store`); chunks of a take
    no done event names (a segment cut short) are never read."""
    from hil.campaign.events import SweepSegmentDone
    from hil.campaign.sweep_plan import record_from_store

    done: dict[int, SweepSegmentDone] = {}
    for event in store.events(campaign, types=("SweepSegmentDone",)):
        if isinstance(event, SweepSegmentDone):
            done[event.segment] = event
    return {k: record_from_store(k, e.session, store.stream_chunks(campaign, k, e.take, "joints"),
                                 store.stream_chunks(campaign, k, e.take, "tracker"), e.anchor)
            for k, e in sorted(done.items())}
