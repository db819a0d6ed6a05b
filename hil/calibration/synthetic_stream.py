"""Synthetic sweep streams: a smooth joint path, its joint stream and its tracker stream, each stamped
on its own clock, for testing and benchmarking the stream join without the simulators.

The path is q(t) = q_c + A ⊙ sin(2π·fᵢ·t + φᵢ): every joint swings at its own frequency, so the tool's
speed keeps changing and every joint reverses again and again — the motion that makes a clock offset
observable (`hil.calibration.stream_join`). Its frequencies are scaled so that the SMR's RMS speed is
the one asked for (the path in space stays the same; accelerations grow with the speed squared).

Truth: the controller samples the encoders every 2 ms of *its* clock (RTDE, 500 Hz), the tracker the
SMR every 1 ms of *its* clock (emScon continuous time mode at the AT960's 1000 Hz); each sample's true
time follows from its clock (`hil.calibration.stream_clocks`), the stamps carry their clock's jitter.
The SMR is where the moving compliant arm puts it (`hil.arm.dynamics.MovingArm`: the deflection
follows the inertial torques) at the true time, read with the tracker's noise
(`hil.calibration.synthetic.Noise`); the joints read with the encoders' noise.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from hil.arm.dynamics import MovingArm
from hil.arm.geometry import Geometry
from hil.arm.joint_directions import directions_along
from hil.calibration.stream_clocks import StationClocks
from hil.calibration.stream_join import JointStream, TrackerStream
from hil.calibration.synthetic import Noise

#: Joint-space centre of the example sweep (rad): elbow up, the wrist turned toward +x, the SMR about
#: 0.5 m from the base — a posture every catalog arm reaches.
CENTRE = np.array([0.0, -1.2, 1.4, -1.8, -1.5708, 0.0])
#: Swing amplitudes (rad) and relative frequencies of the joints; incommensurate, so the path does not
#: repeat within a sweep.
AMPLITUDE = np.array([0.5, 0.25, 0.3, 0.4, 0.4, 0.5])
RELATIVE_FREQUENCY = np.array([1.0, 1.37, 0.71, 1.73, 1.19, 0.89])
CONTROLLER_PERIOD_S = 0.002  # RTDE at 500 Hz (UR's RTDE guide; docs/design.md, Facts: streaming on UR)
TRACKER_PERIOD_S = 0.001  # the AT960's 1000 Hz output (stream_clocks' docstring)


@dataclass(frozen=True)
class SweepPath:
    """The smooth joint path: q(t), q̇(t), q̈(t) in closed form."""

    centre: np.ndarray
    amplitude: np.ndarray
    omega: np.ndarray  # rad/s per joint
    phase: np.ndarray

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, q̇, q̈), each (N, 6), at true times `t` (N,)."""
        arg = np.outer(np.asarray(t, dtype=float), self.omega) + self.phase
        s, c = np.sin(arg), np.cos(arg)
        return (self.centre + self.amplitude * s, self.amplitude * self.omega * c,
                -self.amplitude * self.omega**2 * s)


class SplinePath:
    """Any smooth joint path given as samples (a planned tour, `hil.calibration.sweep_path.SweepTour`):
    q, q̇, q̈ from the cubic spline through them (``scipy.interpolate.CubicSpline``; a tour is itself a
    cubic spline, so this recovers it between its samples)."""

    def __init__(self, t: np.ndarray, q: np.ndarray) -> None:
        self._spline = CubicSpline(np.asarray(t, dtype=float), np.asarray(q, dtype=float), axis=0)
        self.duration = float(t[-1] - t[0])

    def at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(q, q̇, q̈), each (N, 6), at true times `t` (N,)."""
        t = np.asarray(t, dtype=float)
        return self._spline(t), self._spline(t, 1), self._spline(t, 2)


@dataclass(frozen=True)
class SweepStreams:
    """What a synthetic sweep recorded, and its truth."""

    joints: JointStream
    tracker: TrackerStream
    path: SweepPath | SplinePath
    clocks: StationClocks
    tool_speed_rms: float  # m/s, of the SMR along the path (true)


def sweep_path(truth: Geometry, tool_speed: float, seed: int = 0, duration: float = 20.0,
               centre: np.ndarray = CENTRE, amplitude: np.ndarray = AMPLITUDE) -> SweepPath:
    """The example path, its frequencies scaled so the SMR's RMS speed over `duration` seconds is
    `tool_speed` (m/s; to the 1 % a fixed-point iteration of the scaling leaves)."""
    if not 0 < tool_speed <= 2.0:
        raise ValueError(f"tool speed must be in (0, 2] m/s, got {tool_speed}")
    phase = np.random.default_rng(seed).uniform(0, 2 * np.pi, 6)
    unit = SweepPath(np.asarray(centre, float), np.asarray(amplitude, float), 2 * np.pi * RELATIVE_FREQUENCY,
                     phase)
    path = unit
    for _ in range(6):  # the RMS over a fixed window changes a little as the frequencies scale
        rms = _rms_speed(truth, path, duration)
        path = SweepPath(unit.centre, unit.amplitude, path.omega * tool_speed / rms, phase)
        if abs(rms / tool_speed - 1.0) < 0.01:
            break
    return path


def _rms_speed(truth: Geometry, path: SweepPath | SplinePath, duration: float) -> float:
    t = np.linspace(0.0, duration, 4001)
    p = MovingArm(truth.rigid()).points(path.at(t)[0])
    v = np.linalg.norm(np.diff(p, axis=0), axis=1) / np.diff(t)
    return float(np.sqrt(np.mean(v**2)))


def sweep_streams(truth: Geometry, *, tool_speed: float = 0.25, duration: float = 20.0,
                  clocks: StationClocks | None = None, noise: Noise | None = None, seed: int = 0,
                  beam_breaks: Sequence[tuple[float, float]] = (),
                  joint_gaps: Sequence[tuple[float, float]] = (),
                  path: SplinePath | None = None) -> SweepStreams:
    """A sweep of `duration` true seconds at RMS `tool_speed`.

    `beam_breaks` (true-time intervals) lose the tracker's samples (NaN points, as the emScon driver
    yields a lost beam); `joint_gaps` drop the controller's samples (an RTDE link that stalled).
    `clocks` defaults to `StationClocks.realistic()`, `noise` to `Noise()` (the tracker's model and
    the encoders' σ); `Noise(tracker_sigma=0.0, encoder_sigma=0.0)` is noise-free. A given `path` (a
    planned tour) replaces the example path: then `tool_speed` is unused and `duration` is the path's."""
    clocks = StationClocks.realistic() if clocks is None else clocks
    noise = Noise() if noise is None else noise
    rng = np.random.default_rng(seed)
    if path is None:
        path = sweep_path(truth, tool_speed, seed, duration)
    else:
        duration = path.duration
    ctrl, trk = clocks.controller, clocks.tracker
    # each instrument samples on its own clock's grid, from its reading at true time 0 on
    c_grid = ctrl.reading(0.0) + CONTROLLER_PERIOD_S * np.arange(int(duration / CONTROLLER_PERIOD_S) + 1)
    t_ctrl_true = ctrl.true_time(c_grid)
    keep = ~_inside(t_ctrl_true, joint_gaps)
    t_ctrl_true = t_ctrl_true[keep]
    t_c = ctrl.stamps(t_ctrl_true, rng)
    q = path.at(t_ctrl_true)[0]
    if noise.encoder_sigma > 0:
        q = q + rng.normal(0.0, noise.encoder_sigma, q.shape)
    k_grid = trk.reading(0.0) + TRACKER_PERIOD_S * np.arange(int(duration / TRACKER_PERIOD_S) + 1)
    t_trk_true = trk.true_time(k_grid)
    t_k = trk.stamps(t_trk_true, rng)
    # each joint lags by its lost motion to the side it last moved (the contract's rule), moving too
    moving = path.at(t_trk_true)
    p = MovingArm(truth).points(*moving, directions=directions_along(moving[0]) if truth.has_lost_motion
                                else None)
    if noise.tracker_sigma is None or noise.tracker_sigma > 0:
        p = noise.perturb(p, rng)
    p[_inside(t_trk_true, beam_breaks)] = np.nan
    speed = _rms_speed(truth, path, duration)
    return SweepStreams(JointStream(t_c, q), TrackerStream(t_k, p), path, clocks, speed)


def _inside(t: np.ndarray, intervals: Sequence[tuple[float, float]]) -> np.ndarray:
    out = np.zeros(len(t), dtype=bool)
    for a, b in intervals:
        out |= (t >= a) & (t < b)
    return out
