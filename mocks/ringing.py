"""Residual vibration: the SMR rings after a joint move stops; the encoders do not see it.

A UR arm's links and strain-wave gears flex under the inertial load of a move. Its encoders sit on the
motor side and on the joint's output shaft, so ``actual_q`` shows the commanded profile, while the SMR
on the flange, which the tracker sees, keeps oscillating after the profile has ended. This module
models that as one damped mode of the arm along the SMR's direction of travel, driven by the tip
acceleration of the move's trapezoidal profile.

Physics. The deflection x of the tip relative to where the rigid joints put it obeys
``x'' + 2ζωₙx' + ωₙ²x = −a_tip(t)`` (the links lag the acceleration). A `mocks.ur.motion.JointMove`
accelerates its lead joint by +a, coasts, and decelerates by −a: a_tip is piecewise constant, with
steps Δₖ at t = 0, tₐ, T − tₐ and T (tₐ = v/a, or T/2 for a triangular profile). The exact response
to a step Δ at tₖ is ``−(Δ/ωₙ²)·(1 − g(t − tₖ))`` with ``g(τ) = e^(−ζωₙτ)(cos ω_d τ + ζ/√(1 − ζ²)
sin ω_d τ)``; after the move the static parts cancel (Σ Δₖ = 0) and what is left is the ring,
``x(t) = Σₖ (Δₖ/ωₙ²)·g(t − tₖ)``. Its amplitude is the quasi-static deflection under the stop's tip
deceleration, a_tip/ωₙ² (the brief's argument), and it starts at that deflection with zero velocity
(a cosine-led ring, the response of a released spring), not at zero as a pure sine would. The
acceleration steps' direction is the SMR's displacement per radian of the lead joint at the move's
end pose (the tip's tangential acceleration; the centripetal part is zero at rest there).

Constants (every robot model uses the same ones; a UR10e's longer links would ring lower):

* ωₙ = 2π · 9 Hz: the first two natural frequencies of a lightweight 6-axis arm mapped over a
  0.8 m workspace range from about 7 to 10.5 Hz and 7.5 to 12 Hz (Wu, "Intelligence & Robotics"
  2021;1(2):99-115, doi 10.20517/ir.2021.11, Fig. "f₁ [Hz], f₂ [Hz]"); Universal Robots' own work on
  input shaping for its arms is about these low, configuration-dependent modes (Thomsen,
  Søe-Knudsen, Brandt, Zhang, "Experimental Implementation of Time-varying Input Shaping on UR
  Robots", ICINCO 2019).
* ζ = 0.10: structural damping of a robot's modes measured by modal tests is 2-3.6 % (Sci. Rep.
  14, 2024, doi 10.1038/s41598-024-61362-2, Table 3, an industrial arm); a UR's joint servos add
  active damping on top of the structure's, which the modal tests of unpowered arms do not see. 0.10
  is the assumption that keeps a 0.3 s settle (station.example.toml) plausible at the example speeds
  for most stops: a 1 rad/s² stop of a joint 0.5 m from the SMR rings with 0.5/ωₙ² = 160 µm, and
  e^(−ζωₙ·0.3) = 0.18 of it (28 µm) is left after 0.3 s. With the modal tests' 3 % alone the ring
  would last 3× longer.

Stops (a protective stop, a dashboard stop) are not modelled: a move cut short drops its ring (a
real stop rings harder; the campaign re-runs a stopped visit from its move anyway).
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: rad/s: the mode's natural frequency (9 Hz, module docstring).
OMEGA_N = 2 * math.pi * 9.0
#: The mode's damping ratio (module docstring).
ZETA = 0.10
#: Rings older than this many time constants 1/(ζωₙ) are dropped: e^(−12) of their amplitude left.
FORGET_AFTER = 12.0


@dataclass(frozen=True)
class Ring:
    """One move's excitation: acceleration steps (time, m/s² per m of tip direction) along `direction`."""

    steps: tuple[tuple[float, float], ...]  # (time on the controller's clock, Δ lead-joint accel rad/s²)
    direction: np.ndarray  # SMR displacement per radian of the lead joint at the end pose (m/rad, base frame)
    end: float


def step_response(tau: np.ndarray | float, omega: float = OMEGA_N, zeta: float = ZETA) -> np.ndarray:
    """g(τ): the free ring of a released unit deflection (1 at τ = 0, zero velocity), 0 before it."""
    tau = np.asarray(tau, dtype=float)
    wd = omega * math.sqrt(1.0 - zeta * zeta)
    lead = zeta / math.sqrt(1.0 - zeta * zeta)
    g = np.exp(-zeta * omega * tau) * (np.cos(wd * tau) + lead * np.sin(wd * tau))
    return np.where(tau >= 0, g, 0.0)


def profile_steps(start: float, duration: float, accel_time: float, acceleration: float
                  ) -> tuple[tuple[float, float], ...]:
    """The lead joint's acceleration steps of a trapezoidal (or triangular) rest-to-rest profile."""
    a = float(acceleration)
    return ((start, a), (start + accel_time, -a), (start + duration - accel_time, -a),
            (start + duration, a))


class Ringing:
    """The SMR's vibration offset (base frame, metres) at any time, from the moves recorded so far.

    Deterministic given the moves: the offset is a closed-form function of the moves' profiles and the
    time asked for. Thread-safe (the arm records from its tick thread; the trackers read from theirs).
    """

    def __init__(self, omega: float = OMEGA_N, zeta: float = ZETA) -> None:
        if not (omega > 0 and 0 < zeta < 1):
            raise ValueError("the mode needs ωₙ > 0 and 0 < ζ < 1")
        self.omega, self.zeta = float(omega), float(zeta)
        self._rings: list[Ring] = []
        self._lock = threading.Lock()

    @property
    def time_constant(self) -> float:
        """Seconds for the ring's envelope to fall by e: 1/(ζωₙ)."""
        return 1.0 / (self.zeta * self.omega)

    def record(self, start: float, duration: float, accel_time: float, acceleration: float,
               direction: np.ndarray) -> None:
        """A joint move started at `start` (controller clock) with this lead-joint profile."""
        if duration <= 0 or acceleration <= 0:
            return
        ring = Ring(profile_steps(start, duration, accel_time, acceleration),
                    np.asarray(direction, dtype=float).copy(), start + duration)
        with self._lock:
            horizon = start - FORGET_AFTER * self.time_constant
            self._rings = [r for r in self._rings if r.end > horizon] + [ring]

    def cut(self, at: float) -> None:
        """The move in progress at `at` was stopped: its ring is dropped (module docstring)."""
        with self._lock:
            self._rings = [r for r in self._rings if r.end <= at]

    def offset(self, t: float) -> np.ndarray:
        """The SMR's deflection (m, base frame) at controller time `t`: during and after the moves."""
        with self._lock:
            rings = list(self._rings)
        out = np.zeros(3)
        w2 = self.omega * self.omega
        for ring in rings:
            times = np.array([s[0] for s in ring.steps])
            deltas = np.array([s[1] for s in ring.steps])
            started = times <= t
            if not np.any(started):
                continue
            g = step_response(t - times[started], self.omega, self.zeta)
            x = float(np.sum(-(deltas[started] / w2) * (1.0 - g)))
            out += x * ring.direction
        return out

    def offsets(self, t: np.ndarray) -> np.ndarray:
        """(n, 3) `offset` at each of the controller times `t`, all in one pass over the moves.

        An emScon stationary measurement is hundreds of readings; asked one by one (a Python call and a
        lock per instant) they cost the simulator's interpreter about 0.1 s a measurement, which in fast
        time is simulated seconds by which its answer comes late (docs/design.md, Facts: ur_rtde against
        a simulator). Same closed form as `offset`, evaluated for every instant together."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        with self._lock:
            rings = list(self._rings)
        out = np.zeros((len(t), 3))
        w2 = self.omega * self.omega
        for ring in rings:
            times = np.array([s[0] for s in ring.steps])
            deltas = np.array([s[1] for s in ring.steps])
            tau = t[:, None] - times[None, :]
            started = tau >= 0
            g = step_response(np.where(started, tau, 0.0), self.omega, self.zeta)
            x = np.where(started, -(deltas / w2) * (1.0 - g), 0.0).sum(axis=1)
            out += x[:, None] * ring.direction
        return out

    def listener(self, tip_direction: Callable[[np.ndarray, np.ndarray], np.ndarray]
                 ) -> Callable[..., None]:
        """A `mocks.ur.arm.SimArm` listener recording its ``movej`` and ``movej_cut`` events.

        `tip_direction(q_end, u)`: the SMR's displacement per radian of the lead joint at `q_end` when
        the joints move along `u` (joint radians per lead-joint radian), from the world's true arm."""
        def on_event(event: str, **info: object) -> None:
            if event == "movej":
                q0 = np.asarray(info["q0"], dtype=float)
                q1 = np.asarray(info["q1"], dtype=float)
                lead = float(np.max(np.abs(q1 - q0)))
                if lead <= 0:
                    return
                direction = tip_direction(q1, (q1 - q0) / lead)
                self.record(float(info["start"]), float(info["duration"]),  # type: ignore[arg-type]
                            float(info["accel_time"]), float(info["acceleration"]),  # type: ignore[arg-type]
                            direction)
            elif event == "movej_cut":
                self.cut(float(info["at"]))  # type: ignore[arg-type]
        return on_event
