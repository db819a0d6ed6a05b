"""Numerical inverse kinematics of the calibration model (damped least squares on pinocchio).

hil has no closed-form UR IK on purpose: the calibrated model is a general serial chain (every joint
origin carries a 6-D error), so the analytic solution of the nominal DH arm would put the tool where
the *nominal* arm would be. Damped least squares on the flange frame's Jacobian of `Kinematics(geometry)`
solves the calibrated chain itself. It is seeded from the previous sample along a path, so it stays on
the current branch; a target it cannot reach, or one that leaves the joint limits, raises
`UnreachableError` (never a silently clamped or nearby answer).

A model whose links do not sit at their encoder angles (compliance, angle-dependent joint errors;
docs/design.md, Contracts: non-geometric errors) is solved in two steps: the rigid chain gives the link
angles that put the flange at the target, then the encoder angles are the fixed point of
q ← q + (q_link − link(q)), link(q) = q − c ⊙ g(q) + e(q) being the model's map. Its contraction factor is
the map's departure from the identity, c·∂g/∂q + ∂e/∂q ≈ 10⁻³ per step, so a few steps reach the
tolerance. Lost motion is not applied: IK is told nothing about how the joint will approach.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from hil.arm.kinematics import Kinematics
from hil.errors import InputError


class UnreachableError(InputError):
    """A target pose the arm cannot reach (or only outside its joint limits)."""


def solve_ik(kin: Kinematics, target: pin.SE3, seed: np.ndarray, *, tolerance: float = 1e-9,
             max_iterations: int = 200, damping: float = 1e-8) -> np.ndarray:
    """Joint angles putting the flange at `target` (base frame, metres), starting from `seed`.

    Converges when the SE(3) error (log, metres/radians) is below `tolerance`. Raises
    UnreachableError when it does not within `max_iterations` or the answer is outside the limits.
    """
    model, data = kin.model, kin.data
    fid = model.getFrameId("flange")
    q = np.asarray(seed, dtype=float).copy()
    err = np.inf
    for _ in range(max_iterations):
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacement(model, data, fid)
        iMd = data.oMf[fid].actInv(target)
        e = pin.log6(iMd).vector
        err = float(np.linalg.norm(e))
        if err < tolerance:
            break
        J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
        J = -pin.Jlog6(iMd.inverse()) @ J
        # damping grows with the error: robust far away, exact (Gauss-Newton) near the solution
        lam = damping + 1e-3 * min(err, 1.0)
        dq = -J.T @ np.linalg.solve(J @ J.T + lam * np.eye(6), e)
        q = pin.integrate(model, q, dq)
    else:
        raise UnreachableError(f"IK did not converge (pose error {err:.3g}): the target is out of reach "
                               "or at a singularity")
    if not kin.geometry.encoder_exact:
        q = _encoder_angles(kin, q, tolerance)
    lo, hi = model.lowerPositionLimit, model.upperPositionLimit
    # a revolute joint reaches the same pose a turn away: take the turn nearest the seed that lies
    # within the limits (the same pose, not a clamp; far seeds otherwise wander off by 2π)
    turns = np.round((np.asarray(seed, dtype=float) - q) / (2 * np.pi))
    solved = q
    for k in (turns, turns - 1, turns + 1):  # nearest the seed first, then the turns either side
        alt = solved + 2 * np.pi * k
        q = np.where(((q < lo) | (q > hi) | (k == turns)) & (alt >= lo) & (alt <= hi), alt, q)
    if np.any(q < lo) or np.any(q > hi):
        j = int(np.flatnonzero((q < lo) | (q > hi))[0])
        raise UnreachableError(f"IK answer leaves the limits of joint {j + 1} ({q[j]:.3f} rad)")
    return q


def _encoder_angles(kin: Kinematics, q_link: np.ndarray, tolerance: float) -> np.ndarray:
    """The encoder angles whose link angles are `q_link` (fixed point, see the docstring)."""
    q = q_link.copy()
    for _ in range(50):
        nxt = q + (q_link - kin.link_angles(q)[0])
        if np.max(np.abs(nxt - q)) < 1e-3 * tolerance:
            return nxt
        q = nxt
    raise UnreachableError("IK: the encoder angles of these link angles do not settle (compliance or "
                           "joint errors too large)")


def solve_path(kin: Kinematics, targets: list[pin.SE3], seed: np.ndarray, max_step: float = 0.05,
               where: list[str] | None = None) -> np.ndarray:
    """(N, 6) joint angles along a path of flange poses, each seeded by the previous one.

    A step larger than `max_step` rad between consecutive samples means the solution jumped
    branches (or passes a singularity): refused, naming the sample (``where[i]`` when given).
    """
    out = np.empty((len(targets), 6))
    q = np.asarray(seed, dtype=float)
    for i, T in enumerate(targets):
        try:
            q_new = solve_ik(kin, T, q)
        except UnreachableError as exc:
            raise UnreachableError(f"{where[i] if where else f'sample {i}'}: {exc}") from None
        if i and np.max(np.abs(q_new - q)) > max_step:
            raise UnreachableError(f"{where[i] if where else f'sample {i}'}: the joints would jump by "
                                   f"{np.max(np.abs(q_new - q)):.3f} rad in one cycle (singularity?)")
        out[i] = q = q_new
    return out
