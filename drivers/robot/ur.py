"""The Universal Robots driver over ur_rtde — the same code for the simulator, URSim and a real arm.

Design choices, and why:

* No I/O in the constructor; `open()` connects. Before the ur_rtde constructors (which hold the GIL and
  have no timeout) it runs bounded pre-flight checks (`drivers.robot.probe`) and turns every refusal
  into a typed error: unreachable, unsupported version, local control, protective/emergency stop,
  not running. Once connected it reads the controller's own kinematic model (KinematicsInfo, primary
  interface, `drivers.robot.kinematics_info`) into `ControllerInfo.kinematics`; a primary port that does
  not answer leaves it None with a warning, as nothing in a campaign's motion depends on it.
* Targets are validated before any motion and refused — never clamped — outside the joint limits or
  when the TCP would leave the keep-in zone (checked at points along the joint-space path with the
  controller's own FK).
* Moves are sent asynchronously and watched from Python: safety bits, program state, link state and
  speed slider are polled every few milliseconds, so a protective stop, an e-stop or a dropped link
  surfaces within a cycle as ProtectiveStop / EmergencyStop / ConnectionLost instead of a bare False.
  On any error of its own (timeout, slider, abort) the driver stops the arm before raising.
  `move_to` is `start_move` (send) + `wait_move` (watch), also callable apart, so a caller can use
  the travel time (the campaign engine commits the previous point meanwhile).
* `getForwardKinematics(q)` with a zero TCP offset reads stale registers in ur_rtde 1.6.5, so the
  driver always passes a non-zero offset.
* Servo streaming: `follow(Q)` runs a whole trajectory's 500 Hz loop inside the driver, so under
  `IsolatedURRobot` it runs in the child process next to ur_rtde (a per-sample loop must not cross a
  pipe, and a crash of the library on a dropped link must not take the caller down). `servo()` is the
  lower-level in-process loop it is built on.
"""

from __future__ import annotations

import logging
import os
import tempfile
import threading
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any, NoReturn

import numpy as np

from drivers.robot.errors import (
    ConnectionLost,
    EmergencyStop,
    JointLimitViolation,
    KeepInZoneViolation,
    KinematicsInfoUnavailable,
    MotionAborted,
    MotionTimeout,
    NotInRemoteControl,
    ProgramStopped,
    ProtectiveStop,
    RobotError,
    RobotNotReady,
    RobotUnreachable,
    SpeedSliderReduced,
    StartPositionMismatch,
    UnsupportedVersion,
)
from drivers.robot.kinematics_info import KinematicsInfo, read_kinematics_info
from drivers.robot.model import ControllerInfo, FollowResult, JointReading, RobotConfig
from drivers.robot.probe import DashboardLine, controller_model, controller_series, rtde_version
from drivers.robot.trajectory import check_trajectory, keep_in_checkpoints

log = logging.getLogger(__name__)

PROTECTIVE_STOPPED_BIT = 2
EMERGENCY_STOPPED_BIT = 7
RUNTIME_PLAYING = 2
STOP_DECEL = 4.0  # rad/s^2 used when the driver stops the arm itself
_TINY_TCP = (0.0, 0.0, 0.0, 0.0, 0.0, 1e-12)  # non-zero on purpose (see module docstring)


#: ur_rtde interfaces whose link was lost: never disconnected nor destroyed while the process runs,
#: because ur_rtde's reconnection thread may still be using them (see `URRobot.close`).
_ABANDONED: list[Any] = []


class URRobot:
    """A UR arm driven through ur_rtde. ``with URRobot(RobotConfig(host)) as robot: robot.move_to(q)``."""

    def __init__(self, config: RobotConfig) -> None:
        self.config = config
        self.info: ControllerInfo | None = None
        self._c: Any = None  # rtde_control.RTDEControlInterface
        self._r: Any = None  # rtde_receive.RTDEReceiveInterface
        self._cmd_lock = threading.Lock()
        self._abort = threading.Event()
        self._moving: tuple[np.ndarray, float] | None = None  # start_move's target, and when it was sent

    # ------------------------------------------------------------------ connection
    def open(self) -> ControllerInfo:
        """Connect: pre-flight checks, then the ur_rtde receive and control interfaces."""
        cfg = self.config
        version = rtde_version(cfg.host, cfg.connect_timeout)
        major, minor = version[0], version[1]
        if not any(major == vmaj and minor >= vmin for vmaj, vmin in cfg.allowed_versions):
            allowed = ", ".join(f"{a}.{b}+" for a, b in cfg.allowed_versions)
            raise UnsupportedVersion(f"controller software {'.'.join(map(str, version))} is not supported "
                                     f"(supported: {allowed})")
        with DashboardLine(cfg.host, cfg.connect_timeout) as dash:
            status = dash.status(major, minor)
        self._check_dashboard(status.remote_control, status.safety, status.robot_mode)
        series, rate = controller_series(major)
        model = controller_model(status.model, major)
        try:
            import rtde_control
            import rtde_receive

            self._r = rtde_receive.RTDEReceiveInterface(cfg.host, cfg.rtde_frequency)
            self._c = rtde_control.RTDEControlInterface(cfg.host, cfg.rtde_frequency)
        except RuntimeError as exc:
            self.close()
            text = str(exc)
            if "remote control" in text:
                raise NotInRemoteControl(f"{cfg.host}: {text}") from exc
            raise RobotUnreachable(f"{cfg.host}: ur_rtde could not connect: {text}") from exc
        try:
            self._wait_playing()
        except ProgramStopped:
            self.close()
            raise
        self.info = ControllerInfo(model=model, serial=status.serial,
                              software_version=status.polyscope_version or ".".join(map(str, version)),
                              version=version, series=series, rate_hz=rate, kinematics=self._kinematics())
        log.info("connected to %s %s (serial %s, software %s)", cfg.host, model, status.serial,
                 self.info.software_version)
        return self.info

    def _kinematics(self) -> KinematicsInfo | None:
        """The controller's own model from its primary interface; None (logged) when it gives none.

        The campaign can run without it (only comparisons with the controller's model need it), so a
        silent primary port is a warning, not a failure.
        """
        cfg = self.config
        try:
            return read_kinematics_info(cfg.host, cfg.primary_port, cfg.connect_timeout)
        except KinematicsInfoUnavailable as exc:
            log.warning("the controller's kinematic model is unknown: %s", exc)
            return None

    def _wait_playing(self) -> None:
        """Wait (bounded) until the control script plays: it starts asynchronously after an upload."""
        cfg = self.config
        deadline = time.monotonic() + cfg.connect_timeout
        while int(self._r.getRuntimeState()) != RUNTIME_PLAYING:
            if time.monotonic() > deadline:
                raise ProgramStopped(f"{cfg.host}: the control script did not start within "
                                     f"{cfg.connect_timeout} s")
            time.sleep(0.01)

    @staticmethod
    def _check_dashboard(remote: bool | None, safety: str, robot_mode: str) -> None:
        if remote is False:
            raise NotInRemoteControl("the teach pendant is in local control; switch it to remote control")
        if "PROTECTIVE_STOP" in safety:
            raise ProtectiveStop("a protective stop is active; inspect the cause, then unlock it")
        if "EMERGENCY" in safety:
            raise EmergencyStop(f"an emergency stop is active ({safety})")
        if safety not in ("NORMAL", "REDUCED"):
            raise RobotNotReady(f"safety status is {safety}")
        if robot_mode != "RUNNING":
            raise RobotNotReady(f"robot mode is {robot_mode}; power on and release the brakes")

    def close(self) -> None:
        """Disconnect (the control script is stopped so the arm is left idle)."""
        c, r = self._c, self._r
        self._c = self._r = None
        # An interface that lost its link may be inside ur_rtde's own reconnection thread right now;
        # disconnecting (or destroying) it then crashes the process, so it is set aside instead.
        if c is not None:
            if not c.isConnected():
                _ABANDONED.append(c)
            else:
                # after a stop from another thread (the engine's on Ctrl-C) whose stopJ is still under
                # way: ur_rtde's commands share one register, and a stopScript sent beside the stopJ
                # was cleared by it, so the stopScript waited for the script to end (20 s, till the
                # proxy's timeout killed the client). One command at a time, as every other here.
                with self._cmd_lock:
                    try:
                        c.stopScript()
                        c.disconnect()
                    except RuntimeError as exc:
                        log.debug("closing the control interface: %s", exc)
        if r is not None:
            if not r.isConnected():
                _ABANDONED.append(r)
            else:
                try:
                    r.disconnect()
                except RuntimeError as exc:
                    log.debug("closing the receive interface: %s", exc)

    def reconnect(self) -> ControllerInfo:
        """Recover after a dropped link or a stopped program, without tearing the interfaces down.

        ur_rtde's control interface reconnects by itself from a background thread when the link
        drops; destroying the interfaces while that thread runs crashes the process. So: wait
        (bounded) for the library's own recovery, ask for an explicit reconnect where it gave up,
        re-upload the control script if it is not running, then check the controller's state.
        Never connected yet: a plain `open`.

        Known upstream limit (ur_rtde 1.6.5): when the library's automatic reconnection itself fails
        (the controller refuses connections for longer than its attempt), its receive thread can
        crash the process in ``RTDE::isDataAvailable()`` (reproduced against the simulator with a
        3 s refusal, about one run in three). Nothing in this driver can prevent that from inside
        the process; running the client in a child process would.
        """
        c, r = self._c, self._r
        if c is None or r is None:
            return self.open()
        cfg = self.config
        # the controller must accept connections again before anything is tried (timed, pure Python)
        rtde_version(cfg.host, cfg.connect_timeout)
        dropped = not c.isConnected()
        deadline = time.monotonic() + cfg.connect_timeout
        # the library's own reconnection re-uploads the script too: let it finish before touching c
        while dropped and not (c.isConnected() and c.isProgramRunning()) and time.monotonic() < deadline:
            time.sleep(0.05)
        if dropped and not (c.isConnected() and r.isConnected() and c.isProgramRunning()):
            # ur_rtde gave up. Its reconnect() on half-torn-down interfaces corrupts the heap, and
            # their destructors race its threads: keep the old objects (idle now) and start afresh.
            _ABANDONED.extend((c, r))
            self._c = self._r = None
            return self.open()
        try:
            if not r.isConnected():
                r.reconnect()
            if not c.isProgramRunning():
                with self._cmd_lock:
                    c.reuploadScript()
        except RuntimeError as exc:
            raise RobotUnreachable(f"{cfg.host}: reconnecting failed: {exc}") from exc
        if not (c.isConnected() and r.isConnected()):
            raise ConnectionLost(f"{cfg.host}: the link did not come back")
        self._wait_playing()  # else the next check re-uploads, killing the script that is starting
        self.check_status()
        assert self.info is not None
        return self.info

    def __enter__(self) -> URRobot:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ------------------------------------------------------------------ status
    def _require(self) -> tuple[Any, Any]:
        if self._c is None or self._r is None:
            raise ConnectionLost("not connected; call open()")
        return self._c, self._r

    def check_status(self) -> None:
        """Raise the typed error for the current controller state, if any is wrong."""
        c, r = self._require()
        if not r.isConnected() or not c.isConnected():
            raise ConnectionLost(f"lost the RTDE link to {self.config.host}")
        bits = int(r.getSafetyStatusBits())
        if bits & (1 << EMERGENCY_STOPPED_BIT):
            raise EmergencyStop("emergency stop")
        if bits & (1 << PROTECTIVE_STOPPED_BIT):
            raise ProtectiveStop("protective stop")
        if int(r.getRuntimeState()) != RUNTIME_PLAYING:
            raise ProgramStopped("the control program is not running on the controller")
        frac = float(r.getTargetSpeedFraction())
        if frac < self.config.min_speed_fraction - 1e-9:
            raise SpeedSliderReduced(f"speed slider at {frac:.0%} (< {self.config.min_speed_fraction:.0%})")

    # ------------------------------------------------------------------ validation
    def validate_target(self, q: Sequence[float]) -> np.ndarray:
        """The target as an array, or a TargetRejected error (joint limits, keep-in zone)."""
        cfg = self.config
        qa = np.asarray(q, dtype=float)
        if qa.shape != (6,) or not np.all(np.isfinite(qa)):
            raise JointLimitViolation(f"target must be 6 finite joint angles, got {q!r}")
        lo, hi = np.asarray(cfg.joint_lower), np.asarray(cfg.joint_upper)
        bad = np.flatnonzero((qa < lo) | (qa > hi))
        if bad.size:
            j = int(bad[0])
            raise JointLimitViolation(f"joint {j + 1} target {qa[j]:.4f} rad is outside "
                                      f"[{lo[j]:.4f}, {hi[j]:.4f}]")
        if cfg.keep_in is not None:
            _c, r = self._require()
            q0 = np.asarray(r.getActualQ(), dtype=float)
            for s in np.linspace(0.0, 1.0, max(cfg.keep_in_checks, 2)):
                pose = self._outside_keep_in(q0 + s * (qa - q0))
                if pose is not None:
                    where = "at the target" if s == 1.0 else f"at {s:.0%} of the way"
                    raise KeepInZoneViolation(f"TCP {np.round(pose[:3], 4).tolist()} leaves the keep-in "
                                              f"zone {where}")
        return qa

    def _outside_keep_in(self, q: np.ndarray) -> list[float] | None:
        """The TCP pose at `q` (controller FK) if it is outside the keep-in zone, else None."""
        cfg = self.config
        assert cfg.keep_in is not None
        c, _r = self._require()
        tcp = list(cfg.tcp_offset) if any(cfg.tcp_offset) else list(_TINY_TCP)
        with self._typed_errors(), self._cmd_lock:
            pose = list(c.getForwardKinematics(q.tolist(), tcp))
        return pose if len(pose) < 3 or not cfg.keep_in.contains(np.asarray(pose)) else None

    @contextmanager
    def _typed_errors(self) -> Iterator[None]:
        """ur_rtde raises bare RuntimeErrors; turn them into the controller's typed state error.

        The control call can fail (the script stopped) a few frames before the receive thread has
        the frame whose safety bits say why; on a loaded machine that lag reaches tens of
        milliseconds. So the state gets `explain_timeout` to explain the failure before it is
        called a lost link, which would send the operator to the network instead of the pendant.
        """
        try:
            yield
        except RuntimeError as exc:
            self._explain(ConnectionLost(f"ur_rtde: {exc}"), exc)

    def _explain(self, fallback: RobotError, cause: BaseException | None = None) -> NoReturn:
        """Raise the typed error of the controller state within `explain_timeout`, else `fallback`."""
        deadline = time.monotonic() + self.config.explain_timeout
        while True:
            self.check_status()  # raises ProtectiveStop, ProgramStopped, ConnectionLost, ...
            if time.monotonic() >= deadline:
                raise fallback from cause
            time.sleep(self.config.poll_interval)

    # ------------------------------------------------------------------ motion
    def move_to(self, q: Sequence[float], *, speed: float | None = None,
                acceleration: float | None = None, samples: int = 1) -> JointReading:
        """Move (movej) to `q`, wait until steady, return the joints read there.

        Raises TargetRejected before moving, the safety/link errors while moving, MotionTimeout when
        the arm does not settle within the configured timeouts (after stopping it).
        """
        self.start_move(q, speed=speed, acceleration=acceleration)
        return self.wait_move(samples)

    def start_move(self, q: Sequence[float], *, speed: float | None = None,
                   acceleration: float | None = None) -> np.ndarray:
        """The first half of `move_to`: validate `q` and send the movej; returns (the validated
        target) as soon as the controller accepted it, with the arm on its way.

        So a caller can do something else while the arm travels (the campaign engine commits the
        previous point to the store) and then call `wait_move`, which watches the motion as
        `move_to` does. Until then nothing polls the controller: a protective stop or a dropped link
        surfaces in `wait_move`, and `stop()` works meanwhile as always. Raises what `move_to`
        raises before moving (TargetRejected, the controller's state errors).
        """
        cfg = self.config
        self.check_status()  # a stopped controller answers the checks below with bare RuntimeErrors
        target = self.validate_target(q)
        v = cfg.speed if speed is None else min(speed, cfg.speed)
        a = cfg.acceleration if acceleration is None else min(acceleration, cfg.acceleration)
        c, _r = self._require()
        self.check_status()
        self._abort.clear()
        self._moving = None
        with self._typed_errors(), self._cmd_lock:
            accepted = c.moveJ(target.tolist(), v, a, True)
        if not accepted:
            self._explain(ProgramStopped("the controller did not accept the move"))
        # the move's time limit runs from when it was sent, not from when someone waits for it
        self._moving = (target, time.monotonic())
        return target

    def wait_move(self, samples: int = 1) -> JointReading:
        """The second half of `move_to`: watch the move `start_move` sent until the arm is steady at
        its target (safety, link, slider and time-out checks as in `move_to`), then return the
        joints read there. Raises RobotError when no move was started."""
        moving, self._moving = self._moving, None
        if moving is None:
            raise RobotError("wait_move() without a move started by start_move()")
        self._watch_motion(*moving)
        return self.read_joints(samples)

    def _watch_motion(self, target: np.ndarray, t0: float) -> None:
        cfg = self.config
        c, r = self._require()
        deadline = t0 + cfg.move_timeout
        profile_done_at: float | None = None
        while True:
            try:
                self.check_status()
            except (SpeedSliderReduced, ProgramStopped):
                self._stop_quietly()
                raise
            if self._abort.is_set():
                raise MotionAborted("stopped by request")
            now = time.monotonic()
            if profile_done_at is None and int(c.getAsyncOperationProgress()) < 0:
                profile_done_at = now
            if profile_done_at is not None:
                qa = np.asarray(r.getActualQ())
                qd = np.asarray(r.getActualQd())
                if (np.max(np.abs(qa - target)) < cfg.settle_tolerance
                        and np.max(np.abs(qd)) < cfg.steady_velocity):
                    return
                if now - profile_done_at > cfg.settle_timeout:
                    self._stop_quietly()
                    raise MotionTimeout(f"not steady at the target {cfg.settle_timeout} s after the motion "
                                        f"(error {np.max(np.abs(qa - target)):.2e} rad)")
            if now > deadline:
                self._stop_quietly()
                raise MotionTimeout(f"move not finished within {cfg.move_timeout} s")
            time.sleep(cfg.poll_interval)

    def stop(self, deceleration: float = STOP_DECEL) -> None:
        """Stop the arm now (any motion, any thread); a move_to in progress raises MotionAborted."""
        self._abort.set()
        c = self._c
        if c is None or not c.isConnected():
            # no link, nothing to command (a dropped link stops the program on the controller); and
            # calling into ur_rtde while its own thread reconnects crashes the process
            return
        with self._cmd_lock:
            c.stopJ(deceleration, False)

    def _stop_quietly(self) -> None:
        try:
            if self._c is not None and self._c.isConnected():
                with self._cmd_lock:
                    self._c.stopJ(STOP_DECEL, False)
        except RuntimeError as exc:
            log.warning("could not stop the arm: %s", exc)

    # ------------------------------------------------------------------ reading
    def read_joints(self, samples: int = 1, timeout: float = 2.0) -> JointReading:
        """Joint angles averaged over `samples` distinct controller cycles, with their spread."""
        if samples < 1:
            raise ValueError("samples must be >= 1")
        _, r = self._require()
        rows: list[list[float]] = []
        last_ts = None
        deadline = time.monotonic() + timeout + samples / 100.0
        while len(rows) < samples:
            if not r.isConnected():
                raise ConnectionLost(f"lost the RTDE link to {self.config.host}")
            ts = float(r.getTimestamp())
            if ts != last_ts:
                rows.append(list(r.getActualQ()))
                last_ts = ts
            elif time.monotonic() > deadline:
                raise ConnectionLost("the controller stopped sending data")
            else:
                time.sleep(0.0005)
        arr = np.asarray(rows)
        spread = arr.std(axis=0, ddof=1) if samples > 1 else np.zeros(6)
        return JointReading(q=arr.mean(axis=0), spread=spread, samples=samples,
                            timestamp=float(last_ts or 0.0))

    def tcp_pose(self) -> np.ndarray:
        """The controller's actual TCP pose [x, y, z, rx, ry, rz] (its own calibrated kinematics)."""
        _, r = self._require()
        return np.asarray(r.getActualTCPPose(), dtype=float)

    def joint_temperatures(self) -> np.ndarray:
        """The six joints' temperatures (°C): RTDE output ``joint_temperatures``, read by ur_rtde's
        ``RTDEReceiveInterface.getJointTemperatures`` (the warm-up and drift watch record them)."""
        _, r = self._require()
        return np.asarray(r.getJointTemperatures(), dtype=float)

    # ------------------------------------------------------------------ streaming
    def follow(self, Q: object, *, lookahead: float = 0.1, gain: float = 300.0,
               settle: float = 0.0) -> FollowResult:
        """Stream a whole joint trajectory (one sample per controller period), then hold its end.

        The loop runs here, in the driver's process, so under `IsolatedURRobot` it runs in the child
        next to ur_rtde and only `Q` and the result cross the pipe. Before anything moves: every
        sample is checked against the joint limits and each step against `max_joint_speed`
        (refused naming the sample and joint, never clamped), then the controller status, then the
        first sample against the arm's position (`follow_start_tolerance`: a servo stream must not
        start with a jump; `move_to(Q[0])` first), then the keep-in zone at samples
        `keep_in_spacing` rad apart. Each sample is sent with servoJ at the controller period
        (`lookahead` s in [0.03, 0.2], `gain` in [100, 2000]), the last one is held for `settle` s,
        and servoStop ends the stream — on any error too.

        `stop()` from another thread ends it with MotionAborted (no servo target is sent after the
        stop). Returns each sample's send time on ``time.monotonic()`` — the system-wide
        CLOCK_MONOTONIC on Linux, so a parent process can compare them with its own timestamps —
        and the loop-period statistics (`FollowResult`).
        """
        cfg = self.config
        self._abort.clear()  # a stop() from here on aborts this stream
        rate = self.info.rate_hz if self.info else 500.0
        max_step = None if cfg.max_joint_speed is None else np.asarray(cfg.max_joint_speed) / rate
        Qa = check_trajectory(Q, cfg.joint_lower, cfg.joint_upper, max_step)
        if not (0.03 <= lookahead <= 0.2 and 100.0 <= gain <= 2000.0 and 0.0 <= settle < 3600.0):
            raise ValueError(f"lookahead {lookahead} s must be in [0.03, 0.2], gain {gain} in "
                             f"[100, 2000], settle {settle} s in [0, 3600)")
        self.check_status()
        _c, r = self._require()
        jump = np.abs(Qa[0] - np.asarray(r.getActualQ(), dtype=float))
        j = int(np.argmax(jump))
        if jump[j] > cfg.follow_start_tolerance:
            raise StartPositionMismatch(
                f"the trajectory starts {jump[j]:.4f} rad away from the arm at joint {j + 1} (more than "
                f"{cfg.follow_start_tolerance} rad): move to its first sample first")
        if cfg.keep_in is not None:
            for i in keep_in_checkpoints(Qa, cfg.keep_in_spacing):
                pose = self._outside_keep_in(Qa[i])
                if pose is not None:
                    raise KeepInZoneViolation(f"sample {i}: TCP {np.round(pose[:3], 4).tolist()} leaves "
                                              "the keep-in zone (trajectory refused, nothing moved)")
        times = np.empty(len(Qa))
        with tempfile.TemporaryDirectory(prefix="hil-follow-") as tmp:
            frames = os.path.join(tmp, "frames.csv")
            # every frame the controller sends, written by ur_rtde's own receive thread: the loop
            # below reads only the latest frame once a cycle, and a loaded host's late cycles skip
            # frames the join would then interpolate across (`read_frames`)
            start = getattr(r, "startFileRecording", None)  # (a test's stand-in may lack it)
            recording = bool(start(frames, ["timestamp", "actual_q"])) if start is not None else False
            try:
                with self._servo_session(lookahead, gain) as stream:
                    stream.record = True  # the loop's own reads: the host-clock anchors
                    for i, q in enumerate(Qa):
                        times[i] = stream.send(q)
                    for _ in range(round(settle / stream.dt)):
                        stream.send(Qa[-1])
                    hold_end = time.monotonic()
            finally:
                if recording:
                    r.stopFileRecording()
            stamps, joints, hosts = stream.recorded()
            every = read_frames(frames, stamps[0], stamps[-1]) if recording and len(stamps) > 1 else None
        periods = np.asarray(stream.periods)
        frame_t, frame_q = (stamps, joints) if every is None else union_of_frames(stamps, joints, *every)
        return FollowResult(times=times, hold_end=hold_end, period_count=int(periods.size),
                            period_mean=float(periods.mean()) if periods.size else 0.0,
                            period_max=float(periods.max()) if periods.size else 0.0,
                            controller_t=frame_t, actual_q=frame_q, host_t=hosts, host_stamps=stamps)

    @contextmanager
    def servo(self, *, lookahead: float = 0.1, gain: float = 300.0) -> Iterator[ServoStream]:
        """A servo loop at the controller rate; the arm is stopped (servoStop) when the block exits.

        `stop()` from another thread makes the next `step` raise MotionAborted.
        """
        self._abort.clear()
        with self._servo_session(lookahead, gain) as stream:
            yield stream

    @contextmanager
    def _servo_session(self, lookahead: float, gain: float) -> Iterator[ServoStream]:
        c, r = self._require()
        self.check_status()
        stream = ServoStream(self, c, r, lookahead, gain)
        try:
            yield stream
        finally:
            try:
                if c.isConnected():  # never call into ur_rtde while its own thread reconnects
                    with self._cmd_lock:
                        c.servoStop(STOP_DECEL)
            except RuntimeError as exc:
                log.warning("servoStop failed: %s", exc)


class ServoStream:
    """One servo session: ``step(q)`` sends a servoJ target and waits for the next period."""

    def __init__(self, robot: URRobot, c: Any, r: Any, lookahead: float, gain: float) -> None:
        self.robot, self._c, self._r = robot, c, r
        self.lookahead, self.gain = lookahead, gain
        self.dt = 1.0 / (robot.info.rate_hz if robot.info else 500.0)
        self.periods: list[float] = []  # seconds between successive sends (time.monotonic)
        self._t_last: float | None = None
        self._n = 0
        # `follow` turns this on: each cycle's RTDE timestamp and actual_q, read after waitPeriod
        # (ur_rtde's RTDEReceiveInterface getTimestamp / getActualQ: the latest controller frame)
        self.record = False
        self._stamps: list[float] = []
        self._joints: list[list[float]] = []
        self._hosts: list[float] = []

    def step(self, q: Sequence[float], *, pose: bool = False) -> float:
        """Validate and send one target (joints, or a TCP pose with ``pose=True``); see `send`."""
        qa = self.robot.validate_target(q) if not pose else np.asarray(q, dtype=float)
        return self.send(qa, pose=pose)

    def send(self, qa: np.ndarray, *, pose: bool = False) -> float:
        """Send one already validated target, keep the loop period; returns the send time (monotonic).

        Raises MotionAborted after `stop()`, ConnectionLost when the link is gone (checked before
        every command: calling into ur_rtde while its own thread reconnects can crash the process).
        """
        robot, c = self.robot, self._c
        t_start = c.initPeriod()
        now = time.monotonic()
        if self._t_last is not None:
            self.periods.append(now - self._t_last)
        self._t_last = now
        target = qa.tolist()
        with robot._typed_errors(), robot._cmd_lock:
            # checked under the lock stop() holds while sending stopJ: no servo target after a stop
            if robot._abort.is_set():
                raise MotionAborted("stopped by request")
            if not c.isConnected():
                raise ConnectionLost(f"lost the RTDE link to {robot.config.host}")
            if pose:
                ok = c.servoL(target, 0.0, 0.0, self.dt, self.lookahead, self.gain)
            else:
                ok = c.servoJ(target, 0.0, 0.0, self.dt, self.lookahead, self.gain)
        self._n += 1
        if not ok:
            robot._explain(RobotError("the controller refused a servo command"))
        if self._n % 10 == 0:
            robot.check_status()
        c.waitPeriod(t_start)
        if self.record:
            # the stamp read on both sides of the joints: a frame that arrived between the two reads
            # would pair this frame's joints with another's time, so that cycle is not recorded
            stamp = float(self._r.getTimestamp())
            q = list(self._r.getActualQ())
            host = time.monotonic()
            if float(self._r.getTimestamp()) == stamp and (not self._stamps or stamp > self._stamps[-1]):
                self._stamps.append(stamp)
                self._joints.append(q)
                self._hosts.append(host)
        return now

    def recorded(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The controller frames read during the session: timestamps (K,) s, actual_q (K, 6) rad and
        when each was read (K,) on time.monotonic()."""
        return (np.asarray(self._stamps, dtype=float), np.asarray(self._joints, dtype=float).reshape(-1, 6),
                np.asarray(self._hosts, dtype=float))

    def actual_q(self) -> np.ndarray:
        return np.asarray(self._r.getActualQ(), dtype=float)


def read_frames(path: str, first: float, last: float) -> tuple[np.ndarray, np.ndarray] | None:
    """(stamps (K,), actual_q (K, 6)) of the frames ur_rtde recorded to `path` (its CSV: a header
    ``timestamp,actual_q_0,…,actual_q_5``, one row a frame, six decimals: a microsecond, a
    microradian) from controller time `first` to `last`
    (the servo session's first and last frames read; the recording starts a little before and ends
    a little after). Repeated or out-of-order stamps are dropped. None when the file has fewer than
    two such frames or is not that form, and the caller keeps the loop's own reads."""
    try:
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except (OSError, ValueError):
        return None
    if data.ndim != 2 or data.shape[1] != 7:
        return None
    t, q = data[:, 0], data[:, 1:]
    # the file's stamps are rounded to microseconds (ur_rtde writes six decimals)
    keep = (t >= first - 1e-6) & (t <= last + 1e-6) & np.isfinite(data).all(axis=1)
    t, q = t[keep], q[keep]
    if len(t) < 2:
        return None
    rising = np.r_[True, np.diff(t) > 0]
    return t[rising], q[rising]


def union_of_frames(read_t: np.ndarray, read_q: np.ndarray, recorded_t: np.ndarray,
                    recorded_q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every frame either record has, in time order, once: the loop's reads (exact stamps and
    joints) and ur_rtde's recording (rounded to the microsecond). Neither holds the other: ur_rtde
    writes one line per pass of its receive thread, the newest of the frames that arrived together,
    while the loop may have read one of the others; a frame in both (stamps within a microsecond) is
    kept as the loop read it."""
    read_t, recorded_t = np.asarray(read_t, dtype=float), np.asarray(recorded_t, dtype=float)
    fresh = np.ones(len(recorded_t), dtype=bool)
    if len(read_t):
        i = np.searchsorted(read_t, recorded_t)
        left = read_t[np.clip(i - 1, 0, len(read_t) - 1)]
        right = read_t[np.clip(i, 0, len(read_t) - 1)]
        fresh = np.minimum(np.abs(recorded_t - left), np.abs(recorded_t - right)) > 1e-6
    t = np.concatenate([read_t, recorded_t[fresh]])
    q = np.concatenate([np.asarray(read_q, dtype=float).reshape(-1, 6),
                        np.asarray(recorded_q, dtype=float).reshape(-1, 6)[fresh]])
    order = np.argsort(t, kind="stable")
    return t[order], q[order]
