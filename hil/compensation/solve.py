"""Compensation of one target: solve it with the accurate model, express it in the controller's model.

A UR controller moves by its own kinematics (nominal DH + factory deltas). To put the tool where hil's
calibrated model says a target is, the target is solved with the *accurate* model — joints q with
accurate_FK(q)·tcp = target — and the controller is sent either those joints or the pose its own model
maps them to, controller_FK(q)·tcp. The controller then solves that pose back to q (its IK is exact on
its own model), so the tool lands where the accurate model predicts: compensation round-trips exactly.

The branch (shoulder, elbow, wrist configuration) is the one the controller itself would have used for the
uncompensated target: UR's ``get_inverse_kin(pose, qnear)`` and ``movej`` of a pose take, among all the
configurations of the pose, the one nearest `near` (the current joints for a move). Damped least squares
from `near` alone converges to *some* configuration — for a target far from `near` not always the
nearest — so the controller's solution is the nearest of the one seeded from `near` and those seeded
from the nominal arm's configurations (`hil.arm.branches`), measured as UR measures qnear: the largest
joint difference, each joint at its turn nearest `near` within the limits. The accurate solution is
seeded from that, so compensation never changes a target's configuration. A target neither model
reaches within the joint limits, or whose accurate solution lands on another branch (a singularity lies
between the two models), raises `UnreachableError`: never a clamped or nearby answer.

Compliance (a sagging arm) is not modelled yet: the accurate prediction is the calibrated geometry.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from hil.arm.branches import (
    branches_near,
    joint_distance,
    nearest_turns,
    nominal_branches,
    other_branches_distance,
)
from hil.arm.geometry import Geometry
from hil.arm.ik import UnreachableError, solve_ik
from hil.arm.kinematics import Kinematics

#: rad: the largest joint difference between the controller's solution of a target and the accurate
#: one that still counts as the same configuration. Model differences of millimetres move joints by
#: milliradians; a step this large means the two solutions sit on either side of a singularity.
SAME_BRANCH = 0.1
#: SE(3) error (log, m/rad) the IK solves to: far below a tracker's resolution, so the round trip
#: controller IK(command) → accurate FK lands on the target to a nanometre.
TOLERANCE = 1e-12
#: rad: how far the controller's solution may lie from the nominal arm's configuration it was seeded
#: from. Factory deltas are millimetres and milliradians (`hil.arm.controller_model`), which move joints
#: by milliradians, as between the two models of `SAME_BRANCH`; so a nominal configuration farther from
#: `near` than the best solution found by more than this cannot give a nearer one, and is not solved.
SEED_MARGIN = SAME_BRANCH


@dataclass(frozen=True)
class Compensated:
    """One compensated target."""

    target: pin.SE3  # the tool pose wanted (base frame), as given
    q: np.ndarray  # joints that put the tool at `target` by the accurate model
    command: pin.SE3  # the tool pose to send the controller: its model maps it to `q`
    q_controller: np.ndarray  # joints the controller would have used for the uncompensated target

    @property
    def shift(self) -> float:
        """How far the commanded position moved from the target (m)."""
        return float(np.linalg.norm(self.command.translation - self.target.translation))

    @property
    def turn(self) -> float:
        """How far the commanded orientation turned from the target (rad)."""
        return float(np.linalg.norm(pin.log3(self.target.rotation.T @ self.command.rotation)))


@dataclass
class Compensator:
    """hil's accurate model beside the controller's, and the tool both are asked about."""

    accurate: Geometry
    controller: Geometry
    tcp: pin.SE3 = field(default_factory=pin.SE3.Identity)

    def __post_init__(self) -> None:
        if self.accurate.robot != self.controller.robot:
            raise ValueError(f"the model is of a {self.accurate.robot}, the controller's of a "
                             f"{self.controller.robot}")
        self._accurate = Kinematics(self.accurate)
        self._controller = Kinematics(self.controller)
        self._tcp_inv = pin.SE3(self.tcp).inverse()

    def controller_pose(self, q: np.ndarray) -> pin.SE3:
        """The tool pose the controller's model gives for joints `q` (what it reports and moves to)."""
        return pin.SE3(self._controller.flange_poses(q)[0]) * self.tcp

    def accurate_pose(self, q: np.ndarray) -> pin.SE3:
        """The tool pose hil's model predicts for joints `q`."""
        return pin.SE3(self._accurate.flange_poses(q)[0]) * self.tcp

    def controller_joints(self, target: pin.SE3, near: np.ndarray) -> np.ndarray:
        """The controller's own IK of a tool pose: its configuration nearest `near`, as UR's qnear."""
        return self._nearest_controller_solution(pin.SE3(target) * self._tcp_inv, np.asarray(near, float))

    def _nearest_controller_solution(self, flange: pin.SE3, near: np.ndarray) -> np.ndarray:
        """The controller model's solution for `flange` nearest `near` (see the module docstring).

        Cheap in the usual case (a target near the previous one): every other configuration lies
        farther from `near` than the solution seeded from it, by more than `SEED_MARGIN`
        (`other_branches_distance`), so that one damped least squares is all. Otherwise the nominal
        configurations are solved nearest first (the one the solution from `near` already is skipped),
        until the next lies too far to give a nearer solution.
        """
        spec = self.controller.spec
        best: np.ndarray | None = None
        best_distance: float = np.inf
        error: UnreachableError | None = None
        try:  # solve_ik puts every joint at its turn nearest the seed, here `near`
            best = solve_ik(self._controller, flange, near, tolerance=TOLERANCE)
            best_distance = joint_distance(best, near)
        except UnreachableError as exc:
            error = exc
        if best is not None and \
                other_branches_distance(spec, flange, best, near) >= best_distance + SEED_MARGIN:
            return best  # every other configuration lies farther: nothing to solve
        seeds = branches_near(nominal_branches(spec, flange), near, spec)
        own, margin = -1, SEED_MARGIN
        if best is not None and len(seeds):
            gaps = np.abs(seeds - best).max(axis=1)
            own = int(np.argmin(gaps))
            if gaps[own] >= SEED_MARGIN:  # no nominal configuration predicts it: try them all
                own, margin = -1, np.inf
        distances = np.abs(seeds - near).max(axis=1)
        for i, seed in enumerate(seeds):
            if distances[i] >= best_distance + margin:
                break  # nearest first: no later configuration can be nearer
            if i == own:
                continue  # the solution seeded from `near` is this configuration's
            try:
                q = solve_ik(self._controller, flange, seed, tolerance=TOLERANCE)
            except UnreachableError:
                continue
            q = nearest_turns(q, near, spec.lower, spec.upper)
            if joint_distance(q, near) < best_distance:
                best, best_distance = q, joint_distance(q, near)
        if best is None:
            raise error or UnreachableError("no configuration reaches the target")
        return best

    def solve(self, target: pin.SE3, near: Sequence[float] | np.ndarray, *,
              search: bool = True) -> Compensated:
        """Compensate one tool pose (base frame); `near`: the joints the branch is chosen by.

        `search`: find the controller's configuration nearest `near` among all of the pose's (as UR's
        IK does); False only follows the branch of `near` by damped least squares — for the samples of
        a path, each a cycle from the previous one, where no other configuration can be nearer.
        """
        target = pin.SE3(target)
        flange = target * self._tcp_inv
        near = np.asarray(near, dtype=float)
        q_ctrl = (self._nearest_controller_solution(flange, near) if search
                  else solve_ik(self._controller, flange, near, tolerance=TOLERANCE))
        q = solve_ik(self._accurate, flange, q_ctrl, tolerance=TOLERANCE)
        jump = float(np.max(np.abs(q - q_ctrl)))
        if jump > SAME_BRANCH:
            raise UnreachableError(f"the accurate solution lies {jump:.3f} rad from the controller's "
                                   "(another configuration: a singularity between the two models)")
        return Compensated(target, q, self.controller_pose(q), q_ctrl)

    def solve_all(self, targets: Sequence[pin.SE3], near: Sequence[float] | np.ndarray,
                  where: Sequence[str] | None = None) -> list[Compensated]:
        """Compensate a sequence, each target's branch chosen nearest the previous one's joints.

        A failure names the target (``where[i]``, e.g. "line 12") it happened at.
        """
        out: list[Compensated] = []
        q = np.asarray(near, dtype=float)
        for i, target in enumerate(targets):
            try:
                c = self.solve(target, q)
            except UnreachableError as exc:
                raise UnreachableError(f"{where[i] if where else f'target {i + 1}'}: {exc}") from None
            out.append(c)
            q = c.q
        return out
