"""Compensation of one target: solve it with the accurate model, express it in the controller's model.

A UR controller moves by its own kinematics (nominal DH + factory deltas). To put the tool where hil's
calibrated model says a target is, the target is solved with the *accurate* model — joints q with
accurate_FK(q)·tcp = target — and the controller is sent either those joints or the pose its own model
maps them to, controller_FK(q)·tcp. The controller then solves that pose back to q (its IK is exact on
its own model), so the tool lands where the accurate model predicts: compensation round-trips exactly.

The branch (shoulder, elbow, wrist configuration) is the one the controller itself would have used for the
uncompensated target — its IK seeded from `near`, as UR's ``get_inverse_kin(pose, qnear)`` and ``movej``
of a pose do — and the accurate solution is seeded from that, so compensation never changes a target's
configuration. A target neither model reaches within the joint limits, or whose accurate solution lands
on another branch (a singularity lies between the two models), raises `UnreachableError`: never a
clamped or nearby answer.

Compliance (a sagging arm) is not modelled yet: the accurate prediction is the calibrated geometry.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

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
        """The controller's own IK of a tool pose, on the branch nearest `near`."""
        return solve_ik(self._controller, pin.SE3(target) * self._tcp_inv, near, tolerance=TOLERANCE)

    def solve(self, target: pin.SE3, near: Sequence[float] | np.ndarray) -> Compensated:
        """Compensate one tool pose (base frame); `near`: the joints the branch is chosen by."""
        target = pin.SE3(target)
        flange = target * self._tcp_inv
        q_ctrl = solve_ik(self._controller, flange, np.asarray(near, dtype=float), tolerance=TOLERANCE)
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
