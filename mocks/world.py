"""The simulated world: the true arm (with hidden errors), where the tracker stands, what it can see.

The robot simulator owns the joints; the tracker simulator asks this world where the SMR truly is
(`target`, the GeoCOM simulator's `TargetSource`). The true flange pose comes from the *truth*
geometry, never from the nominal model the controller reports with, so a calibration has real
errors to find. The SMR is visible when its opening axis (the flange z axis) points within the
acceptance half-angle of the line to the tracker.

The truth is a real arm: it sags under gravity by its joints' compliance (`Kinematics` applies the
truth's ``compliance`` for its ``payload``) and grows as it warms up. At simulated time t the arm is
``truth.grown(rise())`` (docs/design.md, Contracts: non-geometric errors), the temperature rise from
`rise`: the station's `mocks.heating.Heating`, which warms the joints while they move (and a little
while they hold the arm), not while the controller merely runs. Without `rise` the arm is
``truth.warmed(t)``, t read from `clock` (an arm moving all the time); with neither it stays cold.

Its links also differ from its encoders by the truth's angle-dependent joint errors and lag them by
its lost motion in the direction each joint last moved (docs/design.md, Contracts: non-geometric
errors): `directions` reports those directions (the robot simulator follows them cycle by cycle,
`mocks.ur.directions`); without it no lost motion is applied.

The arm also rings after its moves (`mocks.ringing`): with a `ringing` model, the SMR the tracker sees
(`target`) is displaced by the links' residual vibration at the clock's time, while the joints (and so
the controller's ``actual_q``) are not. `tip_direction` gives that model the true arm's SMR direction
of travel at a move's end.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics
from hil.calibration.selection import arm_shape
from mocks.geocom.target import TargetState
from mocks.ringing import Ringing
from selector.arm import segment_distance

#: Points at which a reading's integration of the ring is evaluated (over a 0.1 s reading of a 9 Hz
#: ring: about 18 per period).
READING_SAMPLES = 16

#: The beam is checked from this far beyond the SMR centre (the SMR's own nest is not an obstacle).
BEAM_CLEARANCE = 0.03
#: The simulated links' thickness as a fraction of the selector's (enveloping) capsules.
TRUE_LINK_FRACTION = 0.8
#: The warmed arm's model is rebuilt when its growth factor moved by more than this (relative): a
#: nanometre per metre of arm, far below any tracker's resolution, while the trackers poll the world
#: hundreds of times a second and the factor changes continuously.
SCALE_TOLERANCE = 1e-9


@dataclass
class World:
    """Truth + the arm's joints → the true SMR position in the tracker frame, and its visibility.

    `clock` gives the simulated running time (s) that warms the arm (`Geometry.warmed`); None: cold.
    """

    truth: Geometry
    joints: Callable[[], np.ndarray]
    acceptance_deg: float = 30.0
    blocked: str = ""  # non-empty: something (a person, a cable) is in the beam, and what
    clock: Callable[[], float] | None = None
    ringing: Ringing | None = None  # the links' residual vibration after moves (needs `clock`)
    reading_time: float = 0.0  # seconds one tracker reading integrates over (`ring_offset`)
    directions: Callable[[], np.ndarray] | None = None  # each joint's last direction of motion
    # the arm's recorded true states: (joints, directions) at simulated times (`mocks.ur.history`),
    # and the newest time it has; None: only the current joints are known
    joints_at: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]] | None = None
    known_until: Callable[[], float | None] | None = None
    rise: Callable[[], float] | None = None  # the arm's temperature rise now (K, `mocks.heating`)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def __post_init__(self) -> None:
        self._cold = Kinematics(self.truth)
        self._kin = self._cold
        self._scale = 1.0
        # The selector plans with capsules that envelop the links; the real links are slimmer.
        planned = arm_shape(self.truth.robot)
        self._arm = replace(planned, radii=tuple(TRUE_LINK_FRACTION * r for r in planned.radii))
        self._ring_kin = Kinematics(self.truth)  # its own pinocchio data: called from the arm's thread
        self._ring_lock = threading.Lock()

    def tip_direction(self, q: np.ndarray, u: np.ndarray, step: float = 1e-6) -> np.ndarray:
        """The SMR's displacement (m, base frame) per radian of the lead joint at `q`, the joints moving
        along `u` (radians per lead-joint radian): the direction and lever of a stop's tip acceleration."""
        q = np.asarray(q, dtype=float)
        u = np.asarray(u, dtype=float)
        with self._ring_lock:
            F = self._ring_kin.flange_poses(np.stack([q - step * u, q]))
        p = np.einsum("nij,j->ni", F[:, :3, :3], self.truth.smr) + F[:, :3, 3]
        return (p[1] - p[0]) / step

    def ring_offset(self, at: float | None = None) -> np.ndarray:
        """The SMR's vibration displacement (m, tracker frame) as a reading sees it: averaged over the
        `reading_time` that has just passed (a distance measurement integrates over its measuring time;
        an instantaneous sample of a 9 Hz ring every 0.1 s would alias it to a slow, steady-looking
        offset that no real instrument reports). `at`: a reading ending at that simulated time, else
        now. Zero without a ringing model."""
        now = float(self.clock()) if at is None and self.clock is not None else float(at or 0.0)
        return self.ring_offsets(np.array([now]))[0]

    def ring_offsets(self, ats: np.ndarray, reading_time: float | None = None) -> np.ndarray:
        """(n, 3) `ring_offset` of readings ending at each simulated time of `ats`, each integrated over
        `reading_time` seconds (None: the world's `reading_time`; 0: an instant), computed in one pass
        (`mocks.ringing.Ringing.offsets`): one stationary measurement is hundreds of readings."""
        ats = np.atleast_1d(np.asarray(ats, dtype=float))
        if self.ringing is None or self.clock is None:
            return np.zeros((len(ats), 3))
        span = self.reading_time if reading_time is None else float(reading_time)
        if span > 0:
            back = span * (np.arange(READING_SAMPLES) + 0.5) / READING_SAMPLES
            offsets = self.ringing.offsets((ats[:, None] - back[None, :]).ravel())
            offset = offsets.reshape(len(ats), READING_SAMPLES, 3).mean(axis=1)
        else:
            offset = self.ringing.offsets(ats)
        return offset @ self.truth.tracker.rotation  # each row turned into the tracker frame

    def running_time(self) -> float:
        """Simulated seconds the arm has been running (0 without a clock)."""
        return float(self.clock()) if self.clock is not None else 0.0

    def _warm_kinematics(self) -> Kinematics:
        """The arm as warm as it is now (call with the lock held): rebuilt only when it grew."""
        thermal = self.truth.thermal
        if thermal is None or (self.clock is None and self.rise is None):
            return self._cold
        rise = self.rise() if self.rise is not None else thermal.rise_at(self.running_time())
        scale = thermal.scale_of(rise)
        if abs(scale - self._scale) > SCALE_TOLERANCE * scale:
            self._kin = self._cold if scale == 1.0 else Kinematics(self.truth.grown(rise))
            self._scale = scale
        return self._kin

    def state(self, q: np.ndarray) -> tuple[np.ndarray, float]:
        """(SMR in the tracker frame, angle in degrees between its axis and the line to the tracker)."""
        side = None if self.directions is None else np.asarray(self.directions(), dtype=float)
        with self._lock:  # one pinocchio Data per model: the simulator's threads take turns
            F = self._warm_kinematics().flange_poses(q, side)[0]
        p_base = F[:3, :3] @ self.truth.smr + F[:3, 3]
        return self._in_tracker(p_base), self._angle(F, p_base)

    def positions_at(self, times: np.ndarray, reading_time: float | None = None) -> np.ndarray:
        """(n, 3) true SMR positions (m, tracker frame, ringing included) at simulated `times`, from
        the arm's recorded states (`joints_at`): what a tracker sampling at those instants measures,
        however late its own thread got round to asking. `reading_time`: seconds each reading
        integrates the ring over (`ring_offsets`; None: the world's). Without a record: the current
        position."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        if self.joints_at is None:
            return np.tile(self.target().position, (len(times), 1))
        Q, D = self.joints_at(times)
        side = D if self.directions is not None else None
        with self._lock:
            F = self._warm_kinematics().flange_poses(Q, side)
        p_base = np.einsum("nij,j->ni", F[:, :3, :3], self.truth.smr) + F[:, :3, 3]
        T = self.truth.tracker
        p = (p_base - T.translation) @ T.rotation
        if self.ringing is not None and self.clock is not None:
            p = p + self.ring_offsets(times, reading_time)
        return p

    def _in_tracker(self, p_base: np.ndarray) -> np.ndarray:
        T = self.truth.tracker
        return T.rotation.T @ (p_base - T.translation)

    def _angle(self, F: np.ndarray, p_base: np.ndarray) -> float:
        to_tracker = self.truth.tracker.translation - p_base
        cos = float(F[:3, 2] @ to_tracker / np.linalg.norm(to_tracker))
        return float(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))

    def blocked_by_arm(self, q: np.ndarray) -> bool:
        """Whether a link of the (true) arm cuts the beam between the SMR and the tracker.

        Checked on the cold arm: its growth (a tenth of a millimetre) is nothing next to a link's radius.
        """
        with self._lock:
            frames = self._cold.joint_frames(q)
        F = frames[0, 6]
        smr = F[:3, :3] @ self.truth.smr + F[:3, 3]
        tracker = self.truth.tracker.translation
        beam = tracker - smr
        dist = float(np.linalg.norm(beam))
        start = smr + beam / dist * min(BEAM_CLEARANCE, dist)
        links = self._arm.segments(frames, smr[None])[:, :-1]  # every capsule but the SMR's own
        d = segment_distance(start[None, None], tracker[None, None], links[:, :, 0], links[:, :, 1])
        return bool(np.any(d <= np.asarray(self._arm.radii)[:-1]))

    def target(self) -> TargetState:
        p, angle = self.state(np.asarray(self.joints(), dtype=float))
        p = p + self.ring_offset()  # the links ring; the joints (the encoders) do not show it
        if self.blocked:
            return TargetState(p, False, self.blocked)
        if angle > self.acceptance_deg:
            return TargetState(p, False, f"SMR faces away ({angle:.0f}° > {self.acceptance_deg:.0f}° "
                                         "acceptance)")
        if self.blocked_by_arm(np.asarray(self.joints(), dtype=float)):
            return TargetState(p, False, "the arm blocks the line of sight")
        return TargetState(p, True)

    def block_beam(self, on: bool = True, reason: str = "something is in the beam") -> None:
        """Fault injection: interrupt (or restore) the line of sight."""
        self.blocked = reason if on else ""

    def home_pose(self, rng: np.random.Generator, samples: int = 20000) -> np.ndarray:
        """A start pose where the operator would lock the beam: SMR facing the tracker, arm bent.

        Chosen among random configurations with the upper arm above horizontal, the elbow and wrist
        away from singularities and the elbow and SMR at least 20 cm above the base, as the one facing
        the tracker most directly with the line of sight clear of the arm's own links.
        """
        q = rng.uniform(-np.pi, np.pi, (samples, 6))
        q[:, 1] = rng.uniform(-2.6, -0.5, samples)  # upper arm well above horizontal
        q[:, 2] = rng.uniform(0.6, 2.2, samples) * rng.choice([-1.0, 1.0], samples)
        q[:, 4] = rng.uniform(0.5, 2.6, samples) * rng.choice([-1.0, 1.0], samples)
        kin = Kinematics(self.truth)
        F = kin.flange_poses(q)
        p = np.einsum("nij,j->ni", F[:, :3, :3], self.truth.smr) + F[:, :3, 3]
        to_tracker = self.truth.tracker.translation - p
        cos = np.einsum("ni,ni->n", F[:, :3, 2], to_tracker) / np.linalg.norm(to_tracker, axis=1)
        elbow = kin.joint_frames(q)[:, 2, :3, 3]
        cos[(p[:, 2] < 0.2) | (elbow[:, 2] < 0.2)] = -2.0
        for i in np.argsort(-cos)[:1000]:
            if cos[i] > -2.0 and not self.blocked_by_arm(q[i]):
                return q[i]
        raise ValueError("no start pose sees the tracker: is the tracker placed where the arm can face it?")
