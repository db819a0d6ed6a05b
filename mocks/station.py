"""The simulated station: the tracker simulator and the world, started next to the robot simulator.

`station_service` is a service factory for `mocks.ur.process.serve` (it runs in the robot
simulator's process, because ur_rtde's client must not share an interpreter with the controller, and
the tracker must see the simulated arm's true joints). It loads the hidden truth (or draws a random
realistic one by seed), puts the arm at a start pose facing the tracker and serves GeoCOM on a pty
and on TCP, and emScon TPI on TCP (`mocks.emscon`, on the controller's clock), at the controller's
loopback address. Both tracker simulators measure the same world.

The controller gets its own factory calibration: the truth file's ``controller`` block if it has one,
else one fitted to this truth by seed (`mocks.ur.factory_calibration`), and the truth document the
service reports carries it, so tests and benches know the model the controller moves with.

The arm is a real one unless ``rigid``: the random truth sags under gravity and its payload and warms
up as its joints work (`mocks.heating`: moving, and a little while holding the arm; the world evaluates
``truth.grown(ΔT)``), and the controller reports the warming in RTDE ``joint_temperatures``
(`joint_temperatures`). A truth file's
``noise.encoder_sigma`` sets the controller's encoder noise and ``noise.standstill_sigma`` how far each
joint stops off its target, differently at every stop (the arm's repeatability; a random realistic
arm's is its datasheet figure, `hil.arm.joint_physics.standstill_sigma`). Every arm rings after its
joint moves (`mocks.ringing`, seen by the trackers, not by the encoders), and the GeoCOM instrument takes
`GEOCOM_MEASURE_S` of the controller's time per measurement.

Unless ``ideal`` (or ``rigid``), the random arm's link angles also carry the joint errors and lost
motion of a UR joint (`hil.calibration.synthetic.random_truth`): the robot simulator follows which way
each joint last moved (`mocks.ur.directions`) and the world lags the links by it. A truth file's own
blocks rule over ``rigid`` and ``ideal``.

The tracker's and the controller's clocks are a real station's (`hil.calibration.stream_clocks`,
`StationClocks.realistic` in every mode: an ideal arm still has two instruments): emScon's continuous
samples and RTDE's ``timestamp`` carry their own clock's offset, drift, jitter and latency. The service's
info holds them (``clocks``) and the true map between the two (``clock_map``, `StationService.clock_map`),
so a test reads the truth a stream join must find.

Faults it adds to the controller (``inject(name, **args)`` / the control channel): ``block_beam``
(``on``, ``reason``), ``tracker_unplug``, ``tracker_garble`` (GeoCOM), ``emscon_drop`` (close the
emScon client now), ``emscon_stall`` (``seconds``: wall seconds without reading or sending),
``emscon_garbage`` (a few bytes that are not a TPI packet), ``emscon_laser_cold`` (``seconds``:
simulated seconds with a cold laser).
"""

from __future__ import annotations

import dataclasses
import hashlib
from pathlib import Path
from typing import Any

import numpy as np

from hil.arm.joint_physics import IDEAL_BY_DEFAULT, standstill_sigma
from hil.arm.thermal import Thermal
from hil.calibration.model_file import load_truth, read_json, truth_controller, truth_document
from hil.calibration.stream_clocks import ClockMap, StationClocks
from hil.calibration.synthetic import Noise, random_truth
from mocks.emscon.instrument import EmsconConfig
from mocks.emscon.server import EmsconSimulator, ServerConfig
from mocks.geocom.instrument import InstrumentConfig
from mocks.geocom.server import GeoComSimulator, LinkConfig, SimulatorConfig
from mocks.heating import Heating
from mocks.ringing import Ringing
from mocks.ur.arm import AMBIENT_TEMPERATURE, TemperatureFn
from mocks.ur.factory_calibration import factory_calibration
from mocks.ur.status import RobotMode
from mocks.world import World

#: Seconds one GeoCOM measuring RPC (TMC_GetSimpleMea in tracking mode) takes inside the simulated
#: instrument. GeoCOM is the language of Leica's motorised total stations (docs/design.md,
#: Facts: GeoCOM); their tracking
#: distance mode delivers about 10 distances a second (Leica TPS1200 technical data, "Tracking" EDM
#: mode, ≈0.15 s per distance; the driver's TMC_GetSimpleMea waits up to 100 ms, `TrackerConfig.wait_ms`,
#: for one): 0.1 s is the faster end of that. The emScon simulator's point takes its stationary
#: measuring time (`tracker.measure_time`, 0.5 s by default) per sample, as an AT9xx does.
GEOCOM_MEASURE_S = 0.1


def joint_temperatures(thermal: Thermal | None, heating: Heating | None = None) -> TemperatureFn:
    """Every joint at the lab's ambient plus the arm's warm-up ΔT (none without a thermal block): from
    `heating` (what the arm did) when given, else ΔT(t) of an arm moving since the controller started.

    The truth's thermal block is one ΔT for the whole arm (docs/design.md, Contracts: non-geometric errors),
    so every joint reports it: the
    temperatures say how far the warm-up has come, the number a warm-up watch reads.
    """
    def at(t: float) -> list[float]:
        rise = (0.0 if thermal is None else heating.rise() if heating is not None
                else thermal.rise_at(t))
        return [AMBIENT_TEMPERATURE + rise] * 6

    return at


class StationService:
    """The tracker simulator and its world, as one service of the robot simulator's process."""

    def __init__(self, simulator: GeoComSimulator, world: World, truth_doc: dict[str, Any],
                 home: np.ndarray, emscon: EmsconSimulator | None = None,
                 clocks: StationClocks | None = None, controller: Any = None) -> None:
        self.simulator = simulator
        self.emscon = emscon
        self.world = world
        self.truth_doc = truth_doc
        self.home = home
        self.clocks = StationClocks.ideal() if clocks is None else clocks
        self.controller = controller

    def clock_map(self) -> ClockMap:
        """The true map from an emScon stamp to the RTDE ``timestamp`` of the same instant (after
        `start`): t_ctrl = a + (1 + d)·t_trk.

        The tracker's reference clock τ counts the simulated time from the emScon server's start over
        the station's nominal ``speed`` (`mocks.emscon.server`: its seconds pass in wall seconds while
        the station runs at that speed), the controller's running time the simulated time from the
        controller's start; so simulated time = server start + speed·τ, whatever pace the station ran
        at since (`hil.station.paced_clock`), and the two clocks' truths
        (`hil.calibration.stream_clocks`) do the rest. In fast time the map's drift is speed − 1
        beside the quartzes' ppm."""
        if self.emscon is None or self.controller is None:
            raise RuntimeError("the clock map needs the emScon simulator and the controller")
        trk, ctrl = self.clocks.tracker, self.clocks.controller
        speed = float(self.emscon.config.time_scale)
        start = self.emscon.started_at - float(self.controller.arm.started_at)  # running time at τ = 0
        # τ = (s − o_t)/r_t − λ_t;  t_ctrl = o_c + r_c·(start + speed·τ + λ_c)
        slope = ctrl.rate * speed / trk.rate
        offset = ctrl.offset_s + ctrl.rate * (start + ctrl.latency_s - speed * trk.latency_s) \
            - slope * trk.offset_s
        return ClockMap(offset, slope - 1.0)

    def start(self) -> dict[str, Any]:
        self.simulator.start()
        info = {"tracker_url": self.simulator.url, "tracker_pty": self.simulator.pty_path,
                "truth": self.truth_doc, "home": self.home.tolist()}
        if self.emscon is not None:
            try:
                self.emscon.start()
            except BaseException:
                self.simulator.stop()
                raise
            info["tracker_emscon_url"] = self.emscon.url
            if self.controller is not None:
                clock_map = self.clock_map()
                info["clock_map"] = {"offset_s": clock_map.offset_s, "drift": clock_map.drift}
        info["clocks"] = self.clocks.to_dict()
        return info

    def stop(self) -> None:
        try:
            if self.emscon is not None:
                self.emscon.stop()
        finally:
            self.simulator.stop()


def station_service(controller: Any, truth: str | None = None, seed: int = 0,
                    acceptance_angle: float = 30.0, baudrate: int | None = None,
                    tracker_port: int = 0, rigid: bool = False,
                    ideal: bool = IDEAL_BY_DEFAULT, thermal: bool = True) -> StationService:
    """Build the world and the tracker simulator around a running `SimController`.

    `rigid` (without `truth`): the random arm without compliance, payload and warm-up; `ideal` (without
    `truth`): without joint errors and lost motion; `thermal` False (without `truth`): without thermal
    growth, for tests of something else whose warm-up is off (a warm-up test's arm warms; an arm of
    fixed temperature is no real arm's, but with its warm-up off a campaign rightly reads any warming or
    cooling as drift: a fault campaign's arm started at the full rise cooled by 3.4 K toward its
    campaign's duty, `mocks.heating`).
    """
    rng = np.random.default_rng(seed)
    if truth:
        geometry, noise = load_truth(truth)
        calibration = truth_controller(read_json(truth), str(truth))
        controller.arm.set_encoder_noise(noise.encoder_sigma)
    else:
        robot = controller.config.robot
        # the realistic arm stops off its targets by its datasheet repeatability; the ideal and the rigid
        # arm stop exactly on them, as the simulator's arm did before
        noise = Noise(standstill_sigma=0.0 if rigid or ideal else standstill_sigma(robot))
        geometry, calibration = random_truth(robot, rng, rigid=rigid, ideal=ideal), None
        if not thermal:
            geometry = dataclasses.replace(geometry, thermal=None)
    controller.arm.set_standstill(noise.standstill_sigma)
    if calibration is None:
        calibration = factory_calibration(geometry, seed)
    controller.set_calibration(calibration)
    # the joints warm while they move (and a little while they hold the arm), on the controller's clock
    arm = controller.arm
    heating = None if geometry.thermal is None else Heating(
        geometry.thermal, controller.clock.now, lambda: arm.motion_seconds,
        lambda: arm.robot_mode == RobotMode.RUNNING)
    arm.set_temperatures(joint_temperatures(geometry.thermal, heating))
    # a GeoCOM reading integrates the SMR's position over its measuring time
    world = World(geometry, controller.true_joints, acceptance_angle, clock=controller.clock.now,
                  ringing=Ringing(), reading_time=GEOCOM_MEASURE_S,
                  directions=controller.joint_directions, joints_at=controller.arm.true_joints_at,
                  known_until=controller.arm.history_end,
                  rise=None if heating is None else heating.rise)
    # the links ring after every joint move (`mocks.ringing`): the tracker sees it, the encoders do not
    controller.arm.listeners.append(world.ringing.listener(world.tip_direction))
    home = world.home_pose(rng)
    controller.inject("set_joints", q=home.tolist())
    config = SimulatorConfig(instrument=InstrumentConfig(seed=seed, processing_s=GEOCOM_MEASURE_S),
                             link=LinkConfig(baudrate=baudrate),
                             address=controller.config.address, port=tracker_port)
    # the instrument measures on the controller's clock, as the emScon simulator does: a fast-time
    # station shortens its measuring time with everything else
    simulator = GeoComSimulator(world, config, sleep=controller.clock.sleep, now=controller.clock.now)
    # the tracker's and the controller's clocks differ as two real instruments' do
    # (`hil.calibration.stream_clocks`: offset, drift, jitter, latency, each with its source)
    clocks = StationClocks.realistic()
    controller.arm.controller_clock = clocks.controller
    # the tracker's clock counts the station's time over its nominal speed (`StationService.clock_map`)
    emscon = EmsconSimulator(world, ServerConfig(instrument=EmsconConfig(seed=seed, clock=clocks.tracker),
                                                 address=controller.config.address, port=0,
                                                 time_scale=float(controller.clock.speed)),
                             clock=controller.clock.now)
    # the trackers' faults, reachable through the robot simulator's control channel
    controller.extra_faults.update({
        "block_beam": world.block_beam,
        "tracker_unplug": lambda: simulator.faults.unplug(),
        "tracker_garble": lambda: simulator.faults.garble_next_reply(),
        "emscon_drop": lambda: emscon.drop(),
        "emscon_stall": lambda seconds: emscon.stall(float(seconds)),
        "emscon_garbage": lambda: emscon.garbage(),
        "emscon_laser_cold": lambda seconds: emscon.laser_cold(float(seconds)),
    })
    def clock_pair() -> list[float]:
        """(tracker stamp, RTDE timestamp) of one instant, jitter-free, read from the running clocks
        (the emScon server's paired read of its two clocks): what `StationService.clock_map` predicts."""
        now, tau = emscon.paired_times()
        running = emscon.started_at + now - controller.arm.started_at
        return [float(clocks.tracker.reading(tau + clocks.tracker.latency_s)),
                float(clocks.controller.reading(running + clocks.controller.latency_s))]

    controller.extra_state.update({
        "clock_pair": clock_pair,
        "tracker_measurements": lambda: simulator.instrument.measurements,
        "tracker_measuring_seconds": lambda: simulator.instrument.measuring_seconds,
        # emScon's: its stationary measurements and their measuring time (the sweep's stream is not one)
        "emscon_measurements": lambda: emscon.instrument.stationary_measurements,
        "emscon_measuring_seconds": lambda: emscon.instrument.stationary_seconds,
        # the arm's temperature rise now (K), for tests and benches that check what the arm went through
        "thermal_rise": lambda: 0.0 if heating is None else heating.rise(),
    })
    return StationService(simulator, world, truth_document(geometry, noise, calibration), home, emscon,
                          clocks, controller)


def station_spec(truth: str | None = None, seed: int = 0, acceptance_angle: float = 30.0,
                 baudrate: int | None = None, rigid: bool = False,
                 ideal: bool = IDEAL_BY_DEFAULT, thermal: bool = True) -> str:
    """The service spec that puts the world and the tracker into the robot simulator's process."""
    import json

    options = {"truth": truth, "seed": seed, "acceptance_angle": acceptance_angle, "baudrate": baudrate,
               "rigid": rigid, "ideal": ideal, **({} if thermal else {"thermal": False})}
    return "mocks.station:station_service " + json.dumps(options)


def start_station(robot: str = "ur5e", truth: str | None = None, speed: float = 1.0, seed: int = 0,
                  acceptance_angle: float = 30.0, baudrate: int | None = None, rigid: bool = False,
                  ideal: bool = IDEAL_BY_DEFAULT, thermal: bool = True) -> Any:
    """Start the whole simulated station in its own process on a free loopback address.

    Returns the running `mocks.ur.process.SimProcess`; ``.info["services"][0]`` holds the tracker's
    URL and pty and the hidden truth. The caller must `stop()` it. `rigid`: a random arm without
    compliance, payload and warm-up (the arm of the simulator before they existed); `ideal`: without
    joint errors and lost motion (the ideal arm); `thermal` False: without thermal growth (`station_service`).
    """
    from mocks.ur.controller import SimConfig
    from mocks.ur.testing import start_sim

    spec = station_spec(truth, seed, acceptance_angle, baudrate, rigid, ideal, thermal)
    serial = simulated_serial(robot, seed, truth, rigid, ideal, thermal)
    return start_sim(SimConfig(robot=robot, speed=speed, seed=seed, serial=serial), services=[spec])


def simulated_serial(robot: str, seed: int, truth: str | None = None, rigid: bool = False,
                     ideal: bool = IDEAL_BY_DEFAULT, thermal: bool = True) -> str:
    """The serial number a simulated arm's controller reports (dashboard ``get serial number``).

    Each simulated arm is a robot of its own, as each arm of a plant is: the serial is derived from
    what makes the arm — its type, the seed of its random truth, noise and start pose, the truth file's
    bytes (sha256), whether it is rigid, ideal or without thermal growth (a truth file's arm is what
    the file says, so these count only without one) — so the same simulated arm always has the same serial (a
    re-run resumes its campaign, which is found by serial) and two different ones never share one (on
    one machine they would refuse each other as one robot driven twice; the seed alone once made every
    UR5e and UR10e of seed 1 serial 20235500001). 11 digits like a UR serial (ur_rtde refuses a serial
    that is not a number), beginning ``9999`` where a real one has its year of manufacture, so a
    simulated robot is recognisable in any listing; the other 7 digits come from the arm's hash.
    """
    truth_sha = hashlib.sha256(Path(truth).read_bytes()).hexdigest() if truth else ""
    key = f"{robot.lower()}|seed={int(seed)}|truth={truth_sha}|rigid={bool(rigid)}"
    if not truth and not rigid and not ideal:  # the ideal arm keeps the serial it always had
        key += "|realistic"
    if not truth and not thermal:
        key += "|no-thermal"
    return f"9999{int(hashlib.sha256(key.encode()).hexdigest(), 16) % 10**7:07d}"
