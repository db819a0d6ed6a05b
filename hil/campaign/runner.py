"""Running one campaign end to end: devices, engine, plan, events in and result out.

Shared by the headless CLI and the TUI so both behave the same: it opens the station's devices,
emits `RunStarted`, runs the calibration plan on the engine with the station's suspenders, and
always emits `RunFinished` (accepted, rejected, aborted, interrupted or failed) and closes the
devices — whatever happened in between. A `KeyboardInterrupt` (the CLI's `RunInterrupted` for
SIGINT, SIGTERM, SIGHUP) is an interruption, not an abort: status ``interrupted``, which the store
keeps resumable, so re-running the same command continues the campaign as after ``kill -9``.
"""

from __future__ import annotations

import datetime as _dt
import secrets
import signal
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hil import __version__
from hil.arm.catalog import get_robot
from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.calibration.identification import register
from hil.calibration.measurements import Measurements
from hil.campaign.engine import Clock, Engine, RealClock, RunAborted, RunInterrupted
from hil.campaign.events import EventBus, PlanReady, RunFinished, RunStarted
from hil.campaign.plan import BOOTSTRAP, CampaignResult, ChoosePoses, ResumeState, calibration_plan
from hil.campaign.steps import PoseRecord
from hil.campaign.suspenders import suspenders
from hil.errors import InputError
from hil.station.config import StationConfig
from hil.station.devices import HARDWARE_ERRORS, Devices, open_devices


def new_campaign_id() -> str:
    """A short, sortable, unique campaign id: UTC date-time plus 4 random hex digits."""
    return _dt.datetime.now(_dt.UTC).strftime("%Y%m%d-%H%M%S-") + secrets.token_hex(2)


@dataclass
class RunOutcome:
    """How a run ended, for exit codes and the result file."""

    status: str  # accepted, rejected, aborted, interrupted, failed
    campaign: str
    result: CampaignResult | None = None
    error: BaseException | None = None
    robot_info: dict[str, Any] = field(default_factory=dict)
    tracker_info: dict[str, Any] = field(default_factory=dict)
    timing: dict[str, float] = field(default_factory=dict)

    @property
    def exit_code(self) -> int:
        """0 accepted, 1 rejected, 3 hardware fault, 4 aborted, 128 + the signal number interrupted
        (130 for Ctrl-C, the shell's convention); bad input raises before a run."""
        if self.status == "accepted":
            return 0
        if self.status == "rejected":
            return 1
        if self.status == "aborted":
            return 4
        if self.status == "interrupted":
            return 128 + int(getattr(self.error, "signum", signal.SIGINT))
        return 3


def _nominal_deviation(config: StationConfig) -> Callable[[PoseRecord], float | None]:
    """Distance of each new point from the nominal arm's prediction, shown live to the operator.

    The nominal arm is registered (tracker pose and SMR offset fitted) on the points measured so far,
    so the figure is the arm's kinematic error, not the error of a rough SMR guess. Needs 4 points.
    """
    robot = config.robot["type"]
    smr = np.array(config.smr["offset"])
    seen: list[PoseRecord] = []

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
                 clock: Clock | None = None, devices: Devices | None = None,
                 engine_ready: Callable[[Engine], None] | None = None,
                 validation_cycles: int = 1) -> RunOutcome:
    """Run one calibration campaign on the configured (or given) devices; never raises for hardware.

    Bad input (config, unsafe targets found before motion) still raises InputError. `engine_ready`
    receives the engine before it starts, so a UI can pause or abort it from another thread.
    """
    bus = bus or EventBus()
    campaign = campaign or new_campaign_id()
    outcome = RunOutcome("failed", campaign)
    spec = get_robot(config.robot["type"])
    try:
        devices = devices or open_devices(config)
    except HARDWARE_ERRORS as exc:
        outcome.error = exc
        bus.emit(RunFinished(campaign=campaign, status="failed", detail=f"connect: {exc}"))
        return outcome
    info = getattr(devices.robot, "info", None)
    outcome.robot_info = ({"model": info.model, "serial": info.serial, "software": info.software_version}
                          if info is not None else {})
    ident = getattr(devices.tracker, "identity", None)
    outcome.tracker_info = ({"name": ident.name, "serial": ident.serial_number,
                             "firmware": ".".join(map(str, ident.firmware)), "interface": ident.interface}
                            if ident is not None else {})
    engine: Engine | None = None
    try:  # from here on the devices are closed and RunFinished emitted, even on Ctrl-C
        try:
            home = np.asarray(devices.robot.read_joints(1).q, dtype=float)  # where the operator left it
        except Exception:  # no reading: the first move's path is then not checked from here
            home = None
        engine = Engine(
            devices.robot, devices.tracker, campaign, spec, bus=bus, home=home,
            suspenders=suspenders(devices, relock_timeout=config.timeouts["relock"]),
            clock=clock or RealClock(), suspend_timeout=config.timeouts["suspend"],
            keep_in=(np.array(config.keep_in["min"]), np.array(config.keep_in["max"])),
            check_model=Geometry.nominal(spec, config.smr["offset"]),
            deviation=_nominal_deviation(config))
        if engine_ready is not None:
            engine_ready(engine)
        # One count everywhere (Run screen, progress bar, history): calibration + validation poses, the
        # plan's; the bootstrap's points locate the tracker and are not among them.
        camp = config.campaign
        planned = (len(resume.poses) if resume is not None and resume.poses else
                   camp["calibration_poses"] + camp["validation_poses"] * validation_cycles)
        measured = sum(1 for role, _ in resume.records if role != BOOTSTRAP) if resume else 0
        bus.emit(RunStarted(campaign=campaign, robot=spec.name, station=config.station["name"],
                            poses=planned, resumed=resume is not None, measured=measured))
        result: CampaignResult = engine.run(
            calibration_plan(config, choose, campaign, resume, validation_cycles))
        outcome.result = result
        outcome.status = "accepted" if result.passed else "rejected"
        detail = (f"validation RMS {result.after.rms * 1e3:.4f} mm "
                  f"{'<=' if result.passed else '>'} {config.campaign['acceptance'] * 1e3:.4f} mm")
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
        devices.close()
    bus.emit(RunFinished(campaign=campaign, status=outcome.status, detail=detail,
                         result={"software": __version__}))
    return outcome


def plan_saver(store: Any, campaign: str) -> Callable[[Any], None]:
    """Critical subscriber: the selected poses reach the store before the first of them is visited."""

    def save(event: Any) -> None:
        if isinstance(event, PlanReady) and event.campaign == campaign:
            store.save_plan(campaign, [(p["index"], p["role"], p["q"]) for p in event.poses],
                            plan={"tracker": event.tracker, "selection": event.selection})

    return save


def resume_state(store: Any, campaign: str) -> ResumeState:
    """What an interrupted campaign already has: its plan, tracker estimate and measured poses."""
    record = store.campaign(campaign)
    plan = record.plan or {}
    tracker = None
    if plan.get("tracker"):
        tracker = Geometry.from_dict({**Geometry.nominal(record.robot.type or "ur5e").to_dict(),
                                      "tracker": plan["tracker"]}, source=f"campaign {campaign}").tracker
    targets = {p.index: p for p in record.poses}
    planned = [(p.index, p.role, np.array(p.target)) for p in record.poses if p.role != "bootstrap"]
    records = {}
    for index, m in store.measured_poses(campaign).items():
        pose = targets.get(index)
        target = np.array(pose.target) if pose is not None else np.array(m.q)
        records[(m.role, index)] = PoseRecord(
            index=index, role=m.role, target=target, q=np.array(m.q),
            q_spread=np.array(m.q_spread if m.q_spread is not None else np.zeros(6)), p=np.array(m.p),
            p_spread=np.array(m.p_spread if m.p_spread is not None else np.zeros(3)), samples=m.samples)
    return ResumeState(poses=planned if tracker is not None and planned else None, tracker=tracker,
                       records=records, selection=plan.get("selection") or {})
