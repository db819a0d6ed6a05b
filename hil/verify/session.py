"""One verification on a station's open devices, stored like a campaign: ``hil verify`` and
``hil calibrate --verify`` both run it this way.

* **Identity.** A verification is found again — to resume it after Ctrl-C or ``kill -9``, without
  measuring twice — by the station configuration (as a calibration is, without the calibration's own
  counts, seed and threshold), the robot's serial and a ``verification`` block: the model's sha256 (of
  its geometry), the cube, the cycles and the controller's calibration checksums. Another model, cube
  or controller calibration is another verification.
* **Design before the campaign.** A new verification's targets are computed (and refused, exit 2, when
  no configuration serves the cube) before the campaign is created, so bad input leaves nothing in the
  store; they are stored with the campaign (its plan: ``"kind": "verification"``, the `Design`) and a
  resumed verification drives exactly those, wherever the arm was left.
* **Run.** The plan (`hil.verify.verification_plan`) runs through `hil.campaign.runner.run_plan`, the
  calibration's runner: suspenders, interrupts, the arm stopped on any error, `RunStarted`…`RunFinished`,
  every measurement committed by the store's critical subscriber before the next move.
* **Status.** A verification has no acceptance threshold: a finished one is stored ``accepted`` (the
  store's finished state; exit code 0), its figures in the campaign's result.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from hil import __version__
from hil.arm.controller_model import ControllerCalibration
from hil.arm.geometry import Geometry, pose
from hil.campaign.controller import controller_calibration, controller_record
from hil.campaign.engine import Clock
from hil.campaign.events import Event, EventBus, PlanReady, jsonable
from hil.campaign.runner import RunOutcome, claim_run, run_plan, store_recorder
from hil.compensation.solve import Compensator
from hil.errors import FaultError, InputError
from hil.station.config import StationConfig
from hil.verify.cube import Cube
from hil.verify.design import (
    DEFAULT_CUBE_TURNS,
    MODES,
    UNCOMPENSATED,
    Design,
    default_cube,
    design_test,
    tracker_from_start,
)
from hil.verify.inputs import ModelInput, cube_where
from hil.verify.result import FORMAT, deviation, evaluate, model_frame, registered_frame, summary
from hil.verify.verification_plan import KIND, verification_plan

#: Campaign keys of the station configuration a verification does not depend on (they size and judge
#: a calibration); the rest (samples, stability, max_consecutive_lost) stay in its identity.
_CALIBRATION_ONLY = ("calibration_poses", "validation_poses", "bootstrap_poses", "candidates",
                     "acceptance", "index", "seed")


def controller_of(robot: str, info: Any) -> tuple[ControllerCalibration, dict[str, Any] | None]:
    """The controller's calibration (its KinematicsInfo) and its record; nominal when not reported."""
    record = controller_record(robot, getattr(info, "kinematics", None))
    return (controller_calibration(record) if record is not None else ControllerCalibration()), record


def identity(base: Mapping[str, Any], model: ModelInput | None, cube: Cube | None, cycles: int,
             controller: ControllerCalibration, reported: bool) -> dict[str, Any]:
    """What finds this verification again (module docstring)."""
    out = {k: (dict(v) if isinstance(v, Mapping) else v) for k, v in base.items()}
    if isinstance(out.get("campaign"), dict):
        out["campaign"] = {k: v for k, v in out["campaign"].items() if k not in _CALIBRATION_ONLY}
    out["verification"] = {"kind": KIND, "model": model.sha256 if model else None,
                           "cube": cube.to_dict() if cube else "default", "cycles": int(cycles),
                           "controller": controller.checksums() if reported else None}
    return out


def design_for(config: StationConfig, start: np.ndarray, model: ModelInput | None,
               controller: Geometry, cube: Cube | None, cycles: int) -> Design:
    """The test's targets on this station (`design_test`); the tracker the SMR faces is the model's,
    else the configuration's ``tracker.position``, else along the SMR's axis at the start pose."""
    robot = config.robot["type"]
    tool = model.geometry.smr if model else np.asarray(config.smr["offset"], float)
    if model is not None:
        tracker, source = model.geometry.tracker.translation, "model"
    elif config.tracker["position"] is not None:
        tracker, source = np.asarray(config.tracker["position"], float), "configuration"
    else:
        tracker, source = tracker_from_start(controller, tool, start), "start pose"
    accurate = model.geometry if model else controller
    compensator = Compensator(accurate, controller, pose(tool))
    modes = MODES if model else (UNCOMPENSATED,)
    keep_in = (np.array(config.keep_in["min"]), np.array(config.keep_in["max"]))
    cubes = [cube] if cube is not None else [default_cube(robot, tracker, t) for t in DEFAULT_CUBE_TURNS]
    for i, candidate in enumerate(cubes):
        try:
            return design_test(compensator, candidate, tool, tracker, tracker_source=source, modes=modes,
                               cycles=cycles, keep_in=keep_in,
                               acceptance_angle=config.smr["acceptance_angle"], start=start,
                               where=cube_where(config))
        except InputError:
            if i == len(cubes) - 1:
                raise
    raise AssertionError("unreachable")


def plan_document(design: Design, model: ModelInput | None, controller: Mapping[str, Any] | None
                  ) -> dict[str, Any]:
    """The campaign's plan JSON: what kind of campaign, and everything a resume needs."""
    return {"kind": KIND, "design": design.to_dict(), "model": model.as_dict() if model else None,
            "controller": dict(controller) if controller else None}


def plan_saver(store: Any, campaign: str, plan: Mapping[str, Any]) -> Callable[[Event], None]:
    """Critical subscriber: the visits' targets reach the store (its pose table) before the first move."""

    def save(event: Event) -> None:
        if isinstance(event, PlanReady) and event.campaign == campaign:
            store.save_plan(campaign, [(p["index"], p["role"], p["q"]) for p in event.poses], plan=plan)

    return save


@dataclass
class Verification:
    """How a verification on the station ended."""

    outcome: RunOutcome
    campaign: str
    resumed: bool
    document: dict[str, Any]  # ``hil-verification/1``: the figures (when finished) and provenance

    @property
    def exit_code(self) -> int:
        return self.outcome.exit_code


def verify(store: Any, devices: Any, config: StationConfig, base_identity: Mapping[str, Any],
           robot: Mapping[str, str], *, model: ModelInput | None, cube: Cube | None, cycles: int,
           clock: Clock, subscribers: Sequence[Callable[[Event], None]] = (), new: bool = False,
           resume_only: bool = False, truth: Mapping[str, Any] | None = None,
           close_devices: bool = True,
           on_campaign: Callable[[str, bool], None] | None = None) -> Verification:
    """Run (or resume) the verification on `devices` and store it; see the module docstring.

    `robot` is the store's robot record (type, serial, model, software). `new`: start afresh even if
    an unfinished one exists; `resume_only`: refuse unless one does. Bad input (a cube nothing serves,
    a refused lease) raises InputError before anything moves or is created; `on_campaign` hears the
    campaign id (and whether it resumes) once it is claimed.
    """
    spec_name = config.robot["type"]
    calibration, record = controller_of(spec_name, getattr(devices.robot, "info", None))
    controller = calibration.geometry(spec_name)
    ident = identity(base_identity, model, cube, cycles, calibration, record is not None)
    serial = robot.get("serial") or ""
    found = None if new else store.find_resumable(ident, robot_serial=serial)
    if resume_only and found is None:
        raise InputError("--resume: no unfinished verification of this station, robot, model, cube and "
                         "cycles")
    if found is not None:
        lease, resume = claim_run(store, ident, robot, campaign=found)
        stored = store.campaign(found).plan or {}
        design = Design.from_dict(stored["design"])
        done = {i: r for (_, i), r in (resume.records if resume else {}).items()}
        plan_doc = dict(stored)
    else:
        try:  # where the arm stands: the configuration nearest it is preferred
            start = np.asarray(devices.robot.read_joints(config.robot["joint_samples"]).q, float)
        except Exception as exc:  # a station fault (exit 3), before anything is created
            raise FaultError(f"cannot read the arm's joints: {type(exc).__name__}: {exc}") from exc
        design = design_for(config, start, model, controller, cube, cycles)
        plan_doc = plan_document(design, model, record)
        lease = store.claim_new(ident, robot, plan=plan_doc)
        done = {}
    campaign = lease.campaign
    try:
        if on_campaign is not None:
            on_campaign(campaign, found is not None)
        bus = EventBus()
        bus.subscribe(store_recorder(store), critical=True)
        bus.subscribe(plan_saver(store, campaign, plan_doc), critical=True)
        for subscriber in subscribers:
            bus.subscribe(subscriber)
        frame = model_frame(model.geometry) if model is not None else None

        def figures(records: dict[int, Any], skipped: dict[int, str]) -> dict[str, Any]:
            used = frame or registered_frame(design, records, controller)
            return evaluate(design, records, used, skipped, controller)

        started = time.time()
        visit = config.robot
        outcome = run_plan(
            config, lambda run: verification_plan(
                design, run.campaign, done, evaluate=figures, settle=visit["settle_time"],
                joint_samples=visit["joint_samples"], samples=config.campaign["samples"],
                speed=visit["speed"], acceleration=visit["acceleration"],
                max_lost=config.campaign["max_consecutive_lost"]),
            judge=lambda doc: ("accepted", summary(doc)), poses=len(design.visits()), measured=len(done),
            resumed=found is not None, bus=bus, campaign=campaign, clock=clock, devices=devices,
            lease=lease, deviation=deviation(design, frame) if frame is not None else None,
            close_devices=close_devices)
        doc = document(outcome, config, design, model, record, started, truth)
        store.set_status(campaign, outcome.status, result=doc)
    finally:
        lease.release()
    return Verification(outcome, campaign, found is not None, doc)


def document(outcome: RunOutcome, config: StationConfig, design: Design, model: ModelInput | None,
             controller: Mapping[str, Any] | None, started: float,
             truth: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """The ``hil-verification/1`` document: the figures when the test finished, and its provenance."""
    doc: dict[str, Any] = dict(outcome.result) if isinstance(outcome.result, Mapping) else {
        "format": FORMAT, "robot": design.robot, "cycles": design.cycles, "modes": list(design.modes)}
    doc.update({
        "campaign": outcome.campaign, "status": outcome.status, "exit_code": outcome.exit_code,
        "error": None if outcome.error is None else f"{type(outcome.error).__name__}: {outcome.error}",
        "station": config.station["name"], "model": model.as_dict() if model else None,
        "compensated": model is not None,
        "controller": ({"reported": True, **dict(controller)} if controller else
                       {"reported": False, "note": "the controller reported no KinematicsInfo: its model "
                                                   "taken as the nominal DH"}),
        "robot_info": outcome.robot_info, "tracker": outcome.tracker_info, "timing": outcome.timing,
        "started": started, "finished": time.time(), "software": __version__,
    })
    if truth is not None:
        doc["truth"] = dict(truth)
    return jsonable(doc)
