"""The ISO 9283 pose test as a job: ``hil verify`` on its own, and ``hil calibrate --verify`` right after
an accepted calibration on the same devices.

Both take the station the one way (`hil.jobs.station.take_station`) and run `hil.verify.session.verify`,
which stores the test like a campaign (resumable after Ctrl-C or ``kill -9``). The test cube is checked
against the arm's reach and the keep-in box before anything connects: a cube no configuration serves
is bad input, never a clamped target.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from hil.errors import InputError
from hil.jobs.outcome import EXIT_BAD_INPUT, EXIT_FAULT, JobOutcome
from hil.jobs.station import (
    StationSetup,
    StationSource,
    TakenStation,
    station_setup,
    store_location,
    take_station,
)
from hil.jobs.words import Say, outage_words, quiet

if TYPE_CHECKING:
    from hil.campaign.events import Event
    from hil.campaign.runner import RunOutcome
    from hil.station.config import StationConfig
    from hil.verify.cube import Cube
    from hil.verify.inputs import ModelInput


def checked_cube(config: StationConfig, sim: bool, tool: Any = None) -> Cube | None:
    """The ``[verify]`` cube (None: the simulated station's default), checked against the arm's reach
    and the keep-in box for the SMR at `tool` (default: the configured offset) before anything
    connects."""
    from hil.verify.design import check_cube
    from hil.verify.inputs import cube_where, requested_cube

    cube = requested_cube(config, sim=sim)
    if cube is not None:
        check_cube(config.robot["type"], cube, config.smr["offset"] if tool is None else tool,
                   (config.keep_in["min"], config.keep_in["max"]), cube_where(config))
    return cube


@dataclass(frozen=True)
class VerifyOptions:
    """``hil calibrate --verify``'s options: the cycles (None: ``verify.cycles``), how the result file is
    named in "resume it with --model ..." and the subscribers the pose test's events go to."""

    cycles: int | None = None
    result_name: str | None = None
    subscribers: Callable[[], Sequence[Callable[[Event], None]]] = tuple


@dataclass(frozen=True)
class VerifyAfter:
    """The pose test that follows an accepted calibration, its cube already checked."""

    cube: Cube | None
    cycles: int
    speed: float
    options: VerifyOptions = field(default_factory=VerifyOptions)

    @classmethod
    def of(cls, config: StationConfig, options: VerifyOptions, speed: float, sim: bool) -> VerifyAfter:
        """`options` for the station of `config` (`sim`: the simulated one, whose cube has a default)."""
        return cls(checked_cube(config, sim), options.cycles or config.verify["cycles"], speed, options)


def verify_after(after: VerifyAfter, run: RunOutcome, taken: TakenStation, identity: Mapping[str, Any],
                 truth: Mapping[str, Any] | None, *, say: Say = quiet, setup: StationSetup | None = None
                 ) -> tuple[dict[str, Any], int]:
    """``--verify``: the ISO 9283 pose test with the model just accepted, on the same devices.

    Returns the result's ``verification`` block and the exit code it asks for (0: done; the test's own
    code when it did not finish: 3 fault, 130 interrupted — resumable by ``hil verify --model`` with the
    calibration's result; 2 when no configuration serves the cube). Nothing runs unless the calibration
    was accepted. The calibration's result is already stored, so whatever happens here it stays.
    """
    if run.status != "accepted" or run.result is None or run.unrecorded is not None:
        return {"status": "not run", "reason": f"the calibration ended {run.status}"}, 0
    from hil.arm.geometry import Geometry
    from hil.campaign.engine import RealClock
    from hil.verify.inputs import ModelInput
    from hil.verify.session import verify

    doc = run.result.model
    model = ModelInput.of(doc, Geometry.from_dict(doc, source="the calibrated model"),
                          f"campaign {run.campaign}")
    say("verifying the calibrated model (ISO 9283 pose test)", "information")
    try:
        with (setup.clock(after.speed) if setup is not None
              else contextlib.nullcontext(RealClock(after.speed))) as clock:
            done = verify(taken.store, taken.devices, taken.config, identity, taken.robot.as_dict(),
                          model=model, cube=after.cube, cycles=after.cycles, clock=clock,
                          subscribers=after.options.subscribers(), truth=truth)
    except InputError as exc:  # no configuration serves the cube: the calibration stands, said so
        say(f"error: --verify: {exc}", "error")
        return {"status": "not run", "reason": str(exc)}, EXIT_BAD_INPUT
    if done.outcome.status == "interrupted":
        say(f"verification {done.campaign} is resumable: run hil verify on this station with --model "
            f"{after.options.result_name or 'the calibration result'} to continue it", "information")
    return done.document, done.exit_code


@dataclass(frozen=True)
class VerificationRequest:
    """``hil verify``: the station, hil's model (None: the uncompensated test only) and how to run."""

    source: StationSource
    model: ModelInput | None = None
    cycles: int | None = None  # None: ``verify.cycles``
    db: str | None = None
    new: bool = False  # start afresh even if one is unfinished
    resume_only: bool = False  # refuse unless one is unfinished


def check_model_robot(model: ModelInput | None, config: StationConfig) -> None:
    """A model of another arm type than the station's is bad input, naming both."""
    if model is not None and model.geometry.robot != config.robot["type"]:
        raise InputError(f"--model {model.source} is a model of a {model.geometry.robot}, the station's "
                         f"robot.type is {config.robot['type']}")


def run_verification(request: VerificationRequest, *, subscribers: Sequence[Callable[[Event], None]] = (),
                     say: Say = quiet) -> JobOutcome:
    """Run (or resume) the pose test (module docstring); the outcome's document is its
    ``hil-verification/1``, None unless it finished."""
    from hil.station.devices import HARDWARE_ERRORS

    model = request.model
    if request.db:  # --db needs no config: refused before a simulated station starts
        store_location(request.db, request.source, None)
    with station_setup(request.source) as setup:
        config = setup.config
        check_model_robot(model, config)
        # before anything connects: a cube beyond reach is bad input
        cube = checked_cube(config, request.source.sim is not None, model.geometry.smr if model else None)
        cycles = request.cycles or config.verify["cycles"]
        location = store_location(request.db, request.source, config, say)
        with contextlib.ExitStack() as stack:
            try:
                taken = stack.enter_context(take_station(config, what="hil verify", store=location))
            except HARDWARE_ERRORS as exc:
                say(f"hardware fault: cannot connect: {type(exc).__name__}: {exc}", "error")
                return JobOutcome(EXIT_FAULT, "failed")
            assert taken.store is not None
            taken.store.on_outage = outage_words(say)
            # the run's modules once the station is taken: a refusal before it does not load them
            from hil.store import FINISHED, StoreError
            from hil.verify.session import verify

            def started(campaign: str, resumed: bool) -> None:
                # the run's start itself ("starting verification …", its visits, cycles and modes) is
                # the front-end's to show from RunStarted (the CLI's progress): said here too, it was
                # printed twice; what only the job knows is why the test is uncompensated only
                if model is None:
                    say(f"verification {campaign}: no --model, so the uncompensated test only (the "
                        "controller's own model)", "information")

            try:
                with setup.clock(request.source.speed) as clock:
                    done = verify(taken.store, taken.devices, config, setup.identity, taken.robot.as_dict(),
                                  model=model, cube=cube, cycles=cycles, clock=clock,
                                  subscribers=subscribers, new=request.new, resume_only=request.resume_only,
                                  truth=setup.truth, on_campaign=started)
            except StoreError as exc:  # the result could not be recorded (a full disk): a fault
                say(f"fault: could not record the verification: {exc.__cause__ or exc}", "error")
                return JobOutcome(EXIT_FAULT, "failed")
    status = done.outcome.status
    if status not in FINISHED:
        if status == "interrupted":
            say(f"verification {done.campaign} is resumable: re-run the same command to continue it",
                "information")
        return JobOutcome(done.exit_code, status, done.campaign)
    return JobOutcome(done.exit_code, status, done.campaign, done.document)
