"""How the arm gets from where it is to a target inside the keep-in box: straight, or by a detour.

A moveJ travels a straight line in joint space, and between two poses that are each inside the box
that line can still sweep the SMR outside it. `Router.route` says which targets to move through
instead: straight when that is safe, else the quickest safe detour — through the home pose, or through
one of `TRANSIT_POSTURES` above the start's and the target's base angles. Asked to *approach* a
target by δ, the route ends with a last short leg from δ below the target in every joint, so every
joint arrives moving up: each joint's lost motion then lags the same way at every pose so reached
(ISO 9283 §7.2.1's unidirectional approach, per joint), a constant offset a calibration absorbs; if
that lead-in pose is not safe, the target is approached from wherever the route arrives. The campaign
engine moves along it and a dry run (`hil.campaign.steps.plan_motion`) shows it, so both take the
same way. Nothing
is ever clamped: a target outside the limits or the box is refused (`InputError`), and one with no safe
way to it raises `UnsafePathError`.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from hil.arm.catalog import RobotSpec
from hil.arm.geometry import Geometry
from hil.arm.safety import check_target
from hil.arm.self_collision import SelfCollision
from hil.errors import HilError


class UnsafePathError(HilError):
    """No safe way to a (safe) target from where the arm is: the pose is skipped."""


#: Detour postures (shoulder q2, elbow q3) tried in order when neither the straight path nor the home
#: pose is safe: the upright posture first (a floor-mounted arm's highest), then folded ones. A UR10e
#: stands about 1.5 m tall upright, above a 1.2 m keep-in box, where its straight paths between widely
#: spread poses also sweep outside: with the upright detour alone the example station skipped 15-26 of
#: a 50-pose campaign's poses on UR10e arms (bench/cycle_time.py stations), with these 1-3. The elbow
#: stays within ±2.4 rad, and every folded posture is checked for self-collision (the selector's
#: capsules, `hil.arm.self_collision`) before it is used.
TRANSIT_POSTURES: tuple[tuple[float, float], ...] = (
    (-np.pi / 2, 0.0),
    *((q2, sign * q3) for q3 in (2.4, 2.0, 1.5, 0.8) for sign in (1.0, -1.0)
      for q2 in (-np.pi / 2, -2.2, -1.0, -2.8, -0.4)),
)


def transit(q: np.ndarray, shoulder: float = -np.pi / 2, elbow: float = 0.0) -> np.ndarray:
    """A transit posture above `q`'s base angle (the upright one by default), wrist angles kept."""
    out = np.array(q, dtype=float)
    out[1], out[2] = shoulder, elbow
    return out


def travel(start: np.ndarray, route: list[np.ndarray]) -> float:
    """The leading joint's travel (rad) summed over the legs of `route` from `start`: what a moveJ's
    time grows with, so the measure of a quick route."""
    return sum(float(np.max(np.abs(b - a))) for a, b in zip([start, *route[:-1]], route, strict=True))


@dataclass
class Router:
    """The routes of one arm in one keep-in box (`model`: the nominal geometry with the SMR guess the
    box is checked with; without a box or a model only the joint limits are checked)."""

    spec: RobotSpec
    keep_in: tuple[np.ndarray, np.ndarray] | None = None
    model: Geometry | None = None
    home: np.ndarray | None = None  # a safe pose to route through when a direct path is unsafe

    def __post_init__(self) -> None:
        self._self_collision: SelfCollision | None = None  # made on first use (few legs need it)

    def route(self, here: np.ndarray | None, q: np.ndarray, approach: float = 0.0) -> list[np.ndarray]:
        """Targets to move through from `here` (None: unknown, only `q` is checked) to reach `q` safely;
        with `approach` δ > 0 (rad) the last leg comes up from q − δ in every joint (`approach_pose`).

        The target itself must be safe (joint limits, keep-in box), else InputError: the plan is wrong.
        If the straight joint-space path from `here` leaves the box, detours are tried: through the
        home pose, and through each of `TRANSIT_POSTURES` (the upright posture, q2 = −π/2, q3 = 0, a
        floor-mounted arm's highest, then folded ones) above the current and the target base angles; of
        the safe ones the quickest is taken (the least leading-joint travel summed over its legs,
        `travel`). If every leg of none of them is safe, `UnsafePathError`. Nothing is ever clamped.
        """
        q = np.asarray(q, dtype=float)
        check_target(q, self.spec, self.keep_in, self.model)
        if approach > 0:
            lead = self.approach_pose(here, q, approach)
            if lead is not None:
                return [*self.route(here, lead), q]
        if here is None:
            return [q]
        here = np.asarray(here, dtype=float)
        safe: list[list[np.ndarray]] = []
        for route, folded in self._candidates(here, q):
            try:
                start = here
                for target in route:
                    check_target(target, self.spec, self.keep_in, self.model, start)
                    start = target
            except HilError:
                continue
            if len(route) == 1:  # straight there: nothing is quicker
                return route
            # a folded transit is checked for self-collision only once its legs stay in the box: most
            # fail that first, and the box check (a cached model's FK) costs half the capsules'
            if folded and self.collides(np.linspace(route[0], route[1], 5)):
                continue
            safe.append(route)
        if safe:
            return min(safe, key=lambda r: travel(here, r))
        raise UnsafePathError(f"no safe path from {np.round(here, 3).tolist()} to "
                              f"{np.round(q, 3).tolist()} inside the keep-in box (direct, via home, via "
                              f"{len(TRANSIT_POSTURES)} upright and folded postures)")

    def approach_pose(self, here: np.ndarray | None, q: np.ndarray, approach: float) -> np.ndarray | None:
        """Where the last leg to `q` starts so every joint arrives moving up by at least `approach`:
        q − `approach` in every joint; None when no lead-in is needed (every joint already comes up
        that far from `here`) or when that pose, or the leg from it, is not safe."""
        if here is not None and np.all(q - np.asarray(here, dtype=float) >= approach):
            return None
        lead = q - approach
        try:
            check_target(lead, self.spec, self.keep_in, self.model)
            check_target(q, self.spec, self.keep_in, self.model, lead)
        except HilError:
            return None
        return lead

    def candidates(self, here: np.ndarray, q: np.ndarray) -> Iterator[list[np.ndarray]]:
        """The routes `route` tries, in order, made as they are needed (most legs go straight); a
        transit through a folded posture only if it does not fold the arm onto itself."""
        for route, folded in self._candidates(here, q):
            if not (folded and self.collides(np.linspace(route[0], route[1], 5))):
                yield route

    def _candidates(self, here: np.ndarray, q: np.ndarray) -> Iterator[tuple[list[np.ndarray], bool]]:
        """(route, whether its transit is a folded posture to check for self-collision), in `candidates`'
        order, unchecked."""
        yield [q], False
        if self.home is not None:
            yield [np.asarray(self.home, dtype=float), q], False
        for k, (shoulder, elbow) in enumerate(TRANSIT_POSTURES):
            # the upright posture (k = 0) cannot fold the arm onto itself
            yield [transit(here, shoulder, elbow), transit(q, shoulder, elbow), q], k > 0

    def collides(self, q: np.ndarray) -> bool:
        """Whether any of configurations `q` (n, 6) brings two non-adjacent links of the arm together
        (the selector's capsules and margin on the nominal arm carrying the model's SMR)."""
        if self._self_collision is None:
            smr = None if self.model is None else self.model.smr
            self._self_collision = SelfCollision(self.spec, smr)
        return self._self_collision.collides(q)
