"""Taking a station: the one sequence every job that drives an arm goes through.

Where a job's station comes from (`StationSource`: a station configuration, or the simulated station
started for the job) and how the arm is taken (`take_station`): the host-local lock on the arm's
address, the controller's word on the robot type checked, the robot and the tracker opened, the
store opened or created, one robot identity. ``hil calibrate``, ``hil verify``, ``hil moveb run`` and
the terminal app all take the arm this way, so a guard added here guards every one of them; before
this module each front-end spelled the sequence out itself, and the lock and the robot-type check had
to be added to each in turn.

Order matters, and is the same for all:

1. an existing store is opened first (a damaged or newer one is refused before the arm is touched);
2. the arm's address lock (`hil.store.address_lock`): no second hil process of this host connects;
3. the controller asked what it is (`hil.station.devices.ask_controller`: RTDE's version and the
   dashboard's model and serial, read-only) and its model checked against ``robot.type`` and every
   other claim (`check_controller`) — before the devices, whose opening and closing take seconds
   (the driver's client process, its control script uploaded and stopped again, the tracker): a
   controller of another robot is refused within milliseconds of connecting;
4. the devices (`hil.station.devices.open_devices`; a driver error leaves nothing open and is raised
   as it is, typed, for the caller to report as a station fault), and the connected controller's
   word checked again (it is what the run records as the robot);
5. only then is a new store file created, so a refused station leaves no file behind.

Everything taken is released on every way out (an exception, Ctrl-C, a normal end) in reverse order.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from drivers.robot.model import RobotIdentity
from hil.errors import InputError
from hil.files.quantities import quantity
from hil.jobs.words import Say, quiet, simulated_store_words
from hil.station.config import StationConfig, check_runnable, load_config
from hil.station.robot_type import Claim, agreed_robot, check_controller, config_claim, option_claim

if TYPE_CHECKING:
    from hil.campaign.engine import Clock
    from hil.station.devices import Devices
    from hil.store import Store


@dataclass(frozen=True)
class SimulatedSpec:
    """The simulated station a job starts for itself (``--sim``)."""

    robot: str | None = None  # None: the truth's, else a UR5e
    truth: str | None = None  # a hil-truth/1 file, else a random arm from `seed`
    speed: float = 1.0  # fast-time factor
    seed: int = 1
    tracker_protocol: str = "geocom"
    ideal: bool | None = None  # without `truth`: the ideal arm (None: the simulator's default)


@dataclass(frozen=True)
class StationSource:
    """Where a job's station comes from: a loaded configuration, or a simulated station.

    `overrides` are ``section__key`` values the command line or the app set over the configuration
    (``campaign__calibration_poses``...); with a configuration they change the campaign's identity too.
    """

    config: StationConfig | None = None
    sim: SimulatedSpec | None = None
    overrides: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def of(cls, *, config: str | StationConfig | None, sim: bool, truth: str | None = None,
           speed: float = 1.0, seed: int | None = None, robot: str | None = None,
           tracker_protocol: str | None = None, overrides: dict[str, Any] | None = None,
           ideal: bool | None = None) -> StationSource:
        """The source the options name (``--config`` or ``--sim`` and theirs), checked before anything
        starts: the simulator's options with a configuration, a non-positive speed, an unknown
        ``--robot`` or one the configuration contradicts, ``--ideal``/``--no-ideal`` with a truth file
        (whose own blocks say what the arm has) are bad input (InputError naming them)."""
        said = option_claim(robot)  # an unknown --robot is refused first, named
        overrides = dict(overrides or {})
        if config is not None:
            if ideal is not None:
                raise InputError(f"--{'' if ideal else 'no-'}ideal goes with --sim, not --config: it "
                                 "chooses the simulated arm")
            if truth or speed != 1.0 or tracker_protocol or seed is not None:
                given = [o for o, v in (("--truth", truth), ("--speed", speed != 1.0),
                                        ("--tracker-protocol", tracker_protocol),
                                        ("--seed", seed is not None)) if v]
                raise InputError(f"{', '.join(given)}: {'go' if len(given) > 1 else 'goes'} with --sim, not "
                                 "--config (the configuration's tracker.protocol says which tracker it has, "
                                 "campaign.seed its seed)")
            loaded = config if isinstance(config, StationConfig) else load_config(config)
            loaded = check_runnable(loaded)  # before a store is opened or created
            agreed_robot([config_claim(loaded), *said])  # both must name the same arm
            _check_sweep(overrides.get("campaign__mode"), loaded.tracker["protocol"],
                         f"{loaded.source}: tracker.protocol")
            return cls(config=loaded, overrides=overrides)
        if not sim:
            raise InputError("--config or --sim: which station?")
        quantity("simulated speed").check(float(speed), "--speed")
        _check_sweep(overrides.get("campaign__mode"), tracker_protocol or "geocom",
                     "--tracker-protocol" if tracker_protocol else "--sim's tracker (GeoCOM unless "
                     "--tracker-protocol emscon)")
        if truth and ideal is not None:
            raise InputError(f"--{'' if ideal else 'no-'}ideal chooses a random arm: the truth {truth} "
                             "says itself whether its arm has joint errors and lost motion")
        return cls(sim=SimulatedSpec(robot, truth, speed, 1 if seed is None else seed,
                                     tracker_protocol or "geocom", ideal),
                   overrides=overrides)

    @property
    def speed(self) -> float:
        """The station's clock speed: fast time for a simulated one, real time for a real one."""
        return self.sim.speed if self.sim is not None else 1.0


def _check_sweep(mode: str | None, protocol: str, where: str) -> None:
    """``--mode sweep`` with a tracker that cannot stream is bad input, said in one line before anything
    connects (`hil.station.config.sweep_refused`); the configuration's own ``campaign.mode`` is checked
    with the rest of the file."""
    from hil.station.config import sweep_refused

    problem = sweep_refused(protocol) if mode == "sweep" else None
    if problem:
        raise InputError(f"--mode sweep: {problem} ({where} is {protocol})")


@dataclass(frozen=True)
class StationSetup:
    """A station ready to be taken: its configuration and what identifies its runs in the store."""

    config: StationConfig  # to run with
    identity: dict[str, Any]  # the configuration that identifies a campaign (no addresses of a sim)
    truth: dict[str, Any] | None  # the simulated arm's hidden truth (None: a real station)
    simulator: Any = None  # the running simulator (fault injection), None for a real station

    @contextlib.contextmanager
    def clock(self, speed: float) -> Iterator[Clock]:
        """The engine's clock for a run on this station: the wall clock on a real one; on a simulated
        one in fast time a `PacedClock`, so that the host's computing between steps is not multiplied
        into simulated standstill (`hil.station.paced_clock`). The simulator gets its full speed back
        when the run ends."""
        from hil.campaign.engine import RealClock

        if self.simulator is None or speed == 1.0:
            yield RealClock(speed)
            return
        from hil.station.paced_clock import PacedClock, simulator_pace

        paced = PacedClock(speed, simulator_pace(self.simulator))
        try:
            yield paced
        finally:
            paced.close()


@contextlib.contextmanager
def station_setup(source: StationSource) -> Iterator[StationSetup]:
    """The station of `source`, set up for a job (a simulated one started, and stopped on exit)."""
    if source.sim is None:
        assert source.config is not None
        config = source.config.with_overrides(**source.overrides) if source.overrides else source.config
        yield StationSetup(config, config.as_dict(), None)
        return
    from hil.station.simulated import simulated_station

    sim = source.sim
    with simulated_station(sim.robot, sim.truth, sim.speed, sim.seed, sim.tracker_protocol,
                           ideal=sim.ideal, **source.overrides) as (config, identity, truth, simulator):
        yield StationSetup(config, identity, truth, simulator)


@dataclass
class TakenStation:
    """A station taken by one job: its open devices, the arm they drive, and the store."""

    config: StationConfig
    devices: Devices
    robot: RobotIdentity
    store: Store | None = None
    devices_closed: bool = False  # a run closed them as it ended (`run_plan`): not closed again

    def close_devices(self) -> None:
        """Close the devices, once (`take_station` on its way out, unless a run already did)."""
        if not self.devices_closed:
            self.devices_closed = True
            self.devices.close()


def store_location(db: str | None, source: StationSource, config: StationConfig | None,
                   say: Say = quiet) -> Any:
    """Where a job on `source` keeps its campaigns (`hil.store.resolve_location`): `db` (``--db``) if
    given; else a simulated station's go to the simulated stations' own store, never ``$HIL_DB``'s or
    the default (the plant's history; `hil.store.paths`), and the job says where; else ``$HIL_DB``, the
    configuration's ``store.url``, the user's default."""
    import os

    from hil.store.paths import ENV_VAR, check_store, locate

    simulated = source.sim is not None and not db
    located = locate(db, config, simulated=simulated)
    if simulated:
        say(simulated_store_words(located.location, bool(os.environ.get(ENV_VAR))), "information")
    check_store(located, create=True)  # before any connection: a store that cannot be is bad input
    return located.location


#: Seconds without an RTDE package after which ur_rtde's client drops the link (docs/design.md, Facts:
#: ur_rtde against a simulator).
RTDE_PATIENCE_S = 2.5


def simulator_words(simulator: Any) -> str | None:
    """After a fault on a simulated station, whether the simulator itself went silent: its longest
    wall-time pause between two controller cycles (each sends the RTDE package) against ur_rtde's
    2.5 s of patience, and its late cycles. A link lost under load is then the simulator's starving or
    the client's own, told apart. None for a real station, or a simulator that does not
    answer (it may be what failed)."""
    if simulator is None:
        return None
    try:
        state = simulator.state()
        gap, late = float(state["max_tick_gap_s"]), int(state["late_ticks"])
    except Exception:  # a simulator that died or hangs: the fault said already is the news
        return None
    verdict = ("longer than ur_rtde waits: the simulator starved (a loaded machine)" if gap >= RTDE_PATIENCE_S
               else f"within the {RTDE_PATIENCE_S:g} s ur_rtde waits: the simulator kept sending")
    return (f"the simulated controller's longest pause between cycles was {gap:.2f} s, {verdict}; "
            f"{late} cycles ran late")


def open_existing_store(location: Any, config: StationConfig | None) -> Store | None:
    """The store at `location` if it exists (a server always does), opened now so that a damaged or a
    newer one is refused before the arm is touched; None for a file still to be created."""
    if isinstance(location, Path) and not location.exists():
        return None
    from hil.store import Store  # SQLAlchemy, not needed to find that there is no file yet

    return Store.open(location, config=config)


@contextlib.contextmanager
def take_station(config: StationConfig, *, what: str, claims: Sequence[Claim] = (),
                 store: Any = None) -> Iterator[TakenStation]:
    """Take the station for one job (see the module docstring); `what` names the job in the lock.

    `claims` are further words on the robot type (``--robot``, a model file) the controller must agree
    with; it is asked before the devices are opened, so a disagreement opens nothing. `store`: None
    (the job needs none), an open `Store` (kept open: its owner closes it), or a location
    (`hil.store.resolve_location`) opened here (created once the controller agreed) and closed on exit.
    A held lock is `hil.store.LeaseRefused` (bad input, naming the holder); a controller that does not
    answer, or a device that cannot be opened, raises its driver's error after everything taken is
    released.
    """
    from hil.station import devices as station_devices
    from hil.store import address_lock

    # a location is what `hil.store.resolve_location` returns (a Path or a URL), anything else an open
    # Store: told apart without importing the store (SQLAlchemy, a quarter of a second cold) before
    # the controller is asked, so a refused station is refused without it
    location: Path | str | None = store if isinstance(store, Path | str) else None
    given: Store | None = None if location is not None else store  # handed in: its owner closes it
    with contextlib.ExitStack() as stack:
        opened: Store | None = None
        if location is not None:
            opened = open_existing_store(location, config)
            if opened is not None:
                stack.callback(opened.close)
        stack.enter_context(address_lock(config.robot["address"], what=what))
        check_controller(config, station_devices.ask_controller(config), *claims)  # before opening
        devices = station_devices.open_devices(config)
        info = devices.robot.info
        taken = TakenStation(config, devices, RobotIdentity.of(config.robot["type"], info))
        stack.callback(taken.close_devices)
        check_controller(config, info, *claims)  # the robot the run records, before anything is moved
        if location is not None and opened is None:
            from hil.store import Store

            opened = Store.open(location, config=config)
            stack.callback(opened.close)
        taken.store = given if given is not None else opened
        yield taken
