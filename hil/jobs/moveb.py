"""A MOVEB run as a job: plan the program, stream it through the arm's servo loop, measure the path.

The arm is driven only on a station taken by `hil.jobs.station.take_station` (the arm's host-local
address lock, the one ``hil calibrate``, ``hil verify`` and the terminal app take): a MOVEB run never
drives an arm another hil process of this host drives, and the other way round. That lock is its only
guard: a MOVEB run opens no campaign store, so it takes no robot lease there (a lease in one store is
seen only by the campaigns of that store; the lock by every hil process of this host).

Every source naming the arm must agree — ``--robot``, the model, the truth, the configuration and the
controller: IK on another robot's kinematics would drive the arm somewhere unplanned.
"""

from __future__ import annotations

import contextlib
from dataclasses import dataclass
from typing import Any

from hil.errors import InputError
from hil.files.quantities import quantity
from hil.jobs.outcome import EXIT_FAILED, EXIT_FAULT, EXIT_OK, JobOutcome
from hil.jobs.station import StationSource, station_setup, take_station
from hil.jobs.words import Say, quiet

FORMAT = "hil-moveb-run/1"
#: Where the program runs: as written in the base frame, at the arm's current TCP pose, or in front of
#: the robot towards the tracker with the tool facing it.
FRAMES = ("base", "current", "tracker")


@dataclass(frozen=True)
class MovebRequest:
    """``hil moveb run``'s options, checked (`check`) before the station starts."""

    program: str
    config: str | None = None  # station.toml, or None with `sim`
    sim: bool = False
    truth: str | None = None
    speed: float = 1.0
    seed: int | None = None  # --sim only: None is 1 (`StationSource.of`)
    robot: str | None = None  # --robot
    tracker_protocol: str | None = None
    ideal: bool | None = None  # --sim without a truth: the ideal arm (None: the simulator's default)
    model: str | None = None  # a hil-model/1, a result embedding one, or a truth
    ik: str = "model"  # "model" or "nominal" (the uncalibrated arm, measured in the model's frame)
    continuity: str = "G2"
    frame: str | None = None  # FRAMES; None: "tracker" with --sim, else "base"
    velocity: float = 100.0  # mm/s
    acceleration: float = 1000.0  # mm/s²
    jerk: float = 10000.0  # mm/s³
    normal_acceleration: float = 1000.0  # mm/s²
    joint_speed: float = 1.0  # fraction of the datasheet joint speeds
    joint_acceleration: float | None = None  # rad/s²
    tracker_rate: float = 100.0  # Hz
    min_coverage: float = 0.9

    def check(self) -> None:
        """Refuse ranges the command line's types did not already (a caller other than the CLI)."""
        quantity("tracker rate").check(float(self.tracker_rate), "--tracker-rate")
        quantity("fraction").check(float(self.joint_speed), "--joint-speed")
        quantity("fraction").check(float(self.min_coverage), "--min-coverage")
        if self.joint_acceleration is not None:
            quantity("joint acceleration").check(float(self.joint_acceleration), "--joint-acceleration")

    @property
    def place(self) -> str:
        return self.frame or ("tracker" if self.sim else "base")


@dataclass
class MovebOutcome(JobOutcome):
    """A MOVEB run's end; `run` is the executed run (`hil.moveb.run.RunResult`) for a figure."""

    run: Any = None


def _fault(exc: BaseException) -> MovebOutcome:
    return MovebOutcome(EXIT_FAULT, "hardware fault", document={
        "status": "hardware fault", "error": f"{type(exc).__name__}: {exc}", "exit_code": EXIT_FAULT})


def smr_words(smr_mm: Any, source: str) -> str:
    """What a run without a model says of the SMR offset it assumes: a wrong one shows as path error."""
    x, y, z = (float(v) for v in smr_mm)
    return (f"no model: the SMR centre is assumed at ({x:.1f}, {y:.1f}, {z:.1f}) mm in the flange frame "
            f"({source}); an error in it shows as path error wherever the tool turns")


def run_moveb(request: MovebRequest, *, say: Say = quiet) -> MovebOutcome:
    """Plan, execute and measure the program (module docstring); the outcome's document is the
    ``hil-moveb-run/1`` result (a hardware fault included: ``status`` says it, exit code 3).

    The result names the SMR offset the run used and where it came from (``smr``): the model's, else
    the configuration's ``smr.offset`` (the simulated station's: its SMR holder's drawing). Without a
    model `say` says it before the arm moves: the tracker measures the SMR, the path is commanded for
    the assumed one, and the difference shows wherever the tool turns."""
    # What refuses bad input is imported first; the planner and the run's solvers (SciPy's splines,
    # the compensator: most of a cold start) only once the station is taken, so that a controller of
    # another robot is refused without them (issue 31: every refusal within 2 s).
    import numpy as np

    from hil.arm.geometry import Geometry
    from hil.moveb.program import load_program
    from hil.moveb.timing import Limits
    from hil.station.devices import HARDWARE_ERRORS
    from hil.station.robot_type import Claim, agreed_robot, config_claim, option_claim

    request.check()
    program = load_program(request.program)
    limits = Limits(request.velocity, request.acceleration, request.jerk, request.normal_acceleration)
    model = None
    if request.model:
        from hil.calibration.model_file import load_geometry

        model = load_geometry(request.model)[0]
    place = request.place
    if place == "tracker" and not (request.sim or model is not None):
        raise InputError("--frame tracker: needs --model (its tracker pose) or --sim")
    said = option_claim(request.robot)
    if model is not None:
        said.append(Claim(model.robot, f"the model {request.model} is for {model.robot}"))
    robot = request.robot
    if request.sim:
        if request.truth:
            from hil.calibration.model_file import load_truth

            truth_robot = load_truth(request.truth)[0].robot
            said.append(Claim(truth_robot, f"the truth {request.truth} is for {truth_robot}"))
        robot = agreed_robot(said, default="ur5e")  # the arm the simulator is to simulate
    source = StationSource.of(config=request.config, sim=request.sim, truth=request.truth,
                              speed=request.speed, seed=request.seed, robot=robot,
                              tracker_protocol=request.tracker_protocol, ideal=request.ideal)
    with station_setup(source) as setup, contextlib.ExitStack() as stack:
        config, truth = setup.config, setup.truth
        agreed_robot([config_claim(config), *said])  # --config: its robot.type, before connecting
        geometry = model or Geometry.nominal(config.robot["type"], smr=config.smr["offset"])
        smr_source = (f"the model {request.model}" if model is not None else
                      "the simulated station's smr.offset, from its SMR holder's drawing" if request.sim
                      else f"smr.offset of {request.config}")
        if model is not None and request.ik == "nominal":
            # the uncalibrated arm, measured in the model's base frame (its tracker pose and SMR):
            # the absolute path error calibration removes, not only its non-rigid part
            geometry = Geometry.nominal(model.robot, smr=model.smr, tracker=model.tracker)
        if place == "tracker":  # where the tracker stands: the model's, else the simulated world's
            from hil.moveb.run import facing_frame, program_in_frame

            where = (model.tracker if model is not None else Geometry.from_dict(truth, source="sim")
                     .tracker).translation
            program = program_in_frame(program, facing_frame(program, where, geometry.spec.reach))
        try:
            taken = stack.enter_context(take_station(config, what="hil moveb run", claims=said))
        except HARDWARE_ERRORS as exc:
            return _fault(exc)
        from hil.arm.kinematics import Kinematics
        from hil.moveb.path_plan import plan_program
        from hil.moveb.run import NothingMeasured, execute, program_in_frame

        devices = taken.devices
        smr_mm = [float(v) * 1e3 for v in geometry.smr]
        if model is None:
            say(smr_words(smr_mm, smr_source), "warning")
        try:
            if place == "current":
                q = np.asarray(devices.robot.read_joints(1).q, dtype=float)
                F = Kinematics(geometry).flange_poses(q)[0]
                anchor = F.copy()
                anchor[:3, 3] = (F[:3, :3] @ geometry.smr + F[:3, 3]) * 1e3
                program = program_in_frame(program, anchor)
            plan = plan_program(program, request.continuity)
            keep_in = (np.array(config.keep_in["min"]), np.array(config.keep_in["max"]))
            result = execute(devices, plan, geometry, limits, registered=model is None,
                             tracker_rate=request.tracker_rate, joint_speed_fraction=request.joint_speed,
                             joint_acceleration=request.joint_acceleration, keep_in=keep_in)
        except HARDWARE_ERRORS as exc:
            return _fault(exc)
        except NothingMeasured as exc:  # where the tracker stands, not a fault of the hardware
            return MovebOutcome(EXIT_FAILED, "incomplete", document={
                "format": FORMAT, "status": "incomplete", "exit_code": EXIT_FAILED, "error": str(exc),
                "program": request.program, "frame": place, "coverage": 0.0, "lost_samples": exc.lost,
                "path_accuracy": None})
    doc: dict[str, Any] = {"format": FORMAT, "status": "done", "exit_code": EXIT_OK}
    cov = result.coverage
    if cov is not None and cov.fraction < request.min_coverage:
        a, b = cov.largest_gap
        doc.update(status="incomplete", exit_code=EXIT_FAILED,
                   error=f"the tracker measured {cov.fraction:.0%} of the path ({result.lost} records lost; "
                         f"longest unmeasured stretch s = {a:.1f}-{b:.1f} mm): the figures describe only "
                         "the measured part; keep the SMR facing the tracker with a clear line of sight")
    timing = result.stream
    if timing is not None and timing.warning():
        say(timing.warning(), "warning")
    if timing is not None and timing.disturbed and doc["status"] == "done":
        doc.update(status="stream late", exit_code=EXIT_FAILED,
                   error=f"hil's servo stream left the arm without a new target for up to "
                         f"{timing.max_gap_s * 1e3:.0f} ms (more than the {timing.lookahead_s * 1e3:.0f} ms "
                         f"lookahead): its straight leg can have cut the path by {timing.chord_mm:.3f} mm, "
                         "which the figures include; run on an idle machine")
    doc.update({"program": request.program, "frame": place, "continuity": request.continuity,
                "model": request.model, "ik": "nominal" if model is None else request.ik,
                "registered": result.registered, "smr": {"offset_mm": smr_mm, "source": smr_source},
                "cycle_time_s": result.cycle_time,
                "lost_samples": result.lost,
                "coverage": None if cov is None else cov.fraction,
                "path_accuracy": result.accuracy, "path_accuracy_registered": result.accuracy_registered,
                "joint_speeds": result.joint_speeds,
                "servo": None if timing is None else timing.as_dict()})
    return MovebOutcome(int(doc["exit_code"]), str(doc["status"]), document=doc, run=result)
