"""The simulated arm and controller state: joints, motion, safety, program, RTDE registers.

One `SimArm` is the single source of truth of a simulated controller. The protocol servers (RTDE,
dashboard, script) and the fault-injection channel only call its methods; a tick thread advances it at
the controller rate (500 Hz e-series, 125 Hz CB3) on the shared `SimClock`. Everything is guarded by
one re-entrant lock, so it is safe to read ``true_joints()`` from another service in the same process
(the tracker simulator looks at the *true* joints: what the encoders read, minus their noise).

Each joint move stops a little off its commanded angles, differently at every stop (the arm's
repeatability, `ArmConfig.standstill_sigma`, `hil.arm.joint_physics.standstill_sigma`): the true joints
end at the target plus that error, which the encoders see (``actual_q``) while ``target_q`` keeps the
command during the move. Encoder noise is added to ``actual_q`` only; ``actual_TCP_pose`` is computed
from ``actual_q`` with the controller's *own* model (nominal DH plus its factory deltas,
`mocks.ur.hil_model.controller_fk`), as a real controller does not know the arm's hidden errors.
`set_fk` swaps that model (a new calibration).

RTDE's ``timestamp`` is the controller's running time read on its own clock (`controller_clock`,
perfect unless the simulated station sets its truth: `hil.calibration.stream_clocks`); the joints'
temperatures and every internal duration run on the running time itself.

``joint_temperatures`` come from `SimArm.temperatures`, a function of the controller's running time set by
whoever knows how the arm warms (the simulated station, from its truth's thermal block); without one
every joint stays at the lab's `AMBIENT_TEMPERATURE`.
"""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from hil.calibration.stream_clocks import InstrumentClock
from hil.calibration.synthetic import ENCODER_SIGMA
from mocks.ur.clock import SimClock
from mocks.ur.directions import JointDirections
from mocks.ur.history import JointHistory
from mocks.ur.kin import FkFn, matrix_to_pose, pose_to_matrix
from mocks.ur.motion import Decelerate, JointMove, LinearMove, MotionError
from mocks.ur.status import RobotBit, RobotMode, RuntimeState, SafetyBit, SafetyMode

log = logging.getLogger(__name__)

PROTECTIVE_STOP_UNLOCK_DELAY = 5.0  # simulated seconds, as on PolyScope 5
SAFETY_STOP_DECEL = 8.0  # rad/s^2 of the fastest joint in a category-1/2 stop
# rad/s^2 of the fastest joint when a program stops (dashboard/pendant stop, a script that ends, a program
# replaced by another): a real controller brings the arm to a controlled stop on its trajectory with the
# drives powered (UR user manual, "Stop Categories": category 2), it never lets the last motion run on.
PROGRAM_STOP_DECEL = 4.0
#: The most controller cycles one tick steps through (`SimArm._advance`): 20 s at 500 Hz. A stall
#: longer than that is no load any machine recovers from; its rest is stepped in larger steps.
MAX_SUBSTEPS = 10_000
#: °C, a joint's temperature when it has not warmed up: a lab's air. 20–25 °C is an air-conditioned
#: workshop (ISO 1 puts the reference temperature of dimensional metrology at 20 °C); UR's own guideline
#: takes 21 °C of internal joint temperature as warmed enough for full speed ("Robot start-up in cold
#: environments", universal-robots.com, Robot care & maintenance), so an idle arm in a 25 °C lab is warm
#: enough to run.
AMBIENT_TEMPERATURE = 25.0

#: The joints' temperatures (°C, 6 values) after `t` simulated seconds of running.
TemperatureFn = Callable[[float], Sequence[float]]


class Program(Protocol):
    """A running program (the ur_rtde control script, or a small custom script)."""

    name: str

    def tick(self, arm: SimArm, now: float) -> bool:
        """Advance one controller cycle; False when the program has ended."""
        ...


@dataclass
class ArmConfig:
    """Static properties of the simulated robot."""

    robot: str = "ur5e"
    lower: np.ndarray = field(default_factory=lambda: np.full(6, -2 * np.pi))
    upper: np.ndarray = field(default_factory=lambda: np.full(6, 2 * np.pi))
    max_speed: np.ndarray = field(default_factory=lambda: np.array([3.14, 3.14, 3.14, 3.14, 3.14, 3.14]))
    rate_hz: float = 500.0
    encoder_noise: float = ENCODER_SIGMA  # rad, standard deviation of actual_q around the true joints
    # rad, σ of each joint's stop-to-stop position error after a movej (the arm's repeatability); 0: the
    # joints stop exactly on their targets
    standstill_sigma: float = 0.0
    seed: int = 0
    q_home: np.ndarray = field(
        default_factory=lambda: np.array([0.0, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]))


_INT_REGISTERS = tuple(f"output_int_register_{i}" for i in range(48))
_DOUBLE_REGISTERS = tuple(f"output_double_register_{i}" for i in range(48))


class SimArm:
    """Controller state machine. All public methods are thread-safe."""

    def __init__(self, config: ArmConfig, fk: FkFn, clock: SimClock) -> None:
        self.config = config
        self.clock = clock
        self._fk = fk
        self.lock = threading.RLock()
        self._rng = np.random.default_rng(config.seed)
        # the stops' own stream, so the encoders' noise is the same draws with or without them
        self._stops = np.random.default_rng([config.seed, 1])
        self.q = np.array(config.q_home, dtype=float)
        self.qd = np.zeros(6)
        self.qdd = np.zeros(6)
        self.q_target = self.q.copy()
        self.actual_q = self.q.copy()
        # which way each joint last moved (its lost motion's side), followed cycle by cycle
        self.directions = JointDirections(self.q)
        # every controller cycle's true state in simulated time, for the instruments (`_advance`)
        self.history = JointHistory()
        self.motion: Any = None
        # the simulator's own account of its motion: simulated seconds with a motion primitive running
        # and the joint moves started (the benches' robot time, free of fast-time software overhead)
        self.motion_seconds = 0.0
        self.joint_moves = 0
        self.tcp = np.zeros(6)
        self.robot_mode = RobotMode.RUNNING
        self.safety_mode = SafetyMode.NORMAL
        self.estop_latched = False
        self.protective_stop_at: float | None = None
        self.safety_popup = False
        self.program: Program | None = None
        self.program_paused = False
        self.remote_control = True
        self.speed_slider = 1.0
        self.last_error = ""
        self.in_int = [0] * 48
        self.in_double = [0.0] * 48
        self.out_int = [0] * 48
        self.out_double = [0.0] * 48
        self.inputs: dict[str, Any] = {}
        self._t_last = clock.now()
        self._t_start = self._t_last
        self.timestamp = 0.0  # simulated seconds since the controller started (its running time)
        # how the controller's clock, which stamps RTDE's `timestamp`, errs against the simulated time
        # (`hil.calibration.stream_clocks`): perfect unless the simulated station gives it its truth
        self.controller_clock = InstrumentClock()
        self._stamp_rng = np.random.default_rng((config.seed, 2))
        self.steady_since: float | None = self._t_last
        self.history.append(self._t_last, self.q, self.directions.signs)
        self.snapshot: dict[str, Any] = {}
        # callables(event: str, **info) told about safety events and joint moves ("movej" with its
        # profile, "movej_cut" when one ends before its profile did): `mocks.ringing` listens
        self.listeners: list[Any] = []
        self._tcp_key, self._tcp_matrix = b"", np.eye(4)
        self._held_key, self._held = b"", [0.0] * 6
        self._announced: Any = None  # the last "movej" told to the listeners, while it runs
        self._tick_dt = 0.0
        self.temperatures: TemperatureFn | None = None  # None: every joint at AMBIENT_TEMPERATURE
        self._refresh_snapshot()

    # ----------------------------------------------------------------- kinematics
    def fk_flange(self, q: np.ndarray) -> np.ndarray:
        return self._fk(np.asarray(q, dtype=float))

    def fk_tcp(self, q: np.ndarray, tcp: np.ndarray | None = None) -> np.ndarray:
        off = self.tcp if tcp is None else np.asarray(tcp, dtype=float)
        key = off.tobytes()
        if key != self._tcp_key:  # the TCP changes rarely; FK runs twice every cycle
            self._tcp_key, self._tcp_matrix = key, pose_to_matrix(off)
        return self._fk(np.asarray(q, dtype=float)) @ self._tcp_matrix

    def _held_pose(self, q: np.ndarray) -> list[float]:
        """target_TCP_pose of joints `q`: one FK per new target (an arm at rest holds one for seconds)."""
        key = q.tobytes() + self.tcp.tobytes()
        if key != self._held_key:
            self._held_key, self._held = key, matrix_to_pose(self.fk_tcp(q)).tolist()
        return self._held

    def set_fk(self, fk: FkFn) -> None:
        """Move with another kinematic model from the next cycle on (thread-safe).

        The TCP poses of the current snapshot are recomputed at once (same joints, no new encoder
        noise drawn), so a reader never sees the new model's joints with the old model's pose.
        """
        with self.lock:
            self._fk = fk
            self._held_key = b""
            snap = dict(self.snapshot)
            held = self.q_target if self.motion is not None else self.q
            snap["actual_TCP_pose"] = matrix_to_pose(self.fk_tcp(self.actual_q)).tolist()
            snap["target_TCP_pose"] = matrix_to_pose(self.fk_tcp(held)).tolist()
            self.snapshot = snap

    # ----------------------------------------------------------------- readers
    def true_joints(self) -> np.ndarray:
        """The physical joint angles (no encoder noise): what the world/tracker simulator should use."""
        with self.lock:
            return self.q.copy()

    def joint_directions(self) -> np.ndarray:
        """(6,) the sign of each joint's last motion (`JointDirections`): its lost motion's side."""
        with self.lock:
            return self.directions.signs

    def is_steady(self) -> bool:
        with self.lock:
            return self.motion is None and bool(np.max(np.abs(self.qd)) < 1e-6)

    @property
    def powered(self) -> bool:
        return self.robot_mode in (RobotMode.IDLE, RobotMode.RUNNING, RobotMode.POWER_ON)

    @property
    def can_move(self) -> bool:
        return (self.robot_mode == RobotMode.RUNNING
                and self.safety_mode in (SafetyMode.NORMAL, SafetyMode.REDUCED))

    @property
    def runtime_state(self) -> RuntimeState:
        if self.program is None:
            return RuntimeState.STOPPED
        return RuntimeState.PAUSED if self.program_paused else RuntimeState.PLAYING

    def safety_bits(self) -> int:
        m = self.safety_mode
        bits = 0
        if m == SafetyMode.NORMAL:
            bits |= 1 << SafetyBit.NORMAL_MODE
        if m == SafetyMode.REDUCED:
            bits |= 1 << SafetyBit.REDUCED_MODE
        if m == SafetyMode.PROTECTIVE_STOP:
            bits |= (1 << SafetyBit.PROTECTIVE_STOPPED) | (1 << SafetyBit.STOPPED_DUE_TO_SAFETY)
        if m == SafetyMode.ROBOT_EMERGENCY_STOP:
            bits |= (1 << SafetyBit.ROBOT_EMERGENCY_STOPPED) | (1 << SafetyBit.EMERGENCY_STOPPED)
            bits |= 1 << SafetyBit.STOPPED_DUE_TO_SAFETY
        if m == SafetyMode.SYSTEM_EMERGENCY_STOP:
            bits |= (1 << SafetyBit.SYSTEM_EMERGENCY_STOPPED) | (1 << SafetyBit.EMERGENCY_STOPPED)
            bits |= 1 << SafetyBit.STOPPED_DUE_TO_SAFETY
        return bits

    def robot_bits(self) -> int:
        bits = 0
        if self.powered:
            bits |= 1 << RobotBit.POWER_ON
        if self.runtime_state == RuntimeState.PLAYING:
            bits |= 1 << RobotBit.PROGRAM_RUNNING
        return bits

    # ----------------------------------------------------------------- motion API (used by programs)
    def start_movej(self, q: np.ndarray, v: float, a: float) -> Any:
        q = np.asarray(q, dtype=float)
        if not self._within_limits(q):
            self.protective_stop("movej target outside the joint limits")
            return None
        # where the joints will really stop: the target plus this stop's position error (a movej the
        # controller finishes there, so the profile ends there and no joint turns back at its end)
        sigma = self.config.standstill_sigma
        stop = q + self._stops.normal(0.0, sigma, 6) if sigma > 0 else q
        self.motion = JointMove(self.q, stop, v, a, self.config.max_speed)
        self.joint_moves += 1
        self.q_target = q.copy()
        # the move's first step (this tick's) covers the tick's whole dt: it started at the previous tick
        self._announced = self.motion
        self._notify("movej", start=self._t_last - self._tick_dt, q0=self.q.copy(), q1=q.copy(),
                     duration=self.motion.duration, accel_time=self.motion.accel_time,
                     acceleration=self.motion.acceleration)
        return self.motion

    def start_movel(self, T: np.ndarray, v: float, a: float) -> Any:
        try:
            self.motion = LinearMove(self.fk_tcp, self.q, T, v, a)
        except MotionError as exc:
            self.program_error(str(exc))
            return None
        if not self._within_limits(self.motion.target):
            self.motion = None
            self.protective_stop("movel target outside the joint limits")
            return None
        self.q_target = self.motion.target.copy()
        return self.motion

    def start_stop(self, a: float) -> Any:
        self.motion = Decelerate(self.qd, a if a > 0 else 4.0)
        return self.motion

    def program_error(self, message: str) -> None:
        """A runtime error in the program: the program stops and the arm brakes."""
        log.info("program error: %s", message)
        self.last_error = message
        self.stop_program(decel=PROGRAM_STOP_DECEL)

    # ----------------------------------------------------------------- program / safety control
    def load_program(self, program: Program) -> bool:
        """Start a program sent to the script port; refused unless powered, in remote and not stopped."""
        with self.lock:
            if not self.remote_control:
                log.info("program %s refused: not in remote control", program.name)
                return False
            if not self.can_move:
                log.info("program %s refused: robot mode %s, safety %s", program.name,
                         self.robot_mode.name, self.safety_mode.name)
                return False
            replacing = self.program is not None and self.motion is not None
            if replacing and not isinstance(self.motion, Decelerate):
                # the running program is stopped before the new one starts: its motion brakes
                self.motion = Decelerate(self.qd, PROGRAM_STOP_DECEL)
            self.program = program
            self.program_paused = False
            return True

    def stop_program(self, decel: float = PROGRAM_STOP_DECEL) -> None:
        with self.lock:
            self.program = None
            self.program_paused = False
            if self.motion is not None or np.any(np.abs(self.qd) > 0):
                self.motion = Decelerate(self.qd, decel)

    def protective_stop(self, reason: str = "injected") -> None:
        with self.lock:
            if self.safety_mode in (SafetyMode.ROBOT_EMERGENCY_STOP, SafetyMode.SYSTEM_EMERGENCY_STOP):
                return
            log.info("protective stop: %s", reason)
            self.last_error = f"protective stop: {reason}"
            self.safety_mode = SafetyMode.PROTECTIVE_STOP
            self.protective_stop_at = self.clock.now()
            self.safety_popup = True
            self.stop_program(decel=SAFETY_STOP_DECEL)
            self._notify("protective_stop", reason=reason)

    def unlock_protective_stop(self) -> tuple[bool, str]:
        with self.lock:
            if self.safety_mode != SafetyMode.PROTECTIVE_STOP:
                return True, "Protective stop releasing"
            assert self.protective_stop_at is not None
            if self.clock.now() - self.protective_stop_at < PROTECTIVE_STOP_UNLOCK_DELAY:
                return False, ("Cannot unlock protective stop until 5s after occurrence. "
                               "Always inspect cause of protective stop before unlocking")
            self.safety_mode = SafetyMode.NORMAL
            self.protective_stop_at = None
            return True, "Protective stop releasing"

    def emergency_stop(self, system: bool = False) -> None:
        with self.lock:
            log.info("emergency stop")
            self.last_error = "emergency stop"
            self.estop_latched = True
            self.safety_mode = SafetyMode.SYSTEM_EMERGENCY_STOP if system else SafetyMode.ROBOT_EMERGENCY_STOP
            self.stop_program(decel=SAFETY_STOP_DECEL)
            self._notify("emergency_stop")

    def release_emergency_stop(self) -> None:
        """Twist the e-stop button out: safety returns to normal, the arm stays powered off."""
        with self.lock:
            if not self.estop_latched:
                return
            self.estop_latched = False
            self.safety_mode = SafetyMode.NORMAL
            self.robot_mode = RobotMode.POWER_OFF

    def power_on(self) -> None:
        with self.lock:
            if not self.estop_latched and self.robot_mode in (RobotMode.POWER_OFF, RobotMode.BOOTING):
                self.robot_mode = RobotMode.IDLE

    def power_off(self) -> None:
        with self.lock:
            self.stop_program(decel=SAFETY_STOP_DECEL)
            self.robot_mode = RobotMode.POWER_OFF

    def brake_release(self) -> None:
        with self.lock:
            if self.robot_mode in (RobotMode.IDLE, RobotMode.POWER_ON):
                self.robot_mode = RobotMode.RUNNING

    def set_speed_slider(self, fraction: float) -> None:
        with self.lock:
            self.speed_slider = float(min(max(fraction, 0.0), 1.0))

    def set_remote_control(self, on: bool) -> None:
        with self.lock:
            self.remote_control = bool(on)

    def set_joints(self, q: np.ndarray) -> None:
        """Teleport the arm (test setup only): no motion, no velocity."""
        with self.lock:
            self.q = np.asarray(q, dtype=float).copy()
            self.q_target = self.q.copy()
            self.directions = JointDirections(self.q)  # put there, not moved there: no side known
            self.history.clear()
            self.history.append(self._t_last, self.q, self.directions.signs)
            self.qd = np.zeros(6)
            self.motion = None
            self._refresh_snapshot()

    def _notify(self, event: str, **info: Any) -> None:
        for cb in list(self.listeners):
            try:
                cb(event, **info)
            except Exception:  # a listener must not break the controller
                log.exception("listener failed on %s", event)

    def _within_limits(self, q: np.ndarray) -> bool:
        return bool(((q >= self.config.lower - 1e-9) & (q <= self.config.upper + 1e-9)).all())

    # ----------------------------------------------------------------- inputs
    def write_inputs(self, names: list[str], values: list[Any]) -> None:
        """Values of an RTDE input data package (registers and IO)."""
        with self.lock:
            for name, val in zip(names, values, strict=True):
                if name.startswith("input_int_register_"):
                    self.in_int[int(name[19:])] = int(val)
                elif name.startswith("input_double_register_"):
                    self.in_double[int(name[22:])] = float(val)
                else:
                    self.inputs[name] = val
            mask = self.inputs.pop("speed_slider_mask", 0)
            if mask and "speed_slider_fraction" in self.inputs:
                self.set_speed_slider(float(self.inputs["speed_slider_fraction"]))

    # ----------------------------------------------------------------- the cycle
    def tick(self) -> None:
        """One controller cycle: program step, motion step, safety checks, new RTDE snapshot."""
        with self.lock:
            now = self.clock.now()
            dt = max(now - self._t_last, 0.0)
            self._t_last = now
            self._tick_dt = dt
            self.timestamp = now - self._t_start
            if self.program is not None and not self.program_paused:
                try:
                    alive = self.program.tick(self, now)
                except MotionError as exc:
                    self.program_error(str(exc))
                    alive = True
                if not alive:  # the script ended (e.g. ur_rtde's stopScript): its motion stops with it
                    self.stop_program(decel=PROGRAM_STOP_DECEL)
            q_old = self.q
            qd_old = self.qd
            if self.motion is not None and dt > 0:
                scale = self.speed_slider if not isinstance(self.motion, Decelerate) else 1.0
                if isinstance(self.motion, JointMove):  # the part of this tick the move still ran
                    left = max(self.motion.duration - self.motion.tau, 0.0) / max(scale, 1e-9)
                    self.motion_seconds += min(dt, left)
            self._advance(now - dt, dt)
            if dt > 0:
                self.qd = (self.q - q_old) / dt
                self.qdd = (self.qd - qd_old) / dt
            if not self._within_limits(self.q) and self.safety_mode == SafetyMode.NORMAL:
                self.protective_stop("joint position limit violated")
            if not self.can_move and self.motion is not None and not isinstance(self.motion, Decelerate):
                self.motion = Decelerate(self.qd, SAFETY_STOP_DECEL)
            if self._announced is not None and self.motion is not self._announced:
                if not self._announced.done:  # stopped (or replaced) before its profile ended
                    self._notify("movej_cut", at=now)
                self._announced = None
            self._refresh_snapshot()

    def _advance(self, t_from: float, dt: float) -> None:
        """Move the arm through the `dt` simulated seconds since `t_from`, one controller cycle at a
        time, recording each cycle's true state in `history`.

        A real controller is hard real-time: it steps its motion every 2 ms (500 Hz) whatever else
        runs. This tick thread can be starved for tenths of a second on a loaded machine; stepping the
        motion over such a gap in one go would move the arm on a different path (a servo loop's
        smoothing, a move's profile integrated coarsely) and leave the instruments no state between
        the two ticks. The cycle is the controller's period in simulated time, or longer in fast time
        (`clock.speed` simulated seconds pass per wall second), where the tick thread's own period is
        the finest step this simulator takes anyway. At most `MAX_SUBSTEPS` cycles per tick bound the
        cost of a very long stall.
        """
        speed = float(getattr(self.clock, "speed", 1.0))  # a test's hand-moved clock has none
        cycle = max(1.0, speed) / self.config.rate_hz
        n = min(max(1, math.ceil(dt / cycle - 1e-6)), MAX_SUBSTEPS) if dt > 0 else 1
        h = dt / n
        for k in range(n):
            if self.motion is not None and h > 0:
                scale = self.speed_slider if not isinstance(self.motion, Decelerate) else 1.0
                try:
                    self.q = self.motion.step(h * scale, self.q)
                except MotionError as exc:
                    self.motion = None
                    self.program_error(str(exc))
                if self.motion is not None and self.motion.done:
                    if self.motion.target is not None:
                        self.q = np.array(self.motion.target, dtype=float)
                    self.motion = None
            signs = self.directions.update(self.q)
            self.history.append(t_from + (k + 1) * h, self.q, signs)

    def true_joints_at(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(true joints, joint directions), each (n, 6), at simulated `times` from `history`."""
        return self.history.at(times)

    def history_end(self) -> float | None:
        """The newest simulated time the arm has a true state for (None before its first cycle)."""
        span = self.history.span()
        return None if span is None else span[1]

    def set_encoder_noise(self, sigma: float) -> None:
        """Standard deviation (rad) of ``actual_q`` around the true joints from the next cycle on."""
        if not (np.isfinite(sigma) and sigma >= 0):
            raise ValueError(f"encoder noise must be a non-negative number of radians, got {sigma!r}")
        with self.lock:
            self.config.encoder_noise = float(sigma)

    def set_standstill(self, sigma: float) -> None:
        """σ (rad) of each joint's stop-to-stop position error from the next movej on."""
        if not (np.isfinite(sigma) and sigma >= 0):
            raise ValueError(f"standstill error must be a non-negative number of radians, got {sigma!r}")
        with self.lock:
            self.config.standstill_sigma = float(sigma)

    def set_temperatures(self, temperatures: TemperatureFn | None) -> None:
        """Report joint temperatures from `temperatures(running seconds)` from the next cycle on."""
        with self.lock:
            self.temperatures = temperatures

    def _joint_temperatures(self) -> list[float]:
        """°C per joint at the current running time (the controller's timestamp)."""
        if self.temperatures is None:
            return [AMBIENT_TEMPERATURE] * 6
        values = [float(v) for v in self.temperatures(self.timestamp)]
        if len(values) != 6:
            raise ValueError(f"joint temperatures: expected 6 values, got {len(values)}")
        return values

    @property
    def started_at(self) -> float:
        """The simulated time (`SimClock.now`) at which this controller started: its running time's 0."""
        return self._t_start

    def _stamp(self) -> float:
        """RTDE's ``timestamp`` of this cycle: the running time read on the controller's own clock
        (plain float arithmetic: it runs every 2 ms cycle)."""
        clock = self.controller_clock
        stamp = clock.offset_s + clock.rate * (self.timestamp + clock.latency_s)
        if clock.jitter_s > 0:
            stamp += float(self._stamp_rng.normal(0.0, clock.jitter_s))
        return stamp

    def _refresh_snapshot(self) -> None:
        noise = self._rng.normal(0.0, self.config.encoder_noise, 6) if self.config.encoder_noise > 0 else 0.0
        self.actual_q = self.q + noise
        T_act = self.fk_tcp(self.actual_q)
        zeros6 = [0.0] * 6
        snap: dict[str, Any] = {
            "timestamp": self._stamp(),
            "target_q": (self.q_target if self.motion is not None else self.q).tolist(),
            "target_qd": self.qd.tolist(),
            "target_qdd": self.qdd.tolist(),
            "target_current": zeros6,
            "target_moment": zeros6,
            "actual_q": self.actual_q.tolist(),
            "actual_qd": self.qd.tolist(),
            "actual_qdd": self.qdd.tolist(),
            "actual_current": zeros6,
            "actual_current_as_torque": zeros6,
            "actual_moment": zeros6,
            "joint_control_output": zeros6,
            "actual_TCP_pose": matrix_to_pose(T_act).tolist(),
            "actual_TCP_speed": zeros6,
            "actual_TCP_force": zeros6,
            "target_TCP_pose": self._held_pose(self.q_target if self.motion is not None else self.q),
            "target_TCP_speed": zeros6,
            "actual_digital_input_bits": 0,
            "joint_temperatures": self._joint_temperatures(),
            "actual_execution_time": 0.2,
            "robot_mode": int(self.robot_mode),
            "joint_mode": [253 if self.robot_mode == RobotMode.RUNNING else 255] * 6,
            "safety_mode": int(self.safety_mode),
            "safety_status": int(self.safety_mode),
            "actual_tool_accelerometer": [0.0, 0.0, -9.81],
            "speed_scaling": self.speed_slider if self.can_move else 0.0,
            "target_speed_fraction": self.speed_slider,
            "actual_momentum": 0.0,
            "actual_main_voltage": 48.0,
            "actual_robot_voltage": 48.0 if self.powered else 0.0,
            "actual_robot_current": 0.5 if self.powered else 0.0,
            "actual_joint_voltage": [48.0] * 6,
            "actual_digital_output_bits": 0,
            "runtime_state": int(self.runtime_state),
            "robot_status_bits": self.robot_bits(),
            "safety_status_bits": self.safety_bits(),
            "standard_analog_input0": 0.0,
            "standard_analog_input1": 0.0,
            "standard_analog_output0": 0.0,
            "standard_analog_output1": 0.0,
            "ft_raw_wrench": zeros6,
            "payload": 0.0,
            "payload_cog": [0.0, 0.0, 0.0],
            "payload_inertia": zeros6,
            "output_bit_registers0_to_31": 0,
            "output_bit_registers32_to_63": 0,
        }
        snap.update(zip(_INT_REGISTERS, self.out_int, strict=True))
        snap.update(zip(_DOUBLE_REGISTERS, self.out_double, strict=True))
        self.snapshot = snap
