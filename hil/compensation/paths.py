"""Joint paths through compensated targets: what a streamed trajectory (MOVEB) needs of `Compensator`.

A path streamed with servoJ sends joints, so the controller's model does not move the tool; it still
chooses the branch, as it would for the uncompensated path, and an unreachable sample is refused with
the same words as a compensated program's target. One code path for both keeps them from drifting.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from hil.arm.ik import UnreachableError
from hil.compensation.solve import Compensator


def solve_joint_path(compensator: Compensator, targets: Sequence[pin.SE3], seed: np.ndarray, *,
                     max_step: float = 0.05, where: Sequence[str] | None = None) -> np.ndarray:
    """(N, 6) joints putting the tool at each target by the accurate model, each solved near the
    previous one (the first near `seed`).

    Every target, the first included, only follows the previous joints by damped least squares (no
    branch search): a path starts from where the arm stands (`seed`), on the configuration the arm is
    in, and each sample is a control cycle from the last. The nearest-configuration search a single
    target gets (`Compensator.solve`) could start a path on another configuration — one where the upper
    arm points down, found nearer by joint distance — which the arm would have to swing through its
    workspace to reach.

    A step larger than `max_step` rad between consecutive targets means the solution jumped branches
    (or passes a singularity): refused as `UnreachableError`, naming the target (``where[i]``).
    """
    out = np.empty((len(targets), 6))
    q = np.asarray(seed, dtype=float)
    for i, target in enumerate(targets):
        name = where[i] if where else f"sample {i}"
        try:
            q_new = compensator.solve(target, q, search=False).q
        except UnreachableError as exc:
            raise UnreachableError(f"{name}: {exc}") from None
        step = float(np.max(np.abs(q_new - q)))
        if i and step > max_step:
            raise UnreachableError(f"{name}: the joints would jump by {step:.3f} rad in one cycle "
                                   "(singularity?)")
        out[i] = q = q_new
    return out
